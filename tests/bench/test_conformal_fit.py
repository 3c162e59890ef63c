"""Plan-level conformal calibration from labelled tasks: each task's decisions' nonconformity, its
worst, and the thresholds."""

from __future__ import annotations

from dataclasses import replace

import pytest

from conceptbot.bench.conformal_fit import (
    TaskScores,
    fit,
    nonconformity,
    reading_label,
    split_scores,
    task_scores,
)
from conceptbot.bench.grading import Task
from conceptbot.core.plan import Done, PickAndPlace, Plan
from conceptbot.core.trace import (
    ClarifyingQuestion,
    DecisionTrace,
    GoalTrace,
    JudgementTrace,
    PlanTrace,
    ReadingOption,
    TargetTrace,
)

GOLD = {"type": "assign", "assign": {"lemon": ["bowl"], "jam": ["user"]}}
TASK = Task("dev-x-1", "implicit", "request", "kitchen", GOLD, "")


def _plan(*decisions: DecisionTrace) -> Plan:
    return Plan([Done()], trace=PlanTrace(config="conceptbot", decisions=decisions))


def test_yes_no_and_which_one_decisions_score_against_the_gold() -> None:
    bowl = DecisionTrace(
        TargetTrace("bowl", "all", "named"),
        True,
        (
            JudgementTrace("lemon", 0.8, 1.4, answers=("yes",)),  # right answer yes: 1 - 0.8
            JudgementTrace("cup", 0.3, -0.8, answers=("no",)),  # right answer no: 1 - 0.7
            JudgementTrace("salt", 0.5, 0.0),  # not calibrated: no part
        ),
    )
    user = DecisionTrace(
        TargetTrace("user", 1, "scored"),
        True,
        (JudgementTrace("bread", 0.7, 1.0, p_one=0.6), JudgementTrace("jam", 0.4, -0.4, p_one=0.35)),
        candidates=("bread", "jam"),
    )
    # The which-one decision by the softmax rule: 1 - p_one of the jam, the object the gold accepts.
    assert task_scores(TASK, _plan(bowl, user), "softmax") == pytest.approx([0.2, 0.3, 0.65])
    # By the fits rule: the likeliest, the bread, does not fit by the gold, and P(no) was 0.3.
    assert task_scores(TASK, _plan(bowl, user), "fits") == pytest.approx([0.2, 0.3, 0.7])
    bread = {"type": "assign", "assign": {"lemon": ["bowl"], "bread": ["user"]}}
    fits = Task("dev-x-2", "implicit", "request", "kitchen", bread, "")
    assert task_scores(fits, _plan(bowl, user), "fits")[-1] == pytest.approx(0.3)  # it fits: 1 - P(yes)


def test_a_which_one_decision_the_gold_accepts_nothing_for_is_left_out() -> None:
    shelf = DecisionTrace(
        TargetTrace("shelf", 1, "scored"),
        True,
        (JudgementTrace("bread", 0.7, 1.0, p_one=0.6),),
        candidates=("bread",),
    )
    assert task_scores(TASK, _plan(shelf)) == []
    assert nonconformity(float("nan")) == 1.0


def test_the_thresholds_are_quantiles_of_each_tasks_worst_decision() -> None:
    tasks = [TaskScores((0.1, 0.05 * i)) for i in range(1, 20)]  # worst 0.1, 0.1, 0.15, ..., 0.95
    found = fit(tasks)
    assert found.tasks == 19 and found.decisions == 38
    assert found.qhat[0.8] == pytest.approx(0.8)  # rank ceil(20 * 0.8) = 16 of 19
    assert found.qhat[0.95] == pytest.approx(0.95)  # rank 19 of 19: the worst task
    assert fit(tasks[:10]).qhat[0.95] == 1.0  # too few tasks for 0.95: keep everything
    assert 0.75 <= found.held_out[0.8] <= 0.85
    with pytest.raises(ValueError, match="no task has a calibrated decision"):
        fit([])


