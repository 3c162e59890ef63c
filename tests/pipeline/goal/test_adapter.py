from __future__ import annotations

import pytest

from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline.goal import Goal, GoalFinder, GoalReader, GoalTarget, to_targets
from conceptbot.pipeline.goal.adapter import ScoredChooser
from conceptbot.pipeline.goal.doubt import odds
from conceptbot.pipeline.goal.restate import Restater
from conceptbot.pipeline.goal_planner.targets import ALL, TargetFinder
from conceptbot.pipeline.hazards import is_person
from tests.pipeline.goal.scenes import NURSERY, PANTRY, SHELLS, WORKSHOP


def test_named_places_become_named_targets() -> None:
    goal = Goal(
        targets=(
            GoalTarget("shoe box", "named", ("conch shell",), "", 1),
            GoalTarget("biscuit tin", "remainder"),
        )
    )
    named, rest = to_targets(goal, SHELLS)
    assert (named.name, named.how, named.named, named.count, named.rest) == (
        "shoe box",
        "named",
        ["conch shell"],
        1,
        False,
    )
    assert (rest.name, rest.count, rest.rest, rest.criterion) == ("biscuit tin", ALL, True, "")
    assert rest.to_dict()["rest"] is True


def test_criteria_become_what_the_planner_asks_about() -> None:
    goal = Goal(
        targets=(
            GoalTarget("wood crate", "criterion", (), "by material"),
            GoalTarget("metal crate", "criterion", (), ""),
            GoalTarget("odds crate", "criterion", (), "made of several materials"),
        )
    )
    criteria = [t.criterion for t in to_targets(goal, WORKSHOP)]
    assert criteria == [
        "belongs in the wood crate, by material",
        "belongs in the metal crate",
        "made of several materials",
    ]
    # a target taking a number is decided by the move question, as TargetFinder's are
    (counted,) = to_targets(
        Goal(targets=(GoalTarget("user", "criterion", (), "something to write with", 1),)), SHELLS
    )
    assert (counted.count, counted.criterion) == (1, "")


def test_open_targets_need_a_chooser_except_a_need() -> None:
    (need,) = to_targets(Goal(need="I'm cold", targets=(GoalTarget(None, "need"),)), SHELLS)
    assert (need.name, need.how, need.count) == ("user", "speaker", 1)
    with pytest.raises(ValueError, match="choose="):
        to_targets(Goal(targets=(GoalTarget(None, "criterion", (), "poisonous"),)), SHELLS)
    chosen = to_targets(
        Goal(dish="guacamole", targets=(GoalTarget(None, "ingredients"),)),
        PANTRY,
        choose=lambda target, scene: [("serving bowl", 2.5)],
    )
    assert [(t.name, t.how, t.score, t.ingredients, t.dish, t.criterion) for t in chosen] == [
        ("serving bowl", "scored", 2.5, True, "guacamole", "an ingredient of guacamole")
    ]
    assert to_targets(Goal(stack=True, targets=(GoalTarget(None, "all"),)), SHELLS) == []


def test_a_dish_keeps_the_words_it_was_said_in_beside_the_graph_s_concept() -> None:
    def choose(target: GoalTarget, scene: Scene) -> list[tuple[str, float]]:
        return [("serving bowl", 1.0)]

    goal = Goal(dish="salad", targets=(GoalTarget(None, "ingredients", ("tomato",)),))
    (said,) = to_targets(goal, PANTRY, choose=choose, dish_said="tomato and cucumber salad")
    assert (said.dish, said.criterion, said.dish_said) == (
        "salad",
        "an ingredient of salad",  # the graph's evidence is read for the concept
        "tomato and cucumber salad",
    )
    (same,) = to_targets(goal, PANTRY, choose=choose, dish_said="salad")
    assert same.dish_said == ""  # nothing more said than the concept


def test_the_scored_chooser_asks_the_target_finder_s_question() -> None:
    # per destination: the request's yes/no log-probs, then the content-free request's; the user is
    # a person, never a place the request left open, so it is not asked about
    llm = FakeLLM(scores=[[-0.1, -2.0], [-1.0, -1.0], [-3.0, -0.1], [-1.0, -1.0]])
    chooser = ScoredChooser(TargetFinder(llm, is_person), "Throw away the broken shells.")
    places = chooser(GoalTarget(None, "criterion", (), "broken shells"), SHELLS)
    assert places == [("shoe box", pytest.approx(1.9))]
    assert (
        len(llm.score_requests) == 4
        and "Throw away the broken shells." in llm.score_requests[0].messages[1].content
        and not any("user" in r.messages[1].content.split("\n")[-1] for r in llm.score_requests)
    )
    assert chooser(GoalTarget(None, "need"), SHELLS) == [("user", 0.0)]


def test_a_place_left_open_is_never_a_person() -> None:
    # "put the safety pins out of the toddler's reach": scored as the best place, the toddler is
    # still not where they go
    scene = scene_from_dict(
        {
            "name": "nursery",
            "objects": ["safety pins", "toddler", "top shelf"],
            "pickable_objects": ["safety pins"],
            "destinations": ["toddler", "top shelf"],
        }
    )
    llm = FakeLLM(scores=[[-0.1, -2.0], [-1.0, -1.0]])
    chooser = ScoredChooser(TargetFinder(llm, is_person), "Put the safety pins out of the toddler's reach.")
    assert [p for p, _ in chooser(GoalTarget(None, "named", ("safety pins",), "", 1), scene)] == ["top shelf"]
    assert len(llm.score_requests) == 2


