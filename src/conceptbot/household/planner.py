"""Planners for household robots with SafeAgentBench's 17 actions, and the option to refuse.

* :class:`PlainHouseholdPlanner` — the LLM alone: one call that judges the instruction and plans it
  (the benchmark's plain-LLM baseline, with the same safety instruction as ConceptBot).
* :class:`ConceptBotHouseholdPlanner` — ConceptBot's modules around a planning call that plans what
  was asked: OPE's Risk Index (1-5, with the knowledge graph's relations) for the scene objects the
  instruction names and URP's keywords with their graph relations are the evidence the harm judge
  reads the instruction with (:mod:`conceptbot.household.judge`); the similar cases' reading says how
  the labelled instructions nearest in meaning were judged (:mod:`conceptbot.household.similar`);
  the outcome judge reads what the simulated plan leaves behind; one fitted, calibrated judgement
  over those readings and what the plan does in the symbolic world
  (:mod:`conceptbot.household.harm`) refuses it or lets it go. No
  rule about the request's words decides a refusal. With ``judge=None`` (configuration
  ``conceptbot-joint``, the first design) the evidence goes to the plain planner's call, which
  judges and plans at once.

The reply is constrained (JSON schema with a pattern per step), so every step is one of the 17
actions (for ConceptBot's call, a task step that the robot's skills expand to them,
:mod:`conceptbot.household.skills`) on an object of the scene; it is read into
:class:`~conceptbot.core.plan.HouseholdAction` where it arrives, and the plan still has to be
checked by the executor. Both planners return the
tabletop planners' :class:`~conceptbot.core.plan.Plan`, with a
:class:`~conceptbot.core.trace.HouseholdTrace`; :mod:`conceptbot.systems` builds them by name.
"""

from __future__ import annotations

import json
import math
import re
import time
from dataclasses import dataclass, replace
from typing import Any

from conceptbot.core.errors import ConceptBotError, ConfigError
from conceptbot.core.limits import check_request
from conceptbot.core.observe import SILENT, Observer
from conceptbot.core.plan import (
    HOUSEHOLD_ACTIONS,
    LIQUIDS,
    HouseholdAction,
    Plan,
    format_actions,
    parse_household_actions,
)
from conceptbot.core.scene import HouseScene
from conceptbot.core.system import Ask
from conceptbot.core.trace import (
    DANGEROUS,
    SAFE,
    HarmDecision,
    HarmVerdict,
    HouseholdTrace,
    LLMRepair,
    PlanTrace,
)
from conceptbot.core.usage import Usage
from conceptbot.household.asking import JudgeCalibration, harm_question, judge_set
from conceptbot.household.executor import execute
from conceptbot.household.grounding import ground_plan
from conceptbot.household.harm import HarmModel, plan_features, shipped_model
from conceptbot.household.judge import HarmJudge, OutcomeJudge, safety_text
from conceptbot.household.outcomes import hazardous_outcomes, plan_effects
from conceptbot.household.similar import Example, SimilarCases
from conceptbot.household.skills import expand, parse_task_step, task_step_pattern
from conceptbot.household.thor import catalogue, key
from conceptbot.models.llm import LLM, ChatRequest, Message
from conceptbot.models.structured import chat_json
from conceptbot.pipeline import modes, prompts
from conceptbot.pipeline.ope import ObjectPropertiesExtractor
from conceptbot.pipeline.retrieval import RelationRetriever, edge_text
from conceptbot.pipeline.urp import UserRequestProcessor

PROMPTS = "conceptbot.household.prompts"
MAX_TASK_STEPS = 10


def plannable_objects(scene: HouseScene) -> list[str]:
    """The scene's objects plus what slicing or cracking them makes (``AppleSliced``)."""
    derived = catalogue().derived
    extra = [derived[o] for o in scene.objects if o in derived]
    return sorted({*scene.objects, *extra})


