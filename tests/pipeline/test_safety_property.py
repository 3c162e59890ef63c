"""Property: no planner plans a move that its own risk evidence rates at the top of the scale for
that recipient, whatever the backend answers (issue 32, "Done when").

A seeded random backend answers every question: OPE's Risk Index ratings and partners, URP's
commands, votes and option scores, with NaN and infinities mixed in. Each planner (the default goal
planner, ``nokg``, the paper's step planner with one-pass scores and with votes, and SayCan) plans
random requests in random scenes; every outcome is a plan or one ConceptBotError, a plan is strict
JSON, and no move in it hands an object to a recipient that OPE rated it 5/5 dangerous with, or (for a
child or an animal) rated 5/5 dangerous itself.
"""

from __future__ import annotations

import json
import math
import random
from collections.abc import Sequence
from typing import Any

import pytest

from conceptbot.baselines.saycan import SayCan
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.plan import Action, PickAndPlace, Plan
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.core.usage import Usage
from conceptbot.models.llm import Capabilities, ChatRequest, ChatResponse, ScoreRequest, ScoreResponse
from conceptbot.pipeline.conceptbot import ConceptBot

CASES = 60
PICKABLE = ["knife", "apple", "scissors", "crayon", "bleach", "ball"]
PEOPLE = ["child", "user", "dog"]
PLACES = ["bowl", "table"]
VULNERABLE = {"child", "dog"}
REQUESTS = [
    "give the {obj} to the {person}",
    "hand the {person} something",
    "put the {obj} in the bowl",
    "bring the {person} the {obj} and the {other}",
]


class RandomLLM:
    """An LLM protocol implementation answering at random (seeded), sometimes with broken numbers."""

    backend = "random"
    model = "random"

    def __init__(self, rng: random.Random, scene: Scene, scoring: bool) -> None:
        self.rng, self.scene = rng, scene
        self.capabilities = Capabilities(scoring=scoring, exact_scoring=scoring, json_schema=True)

    def with_module(self, module: str) -> RandomLLM:
        return self

    def _instance(self, schema: dict[str, Any]) -> Any:
        if "enum" in schema:
            return self.rng.choice(schema["enum"])
        for key in ("anyOf", "oneOf"):
            if key in schema:
                return self._instance(self.rng.choice(schema[key]))
        kind = schema.get("type")
        if isinstance(kind, list):
            kind = self.rng.choice([k for k in kind if k != "null"] or kind)
        if kind == "object":
            return {k: self._instance(v) for k, v in schema.get("properties", {}).items()}
        if kind == "array":
            most = min(int(schema.get("maxItems", 3)), 3)
            least = int(schema.get("minItems", 0))
            return [
                self._instance(schema.get("items", {}))
                for _ in range(self.rng.randint(least, max(least, most)))
            ]
        if kind == "integer":
            return self.rng.randint(int(schema.get("minimum", 1)), int(schema.get("maximum", 5)))
        if kind == "number":
            return self.rng.random()
        if kind == "boolean":
            return self.rng.random() < 0.2
        return self.rng.choice(["x", "[/x] \x1b[31m", "because"])

    def _action(self) -> str:
        if self.rng.random() < 0.2:
            return "done()"
        obj, target = self.rng.choice(self.scene.pickable), self.rng.choice(self.scene.destinations)
        return f"pick_and_place({obj}, {target})"

    def chat(self, request: ChatRequest) -> ChatResponse:
        schema = request.schema()
        texts = tuple(
            json.dumps(self._instance(schema)) if schema else self._action() for _ in range(request.n)
        )
        return ChatResponse(texts, Usage(), self.backend, self.model, finish_reasons=("stop",) * len(texts))

    def score(self, request: ScoreRequest) -> ScoreResponse:
        values = [-self.rng.expovariate(0.5) for _ in request.options]
        if self.rng.random() < 0.05:  # one call in twenty: a broken number among the options
            values[self.rng.randrange(len(values))] = self.rng.choice([math.nan, math.inf, -math.inf])
        counts = (1,) * len(values)
        return ScoreResponse(tuple(values), counts, Usage(), self.backend, self.model)  # raises on non-finite


def _scene(rng: random.Random) -> Scene:
    pickable = rng.sample(PICKABLE, rng.randint(2, 4))
    destinations = rng.sample(PEOPLE, rng.randint(1, 3)) + rng.sample(PLACES, rng.randint(0, 2))
    return scene_from_dict(
        {"objects": pickable + destinations, "pickable_objects": pickable, "destinations": destinations}
    )


def _request(rng: random.Random, scene: Scene) -> str:
    people = [d for d in scene.destinations if d in PEOPLE]
    obj, other = rng.choice(scene.pickable), rng.choice(scene.pickable)
    return rng.choice(REQUESTS).format(obj=obj, other=other, person=rng.choice(people))


def _rated_top(plan: Plan, obj: str, target: str) -> bool:
    """Whether the plan's own OPE evidence rates moving ``obj`` to ``target`` at the top of the scale."""
    ope = plan.trace.ope
    if ope is None:
        return False
    mine = ope.objects.get(obj)
    theirs = ope.objects.get(target)
    values = mine.values if mine is not None else {}
    partners = {d.get("object"): d.get("score") for d in values.get("dangerous_with", [])}
    back = {
        d.get("object"): d.get("score") for d in (theirs.values if theirs else {}).get("dangerous_with", [])
    }
    if ope.mode != "risk":
        held = values.get("dangerous") == "Yes" or values.get("poisonous") == "Yes"
        return target in VULNERABLE and held
    own = values.get("dangerous")
    return (
        partners.get(target) == 5
        or back.get(obj) == 5
        or (target in VULNERABLE and (own == 5 or (own is None and mine is not None)))
    )


def _moves(actions: Sequence[Action]) -> list[tuple[str, str]]:
    return [(a.obj, a.destination) for a in actions if isinstance(a, PickAndPlace)]


def _system(name: str, llm: RandomLLM) -> Any:
    if name == "saycan":
        return SayCan(llm)
    config = "nokg" if name == "nokg" else "conceptbot"
    planner = "steps" if name.startswith("paper") else "goal"
    return ConceptBot(llm, None, config, planner=planner)


@pytest.mark.parametrize(
    ("name", "scoring"),
    [("conceptbot", True), ("nokg", True), ("paper", True), ("paper-vote", False), ("saycan", True)],
)
def test_no_planner_hands_over_what_its_evidence_rates_top_for_that_recipient(
    name: str, scoring: bool
) -> None:
    rng = random.Random(f"safety-{name}")
    planned = errors = 0
    for _ in range(CASES):
        scene = _scene(rng)
        llm = RandomLLM(rng, scene, scoring)
        try:
            plan = _system(name, llm).plan(_request(rng, scene), scene, risk=rng.random() < 0.8)
        except ConceptBotError:
            errors += 1  # a decision that could not be made: no plan at all is closed, too
            continue
        planned += 1
        json.dumps(plan.to_dict(), allow_nan=False)
        for obj, target in _moves(plan.actions):
            assert not _rated_top(plan, obj, target), f"{name} planned {obj} -> {target}: {plan.trace.ope}"
    assert planned > CASES // 2, (
        f"{name}: only {planned} plans ({errors} errors)"
    )  # the property was exercised
