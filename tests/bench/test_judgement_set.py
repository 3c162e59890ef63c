"""The judgement set: labelled (object, criterion) judgements for sorting requests (issue 33, item 2).

``benchmarks/data/judgement_set.jsonl`` holds one judgement a line; ``judgement_set.md`` describes it.
"""

from __future__ import annotations

import json
import re
from collections import Counter, defaultdict
from pathlib import Path

import pytest

from conceptbot.bench.grading import load_tasks

DATA = Path(__file__).resolve().parents[2] / "benchmarks" / "data"
SET = DATA / "judgement_set.jsonl"
PAPER_OBJECTS = DATA / "paper_objects.txt"

FIELDS = {"object", "criterion", "kind", "answer", "request", "source"}
OPTIONAL = {"notes"}
# The fewest rows each kind must have.
MINIMUM = {
    "toxic": 100,
    "pet-toxic": 60,
    "edible": 80,
    "venomous": 30,
    "material-only": 120,
    "multi-material": 50,
    "material-class": 50,
    "ingredient": 80,
    "need": 40,
    "child-safe": 40,
}
MAX_ONE_ANSWER = 0.7  # neither answer may make up more than this share of a kind's rows
MIN_DISHES = 10
# An ingredient row's criterion names its dish: "an ingredient of guacamole" (also "for" or "in").
INGREDIENT = re.compile(r"^(?:an?\s+)?ingredients?\s+(?:of|for|in)\s+(?:an?\s+|the\s+)?(.+)$")
# A paper name ending in a class word also forbids the name without it ("death cap" for "Death Cap Mushroom").
CLASS_WORDS = ("mushroom", "plant")


def words(text: str) -> str:
    """Lower-case words of a name or request, to compare them."""
    return " ".join(re.findall(r"[a-z0-9]+", text.lower()))


def load_rows() -> list[dict]:
    lines = SET.read_text(encoding="utf-8").splitlines()
    rows = []
    for number, line in enumerate(lines, 1):
        assert line.strip(), f"line {number} is blank"
        row = json.loads(line)
        assert isinstance(row, dict), f"line {number} is not a JSON object"
        rows.append(row)
    return rows


@pytest.fixture(scope="module")
def rows() -> list[dict]:
    return load_rows()


def test_every_row_has_the_fields_with_their_types(rows: list[dict]) -> None:
    for number, row in enumerate(rows, 1):
        assert FIELDS <= set(row) <= FIELDS | OPTIONAL, (number, sorted(set(row) ^ FIELDS))
        for field in (FIELDS - {"answer"}) | (OPTIONAL & set(row)):
            value = row[field]
            assert isinstance(value, str) and value.strip() == value and value, (number, field, value)
        assert isinstance(row["answer"], bool), (number, row["answer"])
        assert row["kind"] in MINIMUM, (number, row["kind"])


def test_size_and_per_kind_minimums_with_both_answers_represented(rows: list[dict]) -> None:
    assert len(rows) >= 650
    counts = Counter(row["kind"] for row in rows)
    answers = Counter((row["kind"], row["answer"]) for row in rows)
    for kind, minimum in MINIMUM.items():
        assert counts[kind] >= minimum, (kind, counts[kind], minimum)
        for answer in (True, False):
            share = answers[kind, answer] / counts[kind]
            assert share <= MAX_ONE_ANSWER, (kind, answer, share)


def test_criteria_are_worded_in_several_ways_and_ingredients_span_ten_dishes(rows: list[dict]) -> None:
    criteria = defaultdict(set)
    for row in rows:
        criteria[row["kind"]].add(words(row["criterion"]))
    for kind in MINIMUM:
        assert len(criteria[kind]) >= 3, (kind, criteria[kind])
    dishes = set()
    for row in rows:
        if row["kind"] == "ingredient":
            dish = INGREDIENT.match(row["criterion"].lower())
            assert dish, row["criterion"]
            dishes.add(words(dish.group(1)))
    assert len(dishes) >= MIN_DISHES, dishes


def test_no_object_is_one_of_the_papers(rows: list[dict]) -> None:
    names = [line.strip() for line in PAPER_OBJECTS.read_text(encoding="utf-8").splitlines()]
    paper = {words(name) for name in names if name and not name.startswith("#")}
    paper |= {name.rsplit(" ", 1)[0] for name in paper if name.endswith(CLASS_WORDS) and " " in name}
    assert len(paper) > 100
    for row in rows:
        name = words(row["object"])
        singulars = {name, name.removesuffix("s"), name.removesuffix("es")}
        assert not singulars & paper, row["object"]


def test_no_object_and_criterion_pair_has_two_answers(rows: list[dict]) -> None:
    answers = defaultdict(set)
    for row in rows:
        answers[words(row["object"]), words(row["criterion"])].add(row["answer"])
    assert not [pair for pair, given in answers.items() if len(given) > 1]


def test_dev_sources_are_dev_tasks_and_new_requests_are_not_the_papers(rows: list[dict]) -> None:
    dev = {task.id: task for task in load_tasks(split="dev")}
    test_requests = {words(task.request) for task in load_tasks()}
    sources = Counter(row["source"] for row in rows)
    assert sources["new"] and len(sources) > 1
    for row in rows:
        if row["source"] == "new":
            assert words(row["request"]) not in test_requests, row["request"]
        else:
            assert row["source"] in dev, row["source"]
            assert row["request"] == dev[row["source"]].request, (row["source"], row["object"])


def test_rows_sharing_a_request_and_criterion_name_each_object_once(rows: list[dict]) -> None:
    seen = Counter((row["request"], row["criterion"], words(row["object"])) for row in rows)
    assert not [key for key, count in seen.items() if count > 1]
