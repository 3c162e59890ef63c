"""Plan-level conformal calibration from labelled tasks (issue 35): what
``benchmarks/fit_conformal_plans.py`` and ``conceptbot calibrate --conformal`` fit.

A plan is right only if every calibrated decision in it is (KnowNo's multi-step form), so a task is
covered only where every decision's prediction set holds its right answer. A decision's
nonconformity is ``1 - p(right answer)``: for a yes/no decision the gold's answer; for a which-one
decision, by the ``fits`` rule the gold's answer to whether the likeliest candidate fits (its
calibrated P(yes) or P(no)), by the ``softmax`` rule the ``p_one`` of the likeliest object the gold
accepts (one where the gold accepts none of the target's objects is left out either way: the
request was read wrong, and no set of that target's objects can cover it). Both rules' scores come
from the same plans, so one pass over the tasks fits both; the tasks without a calibrated decision
take no part.

Three thresholds per coverage. ``single``: the split-conformal quantile of the tasks' worst
decisions, one threshold for every decision (the reading questions take it where the calibration
has no reading threshold of its own). And a pair, one per
kind of decision: ``qhat`` for yes/no decisions and ``qhat_one`` for which-one decisions, the grid
pair with which the fewest dev tasks get a question while the chosen share of tasks (split
conformal's ``ceil((n + 1) * coverage)``) still has every decision in its prediction set; on a tie,
the least yes/no threshold, then the fewest which-one sets that keep no candidate, and the
which-one threshold in the middle of those tied. A task asks where a yes/no decision keeps both
answers, or a which-one decision keeps two or more candidates or none (then the likeliest are
offered).

The single threshold for both kinds (as before 2026-12-05) let the yes/no decisions
of sorts set the which-one threshold too: at 0.9 a candidate 13% likely was kept, so "which one"
was asked wherever a second object was at all plausible, though the likeliest was acceptable in 44
of the 48 dev which-one decisions. The which-one decisions' own 90% quantile (Mondrian conformal,
tried first) falls on the few confidently wrong ones: it kept nearly every candidate as soon as
four dev tasks were added. Choosing the pair on dev fits two numbers to the calibration tasks; the
leave-one-task-out coverage printed beside each (the pair chosen without the task, then the task
checked) says how well the promise holds on a task the fit has not seen.

The which-reading decision is labelled by :func:`reading_label`, but not fitted here: on the dev
tasks' own requests, which the reading rules were built on, the reading taken was the one meant in
all 21 that read two ways, while on held-out paraphrases of them the reading dropped was meant in
15 of 90. Its threshold is fitted on the paraphrases (``benchmarks/bench_reading_labels.py``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from conceptbot.bench.grading import Task, gold_answer, gold_reply, meant_reading, task_scene
from conceptbot.core.plan import Plan
from conceptbot.core.system import COVERAGES, WHICH_ONE, PlannerSystem
from conceptbot.core.trace import ClarifyingQuestion, ReadingOption
from conceptbot.pipeline.goal_planner.asking import reading_set
from conceptbot.pipeline.goal_planner.conformal import OLD_RULE, conformal_threshold, kind_key

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
        tops: What decides whether a which-one decision's set keeps one candidate: by
            ``softmax`` its two largest ``p_one``; by ``fits`` the likeliest's P(yes) and P(no)
            (it acts where the first is at least the floor and the second is not).
    """

    p_right: float
    covered: bool
    p_yes: float | None = None
    yes: bool | None = None
    one: bool = False
    tops: tuple[float, float] = (1.0, 0.0)


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
        scored = [j for j in d.objects if j.p_one is not None]
        readable = all(j.p_one == j.p_one for j in scored)
        shares = sorted((j.p_one or 0.0 for j in scored), reverse=True) if readable else []
        # Unreadable: a set that always asks (no candidate is likely enough, and two are).
        tops = (shares[0], shares[1] if len(shares) > 1 else 0.0) if shares else (0.0, 1.0)
        if rule == "softmax":
            found.append(Labelled(max(accepted.values()), covered, one=True, tops=tops))
            continue
        if not readable:  # the ranking cannot be read: no score
            found.append(Labelled(float("nan"), covered, one=True, tops=(0.0, 1.0)))
            continue
        top = max(scored, key=lambda j: j.p_one or 0.0)
        fits = top.object in accepted
        right = top.p_yes if fits else 1.0 - top.p_yes
        # The planner acts on the likeliest only where "yes" alone is in its set (asking.one_of):
        # P(yes) at least the floor and P(no) under it, the two "tops" in that order.
        found.append(Labelled(right, covered, top.p_yes, fits, True, (top.p_yes, 1.0 - top.p_yes)))
    return found


