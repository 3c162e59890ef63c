"""Split conformal prediction for the goal planner's decisions (as KnowNo, Ren et al., CoRL 2023).

A decision's prediction set holds every answer at least ``1 - qhat`` likely: one answer, the planner
acts; both, it asks. ``qhat`` ships in ``conformal.json`` at two levels: ``plan`` (a task's worst
decision, so a plan's decisions are covered together) and ``decision``.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError
from conceptbot.core.system import ASK_ALL, COVERAGES, LEVELS, WHICH_ONE

__all__ = [
    "COVERAGES",
    "KINDS",
    "LEVELS",
    "Calibration",
    "DecisionSet",
    "calibration_for",
    "conformal_threshold",
    "decision_set",
    "shipped",
    "user_file",
]

CALIBRATION = "conformal.json"
CALIBRATION_DOC = (
    "Split conformal thresholds (qhat) per combination and coverage, read by "
    "conceptbot.pipeline.goal_planner.conformal. qhat: decision level, on the combination's held-out "
    "P(yes) over the judgement set (benchmarks/fit_judgements.py --conformal --write). plan_qhat: plan "
    "level, a dev task's worst decision (benchmarks/fit_conformal_plans.py --write), for the which-one "
    "rule plan_which_one names; plan_qhat_RULE: for another rule. plan_qhat is one threshold for "
    "every decision (the tasks' worst); plan_qhat_yes_no and plan_qhat_one (plan_qhat_yes_no_RULE, "
    "plan_qhat_one_RULE) are the thresholds the yes/no and which-one decisions take, and "
    "plan_qhat_reading (plan_qhat_reading_RULE) the question of which reading was meant, fitted on "
    "held-out paraphrases (benchmarks/bench_reading_labels.py --write; reading_fitted_on); plan_qhat "
    "where they are missing. model: the model every threshold here was fitted for (the embedded "
    "catalogue's name); the planner tells another model that they are not its own (`conceptbot "
    "calibrate --conformal` fits its own). Refit for another model."
)
#: The model the shipped thresholds were fitted for where the file names none.
SHIPPED_MODEL = "qwen2.5-coder-1.5b"
#: The which-one rule of a calibration that names none, and of the sets where no rule is given.
OLD_RULE = "softmax"


def conformal_threshold(scores: Sequence[float], coverage: float) -> float:
    """Split conformal's ``qhat``: the ``ceil((n + 1) * coverage) / n`` quantile of the nonconformity
    ``scores`` (``1 - p(right answer)``); ``1.0`` where too few reach the coverage.

    Raises:
        ValueError: A coverage outside (0, 1), no scores, or a score that is not a number in [0, 1].
    """
    if not 0.0 < coverage < 1.0:
        raise ValueError(f"coverage must be in (0, 1), got {coverage!r}")
    if not scores:
        raise ValueError("conformal calibration needs at least one score")
    if any(not (isinstance(s, int | float) and 0.0 <= s <= 1.0) for s in scores):  # NaN fails too
        raise ValueError("nonconformity scores are numbers in [0, 1]")
    ordered = sorted(scores)
    rank = math.ceil((len(ordered) + 1) * coverage)
    return 1.0 if rank > len(ordered) else float(ordered[rank - 1])


@dataclass(frozen=True)
class DecisionSet:
    """A yes/no decision's prediction set.

    Attributes:
        p_yes: The decision's calibrated probability of yes.
        answers: ``("yes",)``, ``("no",)``, ``("yes", "no")`` (unsure: ask) or ``()`` (unsure too).
    """

    p_yes: float
    answers: tuple[str, ...]

    @property
    def sure(self) -> bool:
        """One answer: the planner may act on it."""
        return len(self.answers) == 1

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {"p_yes": round(self.p_yes, 4), "answers": list(self.answers)}


def decision_set(p_yes: float, qhat: float) -> DecisionSet:
    """The answers whose probability is at least ``1 - qhat``; NaN keeps both (ask, never guess)."""
    if not (isinstance(p_yes, int | float) and 0.0 <= p_yes <= 1.0):
        return DecisionSet(float("nan"), ("yes", "no"))
    floor = 1.0 - qhat
    answers = tuple(a for a, p in (("yes", p_yes), ("no", 1.0 - p_yes)) if p >= floor)
    return DecisionSet(float(p_yes), answers)


@dataclass(frozen=True)
class Calibration:
    """Conformal thresholds: ``qhat`` per coverage, whether they hold for which-one decisions, their
    rule, the model they were fitted for (``backend:model`` for a user's) and their ``source``."""

    qhat: dict[float, float]
    fitted_on: str
    which_one: bool = True
    rule: str = OLD_RULE
    qhat_one: dict[float, float] | None = None  # which-one decisions' own (None: qhat's)
    qhat_yes_no: dict[float, float] | None = None  # yes/no decisions' own (None: qhat's)
    qhat_reading: dict[float, float] | None = None  # which-reading decisions' own (None: qhat's)
    fitted_for: str = SHIPPED_MODEL
    source: str = "shipped"

    def fits(self, backend: str, model: str) -> bool:
        """Whether the thresholds were fitted on this model's scores, so their coverage holds."""
        if self.source == "shipped":
            return model == self.fitted_for
        return self.fitted_for == f"{backend}:{model}"

    def threshold_one(self, coverage: float) -> float:
        """The which-one decisions' threshold: their own where fitted, else :meth:`threshold`'s.

        Raises:
            ValueError: A coverage without a fitted threshold.
        """
        return self._own(self.qhat_one, coverage)

    def threshold_yes_no(self, coverage: float) -> float:
        """The yes/no decisions' threshold: their own where fitted, else :meth:`threshold`'s.

        Raises:
            ValueError: A coverage without a fitted threshold.
        """
        return self._own(self.qhat_yes_no, coverage)

    def threshold_reading(self, coverage: float) -> float:
        """The which-reading decisions' threshold: their own where fitted, else :meth:`threshold`'s.

        Raises:
            ValueError: A coverage without a fitted threshold.
        """
        return self._own(self.qhat_reading, coverage)

    def _own(self, found: dict[float, float] | None, coverage: float) -> float:
        if coverage == ASK_ALL or not found or coverage not in found:
            return self.threshold(coverage)
        return found[coverage]

    def threshold(self, coverage: float) -> float:
        """``qhat`` for ``coverage`` (one of :data:`COVERAGES`; :data:`ASK_ALL` keeps every answer).

        Raises:
            ValueError: A coverage without a fitted threshold.
        """
        if coverage == ASK_ALL:
            return 1.0
        if coverage not in self.qhat:
            shown = ", ".join(str(c) for c in sorted(self.qhat))
            raise ValueError(f"no conformal threshold for coverage {coverage}; fitted: {shown}")
        return self.qhat[coverage]


def plan_key(data: dict[str, Any], rule: str | None) -> tuple[str, str]:
    """The key of a which-one ``rule``'s plan-level thresholds (``plan_qhat[_RULE]``), and the rule.

    Raises:
        ValueError: A rule that is not one of :data:`WHICH_ONE`.
    """
    named = str(data.get("plan_which_one", OLD_RULE))
    rule = rule or named
    if rule not in WHICH_ONE:
        raise ValueError(f"no which-one rule {rule!r}; known: {', '.join(WHICH_ONE)}")
    return ("plan_qhat" if rule == named else f"plan_qhat_{rule}"), rule


#: The kinds of calibrated decision with thresholds of their own beside the plan-level one.
KINDS = ("yes_no", "one", "reading")


def kind_key(key: str, kind: str) -> str:
    """The key of one kind's thresholds beside the plan-level ``key`` (``plan_qhat`` -> ``plan_qhat_one``)."""
    return key.replace("plan_qhat", f"plan_qhat_{kind}", 1)


def _kind(data: dict[str, Any], key: str, combination: str, kind: str) -> dict[float, float] | None:
    """One kind's thresholds kept beside ``key`` for ``combination``, or None where there are none.

    Raises:
        ValueError: A threshold that is not a number in [0, 1].
    """
    found = data.get(kind_key(key, kind), {})
    if not isinstance(found, dict) or combination not in found:
        return None
    where = f"{kind_key(key, kind)}.{combination}"
    return {float(k): threshold(v, f"{where}.{k}") for k, v in found[combination].items()}


def threshold(value: object, field: str) -> float:
    """A conformal threshold read from a file: a JSON number in [0, 1] (not ``true`` or ``"0.5"``).

    Raises:
        ValueError: Not a number (a boolean, a string, null), NaN, or outside [0, 1]; names ``field``.
    """
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0.0 <= value <= 1.0:
        raise ValueError(f"{field} is {json.dumps(value)[:40]}, not a number in [0, 1]")
    return float(value)


@cache
def shipped(combination: str = "graph", level: str = "plan", rule: str | None = None) -> Calibration:
    """The calibration shipped in ``conformal.json`` for a combination, level and ``rule`` (None: the file's).

    Raises:
        ValueError: A combination, level or rule without a calibration.
    """
    if level not in LEVELS:
        raise ValueError(f"no conformal level {level!r}; known: {', '.join(LEVELS)}")
    text = resources.files("conceptbot.pipeline").joinpath(CALIBRATION).read_text(encoding="utf-8")
    data = json.loads(text)
    if level == "plan":
        (key, rule), where = plan_key(data, rule), "plan_fitted_on"
    else:
        key, where, rule = "qhat", "fitted_on", rule or OLD_RULE
    if combination not in data.get(key, {}):
        raise ValueError(
            f"no {level}-level conformal calibration for the {combination!r} combination ({key})"
        )
    fitted = data[key][combination]
    qhat = {float(k): float(v) for k, v in fitted.items()}
    model = str(data.get("model", SHIPPED_MODEL))
    if level != "plan":
        return Calibration(qhat, str(data[where]), False, rule, fitted_for=model)
    yes_no, ones, reading = (_kind(data, key, combination, kind) for kind in KINDS)
    return Calibration(qhat, str(data[where]), True, rule, ones, yes_no, reading, model)


def user_file(directory: Path, backend: str, model: str) -> Path:
    """Where ``conceptbot calibrate --conformal`` keeps a model's own calibration."""
    name = re.sub(r"[^A-Za-z0-9._-]+", "-", f"{backend}-{model}").strip("-.") or "model"
    return directory / f"conformal-{name[:120]}.json"


def calibration_for(
    directory: Path | None,
    backend: str,
    model: str,
    combination: str = "graph",
    level: str = "plan",
    rule: str | None = None,
) -> Calibration:
    """The model's own plan-level calibration in ``directory`` where there is one, else the shipped one.

    Raises:
        ConfigError: A calibration file that is not one, or has no thresholds for ``rule``.
    """
    path = user_file(directory, backend, model) if directory is not None else None
    if level != "plan" or path is None or not path.is_file():
        return shipped(combination, level, rule)
    fix = f"run `conceptbot calibrate --conformal` again, or remove {path}"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        key, rule = plan_key(data, rule)
        fitted = data[key][combination]
        qhat = {float(c): threshold(fitted[str(c)], f"{key}.{combination}.{c}") for c in COVERAGES}
        where = str(data["fitted_on"])
        yes_no, ones, reading = (_kind(data, key, combination, kind) for kind in KINDS)
    except RecursionError:
        raise ConfigError(f"{path} is nested too deeply to be a conformal calibration", hint=fix) from None
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ConfigError(
            f"{path} is not a conformal calibration for this rule ({type(exc).__name__}: {exc})", hint=fix
        ) from None
    return Calibration(qhat, where, True, rule, ones, yes_no, reading, f"{backend}:{model}", str(path))
