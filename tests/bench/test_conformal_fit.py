"""Plan-level conformal calibration from labelled tasks: each task's decisions' nonconformity, its
worst, and the thresholds."""

from __future__ import annotations

import pytest

from conceptbot.bench.conformal_fit import TaskScores, fit, nonconformity, split_scores, task_scores
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
    tasks = [TaskScores((0.1, 0.05 * i)) for i in range(1, 20)]  # worst 0.1, 0.1, 0.15, ..., 0.95
    found = fit(tasks)
    assert found.tasks == 19 and found.decisions == 38
    assert found.qhat[0.8] == pytest.approx(0.8)  # rank ceil(20 * 0.8) = 16 of 19
    assert found.qhat[0.95] == pytest.approx(0.95)  # rank 19 of 19: the worst task
    assert fit(tasks[:10]).qhat[0.95] == 1.0  # too few tasks for 0.95: keep everything
    assert 0.75 <= found.held_out[0.8] <= 0.85
    with pytest.raises(ValueError, match="no task has a calibrated decision"):
        fit([])


def test_which_one_decisions_get_their_own_threshold() -> None:
    # Twenty tasks: yes/no decisions as sure as 0.05 * i wrong, each with a which-one decision
    # whose acceptable candidate had a share of at least 0.6 (nonconformity 0.4 or less), but for
    # two that were confidently wrong (0.95).
    tasks = [TaskScores((0.05 * i,), (0.4 if i > 2 else 0.95,)) for i in range(1, 21)]
    found = fit(tasks)
    # The which-one decisions' own 0.8 quantile: rank ceil(21 * 0.8) = 17 of 20, a 0.4.
    assert found.qhat_one is not None and found.qhat_one[0.8] == pytest.approx(0.4)
    # Then the yes/no threshold that covers 17 whole tasks of the 18 the which-one threshold does.
    assert found.qhat[0.8] == pytest.approx(0.05 * 19)
    # One threshold for both would have had to keep a candidate 5% likely.
    single = fit([TaskScores((*t.yes_no, *t.one)) for t in tasks])
    assert single.qhat[0.8] == pytest.approx(0.95) and single.qhat_one == single.qhat
    # At 0.95 the confidently wrong which-one decisions must be covered too: rank 20 of 20.
    assert found.qhat_one[0.95] == pytest.approx(0.95) and found.qhat[0.95] == pytest.approx(1.0)
    few = fit(tasks[:5])  # too few tasks for 0.9: the single threshold for both, keep everything
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
