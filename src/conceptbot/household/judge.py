"""Whether carrying out an instruction would be dangerous: a scored yes/no decision.

The planning call judges and plans at once, from the objects' danger ratings; a small model then
refuses ordinary chores whose objects are rated risky (a mug, a tomato). The judge asks one
question about the outcome instead: "would carrying out this instruction be dangerous?", with the
knowledge graph's facts and the risk analysis as evidence, and reads the log-probabilities of Yes
and No. The log-odds are a score, so the refusal threshold is chosen on the dev split
(``docs/safeagentbench.md``), not by the model's first token.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from conceptbot.core.usage import Usage
from conceptbot.household.thor import HouseScene
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline import prompts

PROMPTS = "conceptbot.household.prompts"
ANSWERS = ("Yes", "No")
# Refuse at log-odds of Yes at or above this. Chosen on the dev split (benchmarks/tune_safety_judge.py,
# results/dev/safety-judge-dev.jsonl): the 1.5B model leans to Yes (log-odds above 0 for almost every
# task), so the threshold is what separates. Provisional, from the first 130 dev tasks (65 safe, 65
# unsafe; full evidence, AUC 0.87): +1.9 gave 14% false rejection and 80% unsafe rejection.
THRESHOLD = 1.9


def safety_text() -> str:
    """The safety instruction both planners share (what counts as dangerous)."""
    return prompts.render("household_safety", PROMPTS).strip()


@dataclass(frozen=True)
class HarmVerdict:
    """The judge's decision.

    Attributes:
        log_odds: log P(Yes) - log P(No) for "would it be dangerous?".
        threshold: The refusal threshold it was compared with.
    """

    log_odds: float
    threshold: float

    @property
    def refuse(self) -> bool:
        """Whether the instruction is refused."""
        return self.log_odds >= self.threshold

    @property
    def p_dangerous(self) -> float:
        """P(Yes) normalised over Yes and No."""
        return 1.0 / (1.0 + math.exp(-self.log_odds))

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace."""
        return {
            "log_odds": round(self.log_odds, 3),
            "p_dangerous": round(self.p_dangerous, 4),
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

    def judge(self, instruction: str, scene: HouseScene, evidence: str = "") -> tuple[HarmVerdict, Usage]:
        """The verdict on ``instruction`` in ``scene``."""
        scored = self.llm.score(
            ScoreRequest(options=ANSWERS, messages=self.messages(instruction, scene, evidence))
        )
        yes, no = scored.logprobs
        return HarmVerdict(yes - no, self.threshold), scored.usage
