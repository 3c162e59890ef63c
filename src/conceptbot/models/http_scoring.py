"""Option scoring over HTTP: the best method an OpenAI-compatible server supports.

SayCan and the goal planner score options by log-probability. Over HTTP three ways exist:

* ``echo``: a completions request with ``echo`` and ``logprobs`` returns the log-probability of each
  prompt token, so ``prompt + option`` scores the option exactly as the embedded backend does.
  Prompt-form requests only (a chat prompt's template is the server's). Some servers return these
  numbers shifted by one token (llama-cpp-python 0.3.x, abetlen/llama-cpp-python#1983) or not at
  all (llama.cpp's own server): :func:`echo_is_sound` checks a continuation whose next token is
  certain ("1, 2, 3, 4, 5, 6") before the method is used.
* ``search``: where echo is not sound but completions return the ``top_logprobs`` of the token they
  generate (llama-cpp-python's server, vLLM, OpenAI's instruct models), a best-first search over the
  options' text: each call asks for the next token's top log-probabilities after ``prompt`` plus an
  option's already-read prefix, and follows the likeliest top token each option continues with. The
  options reached are scored exactly as by echo, in the order of their score; an option whose next
  token is not among the top ones gets its prefix's log-probability plus a bound on its own (the
  lowest returned, or the probability the returned ones leave, whichever is lower). A request's
  ``priors`` (log-weights such as SayCan's affordances) steer the search to the best option by
  probability times weight. The search stops once that option is read to its end (a greedy planner
  takes it) or after :data:`SEARCH_CALLS` calls; the options left keep their prefix's
  log-probability (an upper bound, below the best). Prompt-form requests only, like echo.
* ``chat-logprobs``: a chat request for one token with ``logprobs`` and ``top_logprobs`` (OpenAI,
  vLLM, llama.cpp servers). One-token options ("Yes", "No") are read directly; other options are
  asked as a labelled multiple choice ("A) ..., B) ...") and scored by their label's log-probability,
  in groups of at most :data:`MAX_LABELS` (``top_logprobs`` allows 20). An option whose token is not
  among the top ones gets the lowest returned log-probability minus one.
* ``vote``: where neither exists, ``n`` sampled answers to the labelled question; an option's score
  is the log of its share (what the paper did with gpt-4o-mini).

:class:`HTTPScorer` finds the method once per server (``auto``) or uses the configured one.
"""

from __future__ import annotations

import heapq
import itertools
import math
import string
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from conceptbot.core.errors import BackendRequestError, ConfigError, ModelOutputError
from conceptbot.core.usage import Usage
from conceptbot.models.llm import Message, ScoreRequest

METHODS = ("auto", "echo", "search", "chat-logprobs", "vote")
MAX_LABELS = 20  # the most top_logprobs OpenAI-style chat APIs return
LABELS = string.ascii_uppercase[:MAX_LABELS]
VOTES = 5
SEARCH_CALLS = 96  # at most this many calls per scored step (about 40 s on llama-cpp-python, 2 cores)
NOT_READ = -100.0  # the score of an option whose prior is -inf: never read, never taken
SEARCH_TOP = (20, 5)  # top log-probabilities asked for: vLLM and llama.cpp allow 20, OpenAI 5
SOUND_PROMPT = "1, 2, 3, 4, 5,"
SOUND_OPTION = " 6"


@dataclass(frozen=True)
class EchoTokens:
    """Prompt tokens echoed by a completions endpoint: text offsets and log-probabilities."""

    offsets: tuple[int, ...]
    logprobs: tuple[float | None, ...]
    prompt_tokens: int


class Transport(Protocol):
    """The two HTTP calls the scorers need (implemented by ``OpenAILLM``)."""

    def echo(self, prompt: str) -> EchoTokens:
        """Completions with ``echo`` and ``logprobs`` for ``prompt`` (one token generated)."""
        ...

    def next_tokens(self, prompt: str, top: int) -> tuple[dict[str, float], int]:
        """Completions for ``prompt`` (one token, no echo): the ``top`` log-probabilities of the token
        generated, and the prompt's tokens."""
        ...

    def first_token(self, messages: Sequence[Message], top: int) -> tuple[dict[str, float], int]:
        """The ``top`` log-probabilities of the reply's first token, and the prompt's tokens."""
        ...

    def sample(self, messages: Sequence[Message], n: int) -> tuple[list[str], int]:
        """``n`` sampled one-token answers, and the prompt's tokens."""
        ...