def response_schema(
    scene: HouseScene, max_steps: int = 24, refusal: bool = True, task_steps: bool = False
) -> dict[str, Any]:
    """The reply schema: reasoning, the refusal flag, and steps matching the 17 actions' syntax with
    the scene's object names; with ``refusal`` False (a call that plans what was asked), no flag.
    ``task_steps`` asks for task steps instead of actions (:mod:`conceptbot.household.skills`)."""
    objects = "|".join(re.escape(o) for o in plannable_objects(scene))
    with_object = "|".join(v for v, (obj, liquid) in HOUSEHOLD_ACTIONS.items() if obj and not liquid)
    without = "|".join(v for v, (obj, _) in HOUSEHOLD_ACTIONS.items() if not obj)
    liquid = "|".join(LIQUIDS)
    pattern = f"^(({with_object}) ({objects})|fillLiquid ({objects}) ({liquid})|{without})$"
    properties: dict[str, Any] = {
        "reasoning": {"type": "string", "maxLength": 300},
        "refuse": {"type": "boolean"},
        "steps": {"type": "array", "items": {"type": "string", "pattern": pattern}, "maxItems": max_steps},
    }
    if not refusal:
        del properties["refuse"]
    if task_steps:
        properties["steps"]["items"]["pattern"] = task_step_pattern(plannable_objects(scene))
        # a chore has a handful of parts; a small model given room for more repeats itself
        properties["steps"]["maxItems"] = min(max_steps, MAX_TASK_STEPS)
    return {"type": "object", "properties": properties, "required": list(properties)}


def mentioned_objects(instruction: str, scene: HouseScene) -> list[str]:
    """Scene objects the instruction names ("the watering can" -> WateringCan), in scene order."""
    words = re.findall(r"[a-z]+", instruction.lower())
    phrases = {key("".join(words[i : i + n])) for n in (1, 2, 3) for i in range(len(words) - n + 1)}
    phrases |= {p[:-1] for p in phrases if p.endswith("s")}
    cat = catalogue()
    found = []
    for obj in scene.objects:
        names = {key(obj)} | {a for a, t in cat.aliases.items() if t == obj}
        if names & phrases:
            found.append(obj)
    return found


def _words(obj: str) -> str:
    """``WateringCan`` -> ``watering can`` (graph concepts are lower-case words)."""
    return re.sub(r"(?<=[a-z])(?=[A-Z])", " ", obj).lower()


def _labelled(llm: LLM, module: str) -> LLM:
    """The LLM logging its calls under ``module`` where it keeps a call log."""
    return llm.with_module(module)


@dataclass(frozen=True)
class _Reply:
    """The planning call's reply, read: its reasoning, whether it refuses, its steps as actions, and
    the steps as the model wrote them (task steps, for ConceptBot's call)."""

    reasoning: str
    refuse: bool
    steps: tuple[HouseholdAction, ...]
    written: tuple[str, ...]

    @classmethod
    def read(cls, value: dict[str, Any], scene: HouseScene | None = None) -> _Reply:
        """The reply's JSON (validated against :func:`response_schema`), its steps parsed; with a
        ``scene``, the steps are task steps, expanded to actions there."""
        refuse = bool(value.get("refuse", False))
        written = tuple(str(s) for s in value["steps"])
        if scene is None:
            steps = parse_household_actions(list(written))
        else:
            steps = tuple(expand(scene, [parse_task_step(s) for s in written]))
        return cls(str(value["reasoning"]), refuse, steps, written)

    def to_json(self, refusal: bool = True) -> str:
        """As the model wrote it (for the repair round's conversation)."""
        reply: dict[str, Any] = {"reasoning": self.reasoning, "refuse": self.refuse}
        if not refusal:
            del reply["refuse"]
        return json.dumps({**reply, "steps": list(self.written)})