def test_names_with_marks_are_read_as_their_words_and_planned_with_their_own_spelling() -> None:
    from conceptbot.core.scene import scene_from_dict
    from conceptbot.pipeline.goal import GoalReader
    from conceptbot.pipeline.goal.adapter import read_plainly

    scene = scene_from_dict({"pickable_objects": ["apple [/x]", "pear"], "destinations": ["child", "table"]})
    goal = read_plainly(GoalReader(), "give the apple [/x] to the child [bold]", scene)
    [target] = goal.targets
    assert (target.to, target.takes, target.named) == ("child", "named", ("apple [/x]",))


def test_several_kinds_of_thing_each_carry_what_they_are_for() -> None:
    goal = Goal(
        targets=(
            GoalTarget("user", "criterion", (), "something to write with", 1),
            GoalTarget("user", "criterion", (), "something to write on", 1),
            GoalTarget("shoe box", "named", ("conch shell",), "", 1),
        )
    )
    write, paper, box = to_targets(goal, SHELLS)
    assert (write.part, paper.part, box.part) == (
        "as something to write with",
        "as something to write on",
        "",
    )
    assert write.to_dict()["part"] == "as something to write with" and "part" not in box.to_dict()
    needs = Goal(
        need="x",
        targets=(
            GoalTarget(None, "need", (), "I cut my finger"),
            GoalTarget(None, "need", (), "my head aches"),
        ),
    )
    assert [t.part for t in to_targets(needs, SHELLS)] == ['for "I cut my finger"', 'for "my head aches"']
    # each need is decided on its own words; other parts, and a single need, on the whole request
    assert [t.need for t in to_targets(needs, SHELLS)] == ["I cut my finger", "my head aches"]
    # a need takes what helps with it; the other kinds of target do not
    assert all(t.helps for t in to_targets(needs, SHELLS)) and not any(t.helps for t in (write, paper, box))
    assert (write.need, paper.need, box.need) == ("", "", "")
    (alone,) = to_targets(Goal(need="I'm cold", targets=(GoalTarget(None, "need", (), "I'm cold"),)), SHELLS)
    assert alone.need == "" and alone.helps  # a single need is decided on the whole request
    # one thing asked for is asked about as before, with the whole request
    (one,) = to_targets(
        Goal(targets=(GoalTarget("user", "criterion", (), "something to write with", 1),)), SHELLS
    )
    assert one.part == ""


POLITE = "Oh, before I forget, would you be a dear and pop the conch shell in the shoe box?"


def test_the_goal_finder_reads_the_model_s_plain_form_and_says_which_reading_it_took() -> None:
    scorer = FakeLLM(scores=[[-1.0, -1.0]] * 20)  # the other reading's open place, when it is made
    finder = GoalFinder(
        GoalReader(),
        TargetFinder(scorer, is_person),
        restater=Restater(FakeLLM(["Put the conch shell in the shoe box."])),
    )
    read = finder.read(POLITE, SHELLS)
    assert (read.reading, read.plain) == ("plain", "Put the conch shell in the shoe box.")
    assert [(t.name, t.named, t.count) for t in read.targets] == [("shoe box", ["conch shell"], 1)]
    # The words' own reading, kept in the trace: "dear" read as something wanted.
    assert read.other is not None and len(read.other["targets"]) == 2
    assert read.usage.calls == 1
    # Which was meant is a question: both readings in words, the odds of the step that chose.
    doubt = read.doubt
    assert doubt is not None and doubt.taken == "put the conch shell in or on the shoe box"
    assert doubt.other != doubt.taken and (doubt.p_taken, doubt.p_other) == (
        odds(doubt.step).taken,
        odds(doubt.step).other,
    )
    assert not scorer.score_requests  # the other reading is made only when asked for
    other = doubt.alternative()
    assert other.reading == "words" and len(other.targets) >= 2 and scorer.score_requests
    taken = Goal(targets=(GoalTarget("shoe box", "named", ("conch shell",), count=1),))
    assert other.other == taken.to_dict()


def test_readings_that_agree_are_no_doubt() -> None:
    finder = GoalFinder(
        GoalReader(),
        TargetFinder(FakeLLM(), is_person),
        restater=Restater(FakeLLM(["Put the conch shell in the shoe box."])),
    )
    read = finder.read("Put the conch shell in the shoe box.", SHELLS)
    assert (read.reading, read.doubt) == ("both", None)


def test_without_a_restater_the_goal_finder_reads_the_words_alone() -> None:
    read = GoalFinder(GoalReader(), TargetFinder(FakeLLM(), is_person)).read(
        "Put the conch shell in the shoe box.", SHELLS
    )
    assert (read.reading, read.plain, read.other) == ("", "", None)
    assert [(t.name, t.named) for t in read.targets] == [("shoe box", ["conch shell"])]


def test_a_place_the_scene_does_not_have_is_left_to_the_chooser() -> None:
    # A plain form may name an object as the place ("put the rattle in the safety pins"): the
    # plan must never move anything to what is not one of the scene's destinations.
    goal = Goal(targets=(GoalTarget("safety pins", "named", ("rattle",), "", 1),))
    (target,) = to_targets(goal, NURSERY, choose=lambda target, scene: [("top shelf", 0.4)])
    assert (target.name, target.how, target.named) == ("top shelf", "scored", ["rattle"])
