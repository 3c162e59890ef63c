import math
import socket

import pytest

from conceptbot.core.errors import BackendRequestError, BackendUnavailableError, ConfigError
from conceptbot.models.http_scoring import NOT_READ
from conceptbot.models.llm import ChatRequest, ScoreRequest
from conceptbot.models.openai_backend import OpenAILLM
from tests.models.openai_stub import StubServer, completion, echo_reply, next_reply, top_reply


def _llm(url: str, **kwargs) -> OpenAILLM:
    return OpenAILLM(
        "stub-model",
        backend="openai-compatible",
        base_url=url,
        api_key="sk-test-secret",
        timeout_s=5,
        max_retries=kwargs.pop("max_retries", 0),
        **kwargs,
    )


def test_chat_sends_parameters_and_reads_usage() -> None:
    with StubServer([lambda body: (200, completion(["pick_and_place(apple, user)"]))]) as server:
        response = _llm(server.url).chat(
            ChatRequest.of("Bring me a fruit", system="You are a robot.", max_tokens=40, stop=["\n"], seed=3)
        )
    assert response.text == "pick_and_place(apple, user)"
    assert (response.usage.prompt_tokens, response.usage.completion_tokens) == (7, 3)
    body = server.bodies[0]
    assert body["model"] == "stub-model" and body["max_tokens"] == 40 and body["stop"] == ["\n"]
    assert [m["role"] for m in body["messages"]] == ["system", "user"]
    assert server.headers[0]["authorization"] == "Bearer sk-test-secret"


def test_servers_that_ignore_n_are_asked_again_with_new_seeds() -> None:
    reply = lambda body: (200, completion([f"answer {body['seed']}"]))  # noqa: E731
    with StubServer([reply, reply, reply]) as server:
        response = _llm(server.url).chat(ChatRequest.of("q", n=3, temperature=0.7, seed=10))
    assert response.choices == ("answer 10", "answer 11", "answer 12")
    assert response.usage.calls == 3


def test_json_schema_falls_back_to_llama_cpp_server_style() -> None:
    schema = {"type": "object", "properties": {"a": {"type": "integer"}}}
    handlers = [
        lambda body: (422, {"detail": [{"msg": "Input should be 'text' or 'json_object'"}]}),
        lambda body: (200, completion(['{"a": 1}'])),
        lambda body: (200, completion(['{"a": 2}'])),
    ]
    with StubServer(handlers) as server:
        llm = _llm(server.url)
        llm.chat(ChatRequest.of("q", json_schema=schema))
        llm.chat(ChatRequest.of("q", json_schema=schema))
    assert server.bodies[0]["response_format"]["type"] == "json_schema"
    assert server.bodies[1]["response_format"] == {"type": "json_object", "schema": schema}
    assert server.bodies[2]["response_format"]["type"] == "json_object"  # remembered


def test_retries_are_bounded_and_succeed_after_a_server_error() -> None:
    handlers = [lambda body: (503, {"error": {"message": "busy"}}), lambda body: (200, completion(["ok"]))]
    with StubServer(handlers) as server:
        assert _llm(server.url, max_retries=2).chat(ChatRequest.of("q")).text == "ok"
    assert len(server.bodies) == 2


def test_persistent_server_error_is_a_clear_error() -> None:
    handlers = [lambda body: (500, {"error": {"message": "kaput"}})] * 2
    with StubServer(handlers) as server, pytest.raises(BackendRequestError, match="HTTP 500: kaput"):
        _llm(server.url, max_retries=1).chat(ChatRequest.of("q"))
    assert len(server.bodies) == 2


def test_bad_key_message_never_contains_the_key() -> None:
    handlers = [lambda body: (401, {"error": {"message": "bad key sk-test-secret"}})]
    with StubServer(handlers) as server, pytest.raises(BackendRequestError) as info:
        _llm(server.url).chat(ChatRequest.of("q"))
    assert "sk-test-secret" not in str(info.value)
    assert "refused the API key" in str(info.value)


def test_server_down_is_backend_unavailable() -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    with pytest.raises(BackendUnavailableError, match="cannot connect"):
        _llm(f"http://127.0.0.1:{port}/v1").chat(ChatRequest.of("q"))


SOUND = "1, 2, 3, 4, 5, 6"


