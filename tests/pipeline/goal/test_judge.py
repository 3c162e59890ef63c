"""The model's view of which of two readings was meant, and how it moves the step's odds."""

from __future__ import annotations

import math

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline.goal import GoalFinder, GoalReader, doubt
from conceptbot.pipeline.goal.doubt import UNKNOWN, JudgeWeights, Odds, judge_weights, judged, odds
from conceptbot.pipeline.goal.judge import ReadingJudge
from conceptbot.pipeline.goal.restate import Restater
from conceptbot.pipeline.goal_planner.targets import TargetFinder
from conceptbot.pipeline.hazards import is_person
from tests.pipeline.goal.scenes import SHELLS

TAKEN = 'give the dog one "treat"'
OTHER = 'put the ingredients of "treat" where it fits'


def test_the_judge_asks_both_orders_and_averages_away_the_lean_to_the_first() -> None:
    # Order 1 (taken first): A by 1.0. Order 2 (other first): A by 0.4, the model's lean to A.
    llm = FakeLLM(scores=[[-0.5, -1.5], [-0.8, -1.2]])
    found = ReadingJudge(llm).prefer("A treat for  the dog, go on.", TAKEN, OTHER)
    assert found.log_odds == pytest.approx(0.5 * (1.0 - 0.4))
    assert found.usage.calls == 2
    first, second = (r.messages[-1].content for r in llm.score_requests)
    assert first.startswith('A person said to the robot: "A treat for the dog, go on."')
    assert f"A: {TAKEN}\nB: {OTHER}" in first and f"A: {OTHER}\nB: {TAKEN}" in second
    assert all(r.options == ("A", "B") for r in llm.score_requests)


def test_a_model_failure_is_no_preference_and_the_person_is_asked() -> None:
    found = ReadingJudge(FakeLLM()).prefer("A treat for the dog.", TAKEN, OTHER)  # cannot score
    assert math.isnan(found.log_odds)
    moved = judged(Odds(0.8, 0.1, 20), found.log_odds, JudgeWeights(8.0, 0.0))
    assert (moved.taken, moved.other) == UNKNOWN


def test_the_preference_moves_the_mass_the_two_readings_share() -> None:
    weights = JudgeWeights(weight=8.0, bias=0.0)
    step = Odds(0.8, 0.1, 20)
    level = judged(step, 0.0, weights)
    assert (level.taken, level.other) == pytest.approx((0.8, 0.1))  # no view: the step's odds
    sure = judged(step, 0.3, weights)  # the model prefers the reading taken
    doubtful = judged(step, -0.3, weights)  # ... the reading dropped
    assert sure.other < 0.02 < 0.5 < doubtful.other
    for moved in (sure, doubtful):
        assert moved.taken + moved.other == pytest.approx(0.9)  # neither reading keeps its 0.1
        assert moved.rows == 20
    assert judged(step, -1e6, weights).other == pytest.approx(0.9)  # no overflow


def test_the_shipped_weights_are_finite_and_a_broken_file_is_a_config_error(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    shipped = judge_weights()
    assert shipped is not None and shipped.weight > 0  # preferring the reading taken makes it likelier
    monkeypatch.setattr(doubt, "_odds_data", lambda: {"steps": {}, "judge": {"weight": "x", "bias": 0}})
    with pytest.raises(ConfigError, match="judge"):
        judge_weights()
    monkeypatch.setattr(doubt, "_odds_data", lambda: {"steps": {}})
    assert judge_weights() is None


def test_the_goal_finder_weighs_the_model_s_preference_into_the_reading_odds() -> None:
    polite = "Oh, before I forget, would you be a dear and pop the conch shell in the shoe box?"
    judge = FakeLLM(scores=[[-0.2, -2.2], [-2.0, -0.5]])  # prefers the plain reading both ways
    finder = GoalFinder(
        GoalReader(),
        TargetFinder(FakeLLM(scores=[[-1.0, -1.0]] * 20), is_person),
        restater=Restater(FakeLLM(["Put the conch shell in the shoe box."])),
        judge=ReadingJudge(judge),
    )
    read = finder.read(polite, SHELLS)
    found = read.doubt
    assert found is not None and found.taken == "put the conch shell in or on the shoe box"
    assert found.preference == pytest.approx(0.5 * (2.0 + 1.5))
    weights = judge_weights()
    assert weights is not None
    expected = judged(odds(found.step), found.preference, weights)
    assert (found.p_taken, found.p_other) == pytest.approx((expected.taken, expected.other))
    assert found.p_other < odds(found.step).other
    assert read.usage.calls == 3  # the plain form and the two orders
    assert f"A: {found.taken}\nB: {found.other}" in judge.score_requests[0].messages[-1].content
