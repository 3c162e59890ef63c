"""Object Properties Extraction (paper III-A): per object, knowledge-graph relations filtered by
cosine similarity to target properties, then the LLM assigns properties.

Three variants (see :mod:`conceptbot.pipeline.modes`): Yes/No ``properties`` (fragile, hold liquid,
dangerous, safe, deformable, stable, poisonous), the ``risk`` Risk Index (danger 1-5 and
DangerousWith scores 1-5, the appendix's criteria), and ``materials``. Results are cached per
(object, mode, scene objects for the Risk Index, model, graph, theta) in the cache database.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from conceptbot.core.usage import Usage
from conceptbot.knowledge.base import TARGET_PROPERTIES
from conceptbot.models.cache import CacheStore
from conceptbot.models.llm import LLM, ChatRequest
from conceptbot.models.structured import chat_json
from conceptbot.pipeline import modes, prompts
from conceptbot.pipeline.retrieval import RelationRetriever, Retrieval, edge_text

Progress = Callable[[str], None]
YES_NO = {"type": "string", "enum": ["Yes", "No"]}
PROPERTY_NAMES = ("fragile", "hold_liquid", "dangerous", "safe", "deformable", "stable", "poisonous")
MATERIALS = [
    "glass",
    "plastic",
    "paper",
    "cardboard",
    "wax",
    "metal",
    "aluminium",
    "wood",
    "ceramic",
    "fabric",
    "food",
    "plant",
    "other",
]
MATERIAL_TARGETS = ("glass", "plastic", "paper", "cardboard", "wax", "metal", "wood", "made of")
RISK_TARGETS = ("dangerous", "fragile", "poisonous", "sharp", "hot", "toxic", "flammable", "safe")

SCHEMAS: dict[str, dict[str, Any]] = {
    modes.PROPERTIES: {
        "type": "object",
        "properties": {"object": {"type": "string"}, **{p: YES_NO for p in PROPERTY_NAMES}},
        "required": ["object", *PROPERTY_NAMES],
    },
    modes.RISK: {
        "type": "object",
        "properties": {
            "object": {"type": "string"},
            "dangerous": {"type": "integer", "enum": [1, 2, 3, 4, 5]},
            "dangerous_with": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "object": {"type": "string"},
                        "score": {"type": "integer", "enum": [1, 2, 3, 4, 5]},
                    },
                    "required": ["object", "score"],
                },
            },
            "reason": {"type": "string", "maxLength": 160},
        },
        "required": ["object", "dangerous", "dangerous_with", "reason"],
    },
    modes.MATERIALS: {
        "type": "object",
        "properties": {
            "object": {"type": "string"},
            "materials": {"type": "array", "items": {"type": "string", "enum": MATERIALS}},
            "single_material": {"type": "boolean"},
            "reason": {"type": "string", "maxLength": 160},
        },
        "required": ["object", "materials", "single_material", "reason"],
    },
}


def schema_for(mode: str, name: str, objects: list[str]) -> dict[str, Any]:
    """The reply schema; for the Risk Index, interaction partners are limited to the scene's other
    objects (an enum, at most one entry each), so constrained decoding cannot invent objects or
    repeat one until the token budget runs out (small models do both)."""
    schema = json.loads(json.dumps(SCHEMAS[mode]))
    others = [o for o in objects if o != name]
    if mode == modes.RISK:
        items = schema["properties"]["dangerous_with"]
        items["maxItems"] = len(others)
        if others:
            items["items"]["properties"]["object"] = {"type": "string", "enum": others}
    return schema


def targets_for(mode: str) -> tuple[str, ...]:
    """The target texts relations are filtered against in a mode."""
    return {modes.RISK: RISK_TARGETS, modes.MATERIALS: MATERIAL_TARGETS}.get(mode, TARGET_PROPERTIES)


@dataclass
class ObjectProperties:
    """What OPE concluded about one object (``values`` holds the mode's JSON fields)."""

    name: str
    mode: str
    values: dict[str, Any]
    relations: list[str] = field(default_factory=list)
    cached: bool = False

    def notable(self) -> bool:
        """Whether the object has something worth telling the planner (a risk, a material, or a
        property other than the "safe"/"stable" that hold for most things)."""
        if self.mode == modes.RISK:
            return int(self.values.get("dangerous", 1)) > 1 or bool(self.values.get("dangerous_with"))
        if self.mode == modes.MATERIALS:
            return True
        return any(self.values.get(p) == "Yes" for p in PROPERTY_NAMES if p not in ("safe", "stable"))

    def summary(self) -> str:
        """One line for prompts: ``knife: fragile No, dangerous Yes, ...``."""
        if self.mode == modes.RISK:
            others = ", ".join(f"{d['object']} ({d['score']})" for d in self.values.get("dangerous_with", []))
            return f"{self.name}: danger {self.values.get('dangerous')}/5" + (
                f", dangerous with {others}" if others else ""
            )
        if self.mode == modes.MATERIALS:
            single = "single material" if self.values.get("single_material") else "mixed materials"
            return (
                f"{self.name}: made of {', '.join(self.values.get('materials', [])) or 'unknown'} ({single})"
            )
        # Only the properties that hold: half the tokens of "fragile No, hold liquid No, ..." and
        # the prompt of a 25-object scene stays short enough to evaluate quickly on a CPU.
        held = [p.replace("_", " ") for p in PROPERTY_NAMES if self.values.get(p) == "Yes"]
        return f"{self.name}: {', '.join(held) if held else 'none of the listed properties'}"


@dataclass(frozen=True)
class OPEResult:
    """What OPE concluded about a set of objects.

    Attributes:
        properties: Per object, its properties in the run's mode.
        retrievals: Per object, the relations retrieved and filtered (empty without a graph).
        usage: The module's tokens, calls and wall time.
    """

    properties: dict[str, ObjectProperties]
    retrievals: dict[str, Retrieval]
    usage: Usage


class ObjectPropertiesExtractor:
    """Runs OPE for a scene.

    Args:
        llm: The LLM (already behind the cache/log, labelled ``ope``).
        retriever: Relation retrieval + cosine filter; None for the no-knowledge-graph ablation.
        store: Cache database for per-object results, or None.
        graph_version: Identifies the graph's contents in cache keys.
        max_relations: Kept relations shown to the LLM per object.
    """

    def __init__(
        self,
        llm: LLM,
        retriever: RelationRetriever | None,
        store: CacheStore | None = None,
        graph_version: str = "",
        max_relations: int = 20,
    ) -> None:
        self.llm = llm
        self.retriever = retriever
        self.store = store
        self.graph_version = graph_version
        self.max_relations = max_relations

    def _key(self, name: str, mode: str, context: str) -> str:
        # Everything the answer depends on: the prompt text and the retrieval settings included, so
        # editing a prompt or the relation list never serves a stale answer.
        retrieval = [self.retriever.theta, list(self.retriever.relations)] if self.retriever else None
        payload = [
            name,
            mode,
            context,
            self.llm.backend,
            self.llm.model,
            self.graph_version,
            retrieval,
            prompts.render(f"ope_{mode}"),
            self.max_relations,
        ]
        return hashlib.sha256(json.dumps(payload).encode()).hexdigest()

    def run(
        self,
        objects: list[str],
        mode: str,
        request: str = "",
        progress: Progress | None = None,
        scene_objects: list[str] | None = None,
    ) -> OPEResult:
        """Properties for every object, the retrievals behind them, and the module's usage.

        ``scene_objects`` (default: ``objects``) are the objects the Risk Index rates interactions
        with, when only some of a scene's objects are asked about.
        """
        scene_objects = list(scene_objects or objects)
        started = time.perf_counter()
        usage = Usage(calls=0)
        retrievals = self.retriever.retrieve_many(objects, targets_for(mode)) if self.retriever else {}
        results: dict[str, ObjectProperties] = {}
        # The Risk Index judges interactions, so it depends on the other objects and the request.
        context = json.dumps([sorted(scene_objects), request]) if mode == modes.RISK else ""
        for name in objects:
            kept = (
                [edge_text(s.edge) for s in retrievals[name].kept[: self.max_relations]] if retrievals else []
            )
            key = self._key(name, mode, context)
            cached = self.store.get_value("ope", key) if self.store else None
            if cached is not None:
                results[name] = ObjectProperties(name, mode, cached, kept, cached=True)
                continue
            relations = "\n".join(f"- {r}" for r in kept) or "- (none)"
            user = f"Object: {name}\nRelations:\n{relations}\n"
            if mode == modes.RISK:
                others = ", ".join(o for o in scene_objects if o != name)
                user += f"Other objects in the scene: {others}\nUser request: {request}\n"
            request_obj = ChatRequest.of(user, system=prompts.render(f"ope_{mode}"), max_tokens=200)
            value, response = chat_json(self.llm, request_obj, schema_for(mode, name, scene_objects))
            value["object"] = name  # the model sometimes rewrites the name; the scene's name is the truth
            if mode == modes.RISK:
                value["dangerous_with"] = _known_partners(value["dangerous_with"], scene_objects, name)
            usage = usage + response.usage
            if self.store:
                self.store.put_value("ope", key, value)
            results[name] = ObjectProperties(name, mode, value, kept)
        return OPEResult(results, retrievals, usage.with_latency(time.perf_counter() - started))


def _known_partners(items: list[dict[str, Any]], objects: list[str], name: str) -> list[dict[str, Any]]:
    """Interaction scores for objects of the scene only, with the scene's spelling."""
    by_lower = {o.lower(): o for o in objects}
    kept = []
    for item in items:
        other = by_lower.get(str(item["object"]).strip().lower())
        if other is not None and other != name:
            kept.append({"object": other, "score": int(item["score"])})
    return kept
