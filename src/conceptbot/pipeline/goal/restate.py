"""The request said as plain commands by the model ("Put the X in the Y."), for the rules to read: the
rules read talk badly, and a language model reads talk well but writes goals badly.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field

from conceptbot.core.errors import ConceptBotError
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, ChatRequest
from conceptbot.pipeline import prompts

logger = logging.getLogger(__name__)

#: The longest request restated (characters); past it the rules read the words alone.
MAX_REQUEST = 600
#: The prompt's placeholders ("Put the X in the Y."), as words: a sampled plain form may copy one.
PLACEHOLDER = re.compile(r"(?<![&\w'])[DWXYZ](?![&\w'])")


@dataclass(frozen=True)
class Restatement:
    """The model's plain form of a request.

    Attributes:
        text: The plain commands, or "" when the model gave none (an error, an empty or odd reply).
        usage: The model call's tokens and time.
        problem: Why there is no text ("" when there is).
    """

    text: str
    usage: Usage = field(default_factory=lambda: Usage(calls=0))
    problem: str = ""


class Restater:
    """Says a request as plain commands with the model.

    Args:
        llm: The model (greedy, a few dozen tokens per request).
        max_tokens: The longest plain form, in tokens.
    """

    def __init__(self, llm: LLM, max_tokens: int = 96) -> None:
        self.llm = llm
        self.max_tokens = max_tokens

    def restate(self, request: str) -> Restatement:
        """The plain form of ``request``; never raises for a model's failure.

        Args:
            request: What the person said.
        """
        words = " ".join(request.split())
        if not words or len(words) > MAX_REQUEST:
            return Restatement("", problem="empty" if not words else "too long to restate")
        try:
            response = self.llm.chat(self._chat(words))
        except ConceptBotError as exc:  # the words alone are read: a model failure is no reading
            logger.warning("restating %r failed: %s", words[:80], exc)
            return Restatement("", problem=str(exc))
        return _made(response.text, response.usage)

    def _chat(self, words: str) -> ChatRequest:
        """The restating request for ``words``."""
        # The scene is not in the prompt: given it, the model picks objects itself (the planner's job).
        return ChatRequest.of(
            prompts.fill("restate_user", request=words),
            system=prompts.render("restate_system"),
            max_tokens=self.max_tokens,
            stop=("\n",),
        )


def _made(reply: str, usage: Usage) -> Restatement:
    text, problem = _checked(reply)
    return Restatement(text, usage, problem)


def _checked(reply: str) -> tuple[str, str]:
    """The reply's plain form and "" , or "" and what is wrong with it."""
    text = " ".join(reply.strip().split())
    text = re.sub(r"^(plain|request)\s*:\s*", "", text, flags=re.IGNORECASE).strip().strip('"')
    if not re.search(r"[A-Za-z]", text):
        return "", "no words in the reply"
    if PLACEHOLDER.search(text):
        return "", "the reply copies a placeholder of the prompt"
    if len(text) > 4 * MAX_REQUEST:
        return "", "reply too long"
    return text, ""