class _PlanCall:
    """The planning call. The plain planner's judges and plans at once (it may refuse); ConceptBot's
    plans what was asked (``refusal=False``: its prompt explains how the world's appliances work and
    leaves the decision to the harm judgement), in task steps that the robot's skills expand to
    actions (:mod:`conceptbot.household.skills`). A plan whose steps break the actions'
    rules (a ``put`` with nothing in the hand, opening what does not open) is grounded by the robot's
    skill layer (:func:`conceptbot.household.grounding.ground_plan`). With ``repair`` it first goes
    back to the LLM once with the executor's messages, as a robot would report failed actions; the
    proposed repair replaces the plan only if it fails fewer steps (off for ``plain``, which keeps
    the benchmark's one-call baseline; on for ConceptBot's call, where it replaced the plan on 80
    of the 312 tuning tasks)."""

    def __init__(self, llm: LLM, max_tokens: int = 400, repair: bool = False, refusal: bool = True) -> None:
        self.llm = llm
        self.max_tokens = max_tokens
        self.repair = repair
        self.refusal = refusal
        self.task_steps = not refusal

    def system(self) -> str:
        """The call's system prompt."""
        if not self.refusal:
            steps = "household_task_steps" if self.task_steps else "household_actions"
            actions = prompts.render(steps, PROMPTS)
            examples = prompts.render("household_plan_examples", PROMPTS)
            return prompts.render("household_plan_system", PROMPTS, actions=actions, examples=examples)
        actions = prompts.render("household_actions", PROMPTS)
        examples = prompts.render("household_examples", PROMPTS)
        return prompts.render(
            "household_system", PROMPTS, actions=actions, safety=safety_text(), examples=examples
        )

    def __call__(
        self, instruction: str, scene: HouseScene, knowledge: str, trace: HouseholdTrace
    ) -> tuple[_Reply, HouseholdTrace, Usage]:
        """The reply (grounded unless it refuses), the trace with what the call did, and its usage."""
        system = self.system()
        user = prompts.fill(
            "household_user",
            PROMPTS,
            room=scene.room,
            objects=", ".join(scene.objects),
            knowledge=knowledge,
            instruction=instruction,
        )
        messages = [Message("user", user)]
        schema = response_schema(scene, refusal=self.refusal, task_steps=self.task_steps)
        value, response = chat_json(
            self.llm, ChatRequest.of(messages, system=system, max_tokens=self.max_tokens), schema
        )
        tasks = scene if self.task_steps else None
        reply = _Reply.read(value, tasks)
        if not self.refusal:  # a call that plans what was asked does not refuse, whatever it wrote
            reply = replace(reply, refuse=False)
        usage = response.usage
        failures = execute(scene, reply.steps).failures() if not reply.refuse else []
        if self.repair and failures:
            listed = "\n".join(f"- {f}" for f in failures[:6])
            repair = "household_task_repair" if self.task_steps else "household_repair"
            messages += [
                Message("assistant", reply.to_json(self.refusal)),
                Message("user", prompts.render(repair, PROMPTS, failures=listed)),
            ]
            value, response = chat_json(
                self.llm, ChatRequest.of(messages, system=system, max_tokens=self.max_tokens), schema
            )
            repaired = _Reply.read(value, tasks)
            usage = usage + response.usage
            after = execute(scene, repaired.steps).failures()
            # A small model's "repair" is often worse (it picks up the counter it could not close, or
            # gives up), and AI2-THOR skips a failed step, so a plan with one harmless bad step may
            # still do the job: the repair is kept only when it is a plan with fewer failed steps.
            # The safety judgement stays the first one: the repair round is about the steps.
            better = bool(repaired.steps) and not repaired.refuse and len(after) < len(failures)
            trace = replace(
                trace,
                repair=LLMRepair(
                    tuple(failures), tuple(format_actions(repaired.steps)), tuple(after), better
                ),
            )
            if better:
                reply = replace(reply, steps=repaired.steps, written=repaired.written)
        if self.task_steps:
            trace = replace(trace, task_steps=reply.written)
        if not reply.refuse:
            steps, repairs = ground_plan(scene, reply.steps, instruction)
            trace = replace(trace, grounding=tuple(repairs))
            reply = replace(reply, steps=tuple(steps))
        return reply, trace, usage


def similar_tasks(cases: list[Example]) -> str:
    """The planning call's text for tasks like the one asked, with their reference task steps
    (empty without any)."""
    if not cases:
        return ""
    listed = "\n".join(f'- "{c.instruction}": {"; ".join(c.steps)}' for c in cases)
    return prompts.fill("household_similar", PROMPTS, tasks=listed)


def _with_total(usage: dict[str, Usage]) -> dict[str, Usage]:
    total = Usage(calls=0)
    for part in usage.values():
        total = total + part
    return {**usage, "total": total}


def _planned(reply: _Reply, trace: HouseholdTrace, usage: dict[str, Usage], config: str) -> Plan:
    """The plan the planning call made (or its refusal: ``refused_by`` is set by the caller)."""
    trace = replace(trace, reasoning=reply.reasoning)
    steps = () if reply.refuse else reply.steps
    return Plan(
        steps,
        refused=reply.refuse,
        reason=reply.reasoning.strip(),
        trace=PlanTrace(config=config, household=trace),
        usage=_with_total(usage),
    )


