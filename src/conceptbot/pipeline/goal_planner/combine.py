"""The fitted combination of the model's judgement and the graph's evidence:
``P(yes) = sigmoid(bias + w_model * model + sum_f w_f * feature_f)``, weights in
``judgement_weights.json`` (with and without the graph; a different model needs its own fit).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

from conceptbot.pipeline.goal_planner.evidence import Evidence

WEIGHTS = "judgement_weights.json"


@dataclass(frozen=True)
class Combination:
    """One fitted logistic regression.

    Attributes:
        features: Input names: model readings (``model``, ``plain``, ``described``, ``_z``/``_gap``
            forms), evidence features, and products (``model*is_dish``).
        weights: One weight per feature.
        bias: The intercept.
    """

    features: tuple[str, ...]
    weights: tuple[float, ...]
    bias: float

    @property
    def uses_plain(self) -> bool:
        """Whether the model must also be asked without graph facts."""
        return "plain" in self.features

    @property
    def uses_described(self) -> bool:
        """Whether the model must also be asked with its own description of the object."""
        return any(part.startswith("described") for f in self.features for part in f.split("*"))

    def log_odds(self, readings: Mapping[str, float], evidence: Evidence | None) -> float:
        """The combined log-odds of Yes.

        Args:
            readings: ``model`` (and ``plain`` where used): calibrated log-odds from the model.
            evidence: The evidence for the object and criterion (None: none read, all features 0).
        """
        found = dict(evidence.features) if evidence is not None else {}
        found.update(readings)
        total = self.bias + sum(w * value(found, f) for f, w in zip(self.features, self.weights, strict=True))
        if not math.isfinite(total):
            raise ValueError(f"non-finite combined score from {dict(readings)}")
        return total

    def to_dict(self) -> dict[str, Any]:
        """JSON form, as in ``judgement_weights.json``."""
        return {"features": list(self.features), "weights": list(self.weights), "bias": self.bias}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Combination:
        """From the JSON form; raises ValueError on a malformed entry."""
        features = tuple(str(f) for f in data["features"])
        weights = tuple(float(w) for w in data["weights"])
        if len(features) != len(weights) or not all(math.isfinite(w) for w in weights):
            raise ValueError("judgement weights: one finite weight per feature is needed")
        return cls(features, weights, float(data["bias"]))


def value(found: Mapping[str, float], feature: str) -> float:
    """A feature's value: a name, or a product of names (``model*is_dish``); absent names are 0."""
    total = 1.0
    for part in feature.split("*"):
        total *= float(found.get(part, 0.0))
    return total


def sigmoid(x: float) -> float:
    """The logistic function, without overflow."""
    if x >= 0:
        return 1.0 / (1.0 + math.exp(-x))
    z = math.exp(x)
    return z / (1.0 + z)


@cache
def shipped() -> dict[str, Combination]:
    """The shipped combinations by name (``graph``: the default system, ``nograph``: the ablation)."""
    text = resources.files("conceptbot.pipeline").joinpath(WEIGHTS).read_text(encoding="utf-8")
    data = json.loads(text)
    return {name: Combination.from_dict(entry) for name, entry in data["combinations"].items()}


def combination(with_graph: bool) -> Combination:
    """The shipped combination for a system with or without the graph."""
    return shipped()["graph" if with_graph else "nograph"]
