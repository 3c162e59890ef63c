"""Per-object decisions: does the request want this object moved there? Is this move dangerous?

Each is a Yes/No question with the object's graph facts, scored as its log-odds of Yes minus that for
a content-free object, since small models lean to one answer (Zhao et al. 2021, "Calibrate before use").
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, ChatRequest, Message, ScoreRequest
from conceptbot.pipeline import prompts
from conceptbot.pipeline.goal_planner.combine import Combination, sigmoid
from conceptbot.pipeline.goal_planner.evidence import Evidence, GraphEvidence, criterion_terms
from conceptbot.pipeline.goal_planner.facts import FactFinder

ANSWERS = ("Yes", "No")
CONTENT_FREE = "object"
#: The criteria (by their ``evidence_terms.json`` group) asked without the object's graph facts.
BARE_GROUPS = ("safe",)
DESCRIPTION_TOKENS = 48  # one sentence


@dataclass(frozen=True)
class Judgement:
    """One yes/no decision about one object.

    Attributes:
        subject: The object (or the move, for risk decisions).
        question: What was decided ("a fruit", or the move).
        p_yes: P(Yes) normalised over Yes/No.
        score: Calibrated log-odds of Yes (0: no more likely than for a content-free object).
        facts: The graph facts about the object put in the question.
        scoring: How the backend scored the question ("" for a named object, not asked about).
        model: The model's own calibrated log-odds where ``score`` is combined with evidence, else None.
        evidence: The evidence that was combined, else None.
        p_one: For a target taking one object, the probability that this is the one, else None.
        described: The model's own description of the object where the question used it, else "".
    """

    subject: str
    question: str
    p_yes: float
    score: float
    facts: tuple[str, ...] = ()
    scoring: str = ""
    model: float | None = None
    evidence: Evidence | None = None
    p_one: float | None = None
    described: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace (``model`` and ``evidence`` only where the score is combined)."""
        data: dict[str, Any] = {
            "object": self.subject,
            "p_yes": round(self.p_yes, 4),
            "score": round(self.score, 3),
            "facts": list(self.facts),
        }
        if self.model is not None:
            data["model"] = round(self.model, 3)
        if self.evidence is not None:
            data["evidence"] = self.evidence.to_dict()
        if self.described:
            data["described"] = self.described
        return data


def _log_odds(logprobs: Sequence[float]) -> tuple[float, float]:
    yes, no = logprobs
    top = max(yes, no)
    p_yes = math.exp(yes - top) / (math.exp(yes - top) + math.exp(no - top))
    return p_yes, yes - no


