"""Unit tests for each piece of :mod:`conceptbot.models.http_scoring`, one at a time.

The end-to-end paths (each method over a loopback OpenAI stub, the probe refusing shifted echo
numbers, the toy-model search) live in ``tests/models/test_openai_backend.py``; this file drives the
functions and :class:`HTTPScorer` through a scripted in-memory :class:`Transport` (every call
recorded), plus the loopback servers for the fail-closed checks on the real wire format.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import pytest

from conceptbot.core.errors import BackendRequestError, ConceptBotError, ConfigError, ModelOutputError
from conceptbot.models import http_scoring as hs
from conceptbot.models.http_scoring import (
    LABELS,
    MAX_LABELS,
    NOT_READ,
    SEARCH_CALLS,
    SOUND_OPTION,
    SOUND_PROMPT,
    VOTES,
    EchoTokens,
    HTTPScorer,
    as_messages,
    echo_is_sound,
    finite,
    labelled_question,
    search_scores,
    search_top,
)
from conceptbot.models.llm import Message, ScoreRequest
from conceptbot.models.openai_backend import OpenAILLM
from tests.misbehaving import MisbehavingServer
from tests.models.openai_stub import StubServer, echo_reply, next_reply

NON_FINITE = [math.nan, math.inf, -math.inf]
COUNTING = SOUND_PROMPT + " 6, 7, 8,"  # the prompt search_top probes with


def _refuse(*_: Any) -> Any:
    raise BackendRequestError("not served by this fake")


def echoed(prompt: str, pieces: Sequence[tuple[str, float | None]]) -> EchoTokens:
    """What a sound echo returns for ``prompt`` split into ``pieces`` (text, log-probability)."""
    offsets, logprobs, at = [], [], 0
    for text, lp in pieces:
        offsets.append(at)
        logprobs.append(lp)
        at += len(text)
    assert at == len(prompt), "the pieces must spell the prompt"
    return EchoTokens(tuple(offsets), tuple(logprobs), len(pieces))


class FakeTransport:
    """A scripted :class:`~conceptbot.models.http_scoring.Transport` that records every call.

    ``table`` maps a full completions prompt to the top next tokens after it (prompts not listed get
    ``default``, or a refusal where ``default`` is None); the other calls are given as functions.
    """

    def __init__(
        self,
        table: dict[str, dict[str, float]] | None = None,
        *,
        default: dict[str, float] | None = None,
        echo: Callable[[str], EchoTokens] = _refuse,
        first: Callable[[Sequence[Message], int], dict[str, float]] = _refuse,
        sample: Callable[[Sequence[Message], int], list[str]] = _refuse,
        used: int = 3,
        refuse_tops: Sequence[int] = (),
    ) -> None:
        self.table = table or {}
        self.default = default
        self._echo, self._first, self._sample = echo, first, sample
        self.used = used
        self.refuse_tops = set(refuse_tops)
        self.calls: list[tuple[str, Any, Any]] = []

    def echo(self, prompt: str) -> EchoTokens:
        self.calls.append(("echo", prompt, None))
        return self._echo(prompt)

    def next_tokens(self, prompt: str, top: int) -> tuple[dict[str, float], int]:
        self.calls.append(("next", prompt, top))
        if top in self.refuse_tops:
            raise BackendRequestError(f"logprobs must be below {top}")
        if prompt in self.table:
            return dict(self.table[prompt]), self.used
        if self.default is None:
            raise BackendRequestError(f"no scripted answer for {prompt!r}")
        return dict(self.default), self.used

    def first_token(self, messages: Sequence[Message], top: int) -> tuple[dict[str, float], int]:
        self.calls.append(("first", tuple(messages), top))
        return self._first(messages, top), self.used

    def sample(self, messages: Sequence[Message], n: int) -> tuple[list[str], int]:
        self.calls.append(("sample", tuple(messages), n))
        return self._sample(messages, n), self.used

    def read(self, prompt: str = "") -> list[str]:
        """The prefixes (after ``prompt``) the search asked next tokens for, in order."""
        return [
            p.removeprefix(prompt) for kind, p, _ in self.calls if kind == "next" and p.startswith(prompt)
        ]

    def kinds(self) -> list[str]:
        return [kind for kind, _, _ in self.calls]


def sound_echo(prompt: str) -> EchoTokens:
    """The probe's echo as a sound server answers it: " 6" likely after "1, 2, 3, 4, 5,"."""
    assert prompt == SOUND_PROMPT + SOUND_OPTION
    return echoed(prompt, [(SOUND_PROMPT, None), (SOUND_OPTION, -0.05)])


def shifted_echo(prompt: str) -> EchoTokens:
    return echoed(prompt, [(SOUND_PROMPT, None), (SOUND_OPTION, -10.9)])


COUNTING_SOUND = {COUNTING: {" 9": -0.02, " 3": -7.0}}


# --- finite: non-finite numbers fail closed ---------------------------------------------------------