def _judged(verdict: HarmVerdict, decision: HarmDecision | None) -> str:
    """Why the judgement refused."""
    score = f"score {verdict.log_odds:+.2f}"
    if decision is None:
        return f"Carrying it out was judged dangerous ({score}, threshold {verdict.threshold:+.2f})"
    if decision.answer is not None:
        return f"The person said carrying it out would be dangerous ({score})"
    p = decision.p_dangerous
    shown = f"P(dangerous) {p:.2f}" if 0.0 <= p <= 1.0 else "P(dangerous) unreadable"
    if decision.question is not None:
        return f"Unsure whether carrying it out is dangerous ({shown}, {score}) and not answered"
    return f"Carrying it out was judged dangerous ({shown}, {score})"


def _left_behind(effects: list[str]) -> str:
    """The end of a judged refusal's reason: what the plan of what was asked would have left
    behind, so a person sees the outcome the judgement weighed (the request's readings aside)."""
    if not effects:
        return "."
    return ". The plan would leave: " + "; ".join(effects[:6]) + "."


def _refused(reason: str, trace: HouseholdTrace, usage: dict[str, Usage], config: str) -> Plan:
    """A refusal made before or after the planning call (by ``trace.refused_by``), for ``reason``."""
    return Plan(
        (),
        refused=True,
        reason=reason.strip(),
        trace=PlanTrace(config=config, household=replace(trace, reasoning=reason)),
        usage=_with_total(usage),
    )


class PlainHouseholdPlanner:
    """The LLM alone judges and plans.

    Args:
        llm: The LLM.
        llm_repair: Send a plan whose steps fail back to the LLM once before grounding it.
    """

    config = "plain"

    def __init__(self, llm: LLM, llm_repair: bool = False) -> None:
        self._call = _PlanCall(llm, repair=llm_repair)

    def plan(
        self, request: str, scene: HouseScene, observer: Observer | None = None, ask: Ask | None = None
    ) -> Plan:
        """Plan ``request`` in ``scene`` or refuse it (``observer``: a message as the call starts;
        ``ask`` is not used: the plain call makes no calibrated decision to ask about).

        Raises:
            ConfigError: The request is unusable (empty, too long, control characters).
        """
        request = check_request(request)
        observer = observer or SILENT
        started = time.perf_counter()
        observer.progress("planner: judging and planning")
        reply, trace, used = self._call(request, scene, "", HouseholdTrace())
        return _planned(
            reply, trace, {"planner": used.with_latency(time.perf_counter() - started)}, self.config
        )


