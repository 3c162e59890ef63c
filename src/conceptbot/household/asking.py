"""Asking instead of guessing on household instructions (issue 35): the harm judge's score read as a
calibrated probability, its conformal prediction set, and the one question where that set holds
both answers.

The judge (:mod:`conceptbot.household.judge`) adds four log-odds of "dangerous" and refuses at a
threshold; the sum is a score, not a probability. Here it is made one by Platt scaling fitted on
SafeAgentBench's dev split (:mod:`conceptbot.bench.safeagentbench.conformal`), and split conformal
prediction on the same tasks gives, per coverage, the threshold ``qhat``: an answer (``dangerous`` or
``safe``) is kept where its probability is at least ``1 - qhat``. One answer kept: the planner acts
on it. Both kept: the person is asked ("Would carrying out ... be dangerous?"); with no answer, or
an answer that cannot be read, the instruction is refused. A probability that cannot be read (NaN)
keeps both answers, so it is asked about or refused, never carried out on a guess.

The calibration ships as ``judge_conformal.json`` beside this module, fitted for the embedded model
by ``benchmarks/fit_judge_conformal.py``; another model needs its own fit.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib.resources import files
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError
from conceptbot.core.trace import DANGEROUS, SAFE, ClarifyingQuestion

CALIBRATION_FILE = "judge_conformal.json"
WHAT = "harm judge calibration"
ANSWERS = (DANGEROUS, SAFE)
ASK_ALL = 1.0
"""The coverage at which every judged instruction is a question (both answers always kept)."""


@dataclass(frozen=True)
class JudgeCalibration:
    """The harm judge's score as a probability, and the conformal threshold per coverage.

    Attributes:
        slope: Platt scaling: P(dangerous) = sigmoid(slope * score + intercept).
        intercept: See ``slope``.
        qhat: Per coverage (0.8, 0.9, 0.95), the split-conformal threshold.
        fitted_on: What it was fitted on, in words.
    """

    slope: float
    intercept: float
    qhat: Mapping[float, float]
    fitted_on: str = ""

    def p_dangerous(self, log_odds: float) -> float:
        """P(dangerous) for the judge's summed ``log_odds``; NaN where it cannot be computed."""
        z = self.slope * log_odds + self.intercept
        if not math.isfinite(z):
            return math.nan
        return 1.0 / (1.0 + math.exp(-z)) if z >= 0 else math.exp(z) / (1.0 + math.exp(z))

    def threshold(self, coverage: float) -> float:
        """``qhat`` at ``coverage`` (1: every answer kept).

        Raises:
            ConfigError: No threshold for that coverage.
        """
        if coverage == ASK_ALL:
            return 1.0
        found = self.qhat.get(coverage)
        if found is None:
            shipped = ", ".join(str(c) for c in sorted(self.qhat))
            raise ConfigError(
                f"the harm judge has no conformal threshold for coverage {coverage}",
                hint=f"use one of {shipped} or 1",
            )
        return found


def _calibration(data: Any, where: str) -> JudgeCalibration:
    """The calibration in ``data`` (read from ``where``), checked."""
    try:
        slope, intercept = float(data["slope"]), float(data["intercept"])
        qhat = {float(c): float(q) for c, q in data["qhat"].items()}
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ConfigError(
            f"{where}: needs numbers 'slope', 'intercept' and a 'qhat' per coverage ({exc})"
        ) from None
    if not all(math.isfinite(v) for v in (slope, intercept, *qhat.values())):
        raise ConfigError(f"{where}: a value is not a finite number")
    # A slope that is not positive would read a more dangerous score as safer: the check is off.
    if slope <= 0:
        raise ConfigError(
            f"{where}: 'slope' must be positive (a higher score of 'dangerous' is more dangerous)"
        )
    if not all(0.0 <= q <= 1.0 for q in qhat.values()):
        raise ConfigError(f"{where}: each 'qhat' is a probability threshold from 0 to 1")
    return JudgeCalibration(slope, intercept, qhat, str(data.get("fitted_on", "")))


def read_json(source: Path | str, what: str) -> Any:
    """The JSON in ``source``: a file's path, or (a string) the name of a file shipped in this
    package. ``what`` names it in errors.

    Raises:
        ConfigError: It is missing, unreadable or not JSON.
    """
    shipped = isinstance(source, str)
    where = f"{what} {source}"
    try:
        if shipped:
            return json.loads(files("conceptbot.household").joinpath(source).read_text(encoding="utf-8"))
        return json.loads(source.read_text(encoding="utf-8"))
    except FileNotFoundError:
        if shipped:
            raise ConfigError(f"{where} is missing from the package") from None
        raise ConfigError(f"cannot read the {where}: no such file") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read the {where}: {exc}") from None


@cache
def shipped_calibration() -> JudgeCalibration:
    """The calibration shipped with the package (fitted for the embedded model).

    Raises:
        ConfigError: The file is missing or not a calibration.
    """
    return _calibration(read_json(CALIBRATION_FILE, WHAT), f"{WHAT} {CALIBRATION_FILE}")


def load_calibration(path: Path) -> JudgeCalibration:
    """A calibration from a file written by ``benchmarks/fit_judge_conformal.py``.

    Raises:
        ConfigError: It cannot be read or is not a calibration.
    """
    return _calibration(read_json(path, WHAT), str(path))


def judge_set(p_dangerous: float, qhat: float) -> tuple[str, ...]:
    """The conformal prediction set of the judge's decision: each answer at least ``1 - qhat``
    likely, ``dangerous`` first. Both where the probability cannot be read (NaN): the decision
    cannot be made, so it is asked about or refused. Where neither answer reaches the floor (a
    threshold under one half, only in a hand-made file), the likelier alone."""
    if not 0.0 <= p_dangerous <= 1.0:  # NaN fails
        return ANSWERS
    floor = round(1.0 - qhat, 4)
    kept = tuple(
        a for a, p in zip(ANSWERS, (p_dangerous, 1.0 - p_dangerous), strict=True) if round(p, 4) >= floor
    )
    return kept or ((DANGEROUS,) if p_dangerous >= 0.5 else (SAFE,))


def harm_question(instruction: str, p_dangerous: float) -> ClarifyingQuestion:
    """The question where the set holds both answers ("yes": dangerous, the robot will not do it)."""
    shown = p_dangerous if 0.0 <= p_dangerous <= 1.0 else 0.5
    return ClarifyingQuestion(
        f'Would carrying out "{instruction}" be dangerous here? Yes (I will not do it) or no (I will).',
        "",
        (instruction,),
        (round(shown, 4),),
        kind="harm",
    )
