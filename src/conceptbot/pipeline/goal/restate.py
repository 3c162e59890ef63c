"""The request said as plain commands by the model, for the rules to read.

The goal reader's rules read plain requests well (the dev requests 97/98, ordinary rewordings 84%)
and the spoken, terse and very polite ones badly (51-56% on blind rounds of the goal set): each
construction of talk needs a rule of its own, and rules written for one do not carry to the next
(``docs/notes/2026-12-02-reading-repairs.md``). A language model reads talk well but writes goals
badly. So the model does the part it is good at: it says the request again in the few plain forms
the rules read ("Put the X in the Y." "Give me something to write with." "Make D."), keeping the
person's words for what they want and leaving out the talk around it. The rules then read that.

:class:`Restater` is that step (prompts ``restate_system.txt`` and ``restate_user.txt``).
:class:`~conceptbot.pipeline.goal.aided.AidedReader` reads both the request's own words and the
plain form and decides between the two readings.
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

#: The longest request restated (characters); past it the rules read the words alone. The plain
#: form of a long monologue is not worth the model's minute.
MAX_REQUEST = 600
#: The prompt's placeholders ("Put the X in the Y.", "Make D."), as words: a sampled plain form
#: sometimes copied one (20 of 2324 samples of the goal set's dev requests; never a greedy one).
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
        # The scene is not in the prompt: given its objects, the small model picks them for the person
        # ("something to read" became "the paperback novel") or lists them all, which is the
        # planner's job; the rules match the person's words to the scene's names.
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