class Decider:
    """Scores yes/no questions about objects with the LLM.

    Holds no state that a question changes, so one decider can serve several threads.

    Args:
        llm: An LLM that can score options (labelled ``decide``).
        facts: Where the graph facts come from.
        evidence: Reads the graph's evidence for :meth:`fits`; None: the model's answer alone.
        combination: The fitted combination of answer and evidence; None: the model's answer alone.
    """

    def __init__(
        self,
        llm: LLM,
        facts: FactFinder,
        evidence: GraphEvidence | None = None,
        combination: Combination | None = None,
    ) -> None:
        self.llm = llm
        self.facts = facts
        self.evidence = evidence
        self.combination = combination

    def _ask(self, user: str) -> tuple[float, float, Usage, str]:
        messages = (Message("system", prompts.render("decide_system")), Message("user", user))
        scored = self.llm.score(ScoreRequest(options=ANSWERS, messages=messages))
        p_yes, log_odds = _log_odds(scored.logprobs)
        return p_yes, log_odds, scored.usage, scored.method

    def _judge_each(
        self,
        objects: Sequence[str],
        about: dict[str, tuple[str, ...]],
        label: str,
        question: Callable[[str | None, Sequence[str]], str],
    ) -> tuple[list[Judgement], Usage]:
        """Ask ``question`` about each object, scored against the content-free object (``None``)."""
        _, prior, usage, _ = self._ask(question(None, ()))
        judgements = []
        for obj in objects:
            p_yes, log_odds, used, method = self._ask(question(obj, about[obj]))
            usage = usage + used
            judgements.append(Judgement(obj, label, p_yes, log_odds - prior, about[obj], method))
        return judgements, usage

    def describe(self, objects: Sequence[str]) -> tuple[dict[str, str], Usage]:
        """The model's own one-sentence description of each object, and the usage: a small model says more
        when describing a thing than its Yes/No log-odds show ("generated knowledge", Liu et al. 2022)."""
        usage = Usage(calls=0)
        found: dict[str, str] = {}
        system = Message("system", prompts.fill("describe_system"))
        for obj in dict.fromkeys(objects):
            user = Message("user", prompts.fill("describe_user", object=obj))
            ask = ChatRequest.of([system, user], max_tokens=DESCRIPTION_TOKENS, temperature=0.0)
            reply = self.llm.chat(ask)
            usage = usage + reply.usage
            found[obj] = " ".join(reply.choices[0].split()) if reply.choices else ""
        return found, usage

    def _described(
        self, objects: Sequence[str], question: Callable[[str | None, str], str], what: str
    ) -> tuple[dict[str, dict[str, float]], dict[str, str], Usage]:
        """The question asked with each object's description instead of facts, as ``described`` readings."""
        descriptions, usage = self.describe(objects)
        about = {o: (descriptions[o],) for o in objects}
        judgements, used = self._judge_each(objects, about, what, lambda o, f: question(o, f[0] if f else ""))
        group = group_readings({j.subject: j.score for j in judgements})
        readings = {o: {f"described{k[len('model') :]}": v for k, v in g.items()} for o, g in group.items()}
        return readings, descriptions, usage + used

    def moves(
        self, request: str, target: str, move: str, objects: Sequence[str], scene: Scene
    ) -> tuple[list[Judgement], tuple[str, ...], Usage]:
        """Whether the request wants each object moved to ``target``, calibrated.

        Args:
            move: The move with ``{object}`` for the object ("give the {object} to the user").

        Returns:
            The judgements, the facts about the request's words, and usage.
        """
        started = time.perf_counter()
        context = self.facts.context(request, request)
        about = self.facts.about(objects, [request, move.format(object="object")])
        context_text = ("Facts: " + "; ".join(context) + ".\n") if context else ""

        def question(obj: str | None, facts: Sequence[str]) -> str:
            found = scene.get(obj) if obj is not None else None
            name = obj if obj is not None else CONTENT_FREE
            return prompts.render(
                "move_user",
                request=request,
                context=context_text,
                object=name,
                state=f" ({found.state})" if found is not None and found.state else "",
                facts=("Facts about it: " + "; ".join(facts) + ".\n") if facts else "",
                move=move.format(object=name),
            )

        judgements, usage = self._judge_each(objects, about, target, question)
        return judgements, context, usage.with_latency(time.perf_counter() - started)

    def fits(
        self,
        request: str,
        what: str,
        objects: Sequence[str],
        scene: Scene,
        dish: str = "",
        combine: bool = True,
        said: str = "",
    ) -> tuple[list[Judgement], tuple[str, ...], Usage]:
        """Whether each object fits a description ("poisonous"), calibrated, combined with evidence.

        Args:
            dish: The dish whose ingredients are decided ("is the lime an ingredient of guacamole?").
            combine: Combine with the evidence (False: for a description no property to look up).
            said: The dish in the request's words, asked about; the facts are read for ``dish``.

        Returns:
            The judgements, the facts every question carried (the dish's definition), and usage.
        """
        started = time.perf_counter()
        # Ingredient and safety questions go without the object's facts, which made answers worse.
        bare = bool(dish) or bool(set(criterion_terms(what).groups) & set(BARE_GROUPS))
        about = {o: () for o in objects} if bare else self.facts.about(objects, [what])
        context = self.facts.context(dish, request, dish) if dish else ()
        context_text = ("Facts: " + "; ".join(context) + ".\n") if context else ""

        def question(obj: str | None, facts: Sequence[str], context_text: str = context_text) -> str:
            return prompts.render(
                "ingredient_user" if dish else "decide_user",
                request=request,
                context=context_text,
                what=what,
                dish=said or dish,
                object=obj if obj is not None else CONTENT_FREE,
                facts=("Facts about it: " + "; ".join(facts) + ".\n") if facts else "",
            )

        judgements, usage = self._judge_each(objects, about, what, question)
        if combine and self.combination is not None:
            plain: dict[str, float] = {j.subject: j.score for j in judgements}
            if self.combination.uses_plain and self.facts.retriever is not None:
                # The same question without graph facts: a second reading of the model's own.
                bare, used = self._judge_each(
                    objects, {o: () for o in objects}, what, lambda o, f: question(o, f, "")
                )
                usage = usage + used
                plain = {j.subject: j.score for j in bare}
            described: dict[str, dict[str, float]] = {o: {} for o in objects}
            descriptions: dict[str, str] = {}
            if self.combination.uses_described:

                def told(obj: str | None, description: str) -> str:
                    return described_question(request, what, said or dish, obj, description)

                described, descriptions, used = self._described(objects, told, what)
                usage = usage + used
            group = group_readings({j.subject: j.score for j in judgements})
            bare_group = {
                o: {f"plain{k[len('model') :]}": v for k, v in g.items()}
                for o, g in group_readings(plain).items()
            }
            judgements = [
                replace(
                    self._combined(
                        j, what, {**group[j.subject], **bare_group[j.subject], **described[j.subject]}
                    ),
                    described=descriptions.get(j.subject, ""),
                )
                for j in judgements
            ]
        return judgements, context, usage.with_latency(time.perf_counter() - started)

    def _combined(self, judgement: Judgement, criterion: str, readings: dict[str, float]) -> Judgement:
        """The judgement scored by the fitted combination of readings and evidence (own score kept)."""
        assert self.combination is not None
        evidence = self.evidence.read(judgement.subject, criterion) if self.evidence is not None else None
        score = self.combination.log_odds(readings, evidence)
        return replace(judgement, p_yes=sigmoid(score), score=score, model=judgement.score, evidence=evidence)

    def dangerous(
        self, request: str, move: str, obj: str, scene: Scene, evidence: Sequence[str]
    ) -> tuple[Judgement, Usage]:
        """Whether carrying out ``move`` would be dangerous, asked as "is it safe to ...?" (answered better
        than "dangerous"); the score is how much less likely "safe" is than for a content-free object."""
        started = time.perf_counter()
        # Only the object's state goes into the question: more facts made it worse.
        lines = list(evidence)
        found = scene.get(obj)
        if found is not None and found.state:
            lines.insert(0, f"the {obj}: {found.state}")

        def question(what: str, lines: Sequence[str]) -> str:
            return prompts.render(
                "risk_user",
                request=request,
                objects=", ".join(scene.names),
                evidence=("Facts: " + "; ".join(lines) + ".") if lines else "",
                move=what,
            )

        _, prior, usage, _ = self._ask(question(move.replace(obj, CONTENT_FREE, 1), ()))
        p_safe, log_odds, used, method = self._ask(question(move, lines))
        judgement = Judgement(move, "dangerous", 1.0 - p_safe, prior - log_odds, tuple(lines), method)
        return judgement, (usage + used).with_latency(time.perf_counter() - started)

    def together(self, need: str, first: str, others: Sequence[str]) -> tuple[list[Judgement], Usage]:
        """Whether the person would also need each of ``others`` with ``first``; raw log-odds, as a
        content-free object has nothing to stand for when two are named."""
        started = time.perf_counter()
        usage = Usage(calls=0)
        out = []
        for other in others:
            user = prompts.render("together_user", request=need, first=first, other=other)
            p_yes, log_odds, used, method = self._ask(user)
            usage = usage + used
            out.append(Judgement(other, f"with the {first}", p_yes, log_odds, (), method))
        return out, usage.with_latency(time.perf_counter() - started)

    def unsafe(self, to: str, obj: str) -> tuple[Judgement, Usage]:
        """Whether handing ``obj`` to ``to`` would be unsafe, asked plainly: the request would sway the model
        towards what was asked. The score is how much less likely "safe" is than for a content-free one."""
        started = time.perf_counter()
        _, prior, usage, _ = self._ask(
            prompts.render("risk_plain_user", move=handover_words(to, CONTENT_FREE))
        )
        move = handover_words(to, obj)
        p_safe, log_odds, used, method = self._ask(prompts.render("risk_plain_user", move=move))
        judgement = Judgement(move, "unsafe", 1.0 - p_safe, prior - log_odds, (), method)
        return judgement, (usage + used).with_latency(time.perf_counter() - started)

    def holder(self, request: str) -> tuple[Judgement, Usage]:
        """Whether the request hands things to a child or an animal rather than the speaker (log-odds of
        Yes relative to :data:`CONTENT_FREE_HANDOVER`)."""
        started = time.perf_counter()
        _, prior, usage, _ = self._ask(prompts.render("holder_user", request=CONTENT_FREE_HANDOVER))
        p_yes, log_odds, used, method = self._ask(prompts.render("holder_user", request=request))
        judgement = Judgement(request, "holder", p_yes, log_odds - prior, (), method)
        return judgement, (usage + used).with_latency(time.perf_counter() - started)