def test_finite_returns_the_same_mapping_when_every_number_is_finite() -> None:
    top = {"Yes": -0.1, "No": -2}
    assert finite(top) is top
    assert finite({}) == {}


@pytest.mark.parametrize("bad", NON_FINITE)
def test_finite_rejects_nan_and_infinities_naming_the_token(bad: float) -> None:
    with pytest.raises(ModelOutputError, match=r"non-finite or impossible .* for 'No'") as info:
        finite({"Yes": -0.1, "No": bad})
    assert "CONCEPTBOT_SCORING=vote" in (info.value.hint or "")


@pytest.mark.parametrize("bad", [None, "-0.5", [-0.5]])
def test_finite_rejects_values_that_are_not_numbers(bad: Any) -> None:
    with pytest.raises(ModelOutputError):
        finite({"Yes": bad})


# --- _unlisted: the bound on a token that is not among the returned ones ----------------------------


def test_unlisted_is_the_lowest_listed_where_that_is_below_the_leftover() -> None:
    assert hs._unlisted({"a": -3.0, "b": -4.0}) == pytest.approx(-4.0)


def test_unlisted_is_the_leftover_probability_where_that_is_lower() -> None:
    # 0.5 + 0.3 listed: at most 0.2 is left for any other token, below the lowest listed (0.3).
    assert hs._unlisted({"a": math.log(0.5), "b": math.log(0.3)}) == pytest.approx(math.log(0.2))


def test_unlisted_when_the_listed_tokens_take_all_the_probability_is_tiny_but_finite() -> None:
    bound = hs._unlisted({"a": math.log(0.6), "b": math.log(0.5)})  # sums above 1 (rounding, a bad server)
    assert bound == pytest.approx(math.log(1e-12))
    assert bound < math.log(0.5)


def test_unlisted_with_nothing_listed_bounds_nothing() -> None:
    assert hs._unlisted({}) == 0.0


# --- search_scores: prefixes and tokens ----------------------------------------------------------------


def test_search_sends_prompt_plus_the_prefix_read_and_sums_the_tokens_followed() -> None:
    t = FakeTransport({"P:": {"pick": -0.2, "done": -2.0}, "P:pick": {"(a)": -0.3}}, used=11)
    scores, counts, tokens, calls = search_scores(t, "P:", ["pick(a)"], 20)
    assert scores == pytest.approx([-0.5])
    assert counts == [2]
    assert (tokens, calls) == (22, 2)
    assert [(p, top) for _, p, top in t.calls] == [("P:", 20), ("P:pick", 20)]


def test_search_follows_the_likeliest_listed_token_the_option_continues_with() -> None:
    t = FakeTransport({"": {"(": -0.1, "(en": -3.0, "x": -0.01}, "(": {"energy": -0.4, "e": -2.0}})
    scores, counts, _, _ = search_scores(t, "", ["(energy"], 20)
    assert t.read() == ["", "("]  # not the rarer "(en", nor the unrelated likelier "x"
    assert scores == pytest.approx([-0.5])
    assert counts == [2]


def test_search_never_follows_a_token_that_runs_past_the_option_or_is_empty() -> None:
    t = FakeTransport({"": {"ab": -0.01, "": -0.02, "a": -1.0}, "a": {"b": -0.5}})
    scores, counts, _, calls = search_scores(t, "", ["ab"], 20)
    # "ab" is the option's whole text; "" (an empty token) would read nothing forever.
    assert t.read() == [""]
    assert scores == pytest.approx([-0.01])
    assert (counts, calls) == ([1], 1)
    t = FakeTransport({"": {"abc": -0.01, "": -0.02, "a": -1.0}, "a": {"b": -0.5}})
    scores, _, _, _ = search_scores(t, "", ["ab"], 20)
    assert t.read() == ["", "a"]  # "abc" runs past the option's end
    assert scores == pytest.approx([-1.5])


def test_an_option_that_is_a_prefix_of_another_is_scored_where_its_text_ends() -> None:
    t = FakeTransport({"": {"go": -0.5}, "go": {"od": -0.1}})
    scores, counts, _, calls = search_scores(t, "", ["go", "good"], 20)
    assert scores[0] == pytest.approx(-0.5)  # read to its end first: the best
    assert scores[1] == pytest.approx(-0.6)  # its prefix, below the best
    assert counts == [1, 2]
    assert calls == 2


def test_an_empty_option_is_certain_and_the_others_stay_below_it() -> None:
    t = FakeTransport({"": {"a": -0.1}})
    scores, counts, _, calls = search_scores(t, "", ["", "a"], 20)
    # The number echo gives an empty continuation (log 1), the best possible: it is taken first.
    assert scores[0] == 0.0 and counts[0] == 0
    assert scores[1] == pytest.approx(-0.1) and counts[1] == 1
    # The other options are still read on once before the finished one is taken.
    assert calls == 1 and t.read() == [""]


