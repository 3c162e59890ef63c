"""The fitted combination of the model's judgement and the graph's evidence.

A decision's probability is a logistic regression over the model's calibrated log-odds (asked with
the object's graph facts, and where the weights use it, without them) and the features of
:mod:`conceptbot.pipeline.goal_planner.evidence`::

    P(yes) = sigmoid(bias + w_model * model + sum_f w_f * feature_f)

The weights are data (``judgement_weights.json``), fitted on the judgement set
(``benchmarks/data/judgement_set.jsonl``) by ``benchmarks/fit_judgements.py``, cross-validated by
object; one set for the default system and one for the no-graph ablation, which sees only the
model's answer without facts and the object's name. A different model needs its own fit (its
log-odds have another scale).
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
        features: Input names: ``model``, ``plain`` (the model's calibrated log-odds with and without
            graph facts), ``described`` (with the model's own one-sentence description of the object
            instead of graph facts, and its ``_z`` and ``_gap`` forms), ``model_z`` and ``model_gap``
            (the model's log-odds standardised over the objects judged together, and its distance
            below the best of them: the model ranks ingredients well but leans towards No for all of
            them), evidence feature names
            (:data:`conceptbot.pipeline.goal_planner.evidence.FEATURES`), and products of these
            (``model*is_dish``).
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
        """Whether the model must also be asked with its own description of the object
        (``described``, ``described_z``, ``described_gap``)."""
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
