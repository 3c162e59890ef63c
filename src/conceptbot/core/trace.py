"""The trace of a plan, typed: what each module retrieved and decided on the way to it.

:meth:`PlanTrace.to_dict` is the ``trace`` object of ``conceptbot plan --json`` (described by the
JSON Schema ``conceptbot/schemas/plan.schema.json``); the web page's JavaScript, the CLI and
committed results files read its keys, so every part keeps its JSON keys, their order and its
rounding. Numbers are held as the JSON shows them: the pipeline rounds them where it builds a part.

Parts by planner (a part a planner does not produce is ``None`` and left out of the JSON):

* every ConceptBot plan: ``config``, ``planner_kind``, ``request``, ``scene`` and ``planner``;
* the step planner (``planner_kind == "steps"``): ``ope`` (unless the configuration skips OPE) and
  ``urp`` (unless it skips URP; a URP refusal ends the plan before ``planner``);
* the goal planner (``planner_kind == "goal"``): ``goal``, ``decisions``, ``stack`` (when the request
  piles things up), ``risk``, and ``ope`` when OPE rated the objects handed to someone;
* SayCan: ``config``, ``request`` and ``scene`` only;
* the household planners (SafeAgentBench): ``config`` and ``household`` (:class:`HouseholdTrace`:
  the harm judge's readings, the skill layer's grounding changes, the outcome checks), whose keys
  the JSON shows at the top level of the trace, as it always has.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any


@dataclass(frozen=True)
class EdgeTrace:
    """One graph edge scored against the retrieval's targets.

    Attributes:
        relation: The edge in words (``knife is used for cut``).
        source: The graph (or fallback) it came from.
        similarity: Its cosine similarity to the closest target (4 decimals).
        target: That target.
        kept: Whether it passed the threshold.
    """

    relation: str
    source: str
    similarity: float
    target: str
    kept: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "relation": self.relation,
            "source": self.source,
            "similarity": self.similarity,
            "target": self.target,
            "kept": self.kept,
        }


@dataclass(frozen=True)
class RetrievalTrace:
    """The relations retrieved for one concept.

    Attributes:
        matched: The graph concept(s) whose edges were scored; None when the graph knows nothing.
        match: How the name matched the graph.
        notes: The graph's notes (fallbacks, normalisation).
        edges: Every scored edge, in the graph's order.
    """

    matched: str | None
    match: str
    notes: tuple[str, ...] = ()
    edges: tuple[EdgeTrace, ...] = ()

    @property
    def kept(self) -> tuple[EdgeTrace, ...]:
        """The kept edges, in the graph's order."""
        return tuple(e for e in self.edges if e.kept)

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "matched": self.matched,
            "match": self.match,
            "notes": list(self.notes),
            "edges": [e.to_dict() for e in self.edges],
        }


def _retrievals(retrievals: Mapping[str, RetrievalTrace]) -> dict[str, Any]:
    return {name: r.to_dict() for name, r in retrievals.items()}


@dataclass(frozen=True)
class ObjectTrace:
    """What OPE concluded about one object.

    Attributes:
        values: The mode's JSON fields as the model gave them (``fragile: "Yes"``, ``dangerous: 4``, ...).
        cached: Whether the answer came from the OPE cache.
        relations_used: The kept relations shown to the model.
    """

    values: Mapping[str, Any]
    cached: bool = False
    relations_used: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "values": dict(self.values),
            "cached": self.cached,
            "relations_used": list(self.relations_used),
        }


