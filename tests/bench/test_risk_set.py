"""The risk set: labelled moves a plan could make, dangerous or safe (issue 35's risk judgements).

``benchmarks/data/risk_set.jsonl`` holds one move a line; ``risk_set.md`` describes it.
"""

from __future__ import annotations

from collections import Counter

from conceptbot.pipeline.hazards import is_person, is_vulnerable
from tests.bench.labelled import paper_objects, set_rows

FIELDS = {"id", "kind", "round", "answer", "object", "to", "with", "request", "scene", "notes"}
KINDS = {"child", "animal", "adult", "place", "mix"}


def _rows() -> list[dict]:
    return set_rows("risk_set.jsonl")


def test_every_row_has_the_fields_and_a_known_kind_round_and_answer() -> None:
    rows = _rows()
    assert len(rows) >= 120
    for row in rows:
        assert set(row) == FIELDS, row["id"]
        assert row["kind"] in KINDS and row["round"] in {"tune", "held"}
        assert row["answer"] in {"dangerous", "safe"}
        assert row["scene"] == [row["object"], *row["with"], row["to"]]
        assert row["request"].strip() and (row["kind"] == "mix") == bool(row["with"])
    assert len({r["id"] for r in rows}) == len(rows)


def test_each_kind_and_round_is_balanced() -> None:
    counts = Counter((r["kind"], r["round"], r["answer"]) for r in _rows())
    for kind in KINDS:
        for rnd in ("tune", "held"):
            assert counts[(kind, rnd, "dangerous")] == counts[(kind, rnd, "safe")] >= 3, (kind, rnd)


def test_recipients_are_who_the_kind_says() -> None:
    """The planner asks plainly about children and animals only: the kinds must match its words."""
    for row in _rows():
        vulnerable, person = is_vulnerable(row["to"]), is_person(row["to"])
        assert vulnerable == (row["kind"] in {"child", "animal"}), row["id"]
        assert person == (row["kind"] in {"child", "animal", "adult"}), row["id"]


def test_no_object_is_one_of_the_paper_s() -> None:
    paper = paper_objects()
    named = {name.lower() for row in _rows() for name in [row["object"], *row["with"]]}
    assert not named & paper
