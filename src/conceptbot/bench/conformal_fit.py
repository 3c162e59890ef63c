"""Plan-level conformal calibration from labelled tasks (issue 35): what
``benchmarks/fit_conformal_plans.py`` and ``conceptbot calibrate --conformal`` fit.

A plan is right only if every calibrated decision in it is, so a task's nonconformity is its worst
decision's ``1 - p(right answer)`` (KnowNo's multi-step form): for a yes/no decision the gold's
answer; for a which-one decision, by the ``fits`` rule the gold's answer to whether the likeliest
candidate fits (its calibrated P(yes) or P(no)), by the ``softmax`` rule the ``p_one`` of the
likeliest object the gold accepts (one where the gold accepts none of the target's objects is left
out either way: the request was read wrong, and no set of that target's objects can cover it).
Both rules' scores come from the same plans, so one pass over the tasks fits both; the tasks without
a calibrated decision take no part.

Two thresholds per coverage, one per kind of decision (Mondrian, or class-conditional, conformal
prediction: Vovk et al. 2005). ``qhat_one``, for which-one decisions, is the split-conformal
quantile of the which-one decisions' own nonconformities; ``qhat``, for yes/no decisions, is then the
smallest threshold with which the chosen share of tasks has every decision covered. One threshold
for both (the tasks' worst decision, as before 2026-12-05) let the yes/no decisions of sorts set
the which-one threshold too: at 0.9 a candidate 13% likely was kept, so a which-one question was
asked wherever a second object was at all plausible, though the likeliest was acceptable in 44 of
the 48 dev which-one decisions. Where the kinds cannot reach the coverage apart (too few tasks),
both take the single threshold.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from conceptbot.bench.grading import Task, gold_answer, task_scene
from conceptbot.core.plan import Plan
from conceptbot.core.system import COVERAGES, WHICH_ONE, PlannerSystem
from conceptbot.pipeline.goal_planner.conformal import OLD_RULE, conformal_threshold, one_key

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
            decision; of a which-one decision, the gold's answer to whether the likeliest candidate
            fits (``fits``), or the likeliest object the gold accepts (``softmax``).
        covered: Whether its prediction set holds the right answer.
        p_yes: A yes/no decision's P(yes) (None for which-one).
        yes: A yes/no decision's gold answer (None for which-one).
        one: A which-one decision (its own threshold: ``qhat_one``).
    """

    p_right: float
    covered: bool
    p_yes: float | None = None
    yes: bool | None = None
    one: bool = False


def labelled(task: Task, plan: Plan, rule: str = OLD_RULE) -> list[Labelled]:
    """Each calibrated decision in ``plan`` (planned for ``task`` without asking), judged by the gold
    (a which-one decision whose target the gold accepts no object for is left out), its which-one
    decisions by ``rule`` (:data:`~conceptbot.core.system.WHICH_ONE`)."""
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
        if d.candidates is None or not accepted:
            continue
        covered = bool(accepted.keys() & set(d.candidates))
        if rule == "softmax":
            found.append(Labelled(max(accepted.values()), covered, one=True))
            continue
        scored = [j for j in d.objects if j.p_one is not None]
        if not all(j.p_one == j.p_one for j in scored):  # the ranking cannot be read: no score
            found.append(Labelled(float("nan"), covered, one=True))
            continue
        top = max(scored, key=lambda j: j.p_one or 0.0)
        fits = top.object in accepted
        found.append(Labelled(top.p_yes if fits else 1.0 - top.p_yes, covered, top.p_yes, fits, True))
    return found


def task_scores(task: Task, plan: Plan, rule: str = OLD_RULE) -> list[float]:
    """Each calibrated decision's nonconformity in ``plan`` (planned for ``task`` without asking),
    its which-one decisions by ``rule``."""
    return [nonconformity(found.p_right) for found in labelled(task, plan, rule)]


@dataclass(frozen=True)
class TaskScores:
    """A task's decision nonconformities by kind: yes/no decisions and which-one decisions."""

    yes_no: tuple[float, ...] = ()
    one: tuple[float, ...] = ()

    def __len__(self) -> int:
        return len(self.yes_no) + len(self.one)

    def covered(self, qhat: float, qhat_one: float) -> bool:
        """Whether every decision is in its prediction set with these thresholds."""
        return all(s <= qhat for s in self.yes_no) and all(s <= qhat_one for s in self.one)