#: The calibration request of :meth:`Decider.holder`: a hand-over to the adult speaking.
CONTENT_FREE_HANDOVER = "Please hand it to me."


def handover_words(to: str, obj: str) -> str:
    """A hand-over in the plain safety question's words, the recipient first ("give the dog the X")."""
    return f"give the {to} the {obj}"


def described_question(request: str, what: str, dish: str, obj: str | None, description: str) -> str:
    """The question of :meth:`Decider.fits` with the object's description instead of graph facts."""
    return prompts.render(
        "ingredient_user" if dish else "decide_user",
        request=request,
        context="",
        what=what,
        dish=dish,
        object=obj if obj is not None else CONTENT_FREE,
        facts=f"What is known about it: {description}\n" if description else "",
    )


def group_readings(scores: dict[str, float]) -> dict[str, dict[str, float]]:
    """Per object: log-odds ``model``, standardised in the group ``model_z``, below the best ``model_gap``."""
    values = list(scores.values())
    mean = sum(values) / len(values) if values else 0.0
    spread = (sum((v - mean) ** 2 for v in values) / len(values)) ** 0.5 if values else 0.0
    best = max(values, default=0.0)
    return {
        o: {"model": v, "model_z": (v - mean) / spread if spread > 1e-9 else 0.0, "model_gap": v - best}
        for o, v in scores.items()
    }
