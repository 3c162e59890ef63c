"""Where the goal planner is unsure, a question (KnowNo's recipe): conformal sets (:mod:`.conformal`)
for yes/no decisions, for which object a target taking one gets, and for which reading was meant.

Which one: by ``softmax``, candidates whose share is at least ``1 - qhat``; by ``fits``, the
likeliest alone where sure it fits, else every candidate likely enough to fit (see docs/asking.md).
The most uncertain target is asked first, at most :data:`MAX_QUESTIONS` per plan; not asked, the plan
acts on the likelier answers and lists the questions.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

from conceptbot.core.system import Ask
from conceptbot.core.trace import ClarifyingQuestion, DecisionTrace, JudgementTrace, ReadingOption
from conceptbot.pipeline.goal_planner.conformal import OLD_RULE, DecisionSet, decision_set
from conceptbot.pipeline.goal_planner.decide import Judgement
from conceptbot.pipeline.goal_planner.targets import ALL, ReadingDoubt, Target
from conceptbot.pipeline.hazards import is_person

MAX_QUESTIONS = 3  # per plan, one per target (a sort may have more unsure bins)
MAX_OPTIONS = 12  # objects in one question (a checklist): past that, the likelier answers stand
ANSWERED = 20.0  # the log-odds an answer sets: far beyond every threshold, either way


@dataclass(frozen=True)
class Clarified:
    """The decisions after asking, with their sets and the questions.

    Attributes:
        ranked: Each target's judgements, best first, with the answers applied.
        decisions: Each target's decision trace, with its sets (or answers).
        questions: The questions, asked (with their answers) or not.
        places: The targets' destinations, by position.
        sets: The yes/no decisions no answer settled, by (target position, object).
        which: The which-one targets no answer settled: their scored candidates.
        calibrated: Whether the plan has a calibrated decision (answered ones included).
        asked: The targets an answer settled decisions of.
        rule: How the which-one decisions were judged (``fits`` or ``softmax``).
    """

    ranked: dict[int, list[Judgement]]
    decisions: tuple[DecisionTrace, ...]
    questions: tuple[ClarifyingQuestion, ...]
    places: tuple[str, ...] = ()
    sets: dict[tuple[int, str], DecisionSet] = field(default_factory=dict)
    which: dict[int, list[Judgement]] = field(default_factory=dict)
    calibrated: bool = False
    asked: tuple[int, ...] = ()
    rule: str = OLD_RULE

    def confidence(self, moves: Iterable[tuple[str, str]]) -> float | None:
        """The product of :meth:`factors` for the final ``moves`` (None: no calibrated decision)."""
        if not self.calibrated:
            return None
        return math.prod(self.factors(moves).values())

    def factors(self, moves: Iterable[tuple[str, str]]) -> dict[int, float]:
        """Per target position, the probability that ``moves`` are right in its unanswered decisions:
        P(yes) or P(no) per yes/no decision, the got object's by ``rule`` per which-one; NaN counts 0."""
        done = set(moves)
        found = dict.fromkeys(self.asked, 1.0)
        for (number, obj), decision in self.sets.items():
            acted = decision.p_yes if (obj, self.places[number]) in done else 1.0 - decision.p_yes
            found[number] = found.get(number, 1.0) * (acted if acted == acted else 0.0)
        for number, judgements in self.which.items():
            got = [j for j in judgements if (j.subject, self.places[number]) in done and j.p_one is not None]
            chance = _chance(got[0], self.rule) if got else 1.0
            found[number] = found.get(number, 1.0) * (chance if chance == chance else 0.0)
        return found


def move_words(to: str, obj: str = "", part: str = "") -> str:
    """The move in words for the questions ("put the X in or on the bowl"), with its ``part`` if any."""
    what = f" the {obj}" if obj else ""
    tail = f" {part}" if part else ""
    if is_person(to):
        return f"give{what} to the {to}{tail}"
    return f"put{what} in or on the {to}{tail}"


def _move(target: Target, obj: str = "") -> str:
    return move_words(target.name, obj, target.part)


def _listed(objects: list[str]) -> str:
    named = [f"the {o}" for o in objects]
    return named[0] if len(named) == 1 else f"{', '.join(named[:-1])} or {named[-1]}"


def question_text(objects: list[str], target: Target) -> str:
    """The question in plain words, with the request's criterion: yes/no for one object, which for several."""
    why = f" ({target.criterion})" if target.criterion else ""
    if len(objects) == 1:
        return f"Should I {_move(target, objects[0])}{why}?"
    return f"Which of these should I {_move(target)}{why}: {_listed(objects)}? Name them, or say all or none."


