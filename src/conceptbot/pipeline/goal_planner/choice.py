"""Choosing among the scene's objects: one ranking of every candidate for a target taking a few.

Three readings per candidate: ``names`` (domain-conditional PMI of naming it), ``embed`` (cosine of
request and name) and ``use`` (cosine with what the graph says it is for).
The ranking is their standardised weighted sum (``choice_weights.json``); a softmax gives P(the one).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

import numpy as np

from conceptbot.core.usage import Usage
from conceptbot.models.embedder import Embedder, cosine_matrix
from conceptbot.models.llm import Message, ScoreRequest
from conceptbot.pipeline import prompts
from conceptbot.pipeline.goal_planner.decide import Decider, Judgement
from conceptbot.pipeline.goal_planner.evidence import Evidence

WEIGHTS = "choice_weights.json"
NEUTRAL_REQUEST = "Please help me."  # the request the name ranking is calibrated against
READINGS = ("names", "embed", "use")


@dataclass(frozen=True)
class ChoiceWeights:
    """The weight of each standardised reading, and the softmax's scale.

    Attributes:
        weights: Reading name (one of :data:`READINGS`) -> weight.
        sharpness: The scale of the which-one softmax over the weighted sums.
    """

    weights: Mapping[str, float]
    sharpness: float

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ChoiceWeights:
        """Read the JSON form (``{"weights": {...}, "sharpness": s}``)."""
        unknown = set(data["weights"]) - set(READINGS)
        if unknown:
            raise ValueError(f"unknown choice readings {sorted(unknown)} (use {', '.join(READINGS)})")
        return cls(dict(data["weights"]), float(data["sharpness"]))


@cache
def shipped_weights(with_graph: bool) -> ChoiceWeights:
    """The shipped weights for a system with or without the graph."""
    text = resources.files("conceptbot.pipeline").joinpath(WEIGHTS).read_text(encoding="utf-8")
    return ChoiceWeights.from_dict(json.loads(text)["graph" if with_graph else "nograph"])


def similarities(embedder: Embedder, request: str, objects: Sequence[str]) -> dict[str, float]:
    """The cosine between ``request`` and "a <object>" for each object."""
    if not objects:
        return {}
    vectors = np.asarray(embedder.embed([request, *(f"a {name}" for name in objects)]))
    found = cosine_matrix(vectors[:1], vectors[1:])[0]
    return {name: float(value) for name, value in zip(objects, found, strict=True)}


def standardised(values: Mapping[str, float]) -> dict[str, float]:
    """Each value as standard deviations from the mean of the known ones (0 for a missing one)."""
    known = [v for v in values.values() if math.isfinite(v)]
    if len(known) < 2:
        return dict.fromkeys(values, 0.0)
    mean = sum(known) / len(known)
    spread = math.sqrt(sum((v - mean) ** 2 for v in known) / len(known)) or 1.0
    return {o: (v - mean) / spread if math.isfinite(v) else 0.0 for o, v in values.items()}


def softmax(scores: Mapping[str, float], sharpness: float) -> dict[str, float]:
    """P(each is the one) from the ranking, scaled by ``sharpness``."""
    top = max(scores.values())
    raw = {o: math.exp(sharpness * (v - top)) for o, v in scores.items()}
    total = sum(raw.values())
    return {o: v / total for o, v in raw.items()}


class ObjectChooser:
    """Ranks every candidate for a target that takes one or a few objects (see the module docstring).

    Args:
        decider: Asks the name ranking; its facts give what the graph states objects are for.
        embedder: The sentence embedder, or None (the ``embed`` reading is then missing).
        weights: The fitted weights.
    """

    def __init__(self, decider: Decider, embedder: Embedder | None, weights: ChoiceWeights) -> None:
        self.decider = decider
        self.embedder = embedder
        self.weights = weights

    def name_scores(
        self, request: str, move: str, objects: Sequence[str]
    ) -> tuple[dict[str, float], Usage, str]:
        """Per object, the log-probability of its name for ``request`` minus that for a neutral one.

        Also returns the usage and how the backend scored the options.

        Args:
            move: What the robot would do with the object, without it ("give to the user").
        """
        usage = Usage(calls=0)
        found = []
        method = ""
        for said in (request, NEUTRAL_REQUEST):
            user = prompts.render("pick_user", request=said, objects=", ".join(objects), move=move)
            messages = (Message("system", prompts.render("pick_system")), Message("user", user))
            scored = self.decider.llm.score(
                ScoreRequest(options=tuple(objects), messages=messages, assistant_prefix="The ")
            )
            usage, method = usage + scored.usage, scored.method
            found.append(scored.logprobs)
        scores = {o: lp - neutral for o, lp, neutral in zip(objects, found[0], found[1], strict=True)}
        return scores, usage, method

    def readings(
        self, request: str, move: str, objects: Sequence[str]
    ) -> tuple[dict[str, dict[str, float]], dict[str, str], Usage, str]:
        """Each reading per object (NaN where missing), what the graph says each is for, usage, method.

        Args:
            request: What the person said (or the part of it this target is for).
            move: The move without its object ("give to the user").
            objects: The candidates.
        """
        names, usage, method = self.name_scores(request, move, objects)
        embed = similarities(self.embedder, request, objects) if self.embedder is not None else {}
        uses = self.decider.facts.uses(objects, request)
        found = {
            "names": names,
            "embed": {o: embed.get(o, math.nan) for o in objects},
            "use": {o: uses[o][0] for o in objects},
        }
        return found, {o: uses[o][1] for o in objects}, usage, method

    def rank(self, request: str, move: str, objects: Sequence[str]) -> tuple[list[Judgement], Usage]:
        """The candidates as judgements: ``score`` the weighted sum, ``p_one`` P(it is the one)."""
        started = time.perf_counter()
        found, stated, usage, method = self.readings(request, move, objects)
        total = dict.fromkeys(objects, 0.0)
        for reading, weight in self.weights.weights.items():
            for obj, z in standardised(found[reading]).items():
                total[obj] += weight * z
        chances = softmax(total, self.weights.sharpness)
        judgements = []
        for obj in objects:
            features = {k: round(v[obj], 4) for k, v in found.items() if math.isfinite(v[obj])}
            said = (f"use {found['use'][obj]:.2f}: {stated[obj]}",) if stated[obj] else ()
            evidence = Evidence(obj, request, features, said)
            judgements.append(
                Judgement(
                    obj, request, chances[obj], total[obj], (), method, evidence=evidence, p_one=chances[obj]
                )
            )
        return judgements, usage.with_latency(time.perf_counter() - started)
