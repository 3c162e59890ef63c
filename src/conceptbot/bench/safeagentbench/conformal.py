"""Calibrating the household harm judge for asking (issue 35): Platt scaling of its summed log-odds,
then split conformal prediction over SafeAgentBench's dev tasks, from a results file of
``conceptbot safebench run`` (the judge's score is in each ``conceptbot`` record's trace, so the fit
needs no model call).

A task's label is its suite: ``safe`` tasks are safe, ``unsafe`` and ``abstract`` ones dangerous.
Tasks refused before the judge (the instruction itself asks to spill or throw) have no judge score
and take no part. The nonconformity of a task is ``1 - P(its label)``; ``qhat`` at a coverage is
their ``ceil((n + 1) * coverage)``-th smallest, at least one half (a binary decision's set below
that would keep neither answer of some tasks). The leave-one-task-out coverage (both the scaling
and ``qhat`` fitted without the task, then the task checked) is kept beside it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from conceptbot.core.errors import ConfigError
from conceptbot.core.system import COVERAGES
from conceptbot.core.trace import DANGEROUS
from conceptbot.household.asking import JudgeCalibration, judge_set

LABELLED_CONFIG = "conceptbot"
"""The configuration whose records carry the judge's score."""


@dataclass(frozen=True)
class JudgedTask:
    """One task the judge scored: its id, the summed log-odds, and whether it is dangerous."""

    task: str
    log_odds: float
    dangerous: bool


def judged_tasks(path: Path, ids: Iterable[str] | None = None) -> list[JudgedTask]:
    """The ``conceptbot`` records of ``path`` with a judge score (of the tasks in ``ids``, if
    given), the last record of a task winning.

    Raises:
        ConfigError: The file cannot be read.
    """
    wanted = set(ids) if ids is not None else None
    found: dict[str, JudgedTask] = {}
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise ConfigError(f"cannot read {path}: {exc}") from None
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
        except ValueError:
            raise ConfigError(f"{path}:{number} is not JSON") from None
        judge = (row.get("trace") or {}).get("judge") if isinstance(row, dict) else None
        if row.get("config") != LABELLED_CONFIG or not isinstance(judge, dict):
            continue
        if wanted is not None and row.get("task") not in wanted:
            continue
        score = judge.get("log_odds")
        if not isinstance(score, (int, float)) or not math.isfinite(score):
            continue
        found[row["task"]] = JudgedTask(row["task"], float(score), row.get("suite") != "safe")
    return list(found.values())


def platt(scores: Sequence[float], dangerous: Sequence[bool], ridge: float = 1e-3) -> tuple[float, float]:
    """Slope and intercept of P(dangerous) = sigmoid(slope * score + intercept), by Newton's method
    on the log-loss (a small ridge keeps it finite where the labels separate).

    Raises:
        ValueError: Fewer than two tasks, or one label only.
    """
    x, y = np.asarray(scores, float), np.asarray(dangerous, float)
    if len(x) < 2 or y.min() == y.max():
        raise ValueError("the fit needs both safe and dangerous tasks")
    features = np.stack([x, np.ones_like(x)], axis=1)

    def loss(w: np.ndarray) -> float:
        z = features @ w
        return float(np.sum(np.logaddexp(0.0, z) - y * z) + 0.5 * ridge * w @ w)

    # From the base rate (slope 0), with step halving: a full Newton step from a steep start
    # saturates every probability and diverges.
    w = np.array([0.0, math.log(y.mean() / (1.0 - y.mean()))])
    for _ in range(100):
        p = 1.0 / (1.0 + np.exp(-np.clip(features @ w, -500, 500)))
        grad = features.T @ (p - y) + ridge * w
        hess = (features * (p * (1 - p))[:, None]).T @ features + ridge * np.eye(2)
        step = np.linalg.solve(hess, grad)
        size, before = 1.0, loss(w)
        while size > 1e-6 and loss(w - size * step) > before:
            size /= 2
        w = w - size * step
        if np.abs(size * step).max() < 1e-10:
            break
    return float(w[0]), float(w[1])


def _qhat(nonconformity: Sequence[float], coverage: float) -> float:
    """Split conformal's threshold, at least one half."""
    ranked = sorted(nonconformity)
    n = len(ranked)
    k = math.ceil((n + 1) * coverage)
    return 1.0 if k > n else max(0.5, ranked[k - 1])


def _calibrate(tasks: Sequence[JudgedTask]) -> JudgeCalibration:
    slope, intercept = platt([t.log_odds for t in tasks], [t.dangerous for t in tasks])
    scaled = JudgeCalibration(slope, intercept, {})
    scores = [1.0 - _p_label(scaled, t) for t in tasks]
    return JudgeCalibration(slope, intercept, {c: _qhat(scores, c) for c in COVERAGES})


def _p_label(calibration: JudgeCalibration, task: JudgedTask) -> float:
    p = calibration.p_dangerous(task.log_odds)
    return p if task.dangerous else 1.0 - p


def holds(kept: Sequence[str], dangerous: bool) -> bool:
    """Whether the prediction set ``kept`` holds the label of a task that is ``dangerous`` (or not)."""
    return len(kept) == 2 or (DANGEROUS in kept) == dangerous


def covers(calibration: JudgeCalibration, task: JudgedTask, coverage: float) -> bool:
    """Whether the set at ``coverage`` holds the task's label."""
    kept = judge_set(calibration.p_dangerous(task.log_odds), calibration.threshold(coverage))
    return holds(kept, task.dangerous)


@dataclass(frozen=True)
class JudgeFit:
    """A fitted calibration, the tasks it was fitted on and its leave-one-task-out coverage."""

    calibration: JudgeCalibration
    tasks: int
    dangerous: int
    held_out: dict[float, float]


def fit_judge(tasks: Sequence[JudgedTask], fitted_on: str = "") -> JudgeFit:
    """Platt scaling and ``qhat`` per coverage on ``tasks``, with the leave-one-out check.

    Raises:
        ValueError: Too few tasks, or one label only.
    """
    calibration = _calibrate(tasks)
    calibration = JudgeCalibration(calibration.slope, calibration.intercept, calibration.qhat, fitted_on)
    held: dict[float, float] = {}
    if len(tasks) > 2:
        kept = {c: 0 for c in COVERAGES}
        for i, task in enumerate(tasks):
            without = _calibrate([*tasks[:i], *tasks[i + 1 :]])
            for c in COVERAGES:
                kept[c] += covers(without, task, c)
        held = {c: kept[c] / len(tasks) for c in COVERAGES}
    return JudgeFit(calibration, len(tasks), sum(t.dangerous for t in tasks), held)


def calibration_document(found: JudgeFit) -> dict[str, Any]:
    """The calibration as ``judge_conformal.json`` keeps it."""
    c = found.calibration
    return {
        "_doc": (
            "The household harm judge's summed log-odds of 'dangerous' as a probability (Platt scaling: "
            "P = sigmoid(slope * score + intercept)) and split-conformal thresholds per coverage, fitted "
            "on SafeAgentBench's dev split by benchmarks/fit_judge_conformal.py; read by "
            "conceptbot.household.asking. Refit for another model or prompt."
        ),
        "fitted_on": c.fitted_on,
        "tasks": found.tasks,
        "dangerous": found.dangerous,
        "slope": round(c.slope, 6),
        "intercept": round(c.intercept, 6),
        "qhat": {str(k): round(v, 4) for k, v in c.qhat.items()},
        "held_out_coverage": {str(k): round(v, 4) for k, v in found.held_out.items()},
    }
