"""Small deterministic stand-ins for pipeline tests: a dict knowledge graph, JSON reply helpers and
an observer that records what a plan reports."""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from conceptbot.core.scene import scene_from_dict
from conceptbot.knowledge.base import ConceptEdges, Edge
from conceptbot.knowledge.normalize import lookup

EDGES = {
    "knife": [
        ("knife", "IsA", "sharp object"),
        ("knife", "HasProperty", "dangerous"),
        ("knife", "UsedFor", "cut"),
    ],
    "sponge": [("sponge", "UsedFor", "wipe spill"), ("sponge", "HasProperty", "soft")],
    "chips": [("chips", "IsA", "snack")],
    "spill": [("sponge", "UsedFor", "wipe spill"), ("spill", "RelatedTo", "liquid")],
}
#: What the tests' places are: a graph that knows its destinations' kinds decides who they are
#: itself (pipeline/recipients.py); the model is asked only about a name the graph does not know.
PLACES = {
    "table": [("table", "IsA", "furniture")],
    "bowl": [("bowl", "IsA", "container")],
}
EDGES.update(PLACES)
WITH_PLACES = EDGES


class DictGraph:
    """A KnowledgeGraph over a dict of edges (normalised look-up like the real stores)."""

    name = "dict"
    version = "test"

    def __init__(self, edges: dict[str, list[tuple[str, str, str]]] | None = None) -> None:
        self.data = edges if edges is not None else EDGES
        self.asked: list[str] = []

    def _fetch(self, concept: str, relations: Sequence[str] | None, limit: int) -> list[Edge]:
        self.asked.append(concept)
        rows = [Edge(h, r, t, 1.0, "test") for h, r, t in self.data.get(concept, [])]
        return [e for e in rows if relations is None or e.relation in relations][:limit]

    def edges(self, concept: str, relations: Sequence[str] | None = None, limit: int = 100) -> ConceptEdges:
        return lookup(concept, self._fetch, relations, limit)


def spill_scene():
    """The paper's spill example, small and with sizes."""
    return scene_from_dict(
        {
            "name": "spill",
            "objects": ["chips", "sponge", "knife", "table", "user"],
            "pickable_objects": ["chips", "sponge", "knife"],
            "destinations": ["table", "user"],
            "detections": {
                "knife": {"confidence": 0.9, "size_m": [0.02, 0.2, 0.02]},
                "sponge": {"size_m": [0.07, 0.1, 0.03]},
                "chips": {"size_m": [0.05, 0.15, 0.2]},
            },
        }
    )


def properties_reply(**overrides: str) -> str:
    """An OPE properties JSON reply (all No, safe Yes, stable Yes unless overridden)."""
    values = {
        "object": "x",
        "fragile": "No",
        "hold_liquid": "No",
        "dangerous": "No",
        "safe": "Yes",
        "deformable": "No",
        "stable": "Yes",
        "poisonous": "No",
    }
    values.update(overrides)
    return json.dumps(values)


def urp_reply(commands: list[str], reasoning: str = "because", refuse: bool = False, why: str = "") -> str:
    """A URP JSON reply."""
    return json.dumps({"reasoning": reasoning, "refuse": refuse, "refusal_reason": why, "commands": commands})


def risk_reply(danger: int = 1, partners: list[tuple[str, int]] | None = None, reason: str = "r") -> str:
    """An OPE Risk Index JSON reply."""
    return json.dumps(
        {
            "object": "x",
            "dangerous": danger,
            "reason": reason,
            "dangerous_with": [{"object": o, "score": sc} for o, sc in (partners or [])],
        }
    )


class Recorder:
    """An observer that keeps what it is told, in order: ``("progress", message)`` and
    ``("event", name, data)``."""

    def __init__(self) -> None:
        self.seen: list[tuple[Any, ...]] = []

    def progress(self, message: str) -> None:
        self.seen.append(("progress", message))

    def event(self, name: str, part: Any) -> None:
        self.seen.append(("event", name, part.to_dict()))  # a test is an edge too: it reads JSON

    def names(self) -> list[str]:
        """Each progress message, and each event as ``event:NAME``, in order."""
        return [entry[1] if entry[0] == "progress" else f"event:{entry[1]}" for entry in self.seen]
