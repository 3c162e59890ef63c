"""User Request Processing (paper III-B, Algorithm 1).

1. Keywords K from the request (LLM, JSON).
2. Edges of each keyword, filtered by cosine similarity to the request embedding (R_k,fil).
3. Edges of each object, filtered by cosine similarity to the keyword embeddings (R_o,fil).
4. M_sys = robot capabilities + object properties + R_k,fil + R_o,fil + few-shot examples.
5. The LLM answers with reasoning (R_urp) and structured commands (A_urp), or a refusal.

Commands naming objects that are not in the scene (or invalid moves) are dropped and recorded.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field

from conceptbot.core.observe import SILENT, Observer
from conceptbot.core.plan import InvalidActionError, parse_action, valid_actions
from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, ChatRequest
from conceptbot.models.structured import chat_json
from conceptbot.pipeline import prompts
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.retrieval import RelationRetriever, Retrieval, edge_text
from conceptbot.pipeline.vocabulary import PERSON_DESCRIPTIONS

KEYWORDS_SCHEMA = {
    "type": "object",
    "properties": {
        "keywords": {"type": "array", "items": {"type": "string", "maxLength": 40}, "maxItems": 6}
    },
    "required": ["keywords"],
}
MAX_ENUM = 400
RESPONSE_SCHEMA = {
    "type": "object",
    "properties": {
        # Length caps keep small models from rambling past max_tokens (grammar-enforced in llama.cpp).
        "reasoning": {"type": "string", "maxLength": 400},
        "refuse": {"type": "boolean"},
        "refusal_reason": {"type": "string", "maxLength": 200},
        "commands": {"type": "array", "items": {"type": "string", "maxLength": 80}, "maxItems": 12},
    },
    "required": ["reasoning", "refuse", "refusal_reason", "commands"],
}


def response_schema(scene: Scene) -> dict:
    """The URP reply schema, with the commands limited to the scene's valid actions.

    Constrained decoding then cannot name an object that is not in the scene (small models do this
    often, e.g. "pick_and_place(hollandaise, trash can)"); very large scenes fall back to free text,
    checked by :func:`parse_action` afterwards.
    """
    options = [str(a) for a in valid_actions(scene, include_done=False)]
    schema = json.loads(json.dumps(RESPONSE_SCHEMA))
    if 0 < len(options) <= MAX_ENUM:
        schema["properties"]["commands"]["items"] = {"type": "string", "enum": options}
    return schema


@dataclass
class URPResult:
    """What URP concluded, and the module's usage (tokens, calls, wall time)."""

    keywords: list[str]
    reasoning: str
    commands: list[str]
    refused: bool
    refusal_reason: str
    rejected_commands: list[str] = field(default_factory=list)
    keyword_retrievals: dict[str, Retrieval] = field(default_factory=dict)
    object_retrievals: dict[str, Retrieval] = field(default_factory=dict)
    system_message: str = ""
    usage: Usage = field(default_factory=lambda: Usage(calls=0))


class UserRequestProcessor:
    """Runs URP.

    Args:
        llm: The LLM (labelled ``urp``).
        retriever: Relation retrieval; None for the no-knowledge-graph ablation.
        max_relations: Kept relations per keyword/object put in the system message.
    """

    def __init__(self, llm: LLM, retriever: RelationRetriever | None, max_relations: int = 8) -> None:
        self.llm = llm
        self.retriever = retriever
        self.max_relations = max_relations

    def keywords(self, request: str) -> tuple[list[str], Usage]:
        """Keywords of the request (lower case, unique, at most 6)."""
        value, response = chat_json(
            self.llm,
            ChatRequest.of(
                prompts.fill("urp_keywords_user", request=request),
                system=prompts.render("urp_keywords"),
                max_tokens=80,
            ),
            KEYWORDS_SCHEMA,
        )
        words = list(dict.fromkeys(k.strip().lower() for k in value["keywords"] if k.strip()))[:6]
        return words, response.usage

    def run(
        self,
        request: str,
        scene: Scene,
        properties: dict[str, ObjectProperties],
        observer: Observer = SILENT,
    ) -> URPResult:
        """Interpret ``request`` in ``scene`` given OPE's ``properties`` (may be empty); ``observer``
        gets a progress message before the keywords are asked for."""
        started = time.perf_counter()
        usage = Usage(calls=0)
        keyword_retrievals: dict[str, Retrieval] = {}
        object_retrievals: dict[str, Retrieval] = {}
        keywords: list[str] = []
        if self.retriever is not None:
            observer.progress("URP: keywords")
            keywords, used = self.keywords(request)
            usage = usage + used
            if keywords:
                keyword_retrievals = self.retriever.retrieve_many(keywords, [request])
                object_retrievals = self.retriever.retrieve_many(scene.names, keywords)
        relation_lines = []
        for retrievals in (keyword_retrievals, object_retrievals):
            for retrieval in retrievals.values():
                for scored in retrieval.kept[: self.max_relations]:
                    relation_lines.append(f"- {edge_text(scored.edge)}")
        relation_lines = list(dict.fromkeys(relation_lines))
        props = "\n".join(f"- {p.summary()}" for p in properties.values())
        system = prompts.render(
            "urp_system",
            properties=prompts.fill("urp_properties", properties=props) if props else "",
            relations=prompts.fill("urp_relations", relations="\n".join(relation_lines))
            if relation_lines
            else "",
            examples=prompts.render("urp_examples"),
        )
        states = "".join(prompts.fill("urp_state", name=n, state=s) for n, s in scene.entity_states.items())
        # Worded so "destinations" cannot be read as where things are now (small models did).
        user = prompts.fill(
            "urp_user",
            pickable=", ".join(scene.pickable),
            destinations=", ".join(_describe_destinations(scene.destinations)),
            states=states,
            request=request,
        )
        value, response = chat_json(
            self.llm, ChatRequest.of(user, system=system, max_tokens=400), response_schema(scene)
        )
        usage = usage + response.usage
        commands, rejected = [], []
        for text in value["commands"]:
            try:
                action = parse_action(text, scene)
            except InvalidActionError as exc:
                rejected.append(f"{text} ({exc})")
                continue
            if not action.is_done and str(action) not in commands:
                commands.append(str(action))
        return URPResult(
            keywords=keywords,
            reasoning=value["reasoning"].strip(),
            commands=commands,
            refused=bool(value["refuse"]),
            refusal_reason=value["refusal_reason"].strip(),
            rejected_commands=rejected,
            keyword_retrievals=keyword_retrievals,
            object_retrievals=object_retrievals,
            system_message=system,
            usage=usage.with_latency(time.perf_counter() - started),
        )


def _describe_destinations(destinations: list[str]) -> list[str]:
    """Destinations as shown to the LLM: people say who they are, so "user" reads as a recipient and
    not as one more place (small models otherwise pick whichever place is listed first)."""
    return [f"{d} ({who})" if (who := PERSON_DESCRIPTIONS.get(d.lower())) else d for d in destinations]