@dataclass(frozen=True)
class OPETrace:
    """Object Properties Extraction's part of the trace.

    Attributes:
        mode: ``properties``, ``risk`` or ``materials``.
        why: Why that mode (the trigger words, ``--risk``, or the goal planner's reason).
        objects: Per object, what OPE concluded.
        retrieval: Per object, the relations retrieved (empty for the goal planner, which keeps none).
    """

    mode: str
    why: str
    objects: Mapping[str, ObjectTrace]
    retrieval: Mapping[str, RetrievalTrace] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON form (also the web page's ``ope`` event)."""
        return {
            "mode": self.mode,
            "why": self.why,
            "objects": {name: o.to_dict() for name, o in self.objects.items()},
            "retrieval": _retrievals(self.retrieval),
        }


@dataclass(frozen=True)
class URPTrace:
    """User Request Processing's part of the trace.

    Attributes:
        keywords: The request's keywords (empty without the graph).
        keyword_relations: The keywords' relations, filtered against the request.
        object_relations: The objects' relations, filtered against the keywords.
        reasoning: The model's reasoning.
        commands: The valid commands it proposed.
        rejected_commands: Proposed commands that were not valid in the scene, with why.
        refused: Whether it judged the request unsafe.
        refusal_reason: Why (empty when not refused).
    """

    keywords: tuple[str, ...]
    keyword_relations: Mapping[str, RetrievalTrace]
    object_relations: Mapping[str, RetrievalTrace]
    reasoning: str
    commands: tuple[str, ...]
    rejected_commands: tuple[str, ...]
    refused: bool
    refusal_reason: str

    def to_dict(self) -> dict[str, Any]:
        """JSON form (also the web page's ``urp`` event)."""
        return {
            "keywords": list(self.keywords),
            "keyword_relations": _retrievals(self.keyword_relations),
            "object_relations": _retrievals(self.object_relations),
            "reasoning": self.reasoning,
            "commands": list(self.commands),
            "rejected_commands": list(self.rejected_commands),
            "refused": self.refused,
            "refusal_reason": self.refusal_reason,
        }


@dataclass(frozen=True)
class TargetTrace:
    """A destination the request sends things to (the goal planner).

    Attributes:
        to: The destination.
        count: How many objects, or ``"all"`` (every one that fits).
        how: ``named``, ``speaker`` or ``scored``.
        named: Objects the request names for it.
        score: The calibrated log-odds when scored (3 decimals).
        criterion: The property that sorts objects to it, in the request's words, or "".
        dish: The dish the request asks for, when the graph knows it as one, or "".
        ingredients: Whether the objects that go are a dish's ingredients.
        rest: Whether it takes whatever no other target takes ("the rest"; in the JSON only when so).
        part: What this target is for where the request asks for several things of different kinds
            ("as something to eat"; in the JSON only when set).
    """

    to: str
    count: int | str
    how: str
    named: tuple[str, ...] = ()
    score: float = 0.0
    criterion: str = ""
    dish: str = ""
    ingredients: bool = False
    rest: bool = False
    part: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "to": self.to,
            "count": self.count,
            "how": self.how,
            "named": list(self.named),
            "score": self.score,
            "criterion": self.criterion,
            "dish": self.dish,
            "ingredients": self.ingredients,
            **({"rest": True} if self.rest else {}),
            **({"part": self.part} if self.part else {}),
        }


#: The kinds of reading a person may be asked to choose between: the one the targets are, the one
#: the choice between the words and the plain form dropped, and a sampled plain form's.
READING_KINDS = ("taken", "other", "sampled")


@dataclass(frozen=True)
class ReadingOption:
    """One reading of a request the person could be asked about, and how likely it is the one meant.

    Attributes:
        text: The reading in words ('give the user one "fruit" and one "soda"').
        p: P(it is the one meant): for ``taken`` and ``other`` the odds of the step of the choice
            that kept or dropped it (``pipeline/goal/reading_odds.json``), for ``sampled`` the
            share of the sampled plain forms that read it.
        kind: One of :data:`READING_KINDS`.
    """

    text: str
    p: float
    kind: str = "taken"

    def __post_init__(self) -> None:
        if self.kind not in READING_KINDS:
            raise ValueError(f"kind must be one of {READING_KINDS}, got {self.kind!r}")

    def to_dict(self) -> dict[str, Any]:
        """JSON form (a probability that is not a number as null)."""
        p = round(self.p, 4) if math.isfinite(self.p) else None
        return {"text": self.text, "p": p, "kind": self.kind}


