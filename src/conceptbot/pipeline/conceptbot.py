"""ConceptBot composed, with the paper's ablations and two planners.

Planners (``planner=``):

* ``goal`` (default) — the request read into targets, each object
  decided by a scored yes/no question with its graph facts, the plan assembled from the
  decisions and checked for risk (:mod:`conceptbot.pipeline.goal_planner`);
* ``steps`` (system ``paper``) — the paper's pipeline: OPE -> URP -> greedy step-by-step Planner
  (:mod:`conceptbot.pipeline.planner`).

Configurations:

* ``conceptbot`` — everything, with graph relations.
* ``urp``        — without OPE (goal planner: no object properties as risk evidence; steps: the
  planner gets URP's commands but no properties).
* ``ope``        — OPE only, no request interpretation: the paper's step planner (the goal planner
  cannot run without compiling the request).
* ``nokg``       — everything, with no knowledge-graph relations anywhere.

A refusal (an unsafe request) makes the plan just ``done()`` with ``refused: true``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from conceptbot.core.limits import check_request
from conceptbot.core.plan import EventSink, Feedback, Plan
from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.models.cache import CacheStore
from conceptbot.models.llm import LLM
from conceptbot.pipeline import modes
from conceptbot.pipeline.decide import Decider, FactFinder
from conceptbot.pipeline.goal_planner import GoalPlanner, GoalPlanResult, Thresholds, is_person
from conceptbot.pipeline.ope import ObjectPropertiesExtractor, Progress
from conceptbot.pipeline.planner import Planner
from conceptbot.pipeline.retrieval import RelationRetriever, Retrieval, edge_text
from conceptbot.pipeline.targets import TargetFinder
from conceptbot.pipeline.urp import URPResult, UserRequestProcessor

CONFIGS = ("conceptbot", "urp", "ope", "nokg")
PLANNERS = ("auto", "goal", "steps")


@dataclass(frozen=True)
class ConfigSwitches:
    """Which parts a configuration uses."""

    ope: bool
    urp: bool
    knowledge: bool


SWITCHES = {
    "conceptbot": ConfigSwitches(ope=True, urp=True, knowledge=True),
    "urp": ConfigSwitches(ope=False, urp=True, knowledge=True),
    "ope": ConfigSwitches(ope=True, urp=False, knowledge=True),
    "nokg": ConfigSwitches(ope=True, urp=True, knowledge=False),
}


def _retrieval_trace(retrievals: dict[str, Retrieval]) -> dict[str, Any]:
    return {
        name: {
            "matched": r.matched,
            "match": r.match,
            "notes": list(r.notes),
            "edges": [
                {
                    "relation": edge_text(s.edge),
                    "source": s.edge.source,
                    "similarity": round(s.similarity, 4),
                    "target": s.target,
                    "kept": s.kept,
                }
                for s in r.edges
            ],
        }
        for name, r in retrievals.items()
    }


def guidance_from(urp: URPResult) -> str:
    """What the planner is told about URP's interpretation."""
    if not urp.commands:
        return f"Analysis: {urp.reasoning}\nThe analysis found nothing to move."
    steps = " ".join(f"{i}. {c};" for i, c in enumerate(urp.commands, 1))
    return f"Analysis: {urp.reasoning}\nPlan from the analysis: {steps}"


