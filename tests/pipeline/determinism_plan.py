"""Helpers for ``test_determinism.py``, and a script that prints one plan as JSON (no timings)."""

from __future__ import annotations

import hashlib
import json

from conceptbot.core.scene import scene_from_dict
from conceptbot.core.usage import Usage
from conceptbot.models.fake import FakeEmbedder
from conceptbot.models.llm import Capabilities, ChatRequest, ChatResponse, ScoreRequest, ScoreResponse
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph

PARENTS = 20  # more than the 12 IsA parents followed per level


def graph_edges() -> dict[str, list[tuple[str, str, str]]]:
    """A "hotpot" with 20 IsA parents; only the 16th leads to a dish class ("stew")."""
    edges: dict[str, list[tuple[str, str, str]]] = {
        "hotpot": [("hotpot", "IsA", f"kind{i:02d}") for i in range(PARENTS)],
    }
    edges["kind15"] = [("kind15", "IsA", "stew")]
    return edges


class HashLLM:
    """Scores each option by a stable hash of the prompt and the option (no sampling, no state)."""

    backend = "hash"
    model = "hash"
    capabilities = Capabilities(scoring=True, exact_scoring=True, json_schema=True)

    def with_module(self, module: str) -> HashLLM:
        return self

    def chat(self, request: ChatRequest) -> ChatResponse:
        # The goal planner without OPE chats once: the request said plainly (pipeline/goal/aided.py).
        assert "Plain:" in request.messages[-1].content, "without OPE it only restates and scores"
        return ChatResponse(("I would like a hotpot.",), Usage(), self.backend, self.model)

    def score(self, request: ScoreRequest) -> ScoreResponse:
        prompt = request.prompt or json.dumps([[m.role, m.content] for m in request.messages or ()])
        values = tuple(
            -int(hashlib.sha256(f"{prompt}|{o}".encode()).hexdigest()[:6], 16) / 2**24 * 6
            for o in request.options
        )
        return ScoreResponse(values, (1,) * len(values), Usage(), self.backend, self.model)


def main() -> None:
    graph = DictGraph(graph_edges())
    bot = ConceptBot(HashLLM(), RelationRetriever(graph, FakeEmbedder(), theta=0.1), "urp", planner="goal")
    scene = scene_from_dict(
        {"pickable_objects": ["carrot", "onion", "sponge", "book"], "destinations": ["pot", "shelf"]}
    )
    plan = bot.plan("I would like a hotpot", scene)
    data = plan.to_dict()
    data.pop("usage")
    goal = data["trace"]["goal"]
    data["dish_reached"] = any(t.get("dish") for t in goal.get("targets", []))
    print(json.dumps(data, sort_keys=True))


if __name__ == "__main__":
    main()