def echo_is_sound(transport: Transport) -> bool:
    """Whether the server's echoed log-probabilities are those of each token given the ones before:
    " 6" after "1, 2, 3, 4, 5," must be likely (above log 0.1); a server reporting each token's
    probability after itself (the shifted numbers) gives it about -10."""
    try:
        found = transport.echo(SOUND_PROMPT + SOUND_OPTION)
    except BackendRequestError:
        return False
    tail = [lp for off, lp in zip(found.offsets, found.logprobs, strict=False) if off >= len(SOUND_PROMPT)]
    return bool(tail) and all(lp is not None for lp in tail) and sum(tail) > math.log(0.1)  # type: ignore[arg-type]


def search_top(transport: Transport) -> int | None:
    """How many top log-probabilities the server's completions return, or ``None`` where they are
    missing or wrong: searching " 9" and " 3" after "1, 2, 3, 4, 5, 6, 7, 8," must find " 9" likely
    (above log 0.1) and ahead."""
    for top in SEARCH_TOP:
        try:
            scores, _, _, _ = search_scores(transport, SOUND_PROMPT + " 6, 7, 8,", [" 9", " 3"], top)
        except BackendRequestError:
            continue
        return top if scores[0] > max(math.log(0.1), scores[1]) else None
    return None


def _unlisted(found: dict[str, float]) -> float:
    """An upper bound on the log-probability of a token not among ``found``: below the lowest listed
    one and below the probability left over by all of them."""
    floor = min(found.values(), default=0.0)
    left = 1.0 - sum(math.exp(lp) for lp in found.values())
    return min(floor, math.log(max(left, 1e-12)))


def search_scores(
    transport: Transport,
    prompt: str,
    options: Sequence[str],
    top: int,
    priors: Sequence[float] | None = None,
) -> tuple[list[float], list[int], int, int]:
    """The ``search`` method (module docstring): scores, tokens read per option, prompt tokens
    sent and calls made.

    Each heap entry is a text prefix with the options that continue it, keyed by its
    log-probability (an upper bound for theirs) plus the best of their ``priors`` (log-weights the
    caller multiplies the probabilities by, e.g. SayCan's affordances; 0 if not given); the highest
    key is read next, so the first option read to its end is the best by probability times weight.
    An option follows the likeliest top token its text continues with ("(" then "energy", not the
    rarer "(en"), so each option has one path, the model's usual tokenization of it.
    """
    weights = list(priors) if priors is not None else [0.0] * len(options)
    if any(math.isnan(w) or w == math.inf for w in weights):
        # A NaN weight would make the order of reading depend on where it is listed.
        raise ValueError("priors are log-weights: numbers or -inf (never read), not NaN or +inf")
    scores = [0.0] * len(options)
    counts = [0] * len(options)
    calls = tokens = 0
    best: float | None = None  # log-probability plus weight of the best option, once read
    order = itertools.count(1)  # breaks ties between equal keys: first pushed first
    # Entries: (-key, order, log-probability, prefix read, tokens read, options, kind): kind "read"
    # (a prefix to read on), "done" (one option read to its end) or "bound" (its next token unlisted).
    heap: list[tuple[float, int, float, str, int, tuple[int, ...], str]] = []

    def push(logprob: float, read: str, depth: int, members: Sequence[int], kind: str) -> None:
        weight = max(weights[i] for i in members)
        if weight > -math.inf:
            heapq.heappush(
                heap, (-(logprob + weight), next(order), logprob, read, depth, tuple(members), kind)
            )
        else:  # options the caller weighs 0 (it never takes them) are not read at all
            for i in members:
                scores[i], counts[i] = NOT_READ, depth

    push(0.0, "", 0, range(len(options)), "read")
    while heap:
        _, _, logprob, read, depth, members, kind = heapq.heappop(heap)
        if kind == "done":
            scores[members[0]], counts[members[0]] = logprob, depth
            best = logprob + weights[members[0]] if best is None else best
            continue
        if kind == "bound" or best is not None or calls >= SEARCH_CALLS:
            # Not read further: the prefix's log-probability bounds theirs; once the best is read,
            # kept a hair below it (with each option's weight), so no tie puts one of them first.
            for i in members:
                cap = logprob if best is None else min(logprob, best - weights[i] - 1e-6)
                scores[i], counts[i] = cap, depth
            continue
        for i in members:
            if options[i] == read:
                push(logprob, read, depth, [i], "done")
        rest = [i for i in members if len(options[i]) > len(read)]
        if not rest:
            continue
        found, used = transport.next_tokens(prompt + read, top)
        found = finite(found)
        calls, tokens = calls + 1, tokens + used
        children: dict[str, list[int]] = {}
        for i in rest:
            tail = options[i][len(read) :]
            hits = [t for t in found if t and tail.startswith(t)]
            children.setdefault(max(hits, key=found.__getitem__) if hits else "", []).append(i)
        for token, group in children.items():
            if token:
                push(logprob + found[token], read + token, depth + 1, group, "read")
            else:
                push(logprob + _unlisted(found), read, depth + 1, group, "bound")
    return scores, counts, tokens, calls


