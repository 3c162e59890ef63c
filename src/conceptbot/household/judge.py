"""Whether carrying out an instruction would be dangerous: a scored yes/no decision.

The planning call judges and plans at once, from the objects' danger ratings; a small model then
refuses ordinary chores whose objects are rated risky (a mug, a tomato). The judge asks one
question about the outcome instead: "would carrying out this instruction be dangerous?" (with ten
examples from other homes), and reads the log-probabilities of Yes and No. It reads them twice:
with the knowledge graph's facts and the risk analysis as evidence, and with the instruction and
scene alone, and adds the two log-odds. Each reading alone separates unsafe from safe dev tasks
about as well (AUC 0.83-0.84); their sum does better (0.88), and it keeps one scale whether or
not OPE rated anything (an abstract instruction names no object). The sum is a score, so the
refusal threshold is chosen on the dev split (``docs/safeagentbench.md``), not by the model's
first token.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from conceptbot.core.usage import Usage
from conceptbot.household.thor import HouseScene
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline import prompts

PROMPTS = "conceptbot.household.prompts"
ANSWERS = ("Yes", "No")
# Refuse at a score (two readings' log-odds of Yes, added) at or above this. Chosen on the dev split
# with everything else ConceptBot refuses counted (the plain planner's own refusals and the plan
# outcomes of household/outcomes.py): the middle of the plateau of the best harmonic mean on the 200
# detailed dev tasks, +3.14 to +3.18 (81.3%: 12% false rejection, 86% unsafe rejection). The 1.5B
# model leans to Yes (log-odds above 0 for almost every task), so the threshold is what separates,
# and steeply: +3.08 gives 16% / 88%, +3.20 12% / 82% (docs/safeagentbench.md).
THRESHOLD = 3.16


def safety_text() -> str:
    """The safety instruction both planners share (what counts as dangerous)."""
    return prompts.render("household_safety", PROMPTS).strip()


@dataclass(frozen=True)
class HarmVerdict:
    """The judge's decision.

    Attributes:
        log_odds: The score: the sum of the two readings' log P(Yes) - log P(No) for "would it be
            dangerous?".
        threshold: The refusal threshold it was compared with.
        with_evidence: The reading with ConceptBot's evidence.
        without_evidence: The reading with the instruction and scene alone.
    """

    log_odds: float
    threshold: float
    with_evidence: float = 0.0
    without_evidence: float = 0.0

    @property
    def refuse(self) -> bool:
        """Whether the instruction is refused."""
        return self.log_odds >= self.threshold

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace."""
        return {
            "log_odds": round(self.log_odds, 3),
            "with_evidence": round(self.with_evidence, 3),
            "without_evidence": round(self.without_evidence, 3),
            "threshold": self.threshold,
            "refuse": self.refuse,
        }


class HarmJudge:
    """Asks the LLM whether carrying out an instruction would be dangerous.

    Args:
        llm: An LLM that can score options.
        threshold: Refuse at log-odds of Yes at or above this.
        system_prompt: The system prompt's file (in ``household/prompts``), for tuning variants.
    """

    def __init__(
        self, llm: LLM, threshold: float = THRESHOLD, system_prompt: str = "household_judge_system"
    ) -> None:
        self.llm = llm
        self.threshold = threshold
        self.system_prompt = system_prompt

    def messages(self, instruction: str, scene: HouseScene, evidence: str) -> tuple[Message, Message]:
        """The question, with ``evidence`` (risk analysis and facts, may be empty) before it."""
        system = prompts.render(self.system_prompt, PROMPTS, safety=safety_text())
        user = prompts.render(
            "household_judge_user",
            PROMPTS,
            room=scene.room,
            objects=", ".join(scene.objects),
            evidence=evidence.strip(),
            instruction=instruction,
        )
        return Message("system", system), Message("user", user)

    def reading(self, instruction: str, scene: HouseScene, evidence: str = "") -> tuple[float, Usage]:
        """One reading: log P(Yes) - log P(No), with ``evidence`` (may be empty)."""
        scored = self.llm.score(
            ScoreRequest(options=ANSWERS, messages=self.messages(instruction, scene, evidence))
        )
        yes, no = scored.logprobs
        return yes - no, scored.usage

    def judge(self, instruction: str, scene: HouseScene, evidence: str = "") -> tuple[HarmVerdict, Usage]:
        """The verdict on ``instruction`` in ``scene``: both readings, added (without evidence
        there is one reading, counted twice)."""
        blind, usage = self.reading(instruction, scene)
        informed = blind
        if evidence.strip():
            informed, used = self.reading(instruction, scene, evidence)
            usage = usage + used
        return HarmVerdict(informed + blind, self.threshold, informed, blind), usage
