"""One fitted, calibrated judgement of harm for a household plan.

Whether the robot may carry out a plan is decided from what the plan would do, with no rule about
the request's words. The signals are general and each is a number:

* the harm judge's two readings of the instruction (:class:`~conceptbot.household.judge.HarmJudge`:
  "would carrying this out be dangerous?" and "is this an ordinary chore?", without evidence: the
  knowledge graph's facts, OPE's Risk Index and the judge's other two questions added nothing on
  held-out or blind tasks and cost half a plan's time,
  docs/notes/2026-12-07-household-judgement-without-evidence.md);
* the similar cases' reading (:class:`~conceptbot.household.similar.SimilarCases`): how the
  labelled tuning instructions nearest in meaning were judged, as a fitted log-odds;
* the outcome reading (:class:`~conceptbot.household.judge.OutcomeJudge`): the model asked plainly
  whether the state the simulated plan leaves behind is dangerous;
* what the plan does in the symbolic world (:func:`plan_features`): liquid poured onto something
  that neither holds nor drains it, things thrown or broken, an appliance left on with something in
  it, things switched on and left on, and no executable plan at all.

A logistic model over them (:class:`HarmModel`, ``harm_model.json``, fitted by
``benchmarks/fit_household_harm.py`` on SafeAgentBench's dev split and the folded blind household
sets) gives the log-odds that carrying the plan out is dangerous. The plan is refused at or above
the fitted threshold; a score that cannot be computed (a missing or non-finite signal) refuses it.
The same log-odds is a calibrated probability, so asking instead of guessing (a coverage) uses the
fit's conformal thresholds (:class:`~conceptbot.household.asking.JudgeCalibration`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError
from conceptbot.core.plan import HouseholdAction
from conceptbot.core.scene import HouseScene
from conceptbot.core.trace import HarmVerdict
from conceptbot.household.asking import JudgeCalibration, read_json
from conceptbot.household.executor import HouseholdExecutor
from conceptbot.household.outcomes import hazardous_outcomes

MODEL_FILE = "harm_model.json"
WHAT = "household harm model"
READINGS = ("other_examples", "ordinary")
"""The harm judge's readings of the instruction (:data:`~conceptbot.household.judge.QUESTIONS`) that
the judgement weighs: the questions without the graph's evidence."""
PLAN_FEATURES = ("spill", "throw", "broken", "heating_inside", "left_on", "no_plan")
"""What the plan does in the symbolic world (:func:`plan_features`)."""
FEATURES = (*READINGS, "similar", "outcome", *PLAN_FEATURES)
"""Every signal of the judgement, in the order the fit writes its weights."""


def plan_features(scene: HouseScene, steps: Sequence[HouseholdAction]) -> dict[str, float]:
    """What carrying out ``steps`` in ``scene`` does, counted (failed steps do nothing):

    * ``spill``, ``throw``: liquid poured onto something that neither holds nor drains it; a thrown
      object (:func:`~conceptbot.household.outcomes.hazardous_outcomes`);
    * ``broken``: objects the plan leaves broken;
    * ``heating_inside``: switched-on appliances left with something in or on them;
    * ``left_on``: objects the plan switches on and leaves on;
    * ``no_plan``: 1 where no step of the plan can be carried out.
    """
    executor = HouseholdExecutor(scene)
    before = {t: dict(s.flags) for t, s in executor.state.items()}
    outcomes = hazardous_outcomes(scene, steps)
    execution = executor.run(steps)
    state = execution.state
    changed = {
        flag: [t for t, s in state.items() if s.flags.get(flag) and not before.get(t, {}).get(flag)]
        for flag in ("isBroken", "isToggled")
    }
    inside = {s.parents[0] for s in state.values() if s.parents}
    heating = [t for t in changed["isToggled"] if t in inside]
    done = sum(1 for r in execution.results if r.ok)
    return {
        "spill": float(sum(o.kind == "spill" for o in outcomes)),
        "throw": float(sum(o.kind == "throw" for o in outcomes)),
        "broken": float(len(changed["isBroken"])),
        "heating_inside": float(len(heating)),
        "left_on": float(len(changed["isToggled"])),
        "no_plan": float(done == 0),
    }


@dataclass(frozen=True)
class HarmModel:
    """The fitted judgement: log-odds of "dangerous" = bias + the weighted signals.

    Attributes:
        weights: A weight per signal of :data:`FEATURES` (a missing one weighs 0).
        bias: The intercept.
        threshold: Refuse at log-odds at or above this.
        qhat: Per coverage (0.8, 0.9, 0.95), the split-conformal threshold on the probability.
        fitted_on: What it was fitted on, in words.
    """

    weights: Mapping[str, float]
    bias: float
    threshold: float
    qhat: Mapping[float, float]
    fitted_on: str = ""

    def log_odds(self, signals: Mapping[str, float]) -> float:
        """The score of ``signals``; NaN where a weighted signal is missing or not finite, so the
        decision fails closed."""
        total = self.bias
        for name, weight in self.weights.items():
            value = signals.get(name, math.nan)
            if not math.isfinite(value):
                return math.nan
            total += weight * value
        return total

    def verdict(self, signals: Mapping[str, float]) -> HarmVerdict:
        """The decision on ``signals``: their score against the threshold, with the signals."""
        return HarmVerdict(self.log_odds(signals), self.threshold, dict(signals))

    def calibration(self) -> JudgeCalibration:
        """The score as a probability (it is a fitted log-odds already) and the conformal
        thresholds, for asking instead of guessing."""
        return JudgeCalibration(1.0, 0.0, self.qhat, self.fitted_on)

    def to_json(self) -> dict[str, Any]:
        """As ``harm_model.json`` keeps it."""
        return {
            "fitted_on": self.fitted_on,
            "weights": {k: round(v, 5) for k, v in self.weights.items()},
            "bias": round(self.bias, 5),
            "threshold": round(self.threshold, 5),
            "qhat": {str(c): round(q, 5) for c, q in sorted(self.qhat.items())},
        }


def _model(data: Any, where: str) -> HarmModel:
    """The model in ``data`` (read from ``where``), checked."""
    try:
        weights = {str(k): float(v) for k, v in data["weights"].items()}
        bias, threshold = float(data["bias"]), float(data["threshold"])
        qhat = {float(c): float(q) for c, q in data["qhat"].items()}
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ConfigError(f"{where}: needs 'weights', 'bias', 'threshold' and 'qhat' ({exc})") from None
    unknown = sorted(set(weights) - set(FEATURES))
    if unknown:
        raise ConfigError(f"{where}: unknown signals {', '.join(unknown)}", hint=f"use {', '.join(FEATURES)}")
    if not all(math.isfinite(v) for v in (bias, threshold, *weights.values(), *qhat.values())):
        raise ConfigError(f"{where}: a value is not a finite number")
    if not all(0.0 <= q <= 1.0 for q in qhat.values()):
        raise ConfigError(f"{where}: each 'qhat' is a probability threshold from 0 to 1")
    return HarmModel(weights, bias, threshold, qhat, str(data.get("fitted_on", "")))


@cache
def shipped_model() -> HarmModel:
    """The model shipped with the package (fitted for the embedded model).

    Raises:
        ConfigError: The file is missing or not a model.
    """
    return _model(read_json(MODEL_FILE, WHAT), f"{WHAT} {MODEL_FILE}")


def load_model(path: Path) -> HarmModel:
    """A model from a file written by ``benchmarks/fit_household_harm.py``.

    Raises:
        ConfigError: It cannot be read or is not a model.
    """
    return _model(read_json(path, WHAT), str(path))
