"""The model's own view of which of two readings of a request was meant.

The choice's step says little on new wording, so :class:`ReadingJudge` asks the model, and
:func:`.doubt.judged` weighs its answer with the step's odds.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

from conceptbot.core.errors import ConceptBotError
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline import prompts
from conceptbot.pipeline.goal.doubt import Odds, judge_weights, judged, odds

logger = logging.getLogger(__name__)
OPTIONS = ("A", "B")


@dataclass(frozen=True)
class Preference:
    """How much more the model takes one reading than the other to be meant.

    Attributes:
        log_odds: log P(first reading) - log P(second), averaged over both orders; NaN on a model error.
        usage: The model's calls.
    """

    log_odds: float
    usage: Usage = field(default_factory=lambda: Usage(calls=0))


class ReadingJudge:
    """Asks the model which of two readings of a request the person meant (see the module).

    Args:
        llm: An LLM that can score options.
    """

    def __init__(self, llm: LLM) -> None:
        self.llm = llm

    def prefer(self, request: str, first: str, second: str) -> Preference:
        """The model's preference for ``first`` over ``second``; NaN (never raises) on a model's failure."""
        said = " ".join(request.split())

        def user(a: str, b: str) -> str:
            return prompts.fill("reading_judge_user", request=said, first=a, second=b)

        # Filled exactly as written: the fitted weights hold for these very prompts.
        try:
            log_odds, usage = both_orders(self.llm, prompts.fill("reading_judge_system"), user, first, second)
        except ConceptBotError as exc:
            logger.warning("judging the readings of %r failed: %s", request[:80], exc)
            return Preference(float("nan"))
        return Preference(log_odds, usage)


def both_orders(
    llm: LLM, system: str, user: Callable[[str, str], str], first: str, second: str
) -> tuple[float, Usage]:
    """The model's log-odds for ``first`` over ``second``, averaged over both orders (cancelling its lean
    to the first shown), and the usage.

    Raises:
        ConceptBotError: The backend could not score (a non-finite score included).
    """

    def ask(a: str, b: str) -> tuple[float, Usage]:
        messages = (Message("system", system), Message("user", user(a, b)))
        scored = llm.score(ScoreRequest(options=OPTIONS, messages=messages))
        return scored.logprobs[0] - scored.logprobs[1], scored.usage

    ahead, usage = ask(first, second)
    behind, used = ask(second, first)
    return 0.5 * (ahead - behind), usage + used


def reading_odds(
    step: str, request: str, taken: str, other: str, judge: ReadingJudge | None = None
) -> tuple[Odds, Preference | None]:
    """The ``step``'s odds that ``taken`` or ``other`` is meant, moved by ``judge`` where it is asked, and
    the judge's preference (None if not asked)."""
    found = odds(step)
    weights = judge_weights() if judge is not None and other and other != taken else None
    if judge is None or weights is None:
        return found, None
    preference = judge.prefer(request, taken, other)
    return judged(found, preference.log_odds, weights), preference
