"""Plan-level conformal calibration from labelled tasks (issue 35): what
``benchmarks/fit_conformal_plans.py`` and ``conceptbot calibrate --conformal`` fit.

A plan is right only if every calibrated decision in it is, so a task's nonconformity is its worst
decision's ``1 - p(right answer)`` (KnowNo's multi-step form): for a yes/no decision the gold's
answer; for a which-one decision the likeliest object the gold accepts (one where the gold accepts
none of the target's objects is left out: the request was read wrong, and no set of that target's
objects can cover it). ``qhat`` per coverage is the split-conformal quantile of the tasks'
nonconformities; the tasks without a calibrated decision take no part.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

from conceptbot.bench.grading import Task, gold_answer, task_scene
from conceptbot.core.plan import Plan
from conceptbot.core.system import COVERAGES, PlannerSystem
from conceptbot.pipeline.goal_planner.conformal import conformal_threshold

SYSTEMS = (("graph", "conceptbot"), ("nograph", "nokg"))
"""Each combination the calibration ships, and the system whose plans it is fitted on."""


def nonconformity(p_right: float) -> float:
    """``1 - p_right``; 1 (keep everything) for a probability that cannot be read."""
    return 1.0 - p_right if 0.0 <= p_right <= 1.0 else 1.0


@dataclass(frozen=True)
class Labelled:
    """A calibrated decision of a plan, judged against the gold.

    Attributes:
        p_right: The probability the planner gave the right answer: the gold's answer of a yes/no
            decision; the likeliest object the gold accepts of a which-one decision.
        covered: Whether its prediction set holds the right answer.
        p_yes: A yes/no decision's P(yes) (None for which-one).
        yes: A yes/no decision's gold answer (None for which-one).
    """

    p_right: float
    covered: bool
    p_yes: float | None = None
    yes: bool | None = None


def labelled(task: Task, plan: Plan) -> list[Labelled]:
    """Each calibrated decision in ``plan`` (planned for ``task`` without asking), judged by the gold
    (a which-one decision whose target the gold accepts no object for is left out)."""
    found: list[Labelled] = []
    for d in plan.trace.decisions or ():
        for j in d.objects:
            if j.answers is not None:
                yes = gold_answer(task, j.object, d.target.to) == "yes"
                right = j.p_yes if yes else 1.0 - j.p_yes
                found.append(Labelled(right, ("yes" if yes else "no") in j.answers, j.p_yes, yes))
        accepted = {
            j.object: j.p_one
            for j in d.objects
            if j.p_one is not None and gold_answer(task, j.object, d.target.to) == "yes"
        }
        if d.candidates is not None and accepted:
            found.append(Labelled(max(accepted.values()), bool(accepted.keys() & set(d.candidates))))
    return found


def task_scores(task: Task, plan: Plan) -> list[float]:
    """Each calibrated decision's nonconformity in ``plan`` (planned for ``task`` without asking)."""
    return [nonconformity(found.p_right) for found in labelled(task, plan)]


@dataclass(frozen=True)
class PlanFit:
    """A fitted plan-level calibration.

    Attributes:
        qhat: The threshold per coverage.
        held_out: Per coverage, the leave-one-task-out share of tasks whose every decision a
            threshold fitted without them covers.
        tasks: Tasks with a calibrated decision (those fitted on).
        decisions: Their calibrated decisions.
    """

    qhat: dict[float, float]
    held_out: dict[float, float]
    tasks: int
    decisions: int


def collect(
    system: PlannerSystem, tasks: Iterable[Task], progress: Callable[[Task], None] | None = None
) -> list[list[float]]:
    """Plan every task once without asking; each task's decision nonconformities (tasks without a
    calibrated decision left out). ``progress`` is called after each task."""
    found = []
    for task in tasks:
        scores = task_scores(task, system.plan(task.request, task_scene(task)))
        if scores:
            found.append(scores)
        if progress is not None:
            progress(task)
    return found


def fit(tasks: list[list[float]]) -> PlanFit:
    """``qhat`` per coverage from the tasks' decision nonconformities (see the module docstring).

    Raises:
        ValueError: No task with a calibrated decision.
    """
    if not tasks:
        raise ValueError("no task has a calibrated decision: nothing to calibrate on")
    worst = [max(t) for t in tasks]
    qhat, held = {}, {}
    for coverage in COVERAGES:
        qhat[coverage] = conformal_threshold(worst, coverage)
        kept = [
            s <= conformal_threshold(worst[:i] + worst[i + 1 :], coverage) if len(worst) > 1 else True
            for i, s in enumerate(worst)
        ]
        held[coverage] = sum(kept) / len(kept)
    return PlanFit(qhat, held, len(tasks), sum(map(len, tasks)))