def task_scores(task: Task, plan: Plan, rule: str = OLD_RULE) -> list[float]:
    """Each calibrated decision's nonconformity in ``plan`` (planned for ``task`` without asking),
    its which-one decisions by ``rule``."""
    return [nonconformity(found.p_right) for found in labelled(task, plan, rule)]


@dataclass(frozen=True)
class TaskScores:
    """A task's decision nonconformities by kind: yes/no decisions and which-one decisions, and
    each which-one decision's two largest probabilities (``tops``; absent: its right answer the
    likeliest, nothing else likely)."""

    yes_no: tuple[float, ...] = ()
    one: tuple[float, ...] = ()
    tops: tuple[tuple[float, float], ...] = ()

    def __len__(self) -> int:
        return len(self.yes_no) + len(self.one)

    def _tops(self) -> tuple[tuple[float, float], ...]:
        return self.tops if len(self.tops) == len(self.one) else tuple((1.0 - s, 0.0) for s in self.one)

    def covered(self, qhat: float, qhat_one: float) -> bool:
        """Whether every decision's prediction set holds the right answer with these thresholds (a
        which-one set that keeps nothing offers the likeliest, so it does). Compared as the planner
        does: a probability at least ``1 - qhat`` is kept."""
        floor, floor_one = round(1.0 - qhat, 4), round(1.0 - qhat_one, 4)
        return all(round(1.0 - s, 4) >= floor for s in self.yes_no) and all(
            round(1.0 - s, 4) >= floor_one or round(top, 4) < floor_one
            for s, (top, _) in zip(self.one, self._tops(), strict=True)
        )

    def asked(self, qhat: float, qhat_one: float) -> bool:
        """Whether a decision's set keeps both answers (yes/no) or other than one candidate."""
        floor, floor_one = round(1.0 - qhat, 4), round(1.0 - qhat_one, 4)
        return any(round(min(s, 1.0 - s), 4) >= floor for s in self.yes_no) or any(
            round(top, 4) < floor_one or round(second, 4) >= floor_one for top, second in self._tops()
        )


