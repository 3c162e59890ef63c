"""Bounded fuzz: mutated demo scenes through scene loading and planning.

A few hundred random JSON edits of the shipped scenes (wrong types, missing keys, odd names, huge
lists, deep nesting) go through the same path as ``conceptbot plan --scene FILE``: load the file,
then plan with ConceptBot and SayCan on a model double that answers every request validly. Every
outcome must be a plan or a :class:`ConceptBotError` (one clear message); any other exception is a
crash a user would see as a stack trace.
"""

from __future__ import annotations

import hashlib
import json
import random
from pathlib import Path
from typing import Any

from conceptbot.baselines.saycan import SayCan
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.plan import Plan
from conceptbot.core.usage import Usage
from conceptbot.models.fake import FakeEmbedder
from conceptbot.models.llm import Capabilities, ChatRequest, ChatResponse, ScoreRequest, ScoreResponse
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.retrieval import RelationRetriever
from conceptbot.scenes import demo_scene_names, load_demo_scene, resolve_scene
from tests.pipeline.fakes import DictGraph

CASES = 400
ODD_NAMES = [
    "cup, red",
    "cup (red)",
    "bob's mug",
    'a "cup"',
    "",
    "   ",
    "x" * 500,
    "mug\nplate",
    "☕ mug",
    "done()",
    "pick_and_place(a, b)",
    "user",
    "NaN",
    "🍳",
    "\x00",
    "Ünïcödé jar",
    "-",
    "a" * 81,
]
ODD_VALUES: list[Any] = [
    None,
    True,
    0,
    -1,
    1.5,
    float("nan"),
    "",
    "apple",
    [],
    {},
    [1, 2],
    {"a": None},
    [[[]]],
]
REQUESTS = ["bring me a drink", "put things away", "hand me the sharpest thing", "café ☕ (now)"]
KEYS = ["objects", "pickable_objects", "destinations", "entity_states", "detections", "name", "description"]


class SchemaFillingLLM:
    """A model double that answers any request validly: the smallest instance of a JSON schema, or
    ``done()``, and pseudo-random log-probabilities for scored options (deterministic per text)."""

    backend = "fake"
    model = "schema-filler"
    capabilities = Capabilities(scoring=True, json_schema=True, native_n=True)

    def chat(self, request: ChatRequest) -> ChatResponse:
        schema = request.schema()
        text = json.dumps(_instance(schema)) if schema else "done()"
        return ChatResponse((text,) * request.n, Usage(1, 1), self.backend, self.model, ("stop",) * request.n)

    def with_module(self, module: str) -> SchemaFillingLLM:
        return self

    def score(self, request: ScoreRequest) -> ScoreResponse:
        values = tuple(-(hashlib.sha256(o.encode()).digest()[0] / 32.0) for o in request.options)
        return ScoreResponse(values, (1,) * len(values), Usage(), self.backend, self.model)


def _instance(schema: dict[str, Any]) -> Any:
    if "enum" in schema:
        return schema["enum"][0]
    if "anyOf" in schema or "oneOf" in schema:
        return _instance((schema.get("anyOf") or schema["oneOf"])[0])
    kind = schema.get("type")
    if isinstance(kind, list):
        kind = kind[0]
    if kind == "object":
        props = schema.get("properties", {})
        return {k: _instance(props.get(k, {"type": "string"})) for k in schema.get("required", props)}
    if kind == "array":
        return [_instance(schema.get("items", {"type": "string"})) for _ in range(schema.get("minItems", 0))]
    if kind == "integer":
        return int(schema.get("minimum", 1))
    if kind == "number":
        return float(schema.get("minimum", 1))
    if kind == "boolean":
        return False
    return "x"


def _mutate(data: Any, rng: random.Random) -> Any:
    kind = rng.randrange(10)
    if not isinstance(data, dict) or kind == 0:
        return rng.choice([[data], "scene", 3, None, {"objects": data}])
    key = rng.choice(KEYS)
    if kind == 1:
        data.pop(key, None)
    elif kind == 2:
        data[key] = rng.choice(ODD_VALUES)
    elif kind in (3, 4):
        target = rng.choice(["objects", "pickable_objects", "destinations"])
        names = data.get(target) if isinstance(data.get(target), list) else []
        names.insert(rng.randrange(len(names) + 1), rng.choice(ODD_NAMES + ODD_VALUES[:6]))
        data[target] = names
    elif kind == 5:
        data[rng.choice(["objects", "pickable_objects"])] = [
            f"thing {i}" for i in range(rng.choice([99, 150, 5000]))
        ]
    elif kind == 6:
        nested: Any = "deep"
        for _ in range(rng.choice([10, 30, 900])):
            nested = [nested]
        data[key] = nested
    elif kind == 7:
        name = rng.choice(data.get("objects") or ["ghost"])
        data.setdefault("entity_states", {})
        if isinstance(data["entity_states"], dict) and isinstance(name, str):
            data["entity_states"][name] = rng.choice([*ODD_VALUES, "hot", "x" * 300])
    elif kind == 8:
        name = rng.choice(data.get("objects") or ["ghost"])
        if isinstance(name, str):
            det = {rng.choice(["confidence", "bbox_px", "size_m"]): rng.choice([*ODD_VALUES, [1, 2, 3, 4]])}
            data["detections"] = {name: det}
    else:
        data["pickable_objects"], data["destinations"] = (
            data.get("destinations"),
            data.get("pickable_objects"),
        )
    return data


def test_mutated_scenes_plan_or_fail_with_one_clear_message(tmp_path: Path) -> None:
    rng = random.Random(19)
    originals = {name: load_demo_scene(name).to_dict() for name in demo_scene_names()}
    llm = SchemaFillingLLM()
    bots = [
        ConceptBot(llm, RelationRetriever(DictGraph(), FakeEmbedder(), theta=0.1), "conceptbot"),
        ConceptBot(
            llm, RelationRetriever(DictGraph(), FakeEmbedder(), theta=0.1), "conceptbot", planner="steps"
        ),
        SayCan(llm),
    ]
    outcomes = {"plan": 0, "error": 0}
    for case in range(CASES):
        data: Any = json.loads(json.dumps(originals[rng.choice(sorted(originals))]))
        for _ in range(rng.choice([0, 1, 1, 2, 3])):
            data = _mutate(data, rng)
        path = tmp_path / f"case{case}.json"
        text = json.dumps(data) if rng.random() < 0.95 else json.dumps(data)[: rng.randrange(1, 40)]
        path.write_text(text, encoding="utf-8")
        try:
            scene = resolve_scene(str(path))
            result = bots[case % 3].plan(rng.choice([*REQUESTS, "  ", "x" * 600]), scene)
            assert isinstance(result, Plan)
            outcomes["plan"] += 1
        except ConceptBotError as exc:
            assert exc.message and "Traceback" not in exc.message
            outcomes["error"] += 1
    # Both outcomes occur: the mutations are neither all harmless nor all fatal.
    assert outcomes["plan"] > 60 and outcomes["error"] > 100, outcomes
