"""The model's own view of which of two readings of a request was meant.

Where the rules read a request's words and its plain form two ways (:mod:`.aided`), the step of the
choice that kept one says little on new wording: on the goal set's held-out paraphrases (rounds 11
and 12) the steps' odds ranked the meant reading below chance (AUC 0.43). Shown the request and
both readings in words (:func:`.doubt.describe`), the small model picks the meant one far better:
its preference alone ranks them at AUC 0.83 on the same rows, weighed with the steps' odds 0.80
(``benchmarks/bench_restated_reading.py --fit-judge``; ``docs/notes/2026-12-05-reading-judge.md``).
:class:`ReadingJudge` asks it, and :func:`.doubt.judged` weighs its answer with the step's odds.

The model leans to the first option it is shown, so it is asked twice, the readings in each order,
and the two answers' log-odds are averaged: what is left is its preference for the reading itself.
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
        log_odds: log P(the first reading) - log P(the second), averaged over both orders; NaN where
            it could not be had (a model error): the odds are then unknown and the person is asked.
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
        """The model's preference for ``first`` over ``second`` as what ``request`` asks for; never
        raises for a model's failure (a NaN preference: ask, do not guess)."""
        said = " ".join(request.split())

        def user(a: str, b: str) -> str:
            return prompts.fill("reading_judge_user", request=said, first=a, second=b)

        # Both files filled exactly as written: the fitted weights were measured on these very prompts.
        try:
            log_odds, usage = both_orders(self.llm, prompts.fill("reading_judge_system"), user, first, second)
        except ConceptBotError as exc:
            logger.warning("judging the readings of %r failed: %s", request[:80], exc)
            return Preference(float("nan"))
        return Preference(log_odds, usage)


def both_orders(
    llm: LLM, system: str, user: Callable[[str, str], str], first: str, second: str
) -> tuple[float, Usage]:
    """The model's log-odds for ``first`` over ``second``: "A" against "B" with ``first`` shown as A
    (``user(first, second)``), then shown as B, averaged, so that its lean to the option shown
    first cancels; and the two calls' usage.

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
    """How likely the reading ``taken`` and the reading ``other`` (both in words) are the one meant:
    the odds of the choice's ``step``, moved by ``judge``'s preference where a judge is given, the
    odds file has fitted weights and the two read differently in words; and that preference (None
    where the model was not asked)."""
    found = odds(step)
    weights = judge_weights() if judge is not None and other and other != taken else None
    if judge is None or weights is None:
        return found, None
    preference = judge.prefer(request, taken, other)
    return judged(found, preference.log_odds, weights), preference
