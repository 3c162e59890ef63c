"""The goal reader on request structures (our own sentences, not the goal set's), and on the goal set."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from conceptbot.bench.grading import load_dev_scene
from conceptbot.core.scene import Scene, scene_from_dict
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


@pytest.mark.parametrize(
    "request_",
    [
        "The dog is barking and I can't sleep.",  # the first clause is the reason for the one need
        "I fell off the ladder and scraped my elbow.",  # an event and its outcome: one need
        "I'm on the sofa and I'm frozen.",  # where the speaker is: no need of its own
        "I burnt my hand. It hurts.",
        "My hands are covered in sand.",
        "I'm freezing. Can you help?",  # a question after the need is no need of its own
        "I'm painting the fence and it's getting dark.",  # the speaker's doing is no need of its own
    ],
)
def test_one_need_with_its_reason_stays_one_need(reader: GoalReader, request_: str) -> None:
    assert reader.read(request_, SHELLS).targets == (GoalTarget(None, "need"),)


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
    results: dict[str, list[bool]] = {}
    wrong = []
    for row in rows:
        read = reader.read(row["request"], load_dev_scene(row["scene"]))
        key = row["split"] if row["split"] == "original" else f"round {row['round']}"
        results.setdefault(key, []).append(same_goal(read, Goal.from_dict(row["goal"])).ok)
        if key == "original" and not results[key][-1]:
            wrong.append(row["task"])
    # The rules that won no task of blind set 1 were removed on 2026-12-07 (docs/planning.md,
    # "Ablations"): two needs in one request, exceptions, places called by another word, "each
    # into the bin for its material", conditions, polite frames. The originals written for them
    # are read otherwise now; every other original is right.
    assert wrong == [
        "dev-implicit-22", "dev-implicit-23", "dev-implicit-24", "dev-materials-14", "dev-toxic-14",
        "dev-materials-16", "dev-materials-17", "dev-materials-18", "dev-ambiguous-21",
        "dev-ambiguous-22", "dev-ambiguous-23",
    ]  # fmt: skip
    # Floors that keep the rules' reading of the words from slipping. Rounds 1-10 and 14 were tuned
    # on; they lost 5-12 rows each with the removed rules (round 6: 145 -> 135, round 8: 80 -> 70).
    # Held out: round 11 (54/98, as before), 12 (56/98; 57 before), 15 (4/6; 3/6 before).
    tuned = [ok for r in (1, 2, 3, 4, 5) for ok in results[f"round {r}"]]
    assert sum(tuned) >= 460  # of 517
    floors = {6: 135, 7: 13, 8: 70, 9: 51, 10: 48, 11: 54, 12: 56, 14: 2, 15: 4}
    assert {r: sum(results[f"round {r}"]) >= n for r, n in floors.items()} == dict.fromkeys(floors, True)


# Structures that paraphrase round 4 exposed (our own sentences and scenes).


def _criterion(to: str | None, criterion: str, count: int | str = "all") -> GoalTarget:
    return GoalTarget(to, "criterion", (), criterion, count)  # type: ignore[arg-type]


def test_make_sure_asks_for_the_state_it_names(reader: GoalReader) -> None:
    _is(
        reader,
        "Make sure the conch shell ends up in the shoe box.",
        SHELLS,
        _named("shoe box", "conch shell"),
    )
    _is(
        reader,
        "The baby is crawling now, so make sure anything sharp is up on the top shelf.",
        NURSERY,
        _criterion("top shelf", "sharp"),
    )


def test_a_topic_set_apart_is_what_it_sends(reader: GoalReader) -> None:
    _is(
        reader,
        "The conch shell goes in the shoe box; as for the sand dollar, it goes in the biscuit tin.",
        SHELLS,
        _named("shoe box", "conch shell"),
        _named("biscuit tin", "sand dollar"),
    )
    _is(
        reader,
        "Any shells that are chipped, put them in the shoe box.",
        SHELLS,
        _criterion("shoe box", "shells that are chipped"),
    )


def test_a_spaced_dash_ends_a_clause(reader: GoalReader) -> None:
    _is(
        reader,
        "Put the nappy cream on the top shelf - the baby keeps opening it.",
        NURSERY,
        _named("top shelf", "nappy cream"),
    )


def test_a_passive_question_asks_for_what_it_moves(reader: GoalReader) -> None:
    _is(reader, "Could the dog lead be brought over to me?", KENNEL, _named("user", "dog lead"))
    _is(reader, "Could something to eat be brought to me?", PANTRY, _criterion("user", "something to eat", 1))


def test_them_refers_back_to_every_object_named(reader: GoalReader) -> None:
    _is(
        reader,
        "The scallop shell and the sand dollar are sandy, so put them in the shoe box.",
        SHELLS,
        _named("shoe box", "scallop shell", "sand dollar"),
    )


def test_only_phrases_and_whichever(reader: GoalReader) -> None:
    _is(
        reader,
        "Nothing but the broken shells should go in the shoe box.",
        SHELLS,
        _criterion("shoe box", "broken shells"),
    )
    _is(
        reader,
        "Whichever shell is the biggest goes in the biscuit tin.",
        SHELLS,
        _criterion("biscuit tin", "shell is the biggest", 1),
    )


def test_a_wish_keeps_the_objects_joined_on(reader: GoalReader) -> None:
    _is(reader, "Could I have the lime, and the cracker as well?", PANTRY, _named("user", "lime", "cracker"))


def test_looking_at_something_sends_nothing(reader: GoalReader) -> None:
    _is(reader, "Look at my hands, they're covered in sand.", SHELLS, GoalTarget(None, "need"), need="x")


@pytest.mark.parametrize(
    "request_",
    [
        "",
        "   ",
        "...",
        "?!;:",
        " - ",
        "if",
        "make sure",
        "I'd appreciate it if you",
        "otherwise",
        "as for",
        "let's make one",
        "it goes",
        "Les coquillages → la boîte ☃ 🐚 ½",
        "Put the conch shell in the shoe box. " * 400,
        "and and , , , or",
        "\n\t",
    ],
)
def test_odd_input_never_raises(reader: GoalReader, request_: str) -> None:
    read = reader.read(request_, SHELLS)
    assert isinstance(read, Goal) and read.targets


def test_a_rule_that_trips_leaves_a_need(reader: GoalReader, monkeypatch: pytest.MonkeyPatch) -> None:
    import conceptbot.pipeline.goal.reader as reader_module

    def trips(*args: object, **kwargs: object) -> None:
        raise IndexError("an odd parse")

    monkeypatch.setattr(reader_module, "_items", trips)
    read = reader.read("Put the conch shell in the shoe box.", SHELLS)
    assert read.need and read.targets == (GoalTarget(None, "need"),)


_DESK = scene_from_dict(
    {
        "pickable_objects": ["plum", "water bottle", "hole punch", "pretzels", "notebook"],
        "destinations": ["user", "cupboard", "windowsill"],
    }
)


def test_a_three_item_list_sends_every_named_object(reader: GoalReader) -> None:
    _is(
        reader,
        "Fetch me the plum, the notebook and the water bottle.",
        _DESK,
        _named("user", "plum", "notebook", "water bottle"),
    )


def test_a_list_of_two_indefinites_is_two_things(reader: GoalReader) -> None:
    _is(
        reader,
        "I'd like something to nibble on and a cushion.",
        _DESK,
        GoalTarget("user", "criterion", (), "something to nibble on", 1),
        GoalTarget("user", "criterion", (), "cushion", 1),
    )


def test_a_list_mixing_a_name_and_an_indefinite_keeps_both(reader: GoalReader) -> None:
    _is(
        reader,
        "Could you pass me the notebook and something to write with?",
        _DESK,
        _named("user", "notebook"),
        GoalTarget("user", "criterion", (), "something to write with", 1),
    )
    _is(
        reader,
        "Grab me a bag of pretzels and something cold to drink.",
        _DESK,
        _named("user", "pretzels"),
        GoalTarget("user", "criterion", (), "something cold to drink", 1),
    )


def test_lists_for_two_places_stay_apart(reader: GoalReader) -> None:
    _is(
        reader,
        "Put the plum on the windowsill and give me the hole punch and the pretzels.",
        _DESK,
        _named("windowsill", "plum"),
        _named("user", "hole punch", "pretzels"),
    )
    _is(
        reader,
        "The notebook, the plum and the water bottle go in the cupboard.",
        _DESK,
        _named("cupboard", "notebook", "plum", "water bottle"),
    )


def test_requests_put_as_questions_send_to_who_asks_or_is_named(reader: GoalReader) -> None:
    _is(
        reader,
        "May I borrow something crunchy?",
        PANTRY,
        GoalTarget("user", "criterion", (), "something crunchy", 1),
    )
    _is(reader, "Would you mind passing the dog lead my way?", KENNEL, _named("user", "dog lead"))


def test_a_gapped_second_clause_keeps_its_own_place(reader: GoalReader) -> None:
    _is(
        reader,
        "Put the plum in the cupboard, and the notebook on the windowsill.",
        _DESK,
        _named("cupboard", "plum"),
        _named("windowsill", "notebook"),
    )
    _is(reader, "Put the plum, and only the plum, in the cupboard.", _DESK, _named("cupboard", "plum"))


_GARDEN = scene_from_dict(
    {
        "pickable_objects": ["trowel", "watering can", "seed packet", "apple", "bread roll"],
        "destinations": ["user", "shed shelf", "compost bin", "potting bench"],
    }
)


@pytest.mark.parametrize(
    "request_",
    [
        "Do you think you could pass me the trowel?",
        "Could you pass me the trowel?",
    ],
)
def test_a_politeness_frame_reads_as_the_plain_request(reader: GoalReader, request_: str) -> None:
    _is(reader, request_, _GARDEN, _named("user", "trowel"))


def test_as_well_as_and_plus_join_like_and(reader: GoalReader) -> None:
    _is(
        reader,
        "Put the trowel on the shed shelf, plus the seed packet.",
        _GARDEN,
        _named("shed shelf", "trowel", "seed packet"),
    )
    _is(
        reader,
        "Could you hand me an apple, as well as something to dig with?",
        _GARDEN,
        _named("user", "apple"),
        GoalTarget("user", "criterion", (), "something to dig with", 1),
    )


def test_on_me_after_a_verb_that_moves_nothing_is_no_place(reader: GoalReader) -> None:
    read = reader.read("My watering can just broke on me.", _GARDEN)
    assert read.need is not None and read.targets == (GoalTarget(None, "need"),)


def test_both_before_two_indefinites_asks_for_one_of_each(reader: GoalReader) -> None:
    _is(
        reader,
        "Could you hand me both something to nibble on and a cushion?",
        _DESK,
        GoalTarget("user", "criterion", (), "something to nibble on", 1),
        GoalTarget("user", "criterion", (), "cushion", 1),
    )


def test_a_thing_handed_to_no_one_named_goes_to_the_speaker(reader: GoalReader) -> None:
    _is(reader, "Could you bring the trowel over?", _GARDEN, _named("user", "trowel"))


def test_a_terse_bare_noun_asks_for_one(reader: GoalReader) -> None:
    _is(
        reader,
        "Snack and a cushion, please.",
        _DESK,
        GoalTarget("user", "criterion", (), "snack", 1),
        GoalTarget("user", "criterion", (), "cushion", 1),
    )


def test_a_polite_fragment_naming_a_dish_asks_for_the_dish() -> None:
    reader = GoalReader(is_dish=lambda words: "crumble" in words)
    read = reader.read("Apple crumble, please!", _GARDEN)
    assert read.dish is not None and "crumble" in read.dish
    assert reader.read("Something for my sore hands, please.", _GARDEN).dish is None
    assert GoalReader().read("Apple crumble, please!", _GARDEN).dish is None  # no graph: a thing