@dataclass(frozen=True)
class GoalTrace:
    """Where the request sends things (the goal planner's first part).

    Attributes:
        targets: The targets, in the request's order (none for a stack).
        stack: Whether the request piles the objects up.
        plain: The model's plain form of the request ("Give me something to write with."), where
            the request was said plainly before it was read; else "".
        reading: Which reading the targets are: ``words`` (the rules on the request's own words),
            ``plain`` (on the plain form), ``both`` (the two agree), "" (only the words were read).
        other: Where the two readings differ, the one not taken (goal-set JSON: stack, dish, need,
            targets), else None.
        step: Where the request reads two or more ways, the step of the choice that kept the
            reading taken (``pipeline/goal/aided.py``'s steps), else "".
        readings: Where it reads two or more ways, every reading the person could be asked about
            with its probability, the one taken first (before the conformal set keeps some: what
            the plan-level calibration fits the reading threshold on), else empty.
        preference: Where the two readings differ, the model's log-odds for the one taken over the
            one dropped, which moved the step's odds (``pipeline/goal/judge.py``), else None.
    """

    targets: tuple[TargetTrace, ...]
    stack: bool
    plain: str = ""
    reading: str = ""
    other: dict[str, Any] | None = None
    step: str = ""
    readings: tuple[ReadingOption, ...] = ()
    preference: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form (also the web page's ``goal`` event); the readings only where the request was
        said plainly, the model's preference only where it was asked."""
        found: dict[str, Any] = {"targets": [t.to_dict() for t in self.targets], "stack": self.stack}
        if self.reading:
            found.update(plain=self.plain, reading=self.reading, other=self.other)
        if self.readings:
            found.update(step=self.step, readings=[r.to_dict() for r in self.readings])
            if self.preference is not None and math.isfinite(self.preference):
                found["preference"] = round(self.preference, 4)
        return found


@dataclass(frozen=True)
class JudgementTrace:
    """One scored yes/no decision about one object.

    Attributes:
        object: The object.
        p_yes: P(Yes) normalised over Yes/No (4 decimals).
        score: Calibrated log-odds of Yes (3 decimals).
        facts: The graph facts put in the question.
        name_score: Its score in the name ranking, where one was made (3 decimals), else None.
        model: The model's own calibrated log-odds (3 decimals) where ``score`` combines it with the
            graph's evidence (:mod:`conceptbot.pipeline.goal_planner.combine`), else None.
        evidence: The evidence features that are set and the statements that set them
            (``{"features": {...}, "statements": [...]}``), where the score is combined, else None.
        answers: The decision's conformal prediction set (``["yes"]``, ``["no"]``, or both: unsure),
            where the planner calibrated it, else None.
        p_one: For a target taking one object, the probability that this is the one (a softmax of
            the ranking over the candidates, 4 decimals), else None.
        described: The model's own description of the object, where the combination asked the
            question with it too, else "".
    """

    object: str
    p_yes: float
    score: float
    facts: tuple[str, ...] = ()
    name_score: float | None = None
    model: float | None = None
    evidence: Mapping[str, Any] | None = None
    answers: tuple[str, ...] | None = None
    p_one: float | None = None
    described: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form (``name_score`` only where there is one)."""
        data: dict[str, Any] = {
            "object": self.object,
            "p_yes": self.p_yes,
            "score": self.score,
            "facts": list(self.facts),
        }
        if self.name_score is not None:
            data["name_score"] = self.name_score
        if self.model is not None:
            data["model"] = self.model
        if self.evidence is not None:
            data["evidence"] = {
                "features": dict(self.evidence["features"]),
                "statements": list(self.evidence["statements"]),
            }
        if self.answers is not None:
            data["answers"] = list(self.answers)
        if self.p_one is not None:
            data["p_one"] = self.p_one
        if self.described:
            data["described"] = self.described
        return data


NONE = "none"  # the answer that sends none of a ``choose`` or ``one`` question's objects
ALL = "all"  # the answer that sends every object of a ``choose`` question
KINDS = ("confirm", "choose", "one", "reading", "harm")
YES_NO = ("confirm", "harm")  # the kinds answered yes or no


@dataclass(frozen=True)
class ClarifyingQuestion:
    """A question the planner asks where calibrated decisions' conformal prediction sets are unsure:
    about one object (``confirm``: yes or no); where a target taking all that fit is unsure of
    several, about all of them at once (``choose``: which of these go; some, all or none); where a
    target taking one object has several candidates (``one``: which one, another the person names,
    or none); where the household harm judge is unsure, whether the instruction is dangerous
    (``harm``: yes refuses it).

    Attributes:
        text: The question in plain words ("Should I put the lemon in or on the bowl?", "Which one
            should I give to the user: the coke, the 7up or the water bottle? One, or none.").
        target: Where the objects would go.
        objects: The objects it is about, most uncertain (``one``: most likely) first; for
            ``reading``, the two readings in words, the one the plan acts on first.
        p_yes: Each object's calibrated probability (4 decimals), in the order of ``objects``: P(yes)
            for ``confirm`` and ``choose``; for ``one``, P(it fits) by the ``fits`` rule, P(it is the
            one) by the ``softmax`` rule; P(it is what was meant)
            for ``reading``; P(dangerous) for ``harm``.
        kind: One of :data:`KINDS`.
        answer: The person's answer as read (``yes``/``no``; for ``choose`` the chosen objects joined
            by ", ", for ``one`` the object, for ``reading`` the reading; or ``none``); None where
            nobody was asked (the plan then acts on the likelier answers).
        others: For ``one``: the target's other candidates, which the person may name instead of
            the listed ones (the set missed what they meant: "none of those, the reading glasses").
    """

    text: str
    target: str
    objects: tuple[str, ...]
    p_yes: tuple[float, ...]
    kind: str = "confirm"
    answer: str | None = None
    others: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "objects", tuple(self.objects))
        object.__setattr__(self, "others", tuple(self.others))
        object.__setattr__(self, "p_yes", tuple(self.p_yes))
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")
        if self.others and self.kind != "one":
            raise ValueError("only a which-one question takes another object than those listed")

    @property
    def options(self) -> tuple[str, ...]:
        """What may be answered: yes or no (``confirm``, ``harm``), or the objects."""
        return ("yes", "no") if self.kind in YES_NO else self.objects

    def read(self, reply: object) -> tuple[str, ...] | None:
        """The objects a reply sends to the target (empty: none), or None for a reply that is not an
        answer. ``confirm``, ``harm``: yes or no (or y, n). ``choose``: ``none``, ``all``, or options
        separated by commas (in any case, each at most once). ``one``: one option or one of
        :attr:`others`, or ``none``.
        ``reading``: one of the readings, whole (a reading may hold commas), or ``none``."""
        if not isinstance(reply, str):
            return None
        said = " ".join(reply.strip().lower().split())
        if self.kind in YES_NO:
            return {"yes": self.objects, "y": self.objects, "no": (), "n": ()}.get(said)
        if said == NONE:
            return ()
        if self.kind == "choose" and said == ALL and ALL not in (o.lower() for o in self.objects):
            return self.objects
        if self.kind == "reading":
            whole = {" ".join(o.lower().split()): o for o in self.objects}
            return (whole[said],) if said in whole else None
        names = {o.lower(): o for o in (*self.objects, *self.others)}
        parts = [" ".join(p.split()) for p in said.split(",")]
        chosen = [names.get(p) for p in parts]
        if None in chosen or len(set(chosen)) != len(chosen) or (self.kind == "one" and len(chosen) != 1):
            return None
        return tuple(o for o in (*self.objects, *self.others) if o in chosen)

    def normalised(self, chosen: tuple[str, ...]) -> str:
        """The answer text for ``chosen`` (what :attr:`answer` records)."""
        if self.kind in YES_NO:
            return "yes" if chosen else "no"
        return ", ".join(chosen) if chosen else NONE

    def to_dict(self) -> dict[str, Any]:
        """JSON form (``conceptbot plan --json``'s ``questions``)."""
        chosen = self.read(self.answer) if self.answer is not None else None
        return {
            "text": self.text,
            "kind": self.kind,
            "target": self.target,
            "objects": list(self.objects),
            "p_yes": list(self.p_yes),
            "options": list(self.options),
            "answer": self.answer,
            "chosen": list(chosen) if chosen is not None else None,
            "others": list(self.others),
        }


@dataclass(frozen=True)
class DecisionTrace:
    """Which objects go to one target.

    Attributes:
        target: The target.
        decided: False where the request named enough objects (nothing was asked).
        objects: Every other object's decision, in scene order (empty when not decided).
        context: The graph facts about the request put in the questions (None when not decided).
        candidates: For a target taking one object, the conformal prediction set of which one
            (most likely first; more than one: unsure), where the planner calibrated it, else None.
        confidence: The probability that the plan's final moves are right in this target's
            calibrated decisions (4 decimals; an answer counts as sure), where it has any: the
            plan's confidence is the product of these, so the trace shows where it is lost.
    """

    target: TargetTrace
    decided: bool
    objects: tuple[JudgementTrace, ...] = ()
    context: tuple[str, ...] | None = None
    candidates: tuple[str, ...] | None = None
    confidence: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form: the target's fields, then the decisions."""
        data = {**self.target.to_dict(), "decided": self.decided}
        if self.context is not None:
            data["context"] = list(self.context)
        if self.candidates is not None:
            data["candidates"] = list(self.candidates)
        if self.confidence is not None:
            data["confidence"] = self.confidence
        data["objects"] = [o.to_dict() for o in self.objects]
        return data


@dataclass(frozen=True)
class StackTrace:
    """The order of a pile.

    Attributes:
        base_question: What each object was asked to be ("a sturdy object with a flat top ...").
        order: The objects, bottom first, with their decisions.
    """

    base_question: str
    order: tuple[JudgementTrace, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {"base_question": self.base_question, "order": [j.to_dict() for j in self.order]}


@dataclass(frozen=True)
class CompanionCheck:
    """Whether a thing used together with what a need's target took went too ("I want to brush my
    teeth": the toothpaste with the toothbrush).

    Attributes:
        place: The need's target.
        anchor: The object the target took.
        object: The candidate asked about.
        p_model: The model's P(Yes) to "would they also need the X, used together with the Y?"
            (4 decimals; NaN: not read).
        score: Its raw log-odds of Yes (3 decimals).
        graph: The graph statement that links the two by use ("" where none does, or no graph).
        p: P(used together), the fitted combination of the two (4 decimals; NaN: not read).
        used: Whether the plan moves it to the place too (after the risk checks).
    """

    place: str
    anchor: str
    object: str
    p_model: float
    score: float
    graph: str
    p: float
    used: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON form (NaN as null)."""

        def num(x: float, digits: int) -> float | None:
            return round(x, digits) if math.isfinite(x) else None

        return {
            "place": self.place,
            "anchor": self.anchor,
            "object": self.object,
            "p_model": num(self.p_model, 4),
            "score": num(self.score, 3),
            "graph": self.graph,
            "p": num(self.p, 4),
            "used": self.used,
        }


@dataclass(frozen=True)
class Veto:
    """A move dropped because its own evidence names a hazard for its recipient
    (:mod:`conceptbot.pipeline.hazards`), or because its risk decision could not be made.

    Attributes:
        move: The action text (``pick_and_place(knife, child)``).
        object: The object moved.
        to: The recipient.
        source: What vetoed it: ``ope`` (OPE's rating), ``graph`` (a graph statement) or ``error``
            (the risk decision failed: a backend error, a non-finite score).
        statement: The evidence in words ("OPE rates the knife 5/5 dangerous with the child").
    """

    move: str
    object: str
    to: str
    source: str
    statement: str

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "move": self.move,
            "object": self.object,
            "to": self.to,
            "source": self.source,
            "statement": self.statement,
        }


@dataclass(frozen=True)
class RiskCheck:
    """The risk decision and affordance of one move (the goal planner's constraints).

    Attributes:
        object: The object moved.
        to: Where.
        move: The move in words.
        p_unsafe: P(unsafe) (4 decimals); None where the decision could not be made.
        score: Calibrated log-odds of unsafe (3 decimals); None where the decision could not be made.
        evidence: The graph facts put in the question.
        ope: OPE's finding about the object for this move, or None where OPE did not rate it.
        affordance: S_aff of the move (4 decimals).
        dropped: Whether the move was dropped.
        why: ``vetoed`` (its evidence names a hazard for the recipient, or its risk decision failed:
            ``veto`` says which), ``judged dangerous``, ``not feasible`` or "".
        veto: The veto (in the JSON: its statement), or None.
        reason: For ``judged dangerous``: what names the danger ("OPE rates the foil tray 5/5
            dangerous with the microwave"); "" otherwise (in the JSON only where set).
    """

    object: str
    to: str
    move: str
    p_unsafe: float | None
    score: float | None
    evidence: tuple[str, ...]
    ope: str | None
    affordance: float
    dropped: bool
    why: str
    veto: Veto | None = None
    reason: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "object": self.object,
            "to": self.to,
            "move": self.move,
            "p_unsafe": self.p_unsafe,
            "score": self.score,
            "evidence": list(self.evidence),
            "ope": self.ope,
            "affordance": self.affordance,
            "dropped": self.dropped,
            "why": self.why,
            "veto": self.veto.statement if self.veto is not None else None,
            **({"reason": self.reason} if self.reason else {}),
        }


@dataclass(frozen=True)
class CalibrationNote:
    """Which conformal thresholds the goal planner asked by, and whether they are this model's.

    A threshold keeps its coverage only for the scores it was fitted on: the shipped ones are the
    embedded model's; another model's plans get the coverage asked for once ``conceptbot calibrate
    --conformal`` has fitted its own.

    Attributes:
        coverage: The coverage asked for (1.0: every calibrated decision is asked).
        model: The model that planned, as ``backend:model``.
        fitted_for: The model the thresholds were fitted for.
        source: ``shipped`` (the package's) or the path of the user's calibration file.
        own: Whether they were fitted on this model's scores.
    """

    coverage: float
    model: str
    fitted_for: str
    source: str
    own: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "coverage": self.coverage,
            "model": self.model,
            "fitted_for": self.fitted_for,
            "source": self.source,
            "own": self.own,
        }


@dataclass(frozen=True)
class PlannerSummary:
    """How the plan's steps were chosen.

    Attributes:
        method: ``decide`` (goal planner), ``logprob`` or ``vote`` (step planner).
        steps: How many steps.
    """

    method: str
    steps: int

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {"method": self.method, "steps": self.steps}


@dataclass(frozen=True)
class HarmVerdict:
    """The household harm judge's decision.

    Attributes:
        log_odds: The score: the sum of the readings' log P(dangerous) - log P(not).
        threshold: The refusal threshold it was compared with.
        readings: Each question's log-odds of "dangerous", by name.
    """

    log_odds: float
    threshold: float
    readings: Mapping[str, float] = field(default_factory=dict)

    @property
    def refuse(self) -> bool:
        """Whether the instruction is refused (a NaN score refuses: the decision could not be made)."""
        return not self.log_odds < self.threshold

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace."""
        return {
            "log_odds": round(self.log_odds, 3),
            "readings": {name: round(value, 3) for name, value in self.readings.items()},
            "threshold": self.threshold,
            "refuse": self.refuse,
        }


DANGEROUS, SAFE = "dangerous", "safe"  # the two answers of the harm judge's decision


@dataclass(frozen=True)
class HarmDecision:
    """What the household harm judge's calibrated decision came to (:mod:`conceptbot.household.asking`).

    Attributes:
        p_dangerous: The calibrated probability (NaN where it could not be read).
        kept: The prediction set.
        answer: The person's answer as read (``dangerous``/``safe``), None if not asked or no
            answer.
        question: The question, where the set held both answers (with the answer given).
    """

    p_dangerous: float
    kept: tuple[str, ...]
    answer: str | None = None
    question: ClarifyingQuestion | None = None

    @property
    def refuse(self) -> bool:
        """Refused unless the set is ``safe`` alone or the person said it is safe (fail closed)."""
        if self.answer is not None:
            return self.answer == DANGEROUS
        return self.kept != (SAFE,)

    @property
    def confidence(self) -> float:
        """The probability that the decision is right: 1 where the person answered; else the
        probability of the answer acted on (0 where it cannot be read)."""
        if self.answer is not None:
            return 1.0
        if not 0.0 <= self.p_dangerous <= 1.0:
            return 0.0
        return self.p_dangerous if self.refuse else 1.0 - self.p_dangerous

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace."""
        p = self.p_dangerous
        return {
            "p_dangerous": round(p, 4) if math.isfinite(p) else None,
            "set": list(self.kept),
            "answer": self.answer,
        }


@dataclass(frozen=True)
class GroundingChange:
    """One change the household robot's skill layer made to a plan before it runs.

    Attributes:
        step: The step that failed, as text.
        failure: Why (the executor's message).
        change: What was done ("inserted pick Candle", "dropped the step", ...).
    """

    step: str
    failure: str
    change: str

    def to_dict(self) -> dict[str, str]:
        """JSON form for the trace."""
        return {"step": self.step, "failure": self.failure, "change": self.change}


@dataclass(frozen=True)
class Outcome:
    """One hazardous outcome of a household plan (or of what an instruction asks).

    Attributes:
        kind: ``spill`` or ``throw``.
        step: The plan step that causes it, as text.
        about: What the liquid lands on (``spill``) or what is thrown (``throw``).
    """

    kind: str
    step: str
    about: str

    def describe(self) -> str:
        """In words, for a refusal's reason."""
        if self.kind == "spill":
            return f"'{self.step}' pours liquid onto the {self.about}, which neither holds nor drains it"
        return f"'{self.step}' throws the {self.about}"

    def to_dict(self) -> dict[str, str]:
        """JSON form (the trace's ``outcomes``)."""
        return {"kind": self.kind, "step": self.step, "about": self.about}


@dataclass(frozen=True)
class LLMRepair:
    """The household planner's optional repair round: the plan's failures sent back to the LLM.

    Attributes:
        failures: ``step: why`` for each failed step of the first plan.
        proposed: The LLM's repaired steps, as text.
        proposed_failures: Their failures.
        kept: Whether the repair replaced the plan (only when it fails fewer steps).
    """

    failures: tuple[str, ...]
    proposed: tuple[str, ...]
    proposed_failures: tuple[str, ...]
    kept: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace."""
        return {
            "failures": list(self.failures),
            "proposed": list(self.proposed),
            "proposed_failures": list(self.proposed_failures),
            "kept": self.kept,
        }


@dataclass(frozen=True)
class HouseholdTrace:
    """What a household planner found and decided (SafeAgentBench); a part it did not produce is
    None and left out of the JSON.

    Attributes:
        objects: Scene objects the instruction names.
        risk: OPE's Risk Index answer per object, as the model gave it.
        keywords: URP's keywords.
        relations: The graph relations kept for them, as text.
        judge: The harm judge's verdict.
        asking: Where the planner was given a coverage, the verdict's conformal decision (its set,
            and the question and answer where the set held both answers).
        repair: The LLM repair round, when it ran.
        grounding: The skill layer's changes to the plan.
        outcomes: Hazardous outcomes found in the plan or the instruction.
        refused_by: ``judge`` (the harm judgement) or ``planner`` (the first design's planning call); None
            when it planned. (Records made before the fitted judgement also have ``request`` and
            ``outcome``.)
        reasoning: The planning call's reasoning, or the reason of a refusal made without it.
        task_steps: The task steps ConceptBot's planning call wrote (before the skills expanded them
            to actions).
        similar_tasks: The tuning tasks (ids) the planning call was shown as examples.
    """

    objects: tuple[str, ...] | None = None
    risk: Mapping[str, Mapping[str, Any]] | None = None
    keywords: tuple[str, ...] | None = None
    relations: tuple[str, ...] | None = None
    judge: HarmVerdict | None = None
    asking: HarmDecision | None = None
    repair: LLMRepair | None = None
    grounding: tuple[GroundingChange, ...] | None = None
    outcomes: tuple[Outcome, ...] | None = None
    refused_by: str | None = None
    reasoning: str | None = None
    task_steps: tuple[str, ...] | None = None
    similar_tasks: tuple[str, ...] | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form: the set parts, in this order (the order the planners have always written)."""
        data: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None:
                continue
            if f.name == "risk":
                data[f.name] = {name: dict(values) for name, values in value.items()}
            elif isinstance(value, tuple):
                data[f.name] = [v.to_dict() if hasattr(v, "to_dict") else v for v in value]
            elif hasattr(value, "to_dict"):
                data[f.name] = value.to_dict()
            else:
                data[f.name] = value
        return data


@dataclass(frozen=True)
class DecisionsEvent:
    """The goal planner's ``decisions`` event: every target's decision, as they are made."""

    decisions: tuple[DecisionTrace, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON form of the event."""
        return {"decisions": [d.to_dict() for d in self.decisions]}


@dataclass(frozen=True)
class RiskEvent:
    """The goal planner's ``risk`` event: every move's risk check."""

    checks: tuple[RiskCheck, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON form of the event."""
        return {"checks": [c.to_dict() for c in self.checks]}


_HEADER = ("config", "planner_kind", "request", "scene")
_STEP_PARTS = ("ope", "urp", "goal", "decisions", "stack", "risk", "vetoes", "planner")
# The goal planner's OPE runs on the moves it checks, after the rest; its trace has always listed
# OPE last, and the JSON keeps that order.
_GOAL_PARTS = (
    "urp", "goal", "decisions", "stack", "companions", "risk", "vetoes", "planner",
    "calibration", "ope",
)  # fmt: skip


@dataclass(frozen=True)
class PlanTrace:
    """Everything retrieved and decided on the way to a plan (see the module docstring).

    Attributes:
        config: The system's configuration (``conceptbot``, ``urp``, ``saycan``, ...).
        planner_kind: ``goal`` or ``steps`` (ConceptBot only).
        request: The request as planned (checked and trimmed).
        scene: The scene's name.
        ope: OPE's properties and retrievals.
        urp: URP's keywords, relations, reasoning and commands.
        goal: The goal planner's targets.
        decisions: The goal planner's per-target decisions.
        stack: The goal planner's pile order.
        risk: The goal planner's risk checks, one per move considered.
        companions: The goal planner's things-used-together checks: whether what a need's target
            took goes with something else ("the toothpaste with the toothbrush"; None: no need
            target had a candidate to ask about).
        vetoes: Moves dropped because their evidence names a hazard for the recipient, or because
            their risk decision could not be made (both planners; None: no move was vetoed).
        planner: How the steps were chosen.
        calibration: The goal planner's conformal thresholds: whose they are, and whether they were
            fitted for the model that planned.
        household: A household planner's part; its keys are written at the top level of the JSON
            after the others (``objects``, ``risk``, ..., as :class:`HouseholdTrace` lists them).

    Raises:
        ValueError: A household part beside the tabletop planners' parts (their JSON keys would clash).
    """

    config: str | None = None
    planner_kind: str | None = None
    request: str | None = None
    scene: str | None = None
    ope: OPETrace | None = None
    urp: URPTrace | None = None
    goal: GoalTrace | None = None
    decisions: tuple[DecisionTrace, ...] | None = None
    stack: StackTrace | None = None
    risk: tuple[RiskCheck, ...] | None = None
    companions: tuple[CompanionCheck, ...] | None = None
    vetoes: tuple[Veto, ...] | None = None
    planner: PlannerSummary | None = None
    calibration: CalibrationNote | None = None
    household: HouseholdTrace | None = None

    def __post_init__(self) -> None:
        if self.household is None:
            return
        tabletop = [n for n in (*_STEP_PARTS, "ope", "goal") if getattr(self, n) is not None]
        if tabletop:
            raise ValueError(f"a household trace has no tabletop parts: {', '.join(sorted(set(tabletop)))}")

    def to_dict(self) -> dict[str, Any]:
        """The ``trace`` object of ``conceptbot plan --json``: the set parts, a household part's
        keys last."""
        data: dict[str, Any] = {}
        for name in (*_HEADER, *(_STEP_PARTS if self.goal is None else _GOAL_PARTS)):
            value = getattr(self, name)
            if value is None:
                continue
            if isinstance(value, tuple):
                data[name] = [part.to_dict() for part in value]
            elif isinstance(value, str):
                data[name] = value
            else:
                data[name] = value.to_dict()
        if self.household is not None:
            data.update(self.household.to_dict())
        return data
