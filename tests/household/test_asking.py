"""Asking on household instructions (issue 35): the harm judge's calibrated conformal decision, the
question where it is unsure, and refusal whenever no answer can be read."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jsonschema
import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.core.plan import plan_schema
from conceptbot.core.trace import ClarifyingQuestion, HarmVerdict
from conceptbot.core.usage import Usage
from conceptbot.household.asking import (
    JudgeCalibration,
    harm_question,
    judge_set,
    load_calibration,
    shipped_calibration,
)
from conceptbot.household.harm import HarmModel
from conceptbot.household.judge import HarmJudge
from conceptbot.household.planner import ConceptBotHouseholdPlanner
from conceptbot.household.thor import house_scene
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.household.steps import texts
from tests.pipeline.fakes import DictGraph, risk_reply

KITCHEN = house_scene("FloorPlan1", ["Candle", "Mug", "Microwave"])
#: P(dangerous) = sigmoid(score); at 0.9 an answer at least 0.3 likely is kept.
PLAIN = JudgeCalibration(1.0, 0.0, {0.8: 0.5, 0.9: 0.7, 0.95: 0.9})
UNSURE = [[math.log(0.6), math.log(0.4)]] * 4  # score 2 log 1.5 = +0.81: P(dangerous) 0.69
SURE_SAFE = [[math.log(0.2), math.log(0.8)]] * 4  # score 2 log 0.25 = -2.77: P(dangerous) 0.06


READINGS = HarmModel({"informed": 1.0, "blind": 1.0, "other_examples": 1.0, "ordinary": 1.0}, 0.0, 0.5, {})
CANDLE = ["find Candle"]


def _reply(refuse: bool, steps: list[str]) -> str:
    return json.dumps({"reasoning": "r", "refuse": refuse, "steps": steps})


def _planner(scores: list[list[float]], replies: list[str], coverage: float | None = 0.9):
    ope = FakeLLM([risk_reply(4, []), '{"keywords": ["candle"]}'] * 2)
    planner_llm = FakeLLM(replies)
    planner = ConceptBotHouseholdPlanner(
        ope,
        RelationRetriever(
            DictGraph({"candle": [("candle", "UsedFor", "light")]}), FakeEmbedder(), theta=-1.0
        ),
        planner_llm=planner_llm,
        judge=HarmJudge(FakeLLM(scores=scores)),
        harm=READINGS,
        coverage=coverage,
        calibration=PLAIN,
    )
    return planner, planner_llm


class Person:
    """Answers every question with ``answer`` and keeps what it was asked."""

    def __init__(self, answer: str | None) -> None:
        self.answer = answer
        self.asked: list[ClarifyingQuestion] = []

    def __call__(self, question: ClarifyingQuestion) -> str | None:
        self.asked.append(question)
        return self.answer


def test_the_set_keeps_each_answer_likely_enough_and_both_when_the_probability_cannot_be_read() -> None:
    assert judge_set(0.9, 0.7) == ("dangerous",)
    assert judge_set(0.1, 0.7) == ("safe",)
    assert judge_set(0.69, 0.7) == ("dangerous", "safe")
    assert judge_set(math.nan, 0.7) == ("dangerous", "safe")
    assert judge_set(0.55, 0.4) == ("dangerous",)  # neither reaches 0.6: the likelier alone
    assert judge_set(0.3, 1.0) == ("dangerous", "safe")  # coverage 1: every answer kept


def test_the_calibration_reads_a_score_as_a_probability_and_fails_closed() -> None:
    assert PLAIN.p_dangerous(0.0) == pytest.approx(0.5)
    assert PLAIN.p_dangerous(2 * math.log(1.5)) == pytest.approx(2.25 / 3.25)
    assert PLAIN.p_dangerous(-1e6) == 0.0 and PLAIN.p_dangerous(1e6) == 1.0  # no overflow
    assert math.isnan(PLAIN.p_dangerous(math.nan))
    assert PLAIN.threshold(1.0) == 1.0
    with pytest.raises(ConfigError, match=r"coverage 0\.7"):
        PLAIN.threshold(0.7)


def test_the_shipped_calibration_has_every_coverage_and_a_bad_file_is_a_clear_error(tmp_path: Path) -> None:
    shipped = shipped_calibration()
    assert set(shipped.qhat) == {0.8, 0.9, 0.95} and all(0.5 <= q <= 1 for q in shipped.qhat.values())
    assert shipped.slope > 0  # a higher score of "dangerous" is more likely dangerous
    bad = tmp_path / "judge.json"
    bad.write_text('{"slope": "steep", "intercept": 0, "qhat": {}}')
    with pytest.raises(ConfigError, match="slope"):
        load_calibration(bad)
    bad.write_text('{"slope": NaN, "intercept": 0, "qhat": {"0.9": 0.6}}')
    with pytest.raises(ConfigError, match="finite"):
        load_calibration(bad)
    bad.write_text('{"slope": -2.0, "intercept": 6, "qhat": {"0.9": 0.6}}')  # would switch the check off
    with pytest.raises(ConfigError, match="positive"):
        load_calibration(bad)
    bad.write_text('{"slope": 2.0, "intercept": -6, "qhat": {"0.9": 6}}')
    with pytest.raises(ConfigError, match="from 0 to 1"):
        load_calibration(bad)
    good = tmp_path / "good.json"
    good.write_text('{"slope": 2.0, "intercept": -6, "qhat": {"0.9": 0.6}}')
    assert load_calibration(good).threshold(0.9) == 0.6
    bad.write_text("{not json")
    with pytest.raises(ConfigError, match="cannot read the harm judge calibration"):
        load_calibration(bad)
    with pytest.raises(ConfigError, match="no such file"):
        load_calibration(tmp_path / "absent.json")


def test_an_unsure_judge_asks_and_no_lets_the_plain_call_plan() -> None:
    planner, planner_llm = _planner(UNSURE, [_reply(False, ["find Candle"])])
    person = Person("no")
    plan = planner.plan("Put the candle in the microwave.", KITCHEN, ask=person)
    assert not plan.refused and texts(plan.actions) == ["find Candle"] and len(planner_llm.requests) == 1
    (question,) = person.asked
    assert question.kind == "harm" and question.options == ("yes", "no")
    assert question.text.startswith('Would carrying out "Put the candle in the microwave." be dangerous')
    assert question.p_yes == (round(2.25 / 3.25, 4),)
    assert [q.answer for q in plan.questions] == ["no"] and plan.confidence == 1.0
    asking = plan.trace.to_dict()["asking"]
    assert asking == {"p_dangerous": round(2.25 / 3.25, 4), "set": ["dangerous", "safe"], "answer": "safe"}
    schema = plan_schema()  # the question as the plan JSON contract has it
    jsonschema.validate(plan.to_dict()["questions"], {**schema, **schema["properties"]["questions"]})


def test_yes_refuses_the_plan() -> None:
    planner, _ = _planner(UNSURE, [_reply(False, CANDLE)])
    plan = planner.plan("Put the candle in the microwave.", KITCHEN, ask=Person("yes"))
    assert plan.refused and plan.actions == () and plan.trace.to_dict()["refused_by"] == "judge"
    assert plan.reason.startswith("The person said carrying it out would be dangerous")
    assert [q.answer for q in plan.questions] == ["yes"]


@pytest.mark.parametrize("answer", [None, "maybe", "raise"])
def test_no_answer_that_can_be_read_refuses(answer: str | None) -> None:
    planner, _ = _planner(UNSURE, [_reply(False, CANDLE)])

    def ask(question: ClarifyingQuestion) -> str | None:
        if answer == "raise":
            raise TimeoutError("nobody answered")
        return answer

    plan = planner.plan("Put the candle in the microwave.", KITCHEN, ask=ask)
    assert plan.refused and plan.actions == () and "not answered" in plan.reason
    assert [q.answer for q in plan.questions] == [None]  # kept open


def test_without_an_asker_an_unsure_judge_refuses_and_lists_the_question() -> None:
    planner, _ = _planner(UNSURE, [_reply(False, CANDLE)])
    plan = planner.plan("Put the candle in the microwave.", KITCHEN)
    assert plan.refused and len(plan.questions) == 1 and plan.questions[0].answer is None


class _BrokenJudge(HarmJudge):
    """A judge whose score is NaN (a backend's numbers that passed every check)."""

    def judge(self, instruction: str, scene: object, evidence: str = "") -> tuple[HarmVerdict, Usage]:
        return HarmVerdict(math.nan, self.threshold, {"informed": math.nan}), Usage(calls=0)


def test_a_score_that_cannot_be_read_is_asked_about_never_acted_on() -> None:
    planner, _ = _planner([], [_reply(False, ["find Candle"])])
    planner.judge = _BrokenJudge(FakeLLM([]))
    person = Person(None)
    plan = planner.plan("Put the candle in the microwave.", KITCHEN, ask=person)
    assert plan.refused and len(person.asked) == 1 and plan.confidence == 0.0
    assert plan.trace.to_dict()["asking"]["p_dangerous"] is None


def test_a_sure_decision_acts_without_a_question_and_carries_its_confidence() -> None:
    planner, _ = _planner(SURE_SAFE, [_reply(False, ["find Candle"])])
    person = Person("yes")
    plan = planner.plan("Find the candle.", KITCHEN, ask=person)
    assert not plan.refused and person.asked == [] and plan.questions == ()
    assert plan.confidence == pytest.approx(1 - 1 / 17, abs=1e-6)  # P(safe): 1 - sigmoid(2 log 0.25)


def test_without_a_coverage_the_threshold_decides_as_before() -> None:
    planner, _ = _planner(UNSURE, [_reply(False, CANDLE)], coverage=None)
    person = Person("no")
    plan = planner.plan("Put the candle in the microwave.", KITCHEN, ask=person)
    assert plan.refused and person.asked == [] and "threshold +0.50" in plan.reason
    assert "asking" not in plan.trace.to_dict() and plan.confidence is None


def test_asking_needs_the_judge_and_a_known_coverage() -> None:
    retriever = RelationRetriever(DictGraph({}), FakeEmbedder(), theta=-1.0)
    with pytest.raises(ConfigError, match="harm judge"):
        ConceptBotHouseholdPlanner(FakeLLM([]), retriever, coverage=0.9)
    with pytest.raises(ConfigError, match=r"coverage 0\.85"):
        ConceptBotHouseholdPlanner(FakeLLM([]), retriever, judge=HarmJudge(FakeLLM([])), coverage=0.85)


def test_the_harm_question_reads_yes_and_no_only() -> None:
    question = harm_question("Heat the fork in the microwave.", 0.5)
    assert question.read("Yes") == ("Heat the fork in the microwave.",) and question.read(" no ") == ()
    assert question.read("none") is None and question.read(3) is None
    assert question.normalised(()) == "no"
