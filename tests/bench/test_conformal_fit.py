"""Plan-level conformal calibration from labelled tasks: each task's decisions' nonconformity, its
worst, and the thresholds."""

from __future__ import annotations

import pytest

from conceptbot.bench.conformal_fit import fit, nonconformity, task_scores
from conceptbot.bench.grading import Task
from conceptbot.core.plan import Done, Plan
from conceptbot.core.trace import DecisionTrace, JudgementTrace, PlanTrace, TargetTrace

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
    tasks = [[0.1, 0.05 * i] for i in range(1, 20)]  # worst decisions 0.1, 0.1, 0.15, ..., 0.95
    found = fit(tasks)
    assert found.tasks == 19 and found.decisions == 38
    assert found.qhat[0.8] == pytest.approx(0.8)  # rank ceil(20 * 0.8) = 16 of 19
    assert found.qhat[0.95] == pytest.approx(0.95)  # rank 19 of 19: the worst task
    assert fit(tasks[:10]).qhat[0.95] == 1.0  # too few tasks for 0.95: keep everything
    assert 0.75 <= found.held_out[0.8] <= 0.85
    with pytest.raises(ValueError, match="no task has a calibrated decision"):
        fit([])