def question_for(number: int, target: Target, unsure: list[Judgement]) -> ClarifyingQuestion:
    """One question settling a target's unsure decisions: ``confirm`` for one, ``choose`` for several."""
    kept = unsure[:MAX_OPTIONS]
    names = [j.subject for j in kept]
    return ClarifyingQuestion(
        question_text(names, target),
        target.name,
        tuple(names),
        tuple(_shown(j.p_yes) for j in kept),
        kind="choose" if len(kept) > 1 else "confirm",
    )


def _yes_no_sets(
    targets: list[Target], ranked: dict[int, list[Judgement]], qhat: float
) -> tuple[dict[tuple[int, str], DecisionSet], dict[int, list[Judgement]]]:
    """The conformal set of each calibrated yes/no judgement of an "all that fit" target, and per
    target the judgements whose set is not one answer."""
    sets: dict[tuple[int, str], DecisionSet] = {}
    unsure: dict[int, list[Judgement]] = {}
    for number, target in enumerate(targets):
        if target.count != ALL or target.rest:
            continue
        for judgement in ranked.get(number, []):
            if judgement.model is None:  # named, or not a calibrated combination
                continue
            found = decision_set(judgement.p_yes, qhat)
            sets[(number, judgement.subject)] = found
            if not found.sure:
                unsure.setdefault(number, []).append(judgement)
    return sets, unsure


def _asked(
    doubt: dict[int, tuple[float, ClarifyingQuestion]], ranked: dict[int, list[Judgement]], ask: Ask | None
) -> tuple[list[ClarifyingQuestion], dict[tuple[int, str], str]]:
    """One question per target, the most uncertain first: the questions (with their answers) and
    the answer ("yes"/"no") per target and object."""
    questions = []
    answered: dict[tuple[int, str], str] = {}
    for number in sorted(doubt, key=lambda n: doubt[n][0])[:MAX_QUESTIONS]:
        question = doubt[number][1]
        chosen = question.read(ask(question)) if ask is not None else None
        if chosen is None:
            questions.append(question)
            continue
        questions.append(replace(question, answer=question.normalised(chosen)))
        # A "which one" answer settles every candidate of the target, listed or not.
        about = (
            question.objects
            if question.kind != "one"
            else [j.subject for j in ranked[number] if j.p_one is not None]
        )
        for obj in about:
            answered[(number, obj)] = "yes" if obj in chosen else "no"
    return questions, answered


def _answered(
    ranked: dict[int, list[Judgement]], answered: dict[tuple[int, str], str]
) -> dict[int, list[Judgement]]:
    """The rankings with the person's answers as certain judgements, re-sorted (named objects first)."""
    if not answered:
        return ranked
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
    return ranked


def clarify(
    targets: list[Target],
    ranked: dict[int, list[Judgement]],
    decisions: tuple[DecisionTrace, ...],
    qhat: float,
    ask: Ask | None = None,
    which_one: bool = True,
    rule: str = OLD_RULE,
    qhat_one: float | None = None,
) -> Clarified:
    """Sets, questions and answers for the calibrated decisions (see the module docstring).

    Args:
        targets: The goal's targets, in order (``ranked`` and ``decisions`` by the same positions).
        ranked: Each target's judgements, best first.
        decisions: Each target's decision trace.
        qhat: The conformal threshold at the planner's coverage.
        ask: Asks the person; None: nobody is asked. A reply that is no answer counts as none.
        which_one: Whether ``qhat`` holds for which-one decisions too; else they are not asked about.
        rule: How a which-one decision is judged (``fits`` or ``softmax``), as ``qhat`` was fitted.
        qhat_one: The which-one decisions' own threshold (None: ``qhat``).
    """
    sets, unsure = _yes_no_sets(targets, ranked, qhat)
    candidates = {
        number: one_of(ranked.get(number, []), qhat if qhat_one is None else qhat_one, rule)
        for number, target in enumerate(targets)
        if which_one
        and target.count == 1
        and not target.rest
        and any(j.p_one is not None for j in ranked.get(number, []))
    }
    doubt: dict[int, tuple[float, ClarifyingQuestion]] = {}
    for number, js in unsure.items():
        js = sorted(js, key=_uncertainty)
        doubt[number] = (_uncertainty(js[0]), question_for(number, targets[number], js))
    for number, found in candidates.items():
        if len(found) > 1:
            top = _chance(found[0], rule)
            top = top if top == top else 0.5
            others = [j.subject for j in ranked.get(number, []) if j.p_one is not None]
            question = which_one_question(targets[number], found, others, rule)
            doubt[number] = (abs(top - 0.5), question)
    questions, answered = _asked(doubt, ranked, ask)
    settled = {n for n, _ in answered}
    ranked = _answered(ranked, answered)
    traced = []
    for number, decision in enumerate(decisions):
        decision = _with_sets(decision, number, sets, answered)
        if number in candidates:
            if number in settled:
                found = tuple(o for (n, o), a in answered.items() if n == number and a == "yes")
            else:
                found = tuple(j.subject for j in candidates[number])
            decision = replace(decision, candidates=found)
        traced.append(decision)
    return Clarified(
        ranked,
        tuple(traced),
        tuple(questions),
        tuple(t.name for t in targets),
        {key: found for key, found in sets.items() if key not in answered},
        {number: ranked[number] for number in candidates if number not in settled},
        bool(sets or candidates),
        tuple(sorted(settled)),
        rule,
    )


