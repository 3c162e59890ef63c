"""benchmarks/data/goal_set.json is well formed and says what its dev tasks say."""

from __future__ import annotations

import json
import re
from collections import Counter
from pathlib import Path

import pytest

from conceptbot.bench.grading import load_dev_scene, load_tasks
from conceptbot.pipeline.goal import Goal

ROOT = Path(__file__).parents[3]
GOAL_SET = ROOT / "benchmarks" / "data" / "goal_set.json"


@pytest.fixture(scope="module")
def rows() -> list[dict]:
    return json.loads(GOAL_SET.read_text(encoding="utf-8"))["requests"]


@pytest.fixture(scope="module")
def tasks() -> dict:
    return {t.id: t for t in load_tasks(split="dev")}


def test_every_dev_request_is_there_once_with_at_least_two_paraphrases(rows: list[dict], tasks: dict) -> None:
    assert len(rows) >= 255
    originals = [r for r in rows if r["split"] == "original"]
    assert sorted(r["task"] for r in originals) == sorted(tasks)
    for row in originals:
        assert row["request"] == tasks[row["task"]].request
    paraphrases = Counter(r["task"] for r in rows if r["split"] == "paraphrase")
    assert set(paraphrases) == set(tasks) and min(paraphrases.values()) >= 2
    assert {r["split"] for r in rows} == {"original", "paraphrase"}
    assert {r["round"] for r in rows if r["split"] == "paraphrase"} == set(range(1, 17))
    requests = [r["request"] for r in rows]
    assert len(requests) == len(set(requests)), "a request twice"


def test_every_goal_uses_its_task_s_scene_names(rows: list[dict], tasks: dict) -> None:
    for row in rows:
        assert row["scene"] == tasks[row["task"]].scene
        scene = load_dev_scene(row["scene"])
        goal = Goal.from_dict(row["goal"])  # valid kinds and counts
        assert goal.targets, row["request"]
        for target in goal.targets:
            assert target.to is None or target.to in scene.destinations, (row["request"], target.to)
            assert set(target.named) <= set(scene.pickable), (row["request"], target.named)
            if target.takes == "named":
                assert target.named and target.count == len(target.named) and not target.criterion
            if target.takes in ("need", "ingredients"):
                assert target.to is None
        assert (goal.need is not None) == any(t.takes == "need" for t in goal.targets)
        assert (goal.dish is not None) == any(t.takes == "ingredients" for t in goal.targets)


def test_a_paraphrase_keeps_its_original_s_places_and_objects(rows: list[dict]) -> None:
    gold = {r["task"]: Goal.from_dict(r["goal"]) for r in rows if r["split"] == "original"}
    for row in rows:
        goal = Goal.from_dict(row["goal"])
        original = gold[row["task"]]
        assert goal.stack == original.stack and (goal.dish is None) == (original.dish is None)
        named = {n for t in goal.targets for n in t.named}
        assert named == {n for t in original.targets for n in t.named}, row["request"]
        places = {t.to for t in goal.targets if t.takes != "remainder"}
        assert places <= {t.to for t in original.targets}, row["request"]


def _grams(text: str, n: int = 4) -> set[tuple[str, ...]]:
    words = re.findall(r"[a-z0-9'&-]+", text.lower())
    return {tuple(words[i : i + n]) for i in range(len(words) - n + 1)}


def test_no_paraphrase_borrows_wording_from_the_test_split(rows: list[dict]) -> None:
    test = set().union(*(_grams(t.request) for t in load_tasks(split="test")))
    originals = {r["task"]: _grams(r["request"]) for r in rows if r["split"] == "original"}
    borrowed = {
        r["request"]: sorted(_grams(r["request"]) & test - originals[r["task"]])
        for r in rows
        if r["split"] == "paraphrase" and _grams(r["request"]) & test - originals[r["task"]]
    }
    assert borrowed == {}