def _echo_scores(
    transport: Transport, prompt: str, options: Sequence[str]
) -> tuple[list[float], list[int], int]:
    scores, counts, tokens = [], [], 0
    for option in options:
        found = transport.echo(prompt + option)
        tokens += found.prompt_tokens
        tail = [lp for off, lp in zip(found.offsets, found.logprobs, strict=False) if off >= len(prompt)]
        # A token of the option without its number is not certain: the score cannot be read (a
        # missing number read as 0.0 would give the option the best score there is).
        checked = finite({f"token {i}": lp for i, lp in enumerate(tail)})  # type: ignore[misc]
        scores.append(sum(checked.values()))
        counts.append(len(tail))
    return scores, counts, tokens


# A log-probability is at most 0; servers round, so a hair above is tolerated, more is broken.
_ABOVE_ZERO = 1e-3


def finite(top: dict[str, float]) -> dict[str, float]:
    """``top`` if every log-probability in it is a number that can be one: finite and not above 0.

    Raises:
        ModelOutputError: The server sent NaN, an infinity, no number, or a positive "log-probability"
            (an overflow, a broken quantisation): a decision read from it would be arbitrary, so
            none is made.
    """
    bad = {
        token: lp
        for token, lp in top.items()
        if not (isinstance(lp, int | float) and math.isfinite(lp) and lp <= _ABOVE_ZERO)
    }
    if bad:
        token, lp = next(iter(bad.items()))
        raise ModelOutputError(
            f"the server returned a non-finite or impossible log-probability ({lp!r} for {token!r})",
            hint="the server's numbers overflowed or are broken (fp16?); try another model or "
            "CONCEPTBOT_SCORING=vote",
        )
    return top


def _log_sum_exp(values: Sequence[float]) -> float:
    """log(sum(exp(v))), without underflow (OpenAI sends -9999.0 for negligible tokens)."""
    high = max(values)
    return high + math.log(sum(math.exp(v - high) for v in values))


def _read(top: dict[str, float], wanted: Sequence[str]) -> list[float]:
    """Each wanted token's log-probability among ``top`` (leading spaces ignored, variants summed);
    the lowest returned minus one where it is missing.

    Raises:
        ModelOutputError: A log-probability is not finite (:func:`finite`).
    """
    top = finite(top)
    floor = (min(top.values()) if top else 0.0) - 1.0
    out = []
    for token in wanted:
        hits = [lp for text, lp in top.items() if text.strip() == token]
        out.append(_log_sum_exp(hits) if hits else floor)
    return out


def labelled_question(messages: Sequence[Message], options: Sequence[str]) -> tuple[Message, ...]:
    """The request's messages with its options as a lettered choice appended to the last one."""
    listing = "\n".join(f"{label}) {option}" for label, option in zip(LABELS, options, strict=False))
    last = messages[-1]
    content = (
        f"{last.content.rstrip()}\n\nOptions:\n{listing}\nAnswer with the letter of the best option only."
    )
    return (*messages[:-1], Message(last.role, content))