def test_the_pair_of_thresholds_asks_the_fewest_tasks_that_keep_the_coverage() -> None:
    # Twenty tasks: a sure yes/no decision (2% wrong) and a which-one decision. In eighteen the
    # likeliest candidate (0.7) is acceptable, the next 0.25; in two the likeliest (0.9) is wrong
    # and the acceptable one 5% likely.
    good = TaskScores((0.02,), (0.3,), ((0.7, 0.25),))
    wrong = TaskScores((0.02,), (0.95,), ((0.9, 0.05),))
    tasks = [wrong, wrong] + [good] * 18
    assert good.covered(0.5, 0.3) and not good.asked(0.5, 0.3) and good.asked(0.5, 0.8)
    assert not wrong.covered(0.5, 0.3) and wrong.covered(0.5, 0.95)
    found = fit(tasks)
    assert found.qhat_one is not None and found.asked is not None
    # At 0.8, 17 of 20 tasks must be covered: acting on every likeliest candidate covers 18 and
    # asks nothing (a which-one threshold from 0.3 to 0.74: the middle is kept).
    assert (found.qhat[0.8], found.qhat_one[0.8], found.asked[0.8]) == (0.5, 0.52, 0)
    # At 0.9, 19 must be: the wrong two only by keeping what is 5% likely, which asks every task;
    # by sets that keep the likely candidates, not by empty ones that offer the likeliest dozen.
    assert found.asked[0.9] == 20 and found.qhat_one[0.9] >= 0.95
    assert found.held_out[0.8] == pytest.approx(0.9)  # the two wrong ones are missed, held out too
    few = fit(tasks[:5])  # too few tasks for 0.9: keep everything
    assert few.qhat_one is not None and few.qhat_one[0.9] == few.qhat[0.9] == 1.0


def test_split_scores_keep_the_kinds_apart() -> None:
    bowl = DecisionTrace(
        TargetTrace("bowl", "all", "named"), True, (JudgementTrace("lemon", 0.8, 1.4, answers=("yes",)),)
    )
    user = DecisionTrace(
        TargetTrace("user", 1, "scored"),
        True,
        (JudgementTrace("bread", 0.7, 1.0, p_one=0.6), JudgementTrace("jam", 0.4, -0.4, p_one=0.35)),
        candidates=("bread", "jam"),
    )
    found = split_scores(TASK, _plan(bowl, user), "softmax")
    assert found.yes_no == pytest.approx((0.2,)) and found.one == pytest.approx((0.65,))
    assert len(found) == 2 and found.covered(0.2, 0.65) and not found.covered(0.2, 0.6)


class _Readings:
    """A system whose request reads two ways: the reading taken sends the apple to the user, the
    other the coke; it answers a reading question as told and asks nothing else."""

    def __init__(self) -> None:
        self.asked: list[str] = []

    def plan(self, request: str, scene: object, ask: object = None, **_: object) -> Plan:
        options = (ReadingOption("give the apple", 0.65), ReadingOption("give the coke", 0.15, "other"))
        question = ClarifyingQuestion(
            "Did you mean ...?", "", tuple(o.text for o in options), (0.65, 0.15), kind="reading"
        )
        answer = ask(question) if callable(ask) else None
        self.asked += [answer] if answer else []
        thing = "coke" if answer == "give the coke" else "apple"
        goal = GoalTrace((), False, "p", "plain", None, "need", options)
        return Plan(
            [PickAndPlace(thing, "user"), Done()],
            trace=PlanTrace(config="conceptbot", goal=goal),
            questions=[replace(question, answer=answer)],
        )


def test_a_reading_is_labelled_by_the_first_reading_whose_plan_passes() -> None:
    system = _Readings()
    coke = Task(
        "dev-x-3", "implicit", "request", "kitchen", {"type": "assign", "assign": {"coke": ["user"]}}, ""
    )
    options, meant = reading_label(coke, system.plan(coke.request, None), system)
    assert [o.text for o in options] == ["give the apple", "give the coke"] and meant == 1
    assert system.asked == ["give the apple", "give the coke"]
    apple = replace(coke, gold={"type": "assign", "assign": {"apple": ["user"]}})
    assert reading_label(apple, system.plan(apple.request, None), system)[1] == 0
    nothing = replace(coke, gold={"type": "assign", "assign": {"chips": ["user"]}})
    assert reading_label(nothing, system.plan(apple.request, None), system)[1] is None  # left out
    # A plan without a reading question though it read two ways: the system does not ask them all.
    unasked = replace(system.plan(apple.request, None), questions=[])
    with pytest.raises(ValueError, match="coverage ASK_ALL"):
        reading_label(apple, unasked, system)
    assert reading_label(apple, _plan(), system) == ((), None)  # read one way
