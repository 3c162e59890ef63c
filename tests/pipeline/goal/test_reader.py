"""The goal reader on request structures (our own sentences, not the goal set's), and on the goal set."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

from conceptbot.bench.grading import load_dev_scene
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.pipeline.goal import Goal, GoalReader, GoalTarget, same_goal
from tests.pipeline.goal.scenes import KENNEL, NURSERY, PANTRY, SHELLS, WORKSHOP

GOAL_SET = Path(__file__).parents[3] / "benchmarks" / "data" / "goal_set.json"


#: A few IsA parents, as the graph states them, for places called by another word ("basket" for bin).
PARENTS = {
    "bin": {"container", "box"},
    "basket": {"container"},
    "box": {"container"},
    "crate": {"box"},
    "receptacle": {"container"},
    "container": {"object"},
    "shelf": {"support"},
    "tray": {"receptacle"},
}


def same_kind(word: str, other: str) -> bool:
    """FactFinder.same_kind over PARENTS."""
    mine, theirs = PARENTS.get(word, set()), PARENTS.get(other, set())
    return word == other or other in mine or word in theirs or bool(mine & theirs)


@pytest.fixture(scope="module")
def reader() -> GoalReader:
    return GoalReader(same_kind=same_kind)


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
    ("request_", "parts"),
    [
        ("I'm sunburnt and my throat is sore.", ["I'm sunburnt", "my throat is sore"]),
        ("We're hungry and there's nothing to do.", ["We're hungry", "there's nothing to do"]),
        ("I'm hungry and thirsty.", ["I'm hungry", "I'm thirsty"]),
        ("I have a cold and a sore throat.", ["I have a cold", "I have a sore throat"]),
        ("I'm cold. My feet are sore.", ["I'm cold", "My feet are sore"]),
        # "it" joined to the speaker's clause: the surroundings, or the thing just spoken of
        ("I'm thirsty, and it's very dark in here.", ["I'm thirsty", "it's very dark in here"]),
        (
            "Oh, my shirt is torn and it's covered in mud.",
            ["Oh my shirt is torn", "my shirt's covered in mud"],
        ),
        # the present perfect says how things are now; a thing's "-ing" is its state
        ("My nose is running, and I've scraped my elbow.", ["My nose is running", "I've scraped my elbow"]),
        # the parser reads "feet's" as a possessive: read again with "is"
        ("My feet's cold and full of sand.", ["My feet is cold", "My feet is full of sand"]),
        (
            "I've got a blister on my toe and a runny nose.",
            ["I've got a blister on my toe", "I've got a runny nose"],
        ),
    ],
)
def test_a_request_stating_two_needs_has_a_need_target_for_each(
    reader: GoalReader, request_: str, parts: list[str]
) -> None:
    read = reader.read(request_, SHELLS)
    assert read.need == request_.rstrip(".")
    assert [(t.to, t.takes, t.criterion) for t in read.targets] == [(None, "need", p) for p in parts]


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
    # "I cut my finger and now I have a pounding headache": two needs the syntax cannot tell from
    # a cause and its effect (pipeline/goal/needs.py); "the right container for what it's made of"
    # reads as a sort by the bins' names, not "by material" (the same plan); every other is right
    assert wrong == ["dev-implicit-22", "dev-materials-16"]
    # Rounds 1-5 were tuned on (each after its blind run), round 6 too after its blind run (131/170
    # when written): the floors keep what was reached from slipping.
    tuned = [ok for r in (1, 2, 3, 4, 5) for ok in results[f"round {r}"]]
    assert sum(tuned) / len(tuned) >= 0.95
    assert sum(results["round 6"]) >= 140
    # Round 7 was tuned on after its blind run (16/26; 26/26 after)
    assert sum(results["round 7"]) >= 25
    # Round 8 was tuned on after its blind run (76/91; 72/91 with the reader before round 7's fixes)
    assert sum(results["round 8"]) >= 80
    # Round 9 (spoken constructions: reasons, asides, "any chance", "as well as") was tuned on after
    # its blind run (50/98; 49/98 with the reader before round 7's fixes)
    assert sum(results["round 9"]) >= 60
    # Round 10 (terse commands and indirect requests) was tuned on after its blind run (55/98; 55/98
    # with last session's reader too)
    assert sum(results["round 10"]) >= 58  # 66/98 with the graph's dish checks
    # Round 11 (five voices: a busy parent, an older person, a teenager, a learner of English,
    # someone thinking aloud) is held out: 55/98 when first measured (54/98 with the reader of the
    # session before rounds 7-10 were tuned on)
    assert sum(results["round 11"]) >= 54
    # Round 13 (places called by another word than the scene's, for the dev tasks added on
    # 2026-12-05) is held out: 4/6 when first measured, 5/6 after a fix made for the originals
    assert sum(results["round 13"]) >= 5
    # Round 14 (an object named to be left out, for the dev tasks added on 2026-12-05) was tuned
    # on after its blind run (2/6: exceptions after the place, fronted, or after "but"; 5/6 after);
    # round 15, written then, is held out: 3/6 when first measured
    assert sum(results["round 14"]) >= 5
    assert sum(results["round 15"]) >= 3


@pytest.mark.parametrize(
    ("request_", "criterion", "count", "excluded"),
    [
        ("Pass me a drink other than the juice box.", "drink", 1, ("juice box",)),
        ("Hand me a drink that isn't the juice box.", "drink", 1, ("juice box",)),
        ("Give me any drink except the juice box.", "drink", "all", ("juice box",)),
        ("Hand me something to drink apart from the thermos.", "something to drink", 1, ("thermos",)),
    ],
)
def test_an_object_named_in_an_exception_is_left_out_not_sent(
    reader: GoalReader, request_: str, criterion: str, count: int | str, excluded: tuple[str, ...]
) -> None:
    [target] = reader.read(request_, load_dev_scene("dev-picnic")).targets
    assert (target.to, target.takes, target.criterion, target.count) == (
        "user",
        "criterion",
        criterion,
        count,
    )
    assert target.excluded == excluded


@pytest.mark.parametrize(
    "request_",
    [
        "Excluding the thermos, put the drinks in the picnic basket.",
        "Put the drinks in the picnic basket, apart from the thermos.",
        "Put the drinks in the picnic basket, but not the thermos.",
    ],
)
def test_an_exception_outside_the_object_phrase_is_the_request_s(reader: GoalReader, request_: str) -> None:
    [target] = reader.read(request_, load_dev_scene("dev-picnic")).targets
    assert (target.to, target.takes, target.criterion, target.excluded) == (
        "picnic basket",
        "criterion",
        "drinks",
        ("thermos",),
    )


def test_a_list_an_exception_opens_is_left_out_whole(reader: GoalReader) -> None:
    request_ = "Put everything except the thermos and the sandwich in the picnic basket."
    [target] = reader.read(request_, load_dev_scene("dev-picnic")).targets
    assert (target.takes, target.excluded) == ("all", ("thermos", "sandwich"))


def test_only_phrases_and_negated_criteria_are_no_exceptions(reader: GoalReader) -> None:
    picnic = load_dev_scene("dev-picnic")
    assert reader.read("Give me nothing but the sandwich.", picnic).targets == (_named("user", "sandwich"),)
    # "not" naming no scene object is part of the criterion, as before
    [target] = reader.read("Put the things that are not food in the picnic basket.", picnic).targets
    assert target.excluded == () and "not food" in target.criterion
    # everything but one object: all of them, less it
    [target] = reader.read("Put everything except the thermos in the picnic basket.", picnic).targets
    assert (target.to, target.takes, target.excluded) == ("picnic basket", "all", ("thermos",))


def test_places_called_by_another_word_are_the_scene_s(reader: GoalReader) -> None:
    scene = load_dev_scene("dev-recycling-station")
    bins = ("glass bin", "paper bin", "plastic bin", "metal bin", "mixed bin")
    read = reader.read("Put the empties in the right baskets according to their material.", scene)
    assert tuple(t.to for t in read.targets) == bins
    assert {t.criterion for t in read.targets} == {"by material"}
    # one of them by its other words; and each object's own one ("for what it is made of")
    assert reader.read("Put the newspaper in the paper basket.", scene).targets == (
        _named("paper bin", "newspaper"),
    )
    read = reader.read("Drop each empty into the right container for what it's made of.", scene)
    assert tuple(t.to for t in read.targets) == bins
    # not a kind of bin: no place is guessed
    assert [t.to for t in reader.read("Put the empties on the shelves.", scene).targets] == [None]
    # without the graph's word on kinds, only the scene's own words name places
    plain = GoalReader(nlp=reader.nlp)
    assert [t.to for t in plain.read("Put the newspaper in the paper basket.", scene).targets] != [
        "paper bin"
    ]


# Structures that paraphrase round 4 exposed (our own sentences and scenes).


def _criterion(to: str | None, criterion: str, count: int | str = "all") -> GoalTarget:
    return GoalTarget(to, "criterion", (), criterion, count)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("request_", "targets"),
    [
        ("If it's broken, it goes in the shoe box.", [_criterion("shoe box", "broken")]),
        ("If a shell is chipped, it belongs in the shoe box.", [_criterion("shoe box", "chipped")]),
        (
            "If something is made entirely of shell, put it in the biscuit tin; if it's sandy, it goes"
            " in the shoe box.",
            [_criterion("biscuit tin", "made entirely of shell"), _criterion("shoe box", "sandy")],
        ),
        (
            "If touching it could cut someone, throw it away.",
            [_criterion(None, "touching it could cut someone")],
        ),
        (
            "If it's whole, it goes in the biscuit tin; otherwise, it goes in the shoe box.",
            [_criterion("biscuit tin", "whole"), GoalTarget("shoe box", "remainder")],
        ),
        (
            "If it's cracked, leave it where it is; otherwise it goes in the shoe box.",
            [GoalTarget("shoe box", "remainder")],
        ),
    ],
)
def test_a_condition_is_the_criterion_of_what_it_sends(
    reader: GoalReader, request_: str, targets: list[GoalTarget]
) -> None:
    _is(reader, request_, SHELLS, *targets)


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


@pytest.mark.parametrize(
    "request_",
    [
        "I'd appreciate it if you passed me the lime.",
        "It would be great if you could hand me the lime.",
        "I'd be grateful if you brought me the lime.",
    ],
)
def test_a_polite_if_you_frame_asks_for_its_verb(reader: GoalReader, request_: str) -> None:
    _is(reader, request_, PANTRY, _named("user", "lime"))


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


def test_s_before_a_participle_is_a_verb_not_a_possessor(reader: GoalReader) -> None:
    _is(
        reader,
        "The dog's been patient, so let him have the squeaky bone.",
        KENNEL,
        _named("dog", "squeaky bone"),
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


@pytest.mark.parametrize(
    "request_",
    [
        "Lunch today should be guacamole.",
        "For lunch, I'm thinking guacamole.",
        "This afternoon calls for guacamole.",
        "Nothing would taste better than guacamole.",
        "The crackers need a guacamole on the side; let's make one.",
    ],
)
def test_a_dish_wished_for_by_the_meal_or_a_comparison(reader: GoalReader, request_: str) -> None:
    read = _is(reader, request_, PANTRY, GoalTarget(None, "ingredients"), dish="guacamole")
    assert (read.dish or "").lower() == "guacamole"


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


def _graph_knows(*dishes: str) -> Callable[[str, Sequence[str]], str | None]:
    """A stand-in for ``FactFinder.dish_concept``: these words are dishes."""
    return lambda phrase, pickable: next((d for d in dishes if d in phrase.lower()), None)


def test_a_dish_the_graph_knows_is_read_where_the_rules_find_no_target(reader: GoalReader) -> None:
    knowing = GoalReader(reader.nlp, find_dish=_graph_knows("dip"))
    read = knowing.read("We're getting peckish: let's round off the evening with a dip.", PANTRY)
    assert read.dish == "dip" and [t.takes for t in read.targets] == ["ingredients"]
    # the same request without the graph is a need; a measure word or an activity is no dish
    assert reader.read("We're getting peckish: let's round off the evening with a dip.", PANTRY).dish is None
    slicing = GoalReader(reader.nlp, find_dish=_graph_knows("slice", "time"))
    assert slicing.read("I'd like to cut the lime into slices.", PANTRY).dish is None
    assert slicing.read("It's time for me to do the washing up.", PANTRY).dish is None


def test_a_placed_target_wins_over_a_dish_in_its_words(reader: GoalReader) -> None:
    knowing = GoalReader(reader.nlp, find_dish=_graph_knows("cracker", "olive"))
    _is(knowing, "Put the cracker on the chopping board.", PANTRY, _named("chopping board", "cracker"))


def test_requests_put_as_questions_send_to_who_asks_or_is_named(reader: GoalReader) -> None:
    _is(
        reader,
        "May I borrow something crunchy?",
        PANTRY,
        GoalTarget("user", "criterion", (), "something crunchy", 1),
    )
    _is(
        reader,
        "Could the dog have something to chew?",
        KENNEL,
        GoalTarget("dog", "criterion", (), "something to chew", 1),
    )
    _is(
        reader,
        "Got something to brush him with?",
        KENNEL,
        GoalTarget("user", "criterion", (), "something to brush him with", 1),
    )
    _is(reader, "Would you mind passing the dog lead my way?", KENNEL, _named("user", "dog lead"))


@pytest.mark.parametrize(
    "request_",
    [
        "Grab me something to nibble on, and a cushion too.",
        "Could you bring me something to nibble on, and a cushion as well?",
        "Let me have something to nibble on, and also a cushion.",
    ],
)
def test_a_second_thing_after_a_comma_is_a_second_thing(reader: GoalReader, request_: str) -> None:
    # the small parser joins "and a cushion" to the verb, not to the first object (pipeline/goal/repair)
    _is(
        reader,
        request_,
        _DESK,
        GoalTarget("user", "criterion", (), "something to nibble on", 1),
        GoalTarget("user", "criterion", (), "cushion", 1),
    )


def test_a_gapped_second_clause_keeps_its_own_place(reader: GoalReader) -> None:
    _is(
        reader,
        "Put the plum in the cupboard, and the notebook on the windowsill.",
        _DESK,
        _named("cupboard", "plum"),
        _named("windowsill", "notebook"),
    )
    _is(reader, "Put the plum, and only the plum, in the cupboard.", _DESK, _named("cupboard", "plum"))


@pytest.mark.parametrize(
    "request_",
    [
        "Give me two tools: one to drive in nails and one for sanding.",
        "Give me two tools, one to drive in nails and one for sanding.",
        "Could you hand me a tool to drive in nails and another for sanding?",
    ],
)
def test_each_listed_one_stands_in_for_the_tool(reader: GoalReader, request_: str) -> None:
    read = reader.read(
        request_,
        scene_from_dict({"pickable_objects": ["claw hammer", "sandpaper", "tape"], "destinations": ["user"]}),
    )
    criteria = sorted(t.criterion for t in read.targets)
    assert [t.count for t in read.targets] == [1, 1], read.to_dict()
    assert criteria == ["tool for sanding", "tool to drive in nails"], read.to_dict()


def test_a_colon_list_of_named_things_sends_them(reader: GoalReader) -> None:
    _is(reader, "I need two things: the notebook and the plum.", _DESK, _named("user", "notebook", "plum"))


def test_a_place_that_matches_its_key_sorts_by_the_key(reader: GoalReader) -> None:
    for request_ in (
        "Every piece goes in the crate that matches its material.",
        "Put each piece into the crate matching its material.",
    ):
        read = reader.read(request_, WORKSHOP)
        assert {t.to for t in read.targets} == {"wood crate", "metal crate", "felt crate", "odds crate"}
        assert {t.criterion for t in read.targets} == {"by material"}, read.to_dict()


_GARDEN = scene_from_dict(
    {
        "pickable_objects": ["trowel", "watering can", "seed packet", "apple", "bread roll"],
        "destinations": ["user", "shed shelf", "compost bin", "potting bench"],
    }
)


@pytest.mark.parametrize(
    "request_",
    [
        "It's hot out here; any chance you could pass me the trowel?",
        "Is there any chance you could pass me the trowel?",
        "I was wondering if you could pass me the trowel.",
        "Do you think you could pass me the trowel?",
        "I was hoping you could pass me the trowel.",
        "Would it be possible to pass me the trowel?",
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


@pytest.mark.parametrize(
    "request_",
    [
        "I'm sweating and shaking at the same time.",  # a need: "same time" is no dish
        "Since it's my own garden, I'm tired of weeding it.",
    ],
)
def test_a_reason_or_a_state_names_no_dish(request_: str) -> None:
    reader = GoalReader(find_dish=_graph_knows("time", "garden", "weeding"))
    assert reader.read(request_, _GARDEN).dish is None


def test_a_dish_wished_for_by_sounding_good(reader: GoalReader) -> None:
    read = GoalReader(find_dish=_graph_knows("apple crumble")).read(
        "An apple crumble sounds great right now.", _GARDEN
    )
    assert read.dish is not None and "crumble" in read.dish
    assert reader.read("That sounds great, thanks.", _GARDEN).dish is None


def test_either_of_two_places_sorts_everything(reader: GoalReader) -> None:
    read = reader.read("Sort everything here into either the compost bin or the potting bench.", _GARDEN)
    assert sorted(t.to or "" for t in read.targets) == ["compost bin", "potting bench"], read.to_dict()
    _is(
        reader,
        "Put the apple on the compost bin or the potting bench.",
        _GARDEN,
        _named("compost bin", "apple"),
    )


def test_on_me_after_a_verb_that_moves_nothing_is_no_place(reader: GoalReader) -> None:
    read = reader.read("My watering can just broke on me.", _GARDEN)
    assert read.need is not None and read.targets == (GoalTarget(None, "need"),)


def test_a_sort_header_s_key_goes_to_the_sort(reader: GoalReader) -> None:
    read = reader.read("Sort these by what they're made of, each one into the crate that matches.", WORKSHOP)
    assert {t.criterion for t in read.targets} == {"by material"}, read.to_dict()
    assert len(read.targets) == 4


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