def as_messages(request: ScoreRequest) -> tuple[Message, ...]:
    """Chat messages for a request: its own, or a prompt-form request as one user message."""
    if request.messages is not None:
        messages = request.messages
        if request.assistant_prefix:
            last = messages[-1]
            hint = f"\n(The answer starts with: {request.assistant_prefix.strip()})"
            messages = (*messages[:-1], Message(last.role, last.content.rstrip() + hint))
        return messages
    text = f"{request.prompt}\n\nWhich line comes next?"
    return (Message("user", text),)


def _one_token(options: Sequence[str]) -> bool:
    """Options short enough to be read as one token each ("Yes", "No")."""
    return all(o.strip() and len(o.strip()) <= 4 and o.strip().isalpha() for o in options)


class HTTPScorer:
    """Scores options through a :class:`Transport` with one of :data:`METHODS`.

    Args:
        transport: The HTTP calls.
        method: ``auto`` (probe once: echo if sound, else search if sound, else chat-logprobs, else
            vote) or a fixed one.
    """

    def __init__(self, transport: Transport, method: str = "auto") -> None:
        if method not in METHODS:
            raise ConfigError(f"unknown scoring method {method!r}", hint=f"use one of {', '.join(METHODS)}")
        self.transport = transport
        self.method = method
        self._found: str | None = None if method == "auto" else method
        self._top: int | None = None  # top log-probabilities the completions return (search)

    def resolved(self, prompt_form: bool) -> str:
        """The method used for a prompt-form (``True``) or chat-form request, probing once."""
        if self._found is None:
            self._found = self._probe()
        if self._found in ("echo", "search") and not prompt_form:
            return "chat-logprobs"  # a chat prompt's template is the server's: only text prompts are read
        return self._found

    def _probe(self) -> str:
        if echo_is_sound(self.transport):
            return "echo"
        top = search_top(self.transport)
        if top is not None:
            self._top = top
            return "search"
        try:
            top, _ = self.transport.first_token((Message("user", "Answer Yes or No: is 2 > 1?"),), 5)
        except BackendRequestError:
            return "vote"
        return "chat-logprobs" if top else "vote"

    def _search_top(self) -> int:
        if self._top is None:
            self._top = search_top(self.transport)
            if self._top is None:
                raise BackendRequestError(
                    "the server's completions give no sound top log-probabilities, so search cannot score",
                    hint="use CONCEPTBOT_SCORING=auto to find a method it supports",
                )
        return self._top

    def score(self, request: ScoreRequest) -> tuple[list[float], list[int], Usage, str]:
        """Scores (log-probabilities, or log shares for votes), token counts, usage and the method."""
        started = time.perf_counter()
        method = self.resolved(request.prompt is not None)
        options = list(request.options)
        if method == "echo":
            assert request.prompt is not None
            scores, counts, tokens = _echo_scores(self.transport, request.prompt, options)
            return scores, counts, Usage(tokens, 0, time.perf_counter() - started, 0.0, len(options)), method
        if method == "search":
            assert request.prompt is not None
            scores, counts, tokens, calls = search_scores(
                self.transport, request.prompt, options, self._search_top(), request.priors
            )
            return scores, counts, Usage(tokens, calls, time.perf_counter() - started, 0.0, calls), method
        messages = as_messages(request)
        scores: list[float] = []
        tokens = calls = 0
        if method == "chat-logprobs" and _one_token(options):
            top, tokens = self.transport.first_token(messages, MAX_LABELS)
            scores, calls = _read(top, [o.strip() for o in options]), 1
        else:
            for start in range(0, len(options), MAX_LABELS):
                group = options[start : start + MAX_LABELS]
                asked = labelled_question(messages, group)
                labels = list(LABELS[: len(group)])
                if method == "chat-logprobs":
                    top, used = self.transport.first_token(asked, MAX_LABELS)
                    scores += _read(top, labels)
                else:
                    answers, used = self.transport.sample(asked, VOTES)
                    votes = Counter(a.strip()[:1] for a in answers)
                    scores += [
                        math.log((votes[label] + 0.1) / (len(answers) + 0.1 * len(labels)))
                        for label in labels
                    ]
                tokens += used
                calls += 1
        usage = Usage(tokens, calls, time.perf_counter() - started, 0.0, calls)
        return scores, [1] * len(options), usage, method
