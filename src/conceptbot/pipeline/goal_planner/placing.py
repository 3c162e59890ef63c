"""What the goal planner adds to its moves (a mixin of ``GoalPlanner``): companions and piles."""

from __future__ import annotations

import itertools
import math
from typing import TYPE_CHECKING

from conceptbot.core.errors import (
    BackendRequestError,
    BackendUnavailableError,
    ModelOutputError,
    NotSupportedError,
)
from conceptbot.core.observe import Observer
from conceptbot.core.scene import Scene
from conceptbot.core.trace import (
    CompanionCheck,
    StackTrace,
)
from conceptbot.core.usage import Usage
from conceptbot.pipeline.goal_planner.companions import (
    CompanionWeights,
    candidates,
    graph_link,
)
from conceptbot.pipeline.goal_planner.decide import Decider, Judgement
from conceptbot.pipeline.goal_planner.targets import Target, mentions
from conceptbot.pipeline.tracing import judgement_trace

if TYPE_CHECKING:
    from conceptbot.pipeline.goal_planner.planner import Thresholds

BASE = "a sturdy object with a flat top that other things can safely be stacked on"
#: What goes on top of a pile, whatever its size (the graph states it of many things).
FRAGILE = "fragile"


class Placing:
    """Companions and piles; the planner supplies the attributes below."""

    decider: Decider
    thresholds: Thresholds
    companions: CompanionWeights

    def _companions(
        self,
        request: str,
        targets: list[Target],
        ranked: dict[int, list[Judgement]],
        decided: dict[int, list[Judgement]],
        observer: Observer,
    ) -> tuple[dict[int, tuple[str, list[str]]], list[CompanionCheck], Usage]:
        """Per need target taking one object: its likeliest object and the candidates used with it (a
        failed question adds nothing: a companion is a convenience, not a safety)."""
        spent = Usage(calls=0)
        together: dict[int, tuple[str, list[str]]] = {}
        checks: list[CompanionCheck] = []
        weights = self.companions
        graph = self.decider.facts.retriever.graph if self.decider.facts.retriever is not None else None
        for number, target in enumerate(targets):
            now = [j for j in ranked.get(number, []) if j.scoring]
            if not target.helps or target.count != 1 or not now or weights.considered < 1:
                continue
            anchor = now[0].subject
            if not math.isfinite(now[0].score) or now[0].score <= self.thresholds.one_floor:
                continue  # the target takes nothing (or the person said none): nothing to go with
            before = [(j.subject, j.score) for j in decided.get(number, []) if j.scoring]
            others = candidates(before, anchor, weights.considered)
            if not others:
                continue
            need = target.need or request
            observer.progress(f"Together: would they need {', '.join(others)} with the {anchor}?")
            try:
                answers, used = self.decider.together(need, anchor, others)
                spent = spent + used
            except (ModelOutputError, BackendRequestError, BackendUnavailableError, NotSupportedError):
                answers = [Judgement(o, f"with the {anchor}", math.nan, math.nan) for o in others]
            taken = []
            for answer in answers:
                linked, statement = graph_link(graph, anchor, answer.subject)
                p = weights.p(answer.score, linked)
                check = CompanionCheck(
                    target.name, anchor, answer.subject, answer.p_yes, answer.score, statement, p, False
                )
                checks.append(check)
                if math.isfinite(p) and p > 0.5:
                    taken.append(answer.subject)
            if taken:
                together[number] = (anchor, taken)
        return together, checks, spent

    def _stack(
        self,
        request: str,
        scene: Scene,
        usage: dict[str, Usage],
        asked: list[str],
    ) -> tuple[list[tuple[str, str]], StackTrace | None]:
        """Bottom-up moves for a pile (fragile on top, then larger footprint and better base lower), and
        its order for the trace (None when there is nothing to pile)."""
        named = [o for _, o in mentions(request, scene.pickable)]
        stackable = [o for o in scene.pickable if scene.get(o).destination]  # type: ignore[union-attr]
        items = [o for o in named if o in stackable]
        items = items if len(items) >= 2 else stackable
        if len(items) < 2:
            return [], None
        judgements, _, used = self.decider.fits(request, BASE, items, scene, combine=False)
        fragile, _, used_fragile = self.decider.fits(request, FRAGILE, items, scene)
        usage["decide"] = usage["decide"] + used + used_fragile
        asked.extend(j.scoring for j in (*judgements, *fragile))
        breaks = {j.subject for j in fragile if j.score > self.thresholds.combined}

        def footprint(name: str) -> float:
            size = scene.get(name).size_m  # type: ignore[union-attr]
            return size[0] * size[1] if size else 0.0

        order = sorted(
            judgements, key=lambda j: (j.subject in breaks, -footprint(j.subject), -round(j.score, 1))
        )
        bottom_up = [j.subject for j in order]
        moves = [(upper, lower) for lower, upper in itertools.pairwise(bottom_up)]
        return moves, StackTrace(BASE, tuple(judgement_trace(j) for j in order))
