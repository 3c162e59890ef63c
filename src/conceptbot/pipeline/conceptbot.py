"""ConceptBot composed, with the paper's ablations and two planners.

Planners (``planner=``):

* ``goal`` (default) — the request read into targets, each object
  decided by a scored yes/no question with its graph facts, the plan assembled from the
  decisions and checked for risk (:mod:`conceptbot.pipeline.goal_planner.planner`);
* ``steps`` (system ``paper``) — the paper's pipeline: OPE -> URP -> greedy step-by-step Planner
  (:mod:`conceptbot.pipeline.steps.planner`).

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
from dataclasses import dataclass, replace
from pathlib import Path

from conceptbot.core.limits import check_request
from conceptbot.core.observe import SILENT, Observer
from conceptbot.core.plan import Done, Feedback, Plan
from conceptbot.core.scene import Scene
from conceptbot.core.system import PLANNERS, Ask
from conceptbot.core.trace import CalibrationNote, OPETrace, PlannerSummary, PlanTrace, URPTrace
from conceptbot.core.usage import Usage
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.embedder import Embedder
from conceptbot.models.llm import LLM
from conceptbot.pipeline import modes, prompts
from conceptbot.pipeline.goal import GoalFinder, GoalReader
from conceptbot.pipeline.goal.judge import ReadingJudge
from conceptbot.pipeline.goal.restate import Restater
from conceptbot.pipeline.goal_planner import conformal
from conceptbot.pipeline.goal_planner.choice import ObjectChooser
from conceptbot.pipeline.goal_planner.choice import shipped_weights as shipped_choice
from conceptbot.pipeline.goal_planner.combine import combination
from conceptbot.pipeline.goal_planner.decide import Decider, FactFinder
from conceptbot.pipeline.goal_planner.evidence import GraphEvidence
from conceptbot.pipeline.goal_planner.planner import GoalPlanner, GoalPlanResult, Thresholds
from conceptbot.pipeline.goal_planner.targets import TargetFinder
from conceptbot.pipeline.hazards import HazardCheck
from conceptbot.pipeline.ope import ObjectProperties, ObjectPropertiesExtractor
from conceptbot.pipeline.recipients import Recipients, model_question
from conceptbot.pipeline.retrieval import RelationRetriever
from conceptbot.pipeline.steps.planner import Planner
from conceptbot.pipeline.tracing import ope_trace, urp_trace
from conceptbot.pipeline.urp import URPResult, UserRequestProcessor

CONFIGS = ("conceptbot", "urp", "ope", "nokg")


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


def guidance_from(urp: URPResult) -> str:
    """What the planner is told about URP's interpretation."""
    if not urp.commands:
        return prompts.fill("planner_guidance_none", reasoning=urp.reasoning)
    steps = " ".join(f"{i}. {c};" for i, c in enumerate(urp.commands, 1))
    return prompts.fill("planner_guidance", reasoning=urp.reasoning, steps=steps)


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
        coverage: The goal planner's conformal coverage (see ``SystemOptions``).
        level: What the coverage holds for (``plan`` or ``decision``).
        reading: ``restated``: the goal planner reads the request's words and the model's plain
            form of it and keeps the better reading; ``words``: the rules alone.
        which_one: How a target taking one object is judged sure (``fits`` or ``softmax``); None:
            the rule the calibration names.
        calibration_dir: Where ``conceptbot calibrate --conformal`` wrote a model's thresholds.
        embedder: The sentence embedder for the goal planner's choice among objects (not a graph:
            the no-graph ablation uses it too); default: the retriever's, if any.
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
        coverage: float = 0.9,
        level: str = "plan",
        calibration_dir: Path | None = None,
        reading: str = "restated",
        which_one: str | None = None,
        embedder: Embedder | None = None,
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
        # One veto for both planners: OPE's top ratings and, with a graph, its hazard statements.
        # Who a destination is: its words, the graph's IsA chain, then the model asked plainly
        # where it scores options (pipeline/recipients.py).
        graph = retriever.graph if retriever is not None else None
        ask = model_question(self._llm_for("risk")) if llm.capabilities.scoring else None
        self.hazards = HazardCheck(graph, recipients=Recipients(graph, ask))
        self.planner = Planner(self._llm_for("planner"), method=planner_method, n=n, hazards=self.hazards)
        if planner == "auto":
            # The goal planner measured better on the dev split (51% against SayCan's 28%, with the
            # same model; docs/notes/2026-11-30-planner-redesign.md). It needs option scoring;
            # without it (chat APIs) the paper's step planner votes.
            planner = "goal"
        if planner == "goal" and not (self.switches.urp and llm.capabilities.scoring):
            planner = "steps"  # the goal planner needs the request compiled and options scored
        self.planner_kind = planner
        # Which model's conformal calibration it reads (conformal.user_file), for calibrate --conformal.
        self.calibration_key = (llm.backend, llm.model)
        facts = FactFinder(retriever)
        # Criterion decisions weigh the graph's statements as evidence beside the model's answer
        # (a combination fitted on the judgement set; without a graph, the ablation's own fit).
        decider = Decider(
            self._llm_for("decide"), facts, GraphEvidence(graph), combination(with_graph=graph is not None)
        )
        # The request's structure from its parse; the graph tells a dish to make from other things
        # wished for ("I'd love an omelette" / "I'd love a drink").
        graphed = retriever is not None
        reader = GoalReader(
            is_dish=facts.may_be_dish if graphed else None,
            is_person=self.hazards.is_person,
        )
        calibration = conformal.calibration_for(
            calibration_dir,
            llm.backend,
            llm.model,
            "graph" if graph is not None else "nograph",
            level,
            which_one,
        )
        self.goal_planner = GoalPlanner(
            GoalFinder(
                reader,
                TargetFinder(self._llm_for("goal"), self.hazards.is_person, food=facts),
                facts.dish_concept if retriever is not None else None,
                # The model says the request plainly and the rules read that too: they read plain
                # commands well and talk badly (docs/notes/2026-12-02-restated-reading.md).
                Restater(self._llm_for("restate")) if reading == "restated" else None,
                # Where the two readings differ, the model is asked which was meant: on held-out
                # paraphrases it ranks them far better than the step that chose (goal/judge.py).
                judge=ReadingJudge(self._llm_for("reading")) if reading == "restated" else None,
            ),
            decider,
            self.ope if self.switches.ope else None,
            thresholds,
            hazards=self.hazards,
            # Its decisions' conformal thresholds, fitted on the same combination's probabilities.
            # The model's own where `conceptbot calibrate --conformal` wrote one in calibration_dir.
            calibration=calibration,
            coverage=coverage,
            chooser=ObjectChooser(
                decider,
                embedder or (retriever.embedder if retriever is not None else None),
                shipped_choice(graph is not None),
            ),
        )
        # Every plan says whose thresholds it asked by: another model's break the coverage promised.
        self.calibration_note = CalibrationNote(
            coverage,
            f"{llm.backend}:{llm.model}",
            calibration.fitted_for,
            calibration.source,
            calibration.fits(llm.backend, llm.model),
        )

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        feedback: Feedback | None = None,
        observer: Observer | None = None,
        ask: Ask | None = None,
    ) -> Plan:
        """Plan ``request`` in ``scene``.

        Args:
            request: What the person said.
            scene: What the robot sees.
            risk: Force the Risk Index variant of OPE.
            feedback: What happened when an earlier plan was executed (closed loop): the Planner
                continues from the executed steps and avoids failed actions; OPE and URP are as before.
            observer: Gets a short message as each piece of work starts (LLM calls take seconds) and
                each module's trace part as it finishes: ``goal``, ``decisions``, ``risk`` and
                ``step`` (goal planner), or ``ope``, ``urp`` and ``step`` (step planner); None: silent.
            ask: Asks the person where a calibrated decision of the goal planner is unsure
                (``yes``/``no``, or None for no answer); None: nobody is asked, the plan lists the
                questions and acts on the likelier answers. The step planner never asks.
        """
        observer = observer if observer is not None else SILENT
        started = time.perf_counter()
        request = check_request(request)
        trace = PlanTrace(
            config=self.config, planner_kind=self.planner_kind, request=request, scene=scene.name
        )
        if self.planner_kind == "goal":
            result = self.goal_planner.plan(request, scene, risk, observer, ask)
            return self._from_goal(result, trace, feedback, started)
        usage: dict[str, Usage] = {}
        properties: dict[str, ObjectProperties] = {}
        ope: OPETrace | None = None
        mode, why = modes.choose_mode(request, scene.names, force_risk=risk)
        if self.switches.ope:
            found = self.ope.run(scene.names, mode, request)
            properties, usage["ope"] = found.properties, found.usage
            ope = ope_trace(mode, why, properties, found.retrievals)
            observer.event("ope", ope)
        guidance = ""
        commands: list[str] = []
        urp: URPTrace | None = None
        if self.switches.urp:
            interpreted = self.urp.run(request, scene, properties, observer)
            usage["urp"] = interpreted.usage
            urp = urp_trace(interpreted)
            observer.event("urp", urp)
            if interpreted.refused:
                usage["total"] = _total(usage, started)
                reason = interpreted.refusal_reason or "judged unsafe"
                return Plan((Done(),), [], True, reason, replace(trace, ope=ope, urp=urp), usage)
            guidance = guidance_from(interpreted)
            commands = interpreted.commands
        planned = self.planner.plan(request, scene, properties, guidance, commands, feedback, observer)
        usage["planner"] = planned.usage
        usage["total"] = _total(usage, started)
        summary = PlannerSummary(self.planner.method, len(planned.steps))
        vetoes = planned.vetoes or None
        trace = replace(trace, ope=ope, urp=urp, planner=summary, vetoes=vetoes)
        # Nothing moved because what the model wanted was vetoed: that is a refusal, with its reason.
        fresh = planned.actions[len(feedback.executed) if feedback else 0 :]
        refused = bool(planned.vetoes) and list(fresh) == [Done()]
        reason = "; ".join(f"{v.move}: vetoed, {v.statement}" for v in planned.vetoes) if refused else None
        return Plan(planned.actions, planned.steps, refused, reason, trace, usage)

    def _from_goal(
        self, result: GoalPlanResult, trace: PlanTrace, feedback: Feedback | None, started: float
    ) -> Plan:
        ope = None
        if result.properties:
            any_props = next(iter(result.properties.values()))
            ope = ope_trace(any_props.mode, "objects the plan moves", result.properties)
        trace = replace(
            result.trace,
            config=trace.config,
            planner_kind=trace.planner_kind,
            request=trace.request,
            scene=trace.scene,
            planner=PlannerSummary("decide", len(result.steps)),
            calibration=self.calibration_note,
            ope=ope,
        )
        actions = result.actions
        if feedback is not None:
            # Closed loop: keep what ran, never retry what failed, then the rest of the plan.
            done = list(feedback.executed)
            rest = [a for a in actions[:-1] if a not in done and a not in feedback.failed_actions]
            actions = [*done, *rest, Done()]
        usage = dict(result.usage)
        usage["total"] = _total(usage, started)
        return Plan(
            actions,
            result.steps,
            result.refused,
            result.reason,
            trace,
            usage,
            # A refusal carries out nothing: no confidence that its decisions are right to show.
            confidence=None if result.refused else result.confidence,
            questions=result.questions,
        )


def _total(usage: dict[str, Usage], started: float) -> Usage:
    total = Usage(calls=0)
    for part in usage.values():
        total = total + part
    return total.with_latency(time.perf_counter() - started)
