"""Things used together: where what helps with a need is two things at once.

A need's target takes one object ("I'm thirsty": a drink). Some needs are met by two things used
together ("I want to brush my teeth": the toothbrush *and* the toothpaste; "I need to sew this button
back on": the needle and the thread), others by either of two ("I'm thirsty": the juice box or the
bottle of water, not both). After a need's target has its object, the next candidates that help are
each asked "would they also need the X, used together with the Y?" (:meth:`Decider.together`), and
the graph is read for whether it links the two by use ("toothpaste UsedFor clean tooth toothbrush",
"match UsedFor light candle") rather than by kind ("mitten IsA glove", "handkerchief IsA tissue":
substitutes). The two together, a logistic fit on the labelled set's tune round
(``benchmarks/data/together_set.jsonl``, ``benchmarks/bench_together.py --write``), give P(used
together); above one half the companion goes to the same place.

Companions are not calibrated decisions of the asking machinery (:mod:`asking`): they are never
asked about, and a plan's confidence does not count them. They pass the same risk checks as every
other move. A question that cannot be answered (an error, NaN) adds nothing.
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

#: Relations by which the graph says two things are used together: one is for, needs, or goes with
#: doing something with the other ("toothpaste UsedFor clean tooth toothbrush", "drive nail
#: HasPrerequisite hammer", "tape CapableOf stick paper").
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
EDGES_READ = 200  # per object; the offline graph's busiest objects ("hammer") have about that many


@dataclass(frozen=True)
class CompanionWeights:
    """The fitted combination: P(used together) = sigmoid(intercept + model * log-odds + graph * link).

    Attributes:
        intercept: The fit's intercept.
        model: Weight of the model's raw log-odds of Yes to "would they also need the X?".
        graph: Weight of the graph's link (1 where it links the two by use more than by kind).
        considered: How many of a need's next candidates (those more likely to help than a
            content-free object) are asked about.
        fitted_on: What the fit was made on, for the trace and the docs.
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
    """The shipped fit (``companion_weights.json``): ``graph`` for a planner with a knowledge graph,
    else the model-only fit of the no-graph ablation."""
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
    """What a name is about for the graph: the contents of a container phrase ("box of nails" ->
    "nails", "roll of sticky tape" -> "sticky tape"), else the name."""
    text = " ".join(tokens(name))
    return text.split(" of ", 1)[1] if " of " in text else text


def _head(name: str) -> str:
    words = [w for w in tokens(name) if w.isalpha()]
    return singular(words[-1]) if words else ""


def graph_link(graph: KnowledgeGraph | None, first: str, other: str) -> tuple[bool, str]:
    """Whether the graph links ``first`` and ``other`` by use more often than by kind, and the first
    statement that links them by use ("" where none does). Each object's edges are read (its
    contents for a container phrase); an edge links them where the other's head noun is a word of
    its far end (by use), or is that end's head noun (by kind). False without a graph."""
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
    """The objects asked about as companions of ``anchor``: the next ``considered`` of a need's
    ranking (best first) that help more than a content-free object would (score above 0)."""
    return [o for o, score in ranked if o != anchor and math.isfinite(score) and score > 0.0][:considered]