def split_scores(task: Task, plan: Plan, rule: str = OLD_RULE) -> TaskScores:
    """:func:`task_scores` split by kind of decision."""
    found = labelled(task, plan, rule)
    return TaskScores(
        tuple(nonconformity(f.p_right) for f in found if not f.one),
        tuple(nonconformity(f.p_right) for f in found if f.one),
        tuple(f.tops for f in found if f.one),
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
        asked: Per coverage, the fitted tasks that get a question with the thresholds.
        single: Per coverage, one threshold for every decision: the split-conformal quantile of
            the tasks' worst decisions (the reading questions take it; None: ``qhat``'s).
    """

    qhat: dict[float, float]
    held_out: dict[float, float]
    tasks: int
    decisions: int
    qhat_one: dict[float, float] | None = None
    asked: dict[float, int] | None = None
    single: dict[float, float] | None = None


def reading_label(
    task: Task, plan: Plan, system: PlannerSystem
) -> tuple[tuple[ReadingOption, ...], int | None]:
    """Where ``plan`` (planned for ``task`` without asking) read the request two or more ways: the
    readings, and which the plan passes with (:func:`~conceptbot.bench.grading.meant_reading`: each
    reading planned as the person's answer, the other questions answered from the gold; None where
    none passes). ``((), None)`` where it read one way.

    Raises:
        ValueError: ``system`` did not ask which reading was meant (it must plan at
            :data:`~conceptbot.core.system.ASK_ALL`, where every reading is in the set).
    """
    options = plan.trace.goal.readings if plan.trace is not None and plan.trace.goal is not None else ()
    listed = [o.text for o in reading_set(options, 1.0)]  # every reading, each once
    if len(listed) < 2:
        return (), None
    if not any(q.kind == "reading" for q in plan.questions):
        raise ValueError("labelling the readings needs a system that asks about every one (coverage ASK_ALL)")
    scene = task_scene(task)

    def plan_as(text: str) -> Plan:
        def fixed(question: ClarifyingQuestion) -> str:
            return text if question.kind == "reading" else gold_reply(task, question)

        return system.plan(task.request, scene, ask=fixed)

    meant = meant_reading(task, listed, plan_as)
    return tuple(options), next((i for i, o in enumerate(options) if o.text == meant), None)


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


#: The grids the pair of thresholds is chosen on (a yes/no threshold under one half keeps no answer
#: of some decisions, so it starts there).
GRID_YES_NO = np.round(np.arange(0.5, 1.0 + 1e-9, 0.0025), 4)
GRID_ONE = np.round(np.arange(0.0, 1.0 + 1e-9, 0.01), 4)


def _grids(tasks: Sequence[TaskScores]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per task and pair of grid thresholds: whether the task is covered, and whether it asks; and
    per task and which-one threshold, how many of its which-one sets keep no candidate."""
    covered = np.zeros((len(tasks), len(GRID_YES_NO), len(GRID_ONE)), dtype=bool)
    asked = np.zeros_like(covered)
    empties = np.zeros((len(tasks), len(GRID_ONE)), dtype=np.int64)
    floors, floors_one = np.round(1.0 - GRID_YES_NO, 4), np.round(1.0 - GRID_ONE, 4)
    # Probabilities are kept to 4 decimals in the traces, and so are these, so that a threshold
    # equal to a score keeps it (1 - 0.05 * 19 is a hair under 0.05).
    for i, task in enumerate(tasks):
        # As the planner compares: a probability at least the floor, 1 - threshold, is kept.
        right = round(min((1.0 - s for s in task.yes_no), default=1.0), 4)
        yes_no_covered = right >= floors
        unsure = [round(min(s, 1.0 - s), 4) for s in task.yes_no]  # the less likely answer
        yes_no_asked = max(unsure) >= floors if unsure else np.zeros(len(floors), dtype=bool)
        one_covered = np.ones(len(floors_one), dtype=bool)
        one_asked = np.zeros(len(floors_one), dtype=bool)
        for s, (top, second) in zip(task.one, task._tops(), strict=True):
            empty = round(top, 4) < floors_one
            empties[i] += empty
            one_covered &= (round(1.0 - s, 4) >= floors_one) | empty
            one_asked |= empty | (round(second, 4) >= floors_one)
        covered[i] = yes_no_covered[:, None] & one_covered[None, :]
        asked[i] = yes_no_asked[:, None] | one_asked[None, :]
    return covered, asked, empties


