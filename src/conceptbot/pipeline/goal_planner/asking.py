"""Where the goal planner is unsure, a question (issue 35; KnowNo's recipe): each calibrated yes/no
decision of a target that takes every object fitting it gets its conformal prediction set
(:mod:`.conformal`); a set with both answers is a question ("Should I put the lemon in or on the
bowl (an ingredient of hollandaise)?"), the most uncertain first, at most :data:`MAX_QUESTIONS`.
Asked (``ask`` given), the answer replaces the decision; not asked, the plan acts on the likelier
answer and lists the question.
The plan's confidence is the product of the probabilities of the answers it acts on (an answer
given counts as sure).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from conceptbot.core.system import Ask
from conceptbot.core.trace import ClarifyingQuestion, DecisionTrace, JudgementTrace
from conceptbot.pipeline.goal_planner.conformal import DecisionSet, decision_set
from conceptbot.pipeline.goal_planner.decide import Judgement
from conceptbot.pipeline.goal_planner.targets import ALL, Target
from conceptbot.pipeline.hazards import is_person

MAX_QUESTIONS = 3
ANSWERED = 20.0  # the log-odds an answer sets: far beyond every threshold, either way


@dataclass(frozen=True)
class Clarified:
    """The decisions after asking, with their sets, the questions and the plan's confidence."""

    ranked: dict[int, list[Judgement]]
    decisions: tuple[DecisionTrace, ...]
    questions: tuple[ClarifyingQuestion, ...]
    confidence: float | None


def is_sort(targets: list[Target]) -> bool:
    """Two or more targets each taking all that fit: each object goes where it fits best."""
    judged = [t for t in targets if not t.rest]
    return len(judged) >= 2 and all(t.count == ALL for t in judged)


def question_text(obj: str, target: Target) -> str:
    """The question in plain words, with the request's criterion: "Should I put the lemon in or on
    the bowl (an ingredient of hollandaise)?"."""
    if is_person(target.name):
        move = f"give the {obj} to the {target.name}"
    else:
        move = f"put the {obj} in or on the {target.name}"
    return f"Should I {move}{f' ({target.criterion})' if target.criterion else ''}?"


def clarify(
    targets: list[Target],
    ranked: dict[int, list[Judgement]],
    decisions: tuple[DecisionTrace, ...],
    qhat: float,
    limit: float,
    ask: Ask | None = None,
) -> Clarified:
    """Sets, questions and answers for the calibrated decisions (see the module docstring).

    Args:
        targets: The goal's targets, in order (``ranked`` and ``decisions`` by the same positions).
        ranked: Each target's judgements, best first.
        decisions: Each target's decision trace.
        qhat: The conformal threshold at the planner's coverage.
        limit: The combined score above which the planner takes an object (its ``combined``
            threshold), to tell the answer it acts on.
        ask: Asks the person; None: nobody is asked.
    """
    sets: dict[tuple[int, str], DecisionSet] = {}
    unsure: list[tuple[float, int, Judgement]] = []
    if not is_sort(targets):
        for number, target in enumerate(targets):
            if target.count != ALL or target.rest:
                continue
            for judgement in ranked.get(number, []):
                if judgement.model is None:  # named, or not a calibrated combination
                    continue
                found = decision_set(judgement.p_yes, qhat)
                sets[(number, judgement.subject)] = found
                if not found.sure:
                    unsure.append((abs(judgement.p_yes - 0.5), number, judgement))
    unsure.sort(key=lambda item: item[0])
    questions = []
    answered: dict[tuple[int, str], str] = {}
    for _, number, judgement in unsure[:MAX_QUESTIONS]:
        target = targets[number]
        question = ClarifyingQuestion(
            question_text(judgement.subject, target),
            judgement.subject,
            target.name,
            round(judgement.p_yes, 4),
        )
        reply = ask(question) if ask is not None else None
        answer = reply.strip().lower() if isinstance(reply, str) else None
        answer = answer if answer in ("yes", "no") else None
        questions.append(replace(question, answer=answer))
        if answer is not None:
            answered[(number, judgement.subject)] = answer
    if answered:
        ranked = dict(ranked)
        for number in {n for n, _ in answered}:
            changed = [
                replace(
                    j,
                    p_yes=1.0 if answered[(number, j.subject)] == "yes" else 0.0,
                    score=ANSWERED if answered[(number, j.subject)] == "yes" else -ANSWERED,
                )
                if (number, j.subject) in answered
                else j
                for j in ranked[number]
            ]
            named = [j for j in changed if j.model is None and j.scoring == ""]
            rest = [j for j in changed if j not in named]
            ranked[number] = named + sorted(rest, key=lambda j: -j.score)
    confidence = None
    if sets:
        confidence = 1.0
        for key, found in sets.items():
            if key in answered:
                continue
            acted_yes = next(j for j in ranked[key[0]] if j.subject == key[1]).score > limit
            acted = found.p_yes if acted_yes else 1.0 - found.p_yes
            confidence *= acted if acted == acted else 0.0  # unreadable (NaN): no confidence in it
    traced = tuple(_with_sets(decision, number, sets, answered) for number, decision in enumerate(decisions))
    return Clarified(ranked, traced, tuple(questions), confidence)


def _with_sets(
    decision: DecisionTrace, number: int, sets: dict[tuple[int, str], DecisionSet], answered: dict
) -> DecisionTrace:
    objects: list[JudgementTrace] = []
    for judgement in decision.objects:
        key = (number, judgement.object)
        if key in answered:
            objects.append(replace(judgement, answers=(answered[key],)))
        elif key in sets:
            objects.append(replace(judgement, answers=sets[key].answers))
        else:
            objects.append(judgement)
    return replace(decision, objects=tuple(objects)) if objects else decision
