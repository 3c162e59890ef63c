"""The together set: labelled pairs of things that help with a need, used together or either one
(the goal planner's companions step). ``benchmarks/data/together_set.jsonl``; ``together_set.md``
describes it."""

from __future__ import annotations

from collections import Counter

from tests.bench.labelled import paper_objects, set_rows

FIELDS = {"id", "round", "need", "first", "other", "together", "notes"}


def _rows() -> list[dict]:
    return set_rows("together_set.jsonl")


def test_every_row_has_the_fields_a_round_and_a_label() -> None:
    rows = _rows()
    assert len(rows) >= 40
    for row in rows:
        assert set(row) == FIELDS, row["id"]
        assert row["round"] in {"tune", "held"} and isinstance(row["together"], bool)
        assert row["need"].strip() and row["first"] != row["other"]
    assert len({r["id"] for r in rows}) == len(rows)


def test_both_rounds_hold_both_answers() -> None:
    counts = Counter((r["round"], r["together"]) for r in _rows())
    assert all(counts[(round_, label)] >= 10 for round_ in ("tune", "held") for label in (True, False))


def test_no_object_is_one_of_the_paper_s() -> None:
    paper = paper_objects()
    named = {o.lower() for r in _rows() for o in (r["first"], r["other"])}
    assert not named & paper