class ConceptBotHouseholdPlanner:
    """ConceptBot's household planner: the plan of what was asked, and one fitted judgement of
    whether carrying it out would be dangerous (:mod:`conceptbot.household.harm`).

    The harm judge reads the instruction, and so do the similar cases; the planning call plans what
    was asked (with one repair round where steps fail); the outcome judge reads what the simulated
    plan leaves behind; the harm model weighs all of it with what the plan does in the symbolic
    world. Without a judge
    (``conceptbot-joint``, the first design) the evidence, OPE's Risk Index for the objects the
    instruction names and URP's keywords with their graph relations, goes to the plain planner's
    call, which judges and plans at once. (As readings of the judgement the evidence added nothing
    on held-out or blind tasks and took half a plan's time:
    docs/notes/2026-12-07-household-judgement-without-evidence.md.)

    Args:
        llm: The LLM for OPE and URP's keywords (``conceptbot-joint``).
        retriever: Graph relations + cosine filter.
        planner_llm: The LLM for the planning call; ``llm`` if None.
        keyword_llm: The LLM for URP's keywords; ``llm`` if None. (Separate contexts of the same
            model keep each module's system prompt evaluated from one task to the next.)
        max_relations: Keyword relations shown per keyword.
        llm_repair: Send a plan whose steps fail back to the LLM once before grounding it.
        judge: Reads the instruction; None: the planning call decides (``conceptbot-joint``).
        outcome: Reads what the plan leaves behind; without one the reading is 0.
        similar: Reads the instruction against labelled ones; without one the reading is missing,
            and a harm model that weighs it refuses (fails closed). Its nearest tasks with their
            reference steps go to the planning call.
        examples: How many of those nearest tasks the planning call sees (0: none).
        harm: The fitted judgement; the shipped one if None.
        coverage: Ask instead of guessing: the judgement's conformal prediction set at this coverage
            decides (0.8, 0.9, 0.95; 1 asks about every instruction); where it holds both answers the
            person is asked, and with no answer the instruction is refused. None: the threshold.
        calibration: The probability and conformal thresholds; the harm model's if None.
    """

    def __init__(
        self,
        llm: LLM,
        retriever: RelationRetriever,
        planner_llm: LLM | None = None,
        keyword_llm: LLM | None = None,
        max_relations: int = 6,
        llm_repair: bool = True,
        judge: HarmJudge | None = None,
        outcome: OutcomeJudge | None = None,
        similar: SimilarCases | None = None,
        examples: int = 3,
        harm: HarmModel | None = None,
        coverage: float | None = None,
        calibration: JudgeCalibration | None = None,
    ) -> None:
        if coverage is not None and judge is None:
            raise ConfigError("asking needs the harm judge: conceptbot-joint has no calibrated decision")
        self.harm = harm or (shipped_model() if judge is not None else None)
        self.calibration = calibration or (self.harm.calibration() if self.harm and coverage else None)
        if self.calibration is not None and coverage is not None:
            self.calibration.threshold(coverage)  # an unknown coverage fails here, not mid-benchmark
        self.coverage = coverage
        self.ope = ObjectPropertiesExtractor(_labelled(llm, "ope"), retriever)
        self.urp = UserRequestProcessor(_labelled(keyword_llm or llm, "urp"), retriever)
        self.retriever = retriever
        self.max_relations = max_relations
        self._call = _PlanCall(planner_llm or llm, repair=llm_repair, refusal=judge is None)
        self.judge = judge
        self.outcome = outcome
        self.similar = similar
        self.examples = examples
        self.config = "conceptbot" if judge is not None else "conceptbot-joint"

    def evidence(
        self, instruction: str, scene: HouseScene, observer: Observer, usage: dict[str, Usage]
    ) -> tuple[str, HouseholdTrace]:
        """What OPE and URP found, as text for the planning call of ``conceptbot-joint``, and the
        trace of it. Fills ``usage`` (``ope``, ``urp``)."""
        objects = mentioned_objects(instruction, scene)
        names = {o: _words(o) for o in objects}
        trace = HouseholdTrace(objects=tuple(objects))
        lines = []
        if objects:
            observer.progress(f"OPE: risk index of {', '.join(objects)}")
            found = self.ope.run(list(names.values()), modes.RISK, instruction)
            props, usage["ope"] = found.properties, found.usage
            trace = replace(trace, risk={n: p.values for n, p in props.items()})
            lines += [f"- {p.summary()} ({p.answer.reason.strip()})" for p in props.values()]
        started = time.perf_counter()
        observer.progress("URP: keywords and their relations")
        keywords, used = self.urp.keywords(instruction)
        relations: list[str] = []
        if keywords:
            for retrieval in self.retriever.retrieve_many(keywords, [instruction]).values():
                relations += [edge_text(s.edge) for s in retrieval.kept[: self.max_relations]]
        relations = list(dict.fromkeys(relations))
        usage["urp"] = used.with_latency(time.perf_counter() - started)
        trace = replace(trace, keywords=tuple(keywords), relations=tuple(relations))
        knowledge = ""
        if lines:
            knowledge += prompts.fill("household_risk", PROMPTS, risks="\n".join(lines))
        if relations:
            knowledge += prompts.fill(
                "household_facts", PROMPTS, facts="\n".join(f"- {r}" for r in relations)
            )
        return knowledge, trace

    def draft(
        self,
        request: str,
        scene: HouseScene,
        trace: HouseholdTrace,
        observer: Observer,
        usage: dict[str, Usage],
    ) -> tuple[_Reply, HouseholdTrace]:
        """The plan of what was asked (no refusal: the harm judgement decides), grounded, with the
        trace of its repair and grounding. Fills ``usage["planner"]``."""
        started = time.perf_counter()
        observer.progress("planner: planning what was asked")
        try:
            like = self.similar.nearest(request, self.examples) if self.similar and self.examples else []
        except ConceptBotError:  # the embedder failed: planned without them (the judgement fails closed)
            like = []
        if like:
            trace = replace(trace, similar_tasks=tuple(c.task for c in like))
        reply, trace, used = self._call(request, scene, similar_tasks(like), trace)
        usage["planner"] = used.with_latency(time.perf_counter() - started)
        return reply, trace

    def _similar(self, request: str) -> dict[str, float]:
        """The similar cases' reading of ``request`` (none without a reader; NaN where the
        embedder fails, so the judgement refuses)."""
        if self.similar is None:
            return {}
        try:
            return {"similar": self.similar.reading(request)}
        except ConceptBotError:
            return {"similar": math.nan}

    def read_plan(
        self,
        scene: HouseScene,
        steps: tuple[HouseholdAction, ...],
        observer: Observer,
        usage: dict[str, Usage],
    ) -> dict[str, float]:
        """The plan's signals for the harm judgement: the outcome reading of what it leaves behind
        and what it does in the symbolic world (:func:`~conceptbot.household.harm.plan_features`).
        Fills ``usage["outcome"]``."""
        signals = plan_features(scene, steps)
        if self.outcome is None:
            return {"outcome": 0.0, **signals}
        started = time.perf_counter()
        observer.progress("outcome: is what the plan leaves behind dangerous?")
        reading, used = self.outcome.reading(scene, plan_effects(scene, steps))
        usage["outcome"] = used.with_latency(time.perf_counter() - started)
        return {"outcome": reading, **signals}

    def plan(
        self, request: str, scene: HouseScene, observer: Observer | None = None, ask: Ask | None = None
    ) -> Plan:
        """Plan ``request`` in ``scene`` or refuse it (``observer``: a message as each piece of
        work starts). With a coverage, where the judgement's prediction set holds both answers,
        ``ask`` is asked whether carrying it out would be dangerous ("yes" refuses it); without
        ``ask``, or without an answer it can read, the instruction is refused. The plan's
        ``questions`` list the question and its ``confidence`` is the decision's probability of
        being right.

        Raises:
            ConfigError: The request is unusable (empty, too long, control characters).
        """
        request = check_request(request)
        observer = observer or SILENT
        usage: dict[str, Usage] = {}
        if self.judge is None or self.harm is None:
            knowledge, trace = self.evidence(request, scene, observer, usage)
            return self._joint(request, scene, knowledge, trace, observer, usage)
        started = time.perf_counter()
        observer.progress("judge: would carrying it out be dangerous?")
        judged, used = self.judge.judge(request, scene, "")
        usage["judge"] = used.with_latency(time.perf_counter() - started)
        trace = HouseholdTrace(objects=tuple(mentioned_objects(request, scene)))
        reply, trace = self.draft(request, scene, trace, observer, usage)
        signals = {
            **judged.readings,
            **self._similar(request),
            **self.read_plan(scene, reply.steps, observer, usage),
        }
        verdict = self.harm.verdict(signals)
        outcomes = tuple(hazardous_outcomes(scene, reply.steps))
        trace = replace(trace, judge=verdict, outcomes=outcomes or None)
        decision = self._decide(request, verdict, ask)
        answered: dict[str, Any] = {}
        if decision is not None:
            trace = replace(trace, asking=decision)
            answered = {
                "questions": (decision.question,) if decision.question else (),
                "confidence": decision.confidence,
            }
        if verdict.refuse if decision is None else decision.refuse:
            reason = _judged(verdict, decision) + _left_behind(plan_effects(scene, reply.steps))
            trace = replace(trace, refused_by="judge", reasoning=reply.reasoning)
            return replace(_refused(reason, trace, usage, self.config), **answered)
        return replace(_planned(reply, trace, usage, self.config), **answered)

    def _joint(
        self,
        request: str,
        scene: HouseScene,
        knowledge: str,
        trace: HouseholdTrace,
        observer: Observer,
        usage: dict[str, Usage],
    ) -> Plan:
        """The first design: the evidence in the plain planner's call, which judges and plans."""
        started = time.perf_counter()
        observer.progress("planner: judging and planning")
        reply, trace, used = self._call(request, scene, knowledge, trace)
        usage["planner"] = used.with_latency(time.perf_counter() - started)
        if reply.refuse:
            trace = replace(trace, refused_by="planner")
        return _planned(reply, trace, usage, self.config)

    def _decide(self, request: str, verdict: HarmVerdict, ask: Ask | None) -> HarmDecision | None:
        """The verdict's conformal decision at the planner's coverage, the person asked where its
        set holds both answers; None without a coverage (the threshold decides)."""
        if self.coverage is None or self.calibration is None:
            return None
        p = self.calibration.p_dangerous(verdict.log_odds)
        kept = judge_set(p, self.calibration.threshold(self.coverage))
        if len(kept) == 1:
            return HarmDecision(p, kept)
        question = harm_question(request, p)
        try:
            reply = ask(question) if ask is not None else None
        except Exception:  # whatever the asker raised, there is no answer: refused (fail closed)
            reply = None
        chosen = question.read(reply)
        if chosen is None:
            return HarmDecision(p, kept, None, question)
        answer = DANGEROUS if chosen else SAFE
        return HarmDecision(p, kept, answer, replace(question, answer=question.normalised(chosen)))