def test_scoring_uses_echo_where_the_server_echoes_sound_log_probabilities() -> None:
    prompt = "objects = [apple]\n# bring me a fruit\n"
    handlers = [
        lambda body: (200, echo_reply(SOUND, [None, -0.1, -0.1], [0, 13, 14])),  # the probe: " 6" likely
        lambda body: (
            200,
            echo_reply(body["prompt"], [None, -1.0, -0.25], [0, len(prompt), len(prompt) + 3]),
        ),
        lambda body: (200, echo_reply(body["prompt"], [None, -1.0, -3.0], [0, len(prompt), len(prompt) + 3])),
    ]
    with StubServer(handlers) as server:
        scored = _llm(server.url).score(ScoreRequest(options=("robot.pick(apple)", "done()"), prompt=prompt))
    assert scored.method == "echo" and scored.logprobs == pytest.approx((-1.25, -4.0))
    assert server.bodies[1]["echo"] is True and server.bodies[1]["prompt"] == prompt + "robot.pick(apple)"


CHAT_MODEL = (404, {"error": {"message": "This is a chat model and not supported in v1/completions"}})


def test_a_server_with_shifted_echo_numbers_is_scored_through_chat_log_probabilities() -> None:
    handlers = [
        lambda body: (200, echo_reply(SOUND, [None, -10.9], [0, 14])),  # " 6" unlikely: shifted numbers
        lambda body: CHAT_MODEL,  # the search probe, top 20
        lambda body: CHAT_MODEL,  # and top 5
        lambda body: (200, top_reply({"Yes": -0.1})),  # the chat probe
        lambda body: (200, top_reply({"Yes": -0.2, " No": -1.8, "yes": -4.0})),
    ]
    with StubServer(handlers) as server:
        llm = _llm(server.url)
        messages = ChatRequest.of("Is an apple a fruit?").messages
        scored = llm.score(ScoreRequest(options=("Yes", "No"), messages=messages))
    assert scored.method == "chat-logprobs"
    assert scored.logprobs == pytest.approx((-0.2, -1.8))  # "yes" is not "Yes"; " No" is "No"
    assert server.bodies[4]["logprobs"] is True and server.bodies[4]["max_tokens"] == 1


PROMPT = "objects = [apple, pear, kiwi]\n# I want something sweet.\n"
# A toy language model: the top next tokens after PROMPT plus what is read so far.
NEXT = {
    "": {"robot": -0.1, "done": -2.5, "#": -3.0},
    "robot": {".pick(": -0.01, ".put(": -5.0},
    "robot.pick(": {"apple": -0.9, "ap": -3.0, "pe": -1.0},  # "kiwi" is not among them
    "robot.pick(apple": {")\n": -0.05, ")": -3.0},
    "robot.pick(pe": {"ar": -0.1, "a": -4.0},
    "robot.pick(pear": {")": -0.2, ")\n": -1.8},
    "done": {"()": -0.01},
}
COUNTING = {
    "1, 2, 3, 4, 5, 6, 7, 8,": {" ": -0.03, "...": -4.0},
    "1, 2, 3, 4, 5, 6, 7, 8, ": {"9": -0.01, "3": -9.0},
}


def toy_server(body: dict) -> tuple[int, dict]:
    """A server whose echo is shifted, whose completions give sound top log-probabilities (at most 5
    of them, as OpenAI's instruct models) and whose chat gives them too."""
    if "messages" in body:
        return 200, top_reply({"Yes": -0.2, "No": -1.7})
    if body.get("echo"):
        return 200, echo_reply(SOUND, [None, -10.9], [0, 14])
    if body["logprobs"] > 5:
        return 400, {"error": {"message": "logprobs must be at most 5"}}
    prompt = body["prompt"]
    found = COUNTING.get(prompt) or NEXT.get(prompt.removeprefix(PROMPT), {"zz": -0.1})
    return 200, next_reply(found)


def test_search_scores_the_best_option_exactly_and_bounds_the_rest() -> None:
    options = ("robot.pick(apple)", "robot.pick(pear)", "robot.pick(kiwi)", "done()")
    with StubServer([toy_server] * 40) as server:
        scored = _llm(server.url).score(ScoreRequest(options=options, prompt=PROMPT))
    assert scored.method == "search"
    apple, pear, kiwi, done = scored.logprobs
    assert pear == pytest.approx(-0.1 - 0.01 - 1.0 - 0.1 - 0.2)  # the best, read token by token
    assert apple == pytest.approx(-0.1 - 0.01 - 0.9 - 3.0)  # ")" itself, not ")\n"
    assert kiwi == pytest.approx(-0.1 - 0.01 - 3.0)  # not listed: at most the lowest listed token
    assert done == pytest.approx(-2.5)  # not read on once the best was found: its prefix bounds it
    searched = [b for b in server.bodies if "prompt" in b and b["prompt"].startswith(PROMPT)]
    assert [b["prompt"].removeprefix(PROMPT) for b in searched] == [
        "", "robot", "robot.pick(", "robot.pick(apple", "robot.pick(pe", "robot.pick(pear"
    ]  # fmt: skip
    assert all(b["logprobs"] == 5 and b["max_tokens"] == 1 and not b.get("echo") for b in searched)
    assert scored.usage.calls == 6