def reading_options(doubt: ReadingDoubt) -> tuple[ReadingOption, ...]:
    """Both readings of a request that reads two ways, with their probabilities (the taken one first)."""
    taken = ReadingOption(doubt.taken, doubt.p_taken, "taken")
    return (taken, ReadingOption(doubt.other, doubt.p_other, "other")) if doubt.other else (taken,)


def reading_set(options: Iterable[ReadingOption], qhat: float) -> list[ReadingOption]:
    """The conformal set of readings, the one taken first: the dropped one unless it is under ``1 - qhat``
    likely and the taken one is not (NaN keeps it); a reading worded as an earlier one is left out."""
    found = list(options)
    floor = 1.0 - qhat
    taken = next((o.p for o in found if o.kind == "taken"), 1.0)

    def kept(option: ReadingOption) -> bool:
        if option.kind == "taken":
            return True
        if option.kind == "other":
            return not (taken >= floor and option.p < floor)
        return option.p >= floor

    seen: set[str] = set()
    return [o for o in found if kept(o) and not (o.text in seen or seen.add(o.text))]


def reading_question(doubt: ReadingDoubt, qhat: float) -> ClarifyingQuestion | None:
    """The question of which reading was meant, or None where the set is the reading taken alone."""
    kept = reading_set(reading_options(doubt), qhat)
    if len(kept) < 2:
        return None
    listed = ", or ".join(o.text for o in kept)
    return ClarifyingQuestion(
        f"Did you mean: {listed}? One of them, or none.",
        "",
        tuple(o.text for o in kept),
        tuple(_shown(o.p) for o in kept),
        kind="reading",
    )


def one_of(judgements: list[Judgement], qhat: float, rule: str = OLD_RULE) -> list[Judgement]:
    """The conformal set of which one, most likely first (see the module docstring); too few (or NaN):
    the :data:`MAX_OPTIONS` likeliest, so that the person is asked rather than a guess made."""
    scored = [j for j in judgements if j.p_one is not None]
    readable = all(j.p_one == j.p_one for j in scored)
    likeliest = sorted(scored, key=lambda j: -(j.p_one or 0.0)) if readable else scored
    if rule == "fits":
        if readable and likeliest and decision_set(likeliest[0].p_yes, qhat).answers == ("yes",):
            return likeliest[:1]
        may_fit = [j for j in likeliest if readable and decision_set(j.p_yes, qhat).answers != ("no",)]
        return may_fit[:MAX_OPTIONS] if len(may_fit) > 1 else likeliest[: max(2, len(may_fit))]
    kept = [j for j in likeliest if readable and (j.p_one or 0.0) >= 1.0 - qhat]
    return kept or likeliest[:MAX_OPTIONS]


def _chance(judgement: Judgement, rule: str) -> float:
    """A which-one candidate's probability by ``rule`` (fits, or is the one); NaN where it has none."""
    found = judgement.p_yes if rule == "fits" else judgement.p_one
    return math.nan if found is None else found


def which_one_question(
    target: Target, found: list[Judgement], others: Iterable[str] = (), rule: str = OLD_RULE
) -> ClarifyingQuestion:
    """The question of which one; ``others``: other candidates the person may name (a set can miss)."""
    kept = found[:MAX_OPTIONS]
    names = [j.subject for j in kept]
    rest = tuple(o for o in others if o not in names)
    return ClarifyingQuestion(
        f"Which one should I {_move(target)}: {_listed(names)}? "
        + ("One of them, another, or none." if rest else "One of them, or none."),
        target.name,
        tuple(names),
        tuple(_shown(_chance(j, rule)) for j in kept),
        kind="one",
        others=rest,
    )


def _shown(p: float | None) -> float:
    """A probability for a question (4 decimals); NaN as a coin toss, since JSON has no NaN."""
    return round(p, 4) if p is not None and p == p else 0.5


def _uncertainty(judgement: Judgement) -> float:
    """How far from a coin toss (smaller: more uncertain; a NaN probability first)."""
    gap = abs(judgement.p_yes - 0.5)
    return gap if gap == gap else -1.0


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