# --- search_scores: best-first order, stopping and bounds ---------------------------------------------


def test_search_reads_the_likeliest_prefix_next() -> None:
    table = {
        "": {"a": -1.0, "b": -0.2},
        "b": {"x": -3.0},  # b's path gets unlikely: a is read next
        "a": {"x": -0.1},
        "ax": {"y": -0.1},
        "bx": {"y": -0.1},
    }
    t = FakeTransport(table)
    scores, counts, _, calls = search_scores(t, "", ["axy", "bxy"], 20, None)
    assert t.read()[:3] == ["", "b", "a"]
    assert "bx" not in t.read()  # the best (a...) is read to its end before bx's -3.2 comes up
    assert calls == len(t.read())
    assert scores[1] == pytest.approx(-3.2) and counts[1] == 2  # bx: its prefix, an upper bound


def test_search_stops_at_the_first_option_read_to_its_end_and_bounds_the_rest() -> None:
    table = {"": {"a": -0.1, "b": -1.0, "c": -1.5}, "a": {"1": -0.2}, "b": {"2": -0.1}, "c": {"3": -0.1}}
    t = FakeTransport(table)
    scores, counts, _, calls = search_scores(t, "", ["a1", "b2", "c3"], 20)
    assert t.read() == ["", "a"]  # a1 (-0.3) finishes before b's -1.0 is read on
    assert scores == pytest.approx([-0.3, -1.0, -1.5])
    assert counts == [2, 1, 1]
    assert calls == 2
    assert max(range(3), key=scores.__getitem__) == 0


def test_an_unlisted_next_token_bounds_the_option_by_its_prefix_plus_the_unlisted_bound() -> None:
    table = {"": {"a": -0.1}, "a": {"x": -0.2, "y": -2.5}}  # "z" is not among them
    t = FakeTransport(table)
    scores, counts, _, _ = search_scores(t, "", ["ax", "az"], 20)
    assert scores[0] == pytest.approx(-0.3)
    assert scores[1] == pytest.approx(-0.1 + hs._unlisted({"x": -0.2, "y": -2.5}))
    assert scores[1] == pytest.approx(-0.1 - 2.5)
    assert counts[1] == 2  # the unlisted token counts as one read


def test_a_bound_read_before_the_best_keeps_its_bound() -> None:
    # "c" is not listed after "": at most the lowest listed (-2.0). That bound is above the score of
    # the option read to its end (-2.5): search_scores reports both as they are (the caller decides).
    table = {"": {"a": -1.0, "b": -2.0}, "a": {"x": -0.5}, "ax": {"y": -0.5}, "axy": {"z": -0.5}}
    t = FakeTransport(table)
    scores, counts, _, calls = search_scores(t, "", ["axyz", "c"], 20)
    assert scores == pytest.approx([-2.5, -2.0])
    assert counts == [4, 1]
    assert calls == 4


def test_a_prefix_tied_with_the_best_is_kept_a_hair_below_it() -> None:
    # Both reach -0.5; "a" finishes first (pushed first), "bc" is then left at a bound just below.
    t = FakeTransport({"": {"a": -0.5, "b": -0.5}, "b": {"c": 0.0}})
    scores, _, _, _ = search_scores(t, "", ["a", "bc"], 20)
    assert scores[0] == pytest.approx(-0.5)
    assert scores[1] < scores[0]
    assert scores[1] == pytest.approx(-0.5, abs=1e-5)


def test_exactly_tied_options_are_read_in_option_order_and_both_scored_exactly() -> None:
    table = {"": {"a": -0.5, "b": -0.5}, "a": {"x": -0.1}, "b": {"x": -0.1}}
    t = FakeTransport(table)
    scores, _, _, _ = search_scores(t, "", ["ax", "bx"], 20)
    assert t.read() == ["", "a", "b"]
    assert scores == pytest.approx([-0.6, -0.6])
    t = FakeTransport(table)
    scores, _, _, _ = search_scores(t, "", ["bx", "ax"], 20)
    assert t.read() == ["", "b", "a"]  # ties: first pushed, first read
    assert scores == pytest.approx([-0.6, -0.6])


def test_duplicate_options_get_the_same_exact_score() -> None:
    t = FakeTransport({"": {"go": -0.7}})
    scores, counts, _, calls = search_scores(t, "", ["go", "go"], 20)
    assert scores == pytest.approx([-0.7, -0.7])
    assert counts == [1, 1] and calls == 1


def test_search_stops_after_search_calls_and_keeps_the_prefix_as_a_bound() -> None:
    long = "a" * (SEARCH_CALLS + 50)
    t = FakeTransport(default={"a": -0.01})
    scores, counts, tokens, calls = search_scores(t, "", [long], 20)
    assert calls == SEARCH_CALLS and len(t.calls) == SEARCH_CALLS
    assert counts == [SEARCH_CALLS]
    assert scores == pytest.approx([-0.01 * SEARCH_CALLS])
    assert tokens == 3 * SEARCH_CALLS


