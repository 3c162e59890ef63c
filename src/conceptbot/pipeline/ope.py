"""Object Properties Extraction (paper III-A): per object, knowledge-graph relations filtered by
cosine similarity to target properties, then the LLM assigns properties.

Three variants, one :class:`~conceptbot.pipeline.modes.OPEMode` each (prompt, schema, targets,
typed answer): Yes/No ``properties`` (fragile, hold liquid, dangerous, safe, deformable, stable,
poisonous), the ``risk`` Risk Index (danger 1-5 and DangerousWith scores 1-5, the appendix's
criteria), and ``materials``. Results are cached per (object, mode, scene objects for the Risk
Index, model, graph, theta) in the cache database; without a store (``--no-cache``) nothing is
read or written. A cache that fails mid-run is a miss, or a skipped write, with a warning: never a
lost answer.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from typing import Any

from conceptbot.core.usage import Usage
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.llm import LLM, ChatRequest
from conceptbot.models.structured import chat_json
from conceptbot.pipeline import modes
from conceptbot.pipeline.modes import OPEMode
from conceptbot.pipeline.ope_answers import OPEAnswer
from conceptbot.pipeline.retrieval import RelationRetriever, Retrieval, edge_text


@dataclass
class ObjectProperties:
    """What OPE concluded about one object.

    Attributes:
        name: The object, as the scene names it.
        mode: The mode's name (:data:`~conceptbot.pipeline.modes.MODES`).
        values: The answer as JSON, exactly as the model gave it (with the scene's names) and as
            the cache and the trace hold it. Read it through :attr:`answer`.
        relations: The relations shown to the model.
        cached: Whether the answer came from the cache.
        answer: The typed answer (:mod:`conceptbot.pipeline.ope_answers`), read from ``values``.
    """

    name: str
    mode: str
    values: dict[str, Any]
    relations: list[str] = field(default_factory=list)
    cached: bool = False
    answer: OPEAnswer = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.answer = modes.get(self.mode).parse(self.values)

    def notable(self) -> bool:
        """Whether the object has something worth telling the planner (a risk, a material, or a
        property other than the "safe"/"stable" that hold for most things)."""
        return self.answer.notable()

    def summary(self) -> str:
        """One line for prompts: ``knife: dangerous, safe``."""
        return self.answer.summary(self.name)


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
        store: Cache database for per-object results, or None to neither read nor write them.
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

    def _key(self, name: str, mode: OPEMode, context: str, kept: list[str]) -> str:
        # Everything the answer depends on: the prompt text, the retrieval settings and the facts
        # put in the prompt included, so editing a prompt, the relation list or how the graph is
        # read (knowledge/normalize.py) never serves a stale answer. (A key missed for unchanged
        # facts costs little: the model's reply to the same prompt is in the answer cache.)
        retrieval = [self.retriever.theta, list(self.retriever.relations)] if self.retriever else None
        payload = [
            name,
            mode.name,
            context,
            self.llm.backend,
            self.llm.model,
            self.graph_version,
            retrieval,
            mode.system_prompt(),
            self.max_relations,
            kept,
        ]
        return hashlib.sha256(json.dumps(payload).encode()).hexdigest()

    def run(
        self,
        objects: list[str],
        mode: str | OPEMode,
        request: str = "",
        scene_objects: list[str] | None = None,
    ) -> OPEResult:
        """Properties for every object, the retrievals behind them, and the module's usage.

        ``mode`` is a mode or its name (:data:`~conceptbot.pipeline.modes.MODES`). ``scene_objects``
        (default: ``objects``) are the objects the Risk Index rates interactions with, when only
        some of a scene's objects are asked about.

        Raises:
            ValueError: ``mode`` names no mode.
        """
        kind = modes.get(mode)
        scene_objects = list(scene_objects or objects)
        started = time.perf_counter()
        usage = Usage(calls=0)
        retrievals = self.retriever.retrieve_many(objects, kind.targets) if self.retriever else {}
        results: dict[str, ObjectProperties] = {}
        context = kind.context(scene_objects, request)
        for name in objects:
            kept = (
                [edge_text(s.edge) for s in retrievals[name].kept[: self.max_relations]] if retrievals else []
            )
            key = self._key(name, kind, context, kept)
            cached = (
                self.store.attempt("read the cache", self.store.get_value, "ope", key) if self.store else None
            )
            if cached is not None:
                results[name] = ObjectProperties(name, kind.name, cached, kept, cached=True)
                continue
            user = kind.user_message(name, kept, scene_objects, request)
            request_obj = ChatRequest.of(
                user, system=kind.system_prompt(), max_tokens=kind.reply_tokens(scene_objects)
            )
            value, response = chat_json(self.llm, request_obj, kind.reply_schema(name, scene_objects))
            value = kind.clean(value, name, scene_objects)
            usage = usage + response.usage
            if self.store:
                self.store.attempt("write the cache", self.store.put_value, "ope", key, value)
            results[name] = ObjectProperties(name, kind.name, value, kept)
        return OPEResult(results, retrievals, usage.with_latency(time.perf_counter() - started))