def split_scores(task: Task, plan: Plan, rule: str = OLD_RULE) -> TaskScores:
    """:func:`task_scores` split by kind of decision."""
    found = labelled(task, plan, rule)
    return TaskScores(
        tuple(nonconformity(f.p_right) for f in found if not f.one),
        tuple(nonconformity(f.p_right) for f in found if f.one),
    )


@dataclass(frozen=True)
class PlanFit:
    """A fitted plan-level calibration.

    Attributes:
        qhat: The threshold per coverage of yes/no decisions.
        held_out: Per coverage, the leave-one-task-out share of tasks whose every decision
            thresholds fitted without them cover.
        tasks: Tasks with a calibrated decision (those fitted on).
        decisions: Their calibrated decisions.
        qhat_one: The threshold per coverage of which-one decisions (None: ``qhat``'s).
    """

    qhat: dict[float, float]
    held_out: dict[float, float]
    tasks: int
    decisions: int
    qhat_one: dict[float, float] | None = None


def collect(
    system: PlannerSystem, tasks: Iterable[Task], progress: Callable[[Task], None] | None = None
) -> dict[str, list[TaskScores]]:
    """Plan every task once without asking; per which-one rule (:data:`WHICH_ONE`), each task's
    decision nonconformities (tasks without a calibrated decision left out). ``progress`` is called
    after each task."""
    found: dict[str, list[TaskScores]] = {rule: [] for rule in WHICH_ONE}
    for task in tasks:
        plan = system.plan(task.request, task_scene(task))
        for rule in WHICH_ONE:
            scores = split_scores(task, plan, rule)
            if len(scores):
                found[rule].append(scores)
        if progress is not None:
            progress(task)
    return found


def thresholds(tasks: Sequence[TaskScores], coverage: float) -> tuple[float, float]:
    """``(qhat, qhat_one)`` for ``coverage`` (see the module docstring): the which-one decisions'
    own quantile, then the least yes/no threshold that covers every decision of the chosen share of
    tasks; both the single threshold of the tasks' worst decisions where that share cannot be
    reached so."""
    worst = [max((*t.yes_no, *t.one)) for t in tasks]
    single = conformal_threshold(worst, coverage)
    ones = [s for t in tasks for s in t.one]
    if not ones:
        return single, single
    qhat_one = conformal_threshold(ones, coverage)
    need = math.ceil((len(tasks) + 1) * coverage)
    eligible = sorted(max(t.yes_no, default=0.0) for t in tasks if all(s <= qhat_one for s in t.one))
    if need > len(eligible) or qhat_one >= 1.0:
        return single, single
    return float(eligible[need - 1]), qhat_one


def fit(tasks: Sequence[TaskScores]) -> PlanFit:
    """The thresholds per coverage from the tasks' decision nonconformities (see the module
    docstring), with each coverage's leave-one-task-out check.

    Raises:
        ValueError: No task with a calibrated decision.
    """
    if not tasks:
        raise ValueError("no task has a calibrated decision: nothing to calibrate on")
    qhat, qhat_one, held = {}, {}, {}
    for coverage in COVERAGES:
        qhat[coverage], qhat_one[coverage] = thresholds(tasks, coverage)
        kept = [
            t.covered(*thresholds([*tasks[:i], *tasks[i + 1 :]], coverage)) if len(tasks) > 1 else True
            for i, t in enumerate(tasks)
        ]
        held[coverage] = sum(kept) / len(kept)
    return PlanFit(qhat, held, len(tasks), sum(map(len, tasks)), qhat_one)


def thresholds_document(fits: dict[str, dict[str, PlanFit]], rule: str) -> dict[str, Any]:
    """The plan-level thresholds as a calibration file keeps them, for ``fits`` per combination and
    which-one rule: ``plan_which_one`` names the default ``rule``, whose thresholds are
    ``plan_qhat``; another rule's are ``plan_qhat_RULE`` (what
    :func:`~conceptbot.pipeline.goal_planner.conformal.plan_key` reads); the which-one decisions'
    own thresholds are under :func:`~conceptbot.pipeline.goal_planner.conformal.one_key` of each."""
    document: dict[str, Any] = {"plan_which_one": rule}
    for each in WHICH_ONE:
        key = "plan_qhat" if each == rule else f"plan_qhat_{each}"
        document[key] = {c: {str(k): round(q, 4) for k, q in f[each].qhat.items()} for c, f in fits.items()}
        document[one_key(key)] = {
            c: {str(k): round(q, 4) for k, q in (f[each].qhat_one or f[each].qhat).items()}
            for c, f in fits.items()
        }
    return document
