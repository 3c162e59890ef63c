"""The odds of the choice between two readings, and the readings in words for the question."""

from __future__ import annotations

import pytest

from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.pipeline.goal import doubt
from conceptbot.pipeline.goal.aided import STEPS
from conceptbot.pipeline.goal.doubt import UNKNOWN, describe, odds
from conceptbot.pipeline.goal.types import Goal, GoalTarget


def test_a_reading_in_words_says_what_each_target_would_do() -> None:
    goal = Goal(
        targets=(
            GoalTarget("user", "criterion", criterion="fruit", count=1),
            GoalTarget("user", "criterion", criterion="soda", count=2),
            GoalTarget("box", "criterion", criterion="poisonous"),
        )
    )
    assert describe(goal) == (
        'give the user one "fruit"; give the user two "soda"'
        ' and put everything that is "poisonous" in or on the box'
    )
    assert describe(Goal(targets=(GoalTarget("tray", "named", ("cup", "jug", "pan"), count=3),))) == (
        "put the cup, the jug and the pan in or on the tray"
    )
    need = Goal(need="my hands are cold", targets=(GoalTarget(None, "need"),))
    assert describe(need) == 'give something for "my hands are cold"'
    dish = Goal(dish="guacamole", targets=(GoalTarget("bowl", "ingredients"), GoalTarget("bin", "remainder")))
    assert describe(dish) == (
        'put the ingredients of "guacamole" in or on the bowl and put the rest in or on the bin'
    )
    assert describe(Goal(stack=True)) == "stack the objects on each other"
    assert describe(Goal()) == "do nothing"


def test_the_shipped_odds_are_probabilities_for_every_step_that_chooses() -> None:
    for step in STEPS:
        if step == "agree":
            continue
        found = odds(step)
        assert 0.0 < found.other < 1.0 and 0.0 < found.taken < 1.0 and found.taken + found.other <= 1.0
    assert (odds("no such step").taken, odds("no such step").other) == UNKNOWN


def test_odds_that_are_not_probabilities_read_as_unknown(monkeypatch: pytest.MonkeyPatch) -> None:
    bad = {"steps": {"fewer": {"taken": float("nan"), "other": 0.1}, "need": {"taken": 2, "other": 0}}}
    monkeypatch.setattr(doubt, "_odds_data", lambda: bad)
    assert (odds("fewer").taken, odds("fewer").other) == UNKNOWN
    assert (odds("need").taken, odds("need").other) == UNKNOWN


def test_a_reading_question_takes_a_whole_reading_with_its_commas_or_none() -> None:
    readings = ("put the cup, the jug and the pan in or on the tray", "give the user the cup")
    question = ClarifyingQuestion("Did you mean ...?", "", readings, (0.6, 0.3), kind="reading")
    assert question.read(" Put the cup,  the jug and the pan in or on the tray ") == (readings[0],)
    assert question.read("give the user the cup") == (readings[1],)
    assert question.read("none") == ()
    assert question.read("the cup") is None and question.read("put the cup") is None
    assert question.to_dict()["kind"] == "reading"