def _choose(
    covered: np.ndarray, asked: np.ndarray, empty: np.ndarray, n: int, coverage: float
) -> tuple[int, int]:
    """The grid pair for ``coverage`` from the summed counts of ``n`` tasks (``empty``: per
    which-one threshold, the which-one decisions whose set keeps no candidate); see the module
    docstring. The last pair (keep everything) where too few tasks reach the coverage."""
    need = math.ceil((n + 1) * coverage)
    if need > n:
        return len(GRID_YES_NO) - 1, len(GRID_ONE) - 1
    # Fewest asked, then the least yes/no threshold (the shortest questions: of the pairs that ask
    # as little, covering more than the chosen share buys nothing the person asked for, and on dev
    # it doubled the reading questions, which take the yes/no threshold), then the fewest which-one
    # sets that keep no candidate (those offer the likeliest dozen, a poor question): one key,
    # smallest wins.
    big = np.iinfo(np.int64).max
    rows = np.arange(covered.shape[0])[:, None]
    width = int(empty.max()) + 1
    key = (asked * covered.shape[0] + rows) * width + empty[None, :]
    key = np.where(covered >= need, key, big)
    best = np.argwhere(key == key.min())
    # Of the pairs tied on it, the which-one threshold in the middle (the farthest from a set that
    # changes).
    y = int(best[:, 0].min())
    tied = sorted(int(o) for yy, o in best if yy == y)
    return y, tied[len(tied) // 2]


def fit(tasks: Sequence[TaskScores]) -> PlanFit:
    """The thresholds per coverage from the tasks' decisions (see the module docstring), with each
    coverage's leave-one-task-out check.

    Raises:
        ValueError: No task with a calibrated decision.
    """
    if not tasks:
        raise ValueError("no task has a calibrated decision: nothing to calibrate on")
    covered, asked, empties = _grids(tasks)
    cover_sum, ask_sum, empty_sum = covered.sum(axis=0), asked.sum(axis=0), empties.sum(axis=0)
    n = len(tasks)
    qhat, qhat_one, held, count = {}, {}, {}, {}
    worst = [max((*t.yes_no, *t.one)) for t in tasks]
    single = {coverage: conformal_threshold(worst, coverage) for coverage in COVERAGES}
    for coverage in COVERAGES:
        y, o = _choose(cover_sum, ask_sum, empty_sum, n, coverage)
        qhat[coverage], qhat_one[coverage] = float(GRID_YES_NO[y]), float(GRID_ONE[o])
        if not any(t.one for t in tasks):  # nothing to fit it on: the yes/no threshold stands in
            qhat_one[coverage] = qhat[coverage]
        count[coverage] = int(asked[:, y, o].sum())
        kept = []
        for i in range(n):
            if n == 1:
                kept.append(True)
                continue
            yi, oi = _choose(
                cover_sum - covered[i], ask_sum - asked[i], empty_sum - empties[i], n - 1, coverage
            )
            kept.append(bool(covered[i, yi, oi]))
        held[coverage] = sum(kept) / len(kept)
    return PlanFit(qhat, held, n, sum(map(len, tasks)), qhat_one, count, single)


def thresholds_document(fits: dict[str, dict[str, PlanFit]], rule: str) -> dict[str, Any]:
    """The plan-level thresholds as a calibration file keeps them, for ``fits`` per combination and
    which-one rule: ``plan_which_one`` names the default ``rule``, whose thresholds are
    ``plan_qhat``; another rule's are ``plan_qhat_RULE`` (what
    :func:`~conceptbot.pipeline.goal_planner.conformal.plan_key` reads). That key holds the one
    threshold for every decision; each kind's own are beside it
    (:func:`~conceptbot.pipeline.goal_planner.conformal.kind_key`)."""

    def rounded(found: dict[float, float]) -> dict[str, float]:
        return {str(k): round(q, 4) for k, q in found.items()}

    document: dict[str, Any] = {"plan_which_one": rule}
    for each in WHICH_ONE:
        key = "plan_qhat" if each == rule else f"plan_qhat_{each}"
        document[key] = {c: rounded(f[each].single or f[each].qhat) for c, f in fits.items()}
        document[kind_key(key, "yes_no")] = {c: rounded(f[each].qhat) for c, f in fits.items()}
        document[kind_key(key, "one")] = {
            c: rounded(f[each].qhat_one or f[each].qhat) for c, f in fits.items()
        }
    return document
