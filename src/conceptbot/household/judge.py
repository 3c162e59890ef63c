"""Whether carrying out an instruction would be dangerous: a scored yes/no decision.

The planning call judges and plans at once, from the objects' danger ratings; a small model then
refuses ordinary chores whose objects are rated risky (a mug, a tomato). The judge asks about the
outcome instead, "would carrying out this instruction be dangerous?", and reads the
log-probabilities of the answers rather than the model's first token. A 1.5B model's answer moves
with any rewording, so the judge asks the question four ways (:data:`QUESTIONS`) and adds the
log-odds of "dangerous":

* with the knowledge graph's facts and OPE's risk analysis as evidence, ten examples from other
  homes in the system prompt;
* the same question with the instruction and scene alone;
* the same question with ten other examples;
* the question turned round, "is it an ordinary, harmless chore?" (a "No" counts as dangerous),
  which cancels the model's lean towards answering Yes.

On the 154 detailed dev tasks the request check lets through, the first two alone separate unsafe
from safe with AUC 0.89, all four with 0.93; on the 125 that nothing else refuses, 0.87 and 0.90
(``docs/notes/2026-12-01-safeagentbench-v4-four-questions-and-request-check.md``).
The ConceptBot household planner does not refuse on the sum: it asks the two questions whose
readings the fitted harm judgement weighs (:data:`~conceptbot.household.harm.READINGS`; the other
two added nothing there). The sum of all four and its threshold remain the judge's own verdict,
for the benchmarks that measure the judge alone.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from conceptbot.core.scene import HouseScene
from conceptbot.core.trace import HarmVerdict
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline import prompts

PROMPTS = "conceptbot.household.prompts"
ANSWERS = ("Yes", "No")


@dataclass(frozen=True)
class Question:
    """One way the judge asks its question.

    Attributes:
        name: The reading's name in the trace.
        system: The system prompt's file (in ``household/prompts``).
        user: The user message's file.
        evidence: Whether ConceptBot's evidence is shown (a question with evidence and none to show
            reads like the same question without).
        danger: The answer that means "dangerous".
    """

    name: str
    system: str
    user: str = "household_judge_user"
    evidence: bool = False
    danger: str = "Yes"


QUESTIONS: tuple[Question, ...] = (
    Question("informed", "household_judge_system", evidence=True),
    Question("blind", "household_judge_system"),
    Question("other_examples", "household_judge_system_examples2"),
    Question("ordinary", "household_judge_system_ordinary", "household_judge_user_ordinary", danger="No"),
)
"""The questions the judge adds up (v4)."""

TWO_READINGS = QUESTIONS[:2]
"""The v3 judge: the first question with evidence and without (threshold +3.16 on dev)."""

# The judge's own verdict (not the planner's decision, which the fitted judgement makes): refuse at
# a score (the four readings' log-odds of "dangerous", added) at or above this. Chosen on
# the dev split with everything else ConceptBot refuses counted (the instruction's and the plan's
# spills and throws, household/outcomes.py, and the plain planner's own refusals): the best
# harmonic mean on the 200 detailed dev tasks, 82.7% (10% false rejection, 88% unsafe rejection),
# in the middle of +3.86 to +4.09, where it stays within 0.6 points (docs/safeagentbench.md). The
# 1.5B model leans to "dangerous" on three of the four questions, so the threshold is what
# separates.
THRESHOLD = 4.0


def safety_text() -> str:
    """The safety instruction both planners share (what counts as dangerous)."""
    return prompts.render("household_safety", PROMPTS).strip()


class HarmJudge:
    """Asks the LLM whether carrying out an instruction would be dangerous.

    Args:
        llm: An LLM that can score options.
        threshold: Refuse at a summed log-odds of "dangerous" at or above this.
        questions: The questions whose readings are added.
        contexts: An LLM per system prompt file, where one should have its own context (with
            llama.cpp, a context keeps its system prompt evaluated from one task to the next);
            ``llm`` for the rest.
    """

    def __init__(
        self,
        llm: LLM,
        threshold: float = THRESHOLD,
        questions: Sequence[Question] = QUESTIONS,
        contexts: Mapping[str, LLM] | None = None,
    ) -> None:
        if not questions:
            raise ValueError("the judge needs at least one question")
        self.llm = llm
        self.threshold = threshold
        self.questions = tuple(questions)
        self.contexts = dict(contexts or {})

    def messages(
        self, question: Question, instruction: str, scene: HouseScene, evidence: str
    ) -> tuple[Message, Message]:
        """``question`` about ``instruction``, with ``evidence`` (may be empty) before it."""
        system = prompts.render(question.system, PROMPTS, safety=safety_text())
        user = prompts.render(
            question.user,
            PROMPTS,
            room=scene.room,
            objects=", ".join(scene.objects),
            evidence=evidence.strip(),
            instruction=instruction,
        )
        return Message("system", system), Message("user", user)

    def reading(
        self, question: Question, instruction: str, scene: HouseScene, evidence: str = ""
    ) -> tuple[float, Usage]:
        """One reading: log P(dangerous) - log P(not), with ``evidence`` (may be empty)."""
        llm = self.contexts.get(question.system, self.llm)
        scored = llm.score(
            ScoreRequest(options=ANSWERS, messages=self.messages(question, instruction, scene, evidence))
        )
        yes, no = scored.logprobs
        log_odds = yes - no if question.danger == "Yes" else no - yes
        return log_odds, scored.usage

    def judge(self, instruction: str, scene: HouseScene, evidence: str = "") -> tuple[HarmVerdict, Usage]:
        """The verdict on ``instruction`` in ``scene``: every question's reading, added.

        A question with evidence, asked when there is none, would repeat the same question without
        it: its reading is that one's, counted again (the score keeps one scale whether or not OPE
        rated anything; an abstract instruction names no object).
        """
        readings: dict[str, float] = {}
        by_prompt: dict[tuple[str, str, str], float] = {}
        usage = Usage(calls=0)
        for question in self.questions:
            shown = evidence if question.evidence else ""
            asked = (question.system, question.user, shown.strip())
            if asked not in by_prompt:
                by_prompt[asked], used = self.reading(question, instruction, scene, shown)
                usage = usage + used
            readings[question.name] = by_prompt[asked]
        return HarmVerdict(sum(readings.values()), self.threshold, readings), usage


#: The calibration outcome of :class:`OutcomeJudge`: a result with nothing in it to judge.
CONTENT_FREE_OUTCOME = ("nothing has changed",)


class OutcomeJudge:
    """Asks the LLM whether the state a plan leaves behind is dangerous or damaging, read from the
    simulated plan (:func:`~conceptbot.household.outcomes.plan_effects`) rather than from the
    request's words: "throw the newspaper in the bin" and "throw the vase" differ in what they
    leave, not in their verb.

    The reading is the log-odds of Yes minus that for a result where nothing changed, since a small
    model leans to one answer (Zhao et al. 2021, "Calibrate before use").

    Args:
        llm: An LLM that can score options.
    """

    def __init__(self, llm: LLM) -> None:
        self.llm = llm
        self._prior: dict[str, float] = {}

    def _ask(self, room: str, effects: Sequence[str]) -> tuple[float, Usage]:
        system = prompts.render("household_outcome_system", PROMPTS)
        user = prompts.render(
            "household_outcome_user", PROMPTS, room=room, effects="\n".join(f"- {e}" for e in effects)
        )
        scored = self.llm.score(
            ScoreRequest(options=ANSWERS, messages=(Message("system", system), Message("user", user)))
        )
        yes, no = scored.logprobs
        return yes - no, scored.usage

    def reading(self, scene: HouseScene, effects: Sequence[str]) -> tuple[float, Usage]:
        """Calibrated log-odds that leaving ``effects`` behind in ``scene`` is dangerous; a plan that
        changes nothing reads 0."""
        usage = Usage(calls=0)
        if scene.room not in self._prior:
            self._prior[scene.room], usage = self._ask(scene.room, CONTENT_FREE_OUTCOME)
        if not effects:
            return 0.0, usage
        log_odds, used = self._ask(scene.room, effects)
        return log_odds - self._prior[scene.room], usage + used
