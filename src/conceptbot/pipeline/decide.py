"""Per-object decisions: does this object fit this description? Is this move dangerous?

Each decision is one short question answered Yes or No, scored by the log-probabilities of the two
answers (one forward pass; no sampling), with the object's own graph facts in the question. The
facts are filtered against the description (not only against the request), and include what the
graph says about the object's parents (``IsA``): the offline graph has "green hellebore IsA
hellebore" and "hellebore IsA poisonous plant" but never joins them.

Calibration (Zhao et al. 2021, "Calibrate before use"): small models lean towards one answer
whatever the object. The same question is asked once about a content-free object ("the object",
no facts); a decision's score is its log-odds of Yes minus that prior's, so 0 means "no more
likely than for an unknown object". ``threshold`` applies to this calibrated score.
"""

from __future__ import annotations

import itertools
import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline import prompts
from conceptbot.pipeline.retrieval import RelationRetriever, edge_text

ANSWERS = ("Yes", "No")
CONTENT_FREE = "object"
_STOP = {
    "a", "an", "the", "of", "to", "for", "and", "or", "with", "that", "is", "are", "be", "made", "only",
    "something", "thing", "things", "one", "some", "all", "any", "every", "my", "me", "you", "it", "in",
    "on", "into", "can", "could", "would", "i", "we", "please", "entirely", "more", "than", "from",
}  # fmt: skip


@dataclass(frozen=True)
class Judgement:
    """One yes/no decision about one object.

    Attributes:
        subject: The object (or the move, for risk decisions).
        question: What was decided ("a fruit", or the move).
        p_yes: P(Yes) normalised over Yes/No.
        score: Calibrated log-odds of Yes (0: no more likely than for a content-free object).
        facts: The graph facts put in the question.
    """

    subject: str
    question: str
    p_yes: float
    score: float
    facts: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace."""
        return {
            "object": self.subject,
            "p_yes": round(self.p_yes, 4),
            "score": round(self.score, 3),
            "facts": list(self.facts),
        }


def _log_odds(logprobs: Sequence[float]) -> tuple[float, float]:
    yes, no = logprobs
    top = max(yes, no)
    p_yes = math.exp(yes - top) / (math.exp(yes - top) + math.exp(no - top))
    return p_yes, yes - no


def content_words(text: str) -> list[str]:
    """The words and two-word phrases of ``text`` worth looking up in the graph, longest first."""
    words = [w for w in re.findall(r"[a-z][a-z'-]+", text.lower()) if w not in _STOP and len(w) > 2]
    pairs = [f"{a} {b}" for a, b in itertools.pairwise(words)]
    return list(dict.fromkeys(pairs + words))


@dataclass
class FactFinder:
    """Graph facts about objects and descriptions, filtered against what is being decided.

    Args:
        retriever: Relation retrieval with the cosine filter (None: no facts, the no-graph ablation).
        per_object: Facts about the object itself shown per question.
        inherited: Facts about the object's ``IsA`` parents shown per question.
        per_context: Facts about the description's own words (shared by every object's question).
    """

    retriever: RelationRetriever | None
    per_object: int = 4
    inherited: int = 2
    per_context: int = 3
    _parents: dict[str, list[str]] = field(default_factory=dict)

    def context(self, what: str, request: str) -> tuple[str, ...]:
        """Facts about the description's words ("hollandaise means eggs and butter with lemon juice")."""
        if self.retriever is None:
            return ()
        words = content_words(what)
        if not words:
            return ()
        found = self.retriever.retrieve_many(words, [what, request])
        kept = sorted(
            (s for r in found.values() if r.matched for s in r.kept if s.edge.relation != "RelatedTo"),
            key=lambda s: -s.similarity,
        )
        return tuple(dict.fromkeys(edge_text(s.edge) for s in kept))[: self.per_context]

    def about(self, objects: Sequence[str], targets: Sequence[str]) -> dict[str, tuple[str, ...]]:
        """Per object: its kept facts, then kept facts of its IsA parents, most similar first."""
        if self.retriever is None:
            return {o: () for o in objects}
        own = self.retriever.retrieve_many(objects, targets)
        parents: dict[str, list[str]] = {}
        for name, found in own.items():
            heads = {name.lower(), (found.matched or "").lower()}
            parents[name] = [
                s.edge.tail for s in found.edges if s.edge.relation == "IsA" and s.edge.head.lower() in heads
            ][:3]
        wanted = list(dict.fromkeys(p for ps in parents.values() for p in ps))
        inherited = self.retriever.retrieve_many(wanted, targets) if wanted else {}
        out: dict[str, tuple[str, ...]] = {}
        for name, found in own.items():
            facts = [edge_text(s.edge) for s in found.kept[: self.per_object]]
            above = sorted(
                (s for p in parents[name] for s in inherited[p].kept if s.edge.relation != "RelatedTo"),
                key=lambda s: -s.similarity,
            )
            facts += [edge_text(s.edge) for s in above[: self.inherited]]
            out[name] = tuple(dict.fromkeys(facts))
        return out