def test_search_calls_is_read_at_call_time(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(hs, "SEARCH_CALLS", 2)
    t = FakeTransport(default={"a": -0.25})
    scores, counts, _, calls = search_scores(t, "", ["aaaa", "b"], 20)
    assert calls == 2
    assert scores[0] == pytest.approx(-0.5) and counts[0] == 2
    assert scores[1] == pytest.approx(hs._unlisted({"a": -0.25}))  # bounded at the first call


# --- search_scores: priors ------------------------------------------------------------------------------


def test_priors_steer_the_search_to_the_best_probability_times_weight() -> None:
    table = {"": {"a": -0.1, "b": -1.0}, "a": {"1": -0.1}, "b": {"2": -0.1}}
    plain = FakeTransport(table)
    assert search_scores(plain, "", ["a1", "b2"], 20)[0][0] == pytest.approx(-0.2)
    assert plain.read() == ["", "a"]
    weighed = FakeTransport(table)
    priors = [math.log(0.1), 0.0]  # a1: 0.82 * 0.1, b2: 0.33 * 1
    scores, _, _, _ = search_scores(weighed, "", ["a1", "b2"], 20, priors)
    assert weighed.read() == ["", "b"]
    assert scores[1] == pytest.approx(-1.1)  # read to its end: the best product
    assert scores[0] + priors[0] < scores[1] + priors[1]
    assert scores[0] == pytest.approx(-0.1)  # its prefix: a bound


def test_a_bound_is_capped_below_the_best_product_with_each_options_weight() -> None:
    # "b" (weight 0.1) ties "a" (weight 0) on key; "a" is read first and finishes: "bz" must then
    # stay strictly below it by probability times weight.
    t = FakeTransport({"": {"a": -0.1, "b": -0.2}, "b": {"z": 0.0}})
    scores, _, _, _ = search_scores(t, "", ["a", "bz"], 20, [0.0, 0.1])
    assert scores[0] == pytest.approx(-0.1)
    assert scores[1] + 0.1 < scores[0] + 0.0
    assert scores[1] == pytest.approx(-0.2, abs=1e-5)


def test_options_weighed_minus_infinity_are_never_read() -> None:
    t = FakeTransport({"": {"a": -0.01, "b": -3.0}})
    scores, counts, _, calls = search_scores(t, "", ["aaa", "b"], 20, [-math.inf, 0.0])
    assert scores[0] == NOT_READ and counts[0] == 1
    assert scores[1] == pytest.approx(-3.0)
    assert t.read() == [""] and calls == 1  # "a" was never asked about


def test_all_options_weighed_minus_infinity_cost_no_call() -> None:
    t = FakeTransport(default={"a": -0.1})
    scores, counts, tokens, calls = search_scores(t, "", ["a", "b"], 20, [-math.inf, -math.inf])
    assert scores == [NOT_READ, NOT_READ]
    assert (counts, tokens, calls) == ([0, 0], 0, 0)
    assert t.calls == []


def test_a_nan_prior_does_not_depend_on_the_options_order() -> None:
    table = {"": {"a": -0.1, "b": -0.2}, "a": {"z": -0.1}, "b": {"z": -0.1}}
    try:
        first = search_scores(FakeTransport(table), "", ["az", "bz"], 20, [math.nan, 0.0])[0]
        last = search_scores(FakeTransport(table), "", ["bz", "az"], 20, [0.0, math.nan])[0]
    except (ValueError, ConceptBotError):
        return  # refusing a NaN prior outright is fine too
    assert first == pytest.approx(last[::-1])


# --- search_scores: non-finite numbers ----------------------------------------------------------------


@pytest.mark.parametrize("bad", NON_FINITE)
def test_a_non_finite_number_at_any_depth_fails_the_whole_search(bad: float) -> None:
    t = FakeTransport({"": {"a": -0.1}, "a": {"b": bad, "c": -1.0}})
    with pytest.raises(ModelOutputError, match="non-finite"):
        search_scores(t, "", ["ab", "ac"], 20)


@pytest.mark.parametrize("bad", NON_FINITE)
def test_a_non_finite_number_on_a_token_no_option_uses_still_fails(bad: float) -> None:
    t = FakeTransport({"": {"a": -0.1, "zzz": bad}})
    with pytest.raises(ModelOutputError):
        search_scores(t, "", ["a"], 20)


def test_an_impossible_positive_log_probability_fails_as_model_output() -> None:
    t = FakeTransport({"": {"a": 1000.0}})
    with pytest.raises(ModelOutputError):
        search_scores(t, "", ["a", "b"], 20)


# --- echo_is_sound ------------------------------------------------------------------------------------


def test_echo_is_sound_where_the_last_token_is_likely() -> None:
    t = FakeTransport(echo=sound_echo)
    assert echo_is_sound(t) is True
    assert t.calls == [("echo", SOUND_PROMPT + SOUND_OPTION, None)]


def test_echo_with_shifted_numbers_is_not_sound() -> None:
    assert echo_is_sound(FakeTransport(echo=shifted_echo)) is False


@pytest.mark.parametrize(("tail", "sound"), [(-2.2, True), (-2.4, False)])
def test_echo_soundness_threshold_is_log_one_tenth(tail: float, sound: bool) -> None:
    def echo(prompt: str) -> EchoTokens:
        return echoed(prompt, [(SOUND_PROMPT, None), (SOUND_OPTION, tail)])

    assert math.log(0.1) == pytest.approx(-2.303, abs=1e-3)
    assert echo_is_sound(FakeTransport(echo=echo)) is sound


def test_echo_soundness_sums_the_options_tokens_and_ignores_the_prompts() -> None:
    def split(prompt: str) -> EchoTokens:  # " 6" as " " and "6"; an unlikely prompt token before it
        return echoed(prompt, [("1, 2, 3, 4,", None), (" 5,", -9.0), (" ", -1.0), ("6", -1.5)])

    assert echo_is_sound(FakeTransport(echo=split)) is False  # -2.5 together
    assert (
        echo_is_sound(
            FakeTransport(
                echo=lambda p: echoed(p, [("1, 2, 3, 4,", None), (" 5,", -9.0), (" ", -1.0), ("6", -1.0)])
            )
        )
        is True
    )


@pytest.mark.parametrize(
    "pieces",
    [
        [(SOUND_PROMPT, None), (SOUND_OPTION, None)],  # no number for " 6"
        [(SOUND_PROMPT + SOUND_OPTION, -0.01)],  # no token starts after the prompt
        [(SOUND_PROMPT, None), (SOUND_OPTION, math.nan)],
    ],
)
def test_echo_without_a_usable_number_is_not_sound(pieces: list[tuple[str, float | None]]) -> None:
    assert echo_is_sound(FakeTransport(echo=lambda p: echoed(p, pieces))) is False


def test_echo_refused_by_the_server_is_not_sound() -> None:
    assert echo_is_sound(FakeTransport()) is False


# --- search_top -------------------------------------------------------------------------------------


def test_search_top_takes_twenty_where_the_server_allows_it() -> None:
    t = FakeTransport(COUNTING_SOUND)
    assert search_top(t) == 20
    assert {(p, top) for _, p, top in t.calls} == {(COUNTING, 20)}


def test_search_top_falls_back_to_five_where_twenty_is_refused() -> None:
    t = FakeTransport(COUNTING_SOUND, refuse_tops=[20])
    assert search_top(t) == 5
    assert [top for _, _, top in t.calls] == [20, 5]


def test_search_top_is_none_where_completions_are_refused() -> None:
    t = FakeTransport()
    assert search_top(t) is None
    assert [top for _, _, top in t.calls] == [20, 5]


@pytest.mark.parametrize(
    "found",
    [
        {" 3": -0.1, " 9": -0.5},  # the wrong number ahead
        {" 9": -2.5, " 3": -3.0},  # ahead but unlikely (below log 0.1)
        {" 10": -0.1, " 1": -0.5},  # neither listed: both bounded, " 9" not above log 0.1
    ],
)
def test_search_top_refuses_unsound_numbers_without_trying_five(found: dict[str, float]) -> None:
    t = FakeTransport({COUNTING: found})
    assert search_top(t) is None
    assert [top for _, _, top in t.calls] == [20]


def test_search_top_does_not_swallow_non_finite_numbers() -> None:
    t = FakeTransport({COUNTING: {" 9": math.nan, " 3": -5.0}})
    with pytest.raises(ModelOutputError):
        search_top(t)


# --- _echo_scores -----------------------------------------------------------------------------------


def test_echo_scores_sum_the_tokens_after_the_prompt() -> None:
    prompt = "Q: "

    def echo(text: str) -> EchoTokens:
        option = text.removeprefix(prompt)
        pieces: list[tuple[str, float | None]] = [("Q:", None), (" ", -7.0)]
        pieces += [(ch, -0.5) for ch in option]
        return echoed(text, pieces)

    t = FakeTransport(echo=echo)
    scores, counts, tokens = hs._echo_scores(t, prompt, ["ab", "xyz"])
    assert scores == pytest.approx([-1.0, -1.5])  # the prompt's -7.0 is not the options'
    assert counts == [2, 3]
    assert tokens == (2 + 2) + (2 + 3)
    assert [p for _, p, _ in t.calls] == ["Q: ab", "Q: xyz"]


@pytest.mark.parametrize("bad", NON_FINITE)
def test_echo_scores_fail_closed_on_a_non_finite_number(bad: float) -> None:
    t = FakeTransport(echo=lambda text: echoed(text, [("Q:", None), ("a", -0.1), ("b", bad)]))
    with pytest.raises(ModelOutputError, match="non-finite"):
        hs._echo_scores(t, "Q:", ["ab"])


def test_echo_scores_do_not_read_a_missing_number_as_certainty() -> None:
    def echo(text: str) -> EchoTokens:
        if text.endswith("risky"):
            return echoed(text, [("Q:", None), ("risky", None)])
        return echoed(text, [("Q:", None), ("safe", -0.5)])

    try:
        scores, _, _ = hs._echo_scores(FakeTransport(echo=echo), "Q:", ["safe", "risky"])
    except ConceptBotError:
        return  # refusing the reply is the fail-closed answer
    assert scores[1] < scores[0]


# --- _read: chat log-probabilities ------------------------------------------------------------------


def test_read_ignores_leading_spaces_and_sums_variants() -> None:
    top = {"Yes": math.log(0.5), " Yes": math.log(0.25), "No": math.log(0.2)}
    assert hs._read(top, ["Yes", "No"]) == pytest.approx([math.log(0.75), math.log(0.2)])


def test_read_is_case_sensitive() -> None:
    assert hs._read({"yes": -0.1, "No": -1.0}, ["Yes"]) == pytest.approx([-2.0])


def test_read_gives_missing_tokens_the_lowest_returned_minus_one() -> None:
    assert hs._read({"A": -0.3, "B": -1.5}, ["B", "C", "D"]) == pytest.approx([-1.5, -2.5, -2.5])


def test_read_with_nothing_returned_gives_every_option_the_same_floor() -> None:
    assert hs._read({}, ["Yes", "No"]) == [-1.0, -1.0]


@pytest.mark.parametrize("bad", NON_FINITE)
def test_read_fails_closed_on_a_non_finite_number_even_one_not_wanted(bad: float) -> None:
    with pytest.raises(ModelOutputError):
        hs._read({"Yes": -0.1, "Maybe": bad}, ["Yes"])


def test_read_handles_a_vanishingly_unlikely_token() -> None:
    yes, no = hs._read({"Yes": -0.0001, "No": -9999.0}, ["Yes", "No"])
    assert yes == pytest.approx(-0.0001)
    assert no <= -9999.0 + 1e-6


# --- labelled_question, as_messages, _one_token -----------------------------------------------------


def test_labelled_question_appends_lettered_options_to_the_last_message_only() -> None:
    messages = (Message("system", "Be brief."), Message("user", "Which one?  \n"))
    asked = labelled_question(messages, ["the red apple", "a car"])
    assert asked[0] == messages[0]
    assert asked[-1].role == "user"
    assert asked[-1].content == (
        "Which one?\n\nOptions:\nA) the red apple\nB) a car\nAnswer with the letter of the best option only."
    )
    assert len(asked) == 2


def test_labelled_question_letters_at_most_max_labels() -> None:
    asked = labelled_question((Message("user", "q"),), [f"o{i}" for i in range(MAX_LABELS + 3)])
    listed = [line for line in asked[-1].content.splitlines() if ") o" in line]
    assert len(listed) == MAX_LABELS
    assert listed[-1] == f"{LABELS[-1]}) o{MAX_LABELS - 1}"
    assert LABELS == "ABCDEFGHIJKLMNOPQRST"


def test_as_messages_asks_a_prompt_form_request_as_one_user_message() -> None:
    out = as_messages(ScoreRequest(options=("a",), prompt="objects = [x]\n"))
    assert out == (Message("user", "objects = [x]\n\n\nWhich line comes next?"),)


def test_as_messages_keeps_chat_messages_and_states_the_assistant_prefix() -> None:
    messages = (Message("system", "s"), Message("user", "Pick one. "))
    assert as_messages(ScoreRequest(options=("a",), messages=messages)) == messages
    out = as_messages(ScoreRequest(options=("a",), messages=messages, assistant_prefix=" Answer: "))
    assert out[0] == messages[0]
    assert out[-1] == Message("user", "Pick one.\n(The answer starts with: Answer:)")


@pytest.mark.parametrize(
    ("options", "one"),
    [
        (("Yes", "No"), True),
        ((" Yes", "No\n"), True),
        (("lamp",), True),
        (("Maybe", "No"), False),  # five letters
        (("A1",), False),
        (("",), False),
        (("  ",), False),
        (("no way",), False),
    ],
)
def test_one_token_options(options: tuple[str, ...], one: bool) -> None:
    assert hs._one_token(options) is one


# --- HTTPScorer: choosing the method ----------------------------------------------------------------


def test_an_unknown_method_is_a_config_error_naming_the_methods() -> None:
    with pytest.raises(ConfigError, match="unknown scoring method 'logits'") as info:
        HTTPScorer(FakeTransport(), "logits")
    assert "chat-logprobs" in (info.value.hint or "")


def test_the_probe_takes_echo_where_it_is_sound_and_runs_once() -> None:
    t = FakeTransport(echo=sound_echo)
    scorer = HTTPScorer(t)
    assert scorer.resolved(True) == "echo"
    assert scorer.resolved(False) == "chat-logprobs"  # a chat prompt's template is the server's
    assert scorer.resolved(True) == "echo"
    assert t.kinds() == ["echo"]


def test_the_probe_takes_search_where_echo_is_shifted_and_remembers_the_top() -> None:
    t = FakeTransport(COUNTING_SOUND, refuse_tops=[20], echo=shifted_echo)
    scorer = HTTPScorer(t)
    assert scorer.resolved(True) == "search"
    assert scorer.resolved(False) == "chat-logprobs"
    assert scorer._search_top() == 5
    assert t.kinds() == ["echo", "next", "next"]  # no second probe for the top


def test_the_probe_takes_chat_logprobs_where_completions_give_nothing() -> None:
    t = FakeTransport(first=lambda m, top: {"Yes": -0.1})
    assert HTTPScorer(t).resolved(True) == "chat-logprobs"
    assert t.kinds() == ["echo", "next", "next", "first"]


@pytest.mark.parametrize("first", [lambda m, top: {}, _refuse])
def test_the_probe_falls_back_to_votes(first: Callable[..., dict[str, float]]) -> None:
    t = FakeTransport(first=first)
    scorer = HTTPScorer(t)
    assert scorer.resolved(True) == scorer.resolved(False) == "vote"
    assert t.kinds().count("first") == 1


def test_a_fixed_method_is_not_probed() -> None:
    t = FakeTransport()
    assert HTTPScorer(t, "vote").resolved(True) == "vote"
    assert HTTPScorer(t, "echo").resolved(True) == "echo"
    assert HTTPScorer(t, "echo").resolved(False) == "chat-logprobs"
    assert t.calls == []


def test_a_probe_that_meets_a_non_finite_number_fails_and_probes_again_next_time() -> None:
    t = FakeTransport({COUNTING: {" 9": math.nan}}, echo=shifted_echo)
    scorer = HTTPScorer(t)
    for _ in range(2):
        with pytest.raises(ModelOutputError):
            scorer.resolved(True)
    assert t.kinds().count("echo") == 2


# --- HTTPScorer.score -------------------------------------------------------------------------------


def test_score_by_echo() -> None:
    def echo(text: str) -> EchoTokens:
        return echoed(text, [("P", None), *((ch, -0.25) for ch in text[1:])])

    t = FakeTransport(echo=echo)
    scores, counts, usage, method = HTTPScorer(t, "echo").score(
        ScoreRequest(options=("ab", "abcd"), prompt="P")
    )
    assert method == "echo"
    assert scores == pytest.approx([-0.5, -1.0])
    assert counts == [2, 4]
    assert (usage.prompt_tokens, usage.calls) == (3 + 5, 2)


def test_score_by_search_passes_the_priors_and_counts_the_calls() -> None:
    table = {
        **COUNTING_SOUND,
        "P": {"a": -0.1, "b": -1.0},
        "Pa": {"1": -0.1},
        "Pb": {"2": -0.1},
    }
    t = FakeTransport(table, used=4)
    scorer = HTTPScorer(t, "search")
    request = ScoreRequest(options=("a1", "b2"), prompt="P", priors=(math.log(0.1), 0.0))
    scores, counts, usage, method = scorer.score(request)
    assert method == "search"
    assert scores[1] == pytest.approx(-1.1)  # the best product, read to its end
    assert counts == [1, 2]
    assert t.read("P") == ["", "b"]
    assert (usage.prompt_tokens, usage.calls) == (8, 2)  # the probe's calls are not this request's
    scorer.score(request)
    assert [p for _, p, _ in t.calls].count(COUNTING) == 1  # the top is probed once


def test_score_by_search_without_sound_top_log_probabilities_is_a_clear_error() -> None:
    t = FakeTransport({COUNTING: {" 3": -0.1, " 9": -3.0}})
    with pytest.raises(BackendRequestError, match="no sound top log-probabilities"):
        HTTPScorer(t, "search").score(ScoreRequest(options=("a",), prompt="P"))
    assert "P" not in t.read()


def test_score_one_token_options_from_one_chat_call() -> None:
    t = FakeTransport(first=lambda m, top: {" Yes": -0.3, "No": -1.4, "yes": -2.0})
    messages = (Message("user", "Is it safe?"),)
    scores, counts, usage, method = HTTPScorer(t, "chat-logprobs").score(
        ScoreRequest(options=("Yes", " No", "Okay"), messages=messages)
    )
    assert method == "chat-logprobs"
    assert scores == pytest.approx([-0.3, -1.4, -3.0])  # "Okay" is missing: the lowest minus one
    assert counts == [1, 1, 1]
    assert usage.calls == 1
    assert t.calls == [("first", messages, MAX_LABELS)]  # asked as is, not as a lettered choice


def test_score_long_options_by_letter_in_groups_of_max_labels() -> None:
    options = tuple(f"option number {i}" for i in range(MAX_LABELS + 5))
    answers = iter([{"C": -0.1, "A": -2.0}, {"B": -0.2}])
    t = FakeTransport(first=lambda m, top: next(answers))
    scores, _, usage, _ = HTTPScorer(t, "chat-logprobs").score(
        ScoreRequest(options=options, messages=(Message("user", "Which?"),))
    )
    assert len(scores) == len(options)
    assert scores[:3] == pytest.approx([-2.0, -3.0, -0.1])
    assert scores[MAX_LABELS : MAX_LABELS + 2] == pytest.approx([-1.2, -0.2])  # second group: own floor
    assert usage.calls == 2
    second = t.calls[1][1][-1].content
    assert "A) option number 20" in second and "E) option number 24" in second and "F)" not in second


def test_score_by_chat_fails_closed_on_nan() -> None:
    t = FakeTransport(first=lambda m, top: {"Yes": math.nan, "No": -0.1})
    with pytest.raises(ModelOutputError):
        HTTPScorer(t, "chat-logprobs").score(ScoreRequest(options=("Yes", "No"), prompt="P"))


def test_score_by_votes_is_the_smoothed_log_share_of_each_letter() -> None:
    t = FakeTransport(sample=lambda m, n: ["A", " A", "B) pear", "a", "A."])
    scores, counts, usage, method = HTTPScorer(t, "vote").score(
        ScoreRequest(options=("apple", "pear", "plum"), messages=(Message("user", "Which?"),))
    )
    assert method == "vote"
    # "a" is no letter; three A, one B, no C among five answers.
    assert scores == pytest.approx([math.log(3.1 / 5.3), math.log(1.1 / 5.3), math.log(0.1 / 5.3)])
    assert counts == [1, 1, 1]
    assert usage.calls == 1
    assert t.calls[0][0] == "sample" and t.calls[0][2] == VOTES
    assert "C) plum" in t.calls[0][1][-1].content


def test_votes_that_all_land_on_letters_share_all_the_probability() -> None:
    t = FakeTransport(sample=lambda m, n: ["A", "B", "B", "C", "A"])
    scores, _, _, _ = HTTPScorer(t, "vote").score(
        ScoreRequest(options=("x", "y", "z"), messages=(Message("user", "?"),))
    )
    assert sum(math.exp(s) for s in scores) == pytest.approx(1.0)


# --- Through real HTTP: non-finite numbers never become scores -----------------------------------


@pytest.mark.parametrize("mode", ["lp_nan", "lp_neginf", "lp_posinf"])
@pytest.mark.parametrize("scoring", ["auto", "chat-logprobs"])
def test_non_finite_chat_numbers_over_http_fail_closed(mode: str, scoring: str) -> None:
    with MisbehavingServer() as server:
        llm = OpenAILLM(
            "m",
            backend="openai-compatible",
            base_url=server.url(mode),
            api_key="k",
            timeout_s=5,
            max_retries=0,
            scoring=scoring,
        )
        with pytest.raises(ModelOutputError, match="non-finite"):
            llm.score(ScoreRequest(options=("Yes", "No"), messages=(Message("user", "Safe?"),)))


def test_a_nan_in_the_middle_of_a_search_over_http_fails_closed() -> None:
    def server(body: dict) -> tuple[int, dict]:
        prompt = body["prompt"]
        if prompt.startswith(COUNTING):  # the probe: sound numbers
            return 200, next_reply({" 9": -0.01, " 3": -6.0} if prompt == COUNTING else {"x": -0.1})
        if prompt == "P":
            return 200, next_reply({"a": -0.1, "b": -2.0})
        return 200, next_reply({"1": math.nan, "2": -0.5})

    with StubServer([server] * 10) as stub:
        llm = OpenAILLM(
            "m",
            backend="openai-compatible",
            base_url=stub.url,
            api_key="k",
            timeout_s=5,
            max_retries=0,
            scoring="search",
        )
        with pytest.raises(ModelOutputError, match="non-finite"):
            llm.score(ScoreRequest(options=("a1", "b2"), prompt="P"))
    assert [b["prompt"] for b in stub.bodies][-2:] == ["P", "Pa"]


def test_an_infinite_echo_passes_the_probe_but_never_becomes_a_score() -> None:
    def server(body: dict) -> tuple[int, dict]:
        prompt = body["prompt"]
        return 200, echo_reply(prompt, [None, math.inf], [0, len(prompt) - 2])

    with StubServer([server] * 5) as stub:
        llm = OpenAILLM(
            "m", backend="openai-compatible", base_url=stub.url, api_key="k", timeout_s=5, max_retries=0
        )
        with pytest.raises(ModelOutputError, match="non-finite"):
            llm.score(ScoreRequest(options=("go", "stop"), prompt="P: "))
    assert [b["prompt"] for b in stub.bodies] == [SOUND_PROMPT + SOUND_OPTION, "P: go"]
    assert all(b.get("echo") for b in stub.bodies)