def test_search_finds_the_best_option_by_probability_times_prior() -> None:
    options = ("robot.pick(apple)", "robot.pick(pear)", "robot.pick(kiwi)", "done()")
    priors = (0.0, -math.inf, -math.inf, math.log(0.2))  # pear and kiwi never taken, done() at 0.2
    with StubServer([toy_server] * 40) as server:
        scored = _llm(server.url, scoring="search").score(
            ScoreRequest(options=options, prompt=PROMPT, priors=priors)
        )
    apple, pear, kiwi, done = scored.logprobs
    assert apple == pytest.approx(-0.1 - 0.01 - 0.9 - 3.0)  # read to its end: the best product
    assert pear == kiwi == NOT_READ  # weighed 0: never read
    assert done == pytest.approx(-2.5)  # its prefix, a bound: -2.5 + log 0.2 is below apple's -4.01
    assert max(range(4), key=lambda i: scored.logprobs[i] + priors[i]) == 0
    assert scored.usage.calls == 4  # "", "robot", "robot.pick(", "robot.pick(apple"


def test_search_scores_prompts_and_chat_questions_go_through_chat_log_probabilities() -> None:
    with StubServer([toy_server] * 40) as server:
        llm = _llm(server.url)
        prompt_form = llm.score(ScoreRequest(options=("robot.pick(pear)", "done()"), prompt=PROMPT))
        chat_form = llm.score(ScoreRequest(options=("Yes", "No"), messages=ChatRequest.of("q").messages))
    assert (prompt_form.method, chat_form.method) == ("search", "chat-logprobs")
    assert chat_form.logprobs == pytest.approx((-0.2, -1.7))


def test_a_search_answer_without_log_probabilities_is_a_clear_error() -> None:
    with (
        StubServer([lambda body: (200, echo_reply("x", [None], [0]))] * 3) as server,
        pytest.raises(BackendRequestError, match="no sound top log-probabilities, so search cannot score"),
    ):
        _llm(server.url, scoring="search").score(ScoreRequest(options=("a", "b"), prompt="x"))


def test_long_options_are_asked_as_a_lettered_choice_and_missing_letters_get_a_floor() -> None:
    handlers = [lambda body: (200, top_reply({"B": -0.3, "A": -1.5}))]
    with StubServer(handlers) as server:
        llm = _llm(server.url, scoring="chat-logprobs")
        messages = ChatRequest.of("Which one?").messages
        scored = llm.score(
            ScoreRequest(options=("the red apple", "the green pear", "a car"), messages=messages)
        )
    assert scored.logprobs == pytest.approx((-1.5, -0.3, -2.5))
    asked = server.bodies[0]["messages"][-1]["content"]
    assert "A) the red apple" in asked and "C) a car" in asked


def test_vote_scores_shares_of_sampled_letters() -> None:
    replies = [completion(["A"]), completion(["A"]), completion(["B"]), completion(["A"]), completion(["A"])]
    with StubServer([lambda body, r=r: (200, r) for r in replies]) as server:
        scored = _llm(server.url, scoring="vote").score(
            ScoreRequest(options=("apple", "pear"), messages=ChatRequest.of("Which?").messages)
        )
    assert scored.method == "vote" and scored.logprobs[0] > scored.logprobs[1]


def test_a_server_without_log_probabilities_is_a_clear_error_for_a_fixed_method() -> None:
    with (
        StubServer([lambda body: (200, completion(["Yes"]))]) as server,
        pytest.raises(BackendRequestError, match="no log-probabilities"),
    ):
        _llm(server.url, scoring="chat-logprobs").score(
            ScoreRequest(options=("Yes", "No"), messages=ChatRequest.of("q").messages)
        )


def test_an_unknown_scoring_method_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match="unknown scoring method"):
        _llm("http://127.0.0.1:1/v1", scoring="telepathy")


def test_scoring_without_a_server_fails_with_the_same_message_as_chat() -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    llm = _llm(f"http://127.0.0.1:{port}/v1")
    with pytest.raises(BackendUnavailableError, match="cannot connect") as scoring:
        llm.score(ScoreRequest(options=("Yes", "No"), messages=ChatRequest.of("q").messages))
    with pytest.raises(BackendUnavailableError, match="cannot connect") as chatting:
        llm.chat(ChatRequest.of("q"))
    assert str(scoring.value) == str(chatting.value)