class Decider:
    """Scores yes/no questions about objects with the LLM.

    Args:
        llm: An LLM that can score options (labelled ``decide``).
        facts: Where the graph facts come from.
    """

    def __init__(self, llm: LLM, facts: FactFinder) -> None:
        self.llm = llm
        self.facts = facts

    def _ask(self, user: str) -> tuple[float, float, Usage]:
        messages = (Message("system", prompts.render("decide_system")), Message("user", user))
        scored = self.llm.score(ScoreRequest(options=ANSWERS, messages=messages))
        p_yes, log_odds = _log_odds(scored.logprobs)
        return p_yes, log_odds, scored.usage

    def fits(
        self, request: str, what: str, count: str, objects: Sequence[str], scene: Scene
    ) -> tuple[list[Judgement], tuple[str, ...], Usage]:
        """Whether each object fits ``what``; returns the judgements, the context facts and usage."""
        started = time.perf_counter()
        context = self.facts.context(what, request)
        about = self.facts.about(objects, [what, request])
        count_text = "one object" if count == "one" else "every object"
        context_text = ("Facts: " + "; ".join(context) + ".\n") if context else ""

        def question(obj: str, facts: Sequence[str], state: str | None) -> str:
            return prompts.render(
                "decide_user",
                request=request,
                count_text=count_text,
                what=what,
                context=context_text,
                object=obj,
                state=f" ({state})" if state else "",
                facts=("Facts about it: " + "; ".join(facts) + ".\n") if facts else "",
            )

        _, prior, usage = self._ask(question(CONTENT_FREE, (), None))
        judgements = []
        for obj in objects:
            found = scene.get(obj)
            p_yes, log_odds, used = self._ask(question(obj, about[obj], found.state if found else None))
            usage = usage + used
            judgements.append(Judgement(obj, what, p_yes, log_odds - prior, about[obj]))
        return judgements, context, usage.with_latency(time.perf_counter() - started)

    def dangerous(
        self, request: str, move: str, obj: str, scene: Scene, evidence: Sequence[str]
    ) -> tuple[Judgement, Usage]:
        """Whether carrying out ``move`` ("give the scissors to the child") would be dangerous."""
        started = time.perf_counter()
        facts = self.facts.about([obj], [f"{obj} is dangerous", move])[obj]
        lines = [*evidence, *facts]
        state = scene.get(obj).state if scene.get(obj) else None
        if state:
            lines.insert(0, f"the {obj} is {state}" if not state.startswith(("is ", "was ")) else state)
        user = prompts.render(
            "risk_user",
            request=request,
            objects=", ".join(scene.names),
            evidence=("Facts: " + "; ".join(lines) + ".") if lines else "",
            move=move,
        )
        p_yes, log_odds, usage = self._ask(user)
        judgement = Judgement(move, "dangerous", p_yes, log_odds, tuple(lines))
        return judgement, usage.with_latency(time.perf_counter() - started)
