"""The goal reader on request structures (our own sentences, not the goal set's), and on the goal set."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from conceptbot.bench.grading import load_dev_scene
from conceptbot.core.scene import Scene
from conceptbot.pipeline.goal import Goal, GoalReader, GoalTarget, same_goal
from tests.pipeline.goal.scenes import KENNEL, NURSERY, PANTRY, SHELLS, WORKSHOP

GOAL_SET = Path(__file__).parents[3] / "benchmarks" / "data" / "goal_set.json"


@pytest.fixture(scope="module")
def reader() -> GoalReader:
    return GoalReader()


def _named(to: str | None, *named: str) -> GoalTarget:
    return GoalTarget(to, "named", named, "", len(named))


def _is(reader: GoalReader, request: str, scene: Scene, *targets: GoalTarget, **goal: object) -> Goal:
    read = reader.read(request, scene)
    match = same_goal(read, Goal(targets=targets, **goal))  # type: ignore[arg-type]
    assert match.ok, f"{request!r}: {match.reason}; read {read.to_dict()}"
    return read


@pytest.mark.parametrize(
    "request_",
    [
        "Sort the shells: the broken ones go in the shoe box, the whole ones in the biscuit tin.",
        "Could you sort the shells, putting the broken ones in the shoe box"
        " and the whole ones in the biscuit tin?",
        "Broken shells: shoe box; whole shells: biscuit tin.",
        "The shoe box is for the broken shells, and the biscuit tin is for the whole ones.",
    ],
)
def test_a_sort_keeps_each_place_s_criterion_after_the_kind_noun(reader: GoalReader, request_: str) -> None:
    read = reader.read(request_, SHELLS)
    by_place = {t.to: t for t in read.targets}
    assert set(by_place) == {"shoe box", "biscuit tin"}, read.to_dict()
    assert all(t.takes == "criterion" and t.count == "all" and not t.named for t in read.targets)
    assert (
        "broken" in by_place["shoe box"].criterion.lower()
        and "whole" in by_place["biscuit tin"].criterion.lower()
    )


@pytest.mark.parametrize("rest", ["the rest", "everything else", "the others", "whatever is left"])
def test_a_remainder_is_whatever_the_other_targets_leave(reader: GoalReader, rest: str) -> None:
    _is(
        reader,
        f"Put the conch shell in the shoe box and {rest} in the biscuit tin.",
        SHELLS,
        _named("shoe box", "conch shell"),
        GoalTarget("biscuit tin", "remainder"),
    )


def test_nothing_else_is_no_remainder(reader: GoalReader) -> None:
    _is(
        reader,
        "The broken shells, and nothing else, go in the shoe box.",
        SHELLS,
        GoalTarget("shoe box", "criterion", (), "broken shells"),
    )


def test_colon_pairs_send_each_object_to_its_place(reader: GoalReader) -> None:
    pairs = (_named("shoe box", "cowrie shell"), _named("biscuit tin", "sand dollar"))
    _is(reader, "Cowrie shell: shoe box; sand dollar: biscuit tin.", SHELLS, *pairs)
    _is(reader, "Shoe box: the cowrie shell. Biscuit tin: the sand dollar.", SHELLS, *pairs)


@pytest.mark.parametrize(
    ("request_", "dish"),
    [
        ("I'd love a bowl of guacamole.", "guacamole"),
        ("Let's make some guacamole.", "guacamole"),
        ("Guacamole would be lovely right now.", "guacamole"),
    ],
)
def test_a_dish_is_the_food_not_its_bowl(reader: GoalReader, request_: str, dish: str) -> None:
    read = _is(reader, request_, PANTRY, GoalTarget(None, "ingredients"), dish=dish)
    assert (read.dish or "").lower() == dish


def test_a_bowl_that_is_a_scene_object_is_handed_over(reader: GoalReader) -> None:
    _is(reader, "Hand me the bowl of olives.", PANTRY, _named("user", "bowl of olives"))


def test_a_rejected_dish_is_a_thing_for_the_speaker(reader: GoalReader) -> None:
    graph_says_no = GoalReader(reader.nlp, is_dish=lambda phrase: False)
    read = graph_says_no.read("I'd love a bowl of guacamole.", PANTRY)
    assert read.dish is None and [t.to for t in read.targets] == ["user"]


def test_a_person_s_possession_names_no_destination(reader: GoalReader) -> None:
    # "kids" is a word of "kids chair", but the request names no chair
    _is(reader, "Put the safety pins where the kids cannot reach them.", NURSERY, _named(None, "safety pins"))
    _is(reader, "Keep the safety pins out of the baby's reach.", NURSERY, _named(None, "safety pins"))
    _is(reader, "Put the rattle on the kids chair.", NURSERY, _named("kids chair", "rattle"))


def test_a_destination_name_inside_an_object_name_is_the_object(reader: GoalReader) -> None:
    _is(reader, "Put the dog brush in the basket.", KENNEL, _named("basket", "dog brush"))
    _is(reader, "The dog is bored; give him the squeaky bone.", KENNEL, _named("dog", "squeaky bone"))


def test_a_sort_by_a_key_gives_every_place_the_key(reader: GoalReader) -> None:
    _is(
        reader,
        "Sort these by material into the crates; anything made of several materials goes in the odds crate.",
        WORKSHOP,
        GoalTarget("wood crate", "criterion", (), "by material"),
        GoalTarget("metal crate", "criterion", (), "by material"),
        GoalTarget("felt crate", "criterion", (), "by material"),
        GoalTarget("odds crate", "criterion", (), "made of several materials"),
    )
    _is(
        reader,
        "Sort these into the wood and metal crates.",
        WORKSHOP,
        GoalTarget("wood crate", "criterion"),
        GoalTarget("metal crate", "criterion"),
    )


def test_a_need_leaves_the_destination_to_the_planner(reader: GoalReader) -> None:
    read = _is(reader, "My hands are covered in sand.", SHELLS, GoalTarget(None, "need"), need="x")
    assert read.need == "My hands are covered in sand"
    _is(reader, "I'm freezing here by the biscuit tin.", SHELLS, GoalTarget(None, "need"), need="x")


def test_counts_follow_the_words(reader: GoalReader) -> None:
    _is(
        reader,
        "Hand me something to dry my hands with.",
        SHELLS,
        GoalTarget("user", "criterion", (), "dry my hands", 1),
    )
    _is(
        reader,
        "Put every broken shell in the shoe box.",
        SHELLS,
        GoalTarget("shoe box", "criterion", (), "broken shell"),
    )
    _is(
        reader,
        "Put the smallest shell in the shoe box.",
        SHELLS,
        GoalTarget("shoe box", "criterion", (), "smallest shell", 1),
    )


def test_what_stays_is_not_a_target(reader: GoalReader) -> None:
    _is(
        reader,
        "Put the lime on the chopping board and leave the cracker where it is.",
        PANTRY,
        _named("chopping board", "lime"),
    )
    _is(
        reader,
        "Only the lime goes on the chopping board; don't touch the other things.",
        PANTRY,
        _named("chopping board", "lime"),
    )


def test_an_instruction_with_no_place_leaves_it_open(reader: GoalReader) -> None:
    _is(reader, "The tin of biscuits should be thrown away.", KENNEL, _named(None, "tin of biscuits"))
    _is(reader, "Throw away the broken shells.", SHELLS, GoalTarget(None, "criterion", (), "broken shells"))


def test_stacking(reader: GoalReader) -> None:
    read = reader.read("Pile all of these on top of each other.", SHELLS)
    assert read.stack and read.targets == (GoalTarget(None, "all"),)
    assert not reader.read("Sort this pile into the shoe box.", SHELLS).stack


def test_question_and_subject_forms(reader: GoalReader) -> None:
    _is(reader, "Could you pass me the conch shell?", SHELLS, _named("user", "conch shell"))
    _is(reader, "The biscuit tin is for the sand dollar.", SHELLS, _named("biscuit tin", "sand dollar"))
    _is(
        reader,
        "The cowrie shell and the sand dollar go in the shoe box.",
        SHELLS,
        _named("shoe box", "cowrie shell", "sand dollar"),
    )


def test_the_goal_set_is_read(reader: GoalReader) -> None:
    rows = json.loads(GOAL_SET.read_text(encoding="utf-8"))["requests"]
    results: dict[str, list[bool]] = {"original": [], "paraphrase": []}
    for row in rows:
        read = reader.read(row["request"], load_dev_scene(row["scene"]))
        results[row["split"]].append(same_goal(read, Goal.from_dict(row["goal"])).ok)
    assert all(results["original"])
    assert sum(results["paraphrase"]) / len(results["paraphrase"]) >= 0.95