class ConceptBot:
    """The planner system of the paper.

    Args:
        llm: The LLM behind the cache/log (its ``with_module`` labels calls by module, if present).
        retriever: Relation retrieval (graph + embedder + theta).
        config: One of :data:`CONFIGS`.
        store: Cache database for OPE results, or None.
        graph_version: Identifies the graph's contents in OPE cache keys.
        planner_method: ``auto``, ``logprob`` or ``vote`` (the step planner's LLM score).
        n: Completions per step for ``vote``.
        planner: ``goal``, ``steps`` or ``auto`` (``goal``); ``goal`` falls back to ``steps`` for
            ``ope`` and when the backend cannot score options.
        thresholds: The goal planner's decision thresholds.
    """

    def __init__(
        self,
        llm: LLM,
        retriever: RelationRetriever | None,
        config: str = "conceptbot",
        store: CacheStore | None = None,
        graph_version: str = "",
        planner_method: str = "auto",
        n: int = 5,
        planner: str = "auto",
        thresholds: Thresholds | None = None,
    ) -> None:
        if config not in SWITCHES:
            raise ValueError(f"config must be one of {CONFIGS}")
        if planner not in PLANNERS:
            raise ValueError(f"planner must be one of {PLANNERS}")
        self.config = config
        self.switches = SWITCHES[config]
        retriever = retriever if self.switches.knowledge else None
        self._llm_for = llm.with_module
        self.ope = ObjectPropertiesExtractor(self._llm_for("ope"), retriever, store, graph_version)
        self.urp = UserRequestProcessor(self._llm_for("urp"), retriever)
        self.planner = Planner(self._llm_for("planner"), method=planner_method, n=n)
        if planner == "auto":
            # The goal planner measured better on the dev split (51% against SayCan's 28%, with the
            # same model; docs/planner-redesign.md). It needs option scoring; without it (chat APIs)
            # the paper's step planner votes.
            planner = "goal"
        if planner == "goal" and not (self.switches.urp and llm.capabilities.scoring):
            planner = "steps"  # the goal planner needs the request compiled and options scored
        self.planner_kind = planner
        facts = FactFinder(retriever)
        self.goal_planner = GoalPlanner(
            TargetFinder(self._llm_for("goal"), is_person, food=facts),
            Decider(self._llm_for("decide"), facts),
            self.ope if self.switches.ope else None,
            thresholds,
        )

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        progress: Progress | None = None,
        feedback: Feedback | None = None,
        events: EventSink | None = None,
    ) -> Plan:
        """Plan ``request`` in ``scene``.

        Args:
            request: What the person said.
            scene: What the robot sees.
            risk: Force the Risk Index variant of OPE.
            progress: Called with a short message as each piece of work starts (LLM calls take seconds).
            feedback: What happened when an earlier plan was executed (closed loop): the Planner
                continues from the executed steps and avoids failed actions; OPE and URP are as before.
            events: Gets ``ope`` and ``urp`` (their trace parts) as those modules finish, and ``step``
                for each planner step.
        """
        emit = events or (lambda name, data: None)
        started = time.perf_counter()
        request = check_request(request)
        trace: dict[str, Any] = {
            "config": self.config,
            "planner_kind": self.planner_kind,
            "request": request,
            "scene": scene.name,
        }
        if self.planner_kind == "goal":
            result = self.goal_planner.plan(request, scene, risk, progress, events)
            return self._from_goal(result, trace, feedback, started)
        usage: dict[str, Usage] = {}
        properties = {}
        mode, why = modes.choose_mode(request, scene.names, force_risk=risk)
        if self.switches.ope:
            properties, retrievals, usage["ope"] = self.ope.run(scene.names, mode, request, progress)
            trace["ope"] = {
                "mode": mode,
                "why": why,
                "objects": {
                    n: {"values": p.values, "cached": p.cached, "relations_used": p.relations}
                    for n, p in properties.items()
                },
                "retrieval": _retrieval_trace(retrievals),
            }
            emit("ope", trace["ope"])
        guidance = ""
        commands: list[str] = []
        if self.switches.urp:
            urp, usage["urp"] = self.urp.run(request, scene, properties, progress)
            trace["urp"] = {
                "keywords": urp.keywords,
                "keyword_relations": _retrieval_trace(urp.keyword_retrievals),
                "object_relations": _retrieval_trace(urp.object_retrievals),
                "reasoning": urp.reasoning,
                "commands": urp.commands,
                "rejected_commands": urp.rejected_commands,
                "refused": urp.refused,
                "refusal_reason": urp.refusal_reason,
            }
            emit("urp", trace["urp"])
            if urp.refused:
                usage["total"] = _total(usage, started)
                return Plan(["done()"], [], True, urp.refusal_reason or "judged unsafe", trace, usage)
            guidance = guidance_from(urp)
            commands = urp.commands
        steps, actions, usage["planner"] = self.planner.plan(
            request, scene, properties, guidance, progress, commands, feedback, events
        )
        trace["planner"] = {"method": self.planner.method, "steps": len(steps)}
        usage["total"] = _total(usage, started)
        return Plan(actions, steps, False, None, trace, usage)

    def _from_goal(
        self, result: GoalPlanResult, trace: dict[str, Any], feedback: Feedback | None, started: float
    ) -> Plan:
        trace.update(result.trace)
        trace["planner"] = {"method": "decide", "steps": len(result.steps)}
        if result.properties:
            any_props = next(iter(result.properties.values()))
            trace["ope"] = {
                "mode": any_props.mode,
                "why": "objects the plan moves",
                "objects": {
                    n: {"values": p.values, "cached": p.cached, "relations_used": p.relations}
                    for n, p in result.properties.items()
                },
                "retrieval": {},
            }
        actions = result.actions
        if feedback is not None:
            # Closed loop: keep what ran, never retry what failed, then the rest of the plan.
            done = list(feedback.executed)
            rest = [a for a in actions[:-1] if a not in done and a not in feedback.failed_actions]
            actions = [*done, *rest, "done()"]
        usage = dict(result.usage)
        usage["total"] = _total(usage, started)
        return Plan(actions, result.steps, result.refused, result.reason, trace, usage)


def _total(usage: dict[str, Usage], started: float) -> Usage:
    total = Usage(calls=0)
    for part in usage.values():
        total = total + part
    return total.with_latency(time.perf_counter() - started)
