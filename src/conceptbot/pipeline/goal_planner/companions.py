"""Things used together (the toothbrush *and* the toothpaste): after a need's target has its object,
the next helpful candidates are asked "would they also need the X?" and the graph is read for a link
by use (not by kind: substitutes). A logistic fit gives P(used together); above one half it goes too.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources

from conceptbot.knowledge.base import KnowledgeGraph
from conceptbot.knowledge.normalize import singular
from conceptbot.pipeline.goal_planner.combine import sigmoid
from conceptbot.pipeline.goal_planner.targets import tokens

#: Relations by which the graph says two things are used together ("drive nail HasPrerequisite hammer").
USE_LINKS = (
    "UsedFor",
    "CapableOf",
    "HasPrerequisite",
    "HasSubevent",
    "HasFirstSubevent",
    "HasLastSubevent",
    "ReceivesAction",
    "MotivatedByGoal",
)
#: Relations by which it says one is a kind of the other: substitutes ("mitten IsA glove").
KIND_LINKS = ("IsA", "Synonym")
EDGES_READ = 200  # per object; about as many as the offline graph's busiest objects have


@dataclass(frozen=True)
class CompanionWeights:
    """The fitted combination: P(used together) = sigmoid(intercept + model * log-odds + graph * link).

    Attributes:
        intercept: The fit's intercept.
        model: Weight of the model's raw log-odds of Yes to "would they also need the X?".
        graph: Weight of the graph's link (1 where it links the two by use more than by kind).
        considered: How many of a need's next helpful candidates are asked about.
        fitted_on: What the fit was made on, for the trace.
    """

    intercept: float
    model: float
    graph: float
    considered: int = 2
    fitted_on: str = ""

    def p(self, log_odds: float, linked: bool) -> float:
        """P(used together); NaN where the model's answer is not a number."""
        if not math.isfinite(log_odds):
            return math.nan
        return sigmoid(self.intercept + self.model * log_odds + (self.graph if linked else 0.0))


@cache
def shipped_weights(graph: bool) -> CompanionWeights:
    """The shipped fit (``companion_weights.json``), with or without the knowledge graph."""
    path = resources.files("conceptbot.pipeline").joinpath("companion_weights.json")
    text = path.read_text(encoding="utf-8")
    data = json.loads(text)["graph" if graph else "nograph"]
    return CompanionWeights(
        float(data["intercept"]),
        float(data["model"]),
        float(data.get("graph", 0.0)),
        int(data.get("considered", 2)),
        str(data.get("fitted_on", "")),
    )


def _thing(name: str) -> str:
    """What a name is about for the graph: a container phrase's contents ("box of nails" -> "nails")."""
    text = " ".join(tokens(name))
    return text.split(" of ", 1)[1] if " of " in text else text


def _head(name: str) -> str:
    words = [w for w in tokens(name) if w.isalpha()]
    return singular(words[-1]) if words else ""


def graph_link(graph: KnowledgeGraph | None, first: str, other: str) -> tuple[bool, str]:
    """Whether the graph links the two by use (not kind) more often, and the first use statement."""
    if graph is None:
        return False, ""
    by_use: list[str] = []
    by_kind = 0
    for this, that in ((first, other), (other, first)):
        mine, theirs = _head(this), _head(that)
        if not mine or not theirs or mine == theirs:
            continue
        found = graph.edges(_thing(this), [*USE_LINKS, *KIND_LINKS], EDGES_READ)
        own = {(found.matched or "").lower().split(" + ")[0], _thing(this)}
        for edge in found.edges:
            near, far = (edge.head, edge.tail) if edge.head.lower() in own else (edge.tail, edge.head)
            if near.lower() not in own and mine not in {singular(w) for w in tokens(near)}:
                continue  # an edge of neither end: the graph matched another concept
            far_words = [singular(w) for w in tokens(far) if w.isalpha()]
            if theirs not in far_words:
                continue
            if edge.relation in KIND_LINKS:
                by_kind += far_words[-1] == theirs
            else:
                by_use.append(f"{edge.head} {edge.relation} {edge.tail}")
    return len(by_use) > by_kind, by_use[0] if by_use else ""


def candidates(ranked: Sequence[tuple[str, float]], anchor: str, considered: int) -> list[str]:
    """The next ``considered`` objects of a need's ranking that help more than a content-free one."""
    return [o for o, score in ranked if o != anchor and math.isfinite(score) and score > 0.0][:considered]
