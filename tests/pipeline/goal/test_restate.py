from __future__ import annotations

import re

from conceptbot.bench.grading import load_tasks
from conceptbot.core.errors import BackendRequestError
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline import prompts
from conceptbot.pipeline.goal.restate import MAX_REQUEST, Restater


def test_the_plain_form_is_the_reply_without_its_label() -> None:
    llm = FakeLLM(["Plain: Put the conch shell in the shoe box.\n"])
    said = Restater(llm).restate("Oh, would you be a dear and pop the conch shell in the shoe box?")
    assert (said.text, said.problem) == ("Put the conch shell in the shoe box.", "")
    message = llm.requests[0].messages[-1].content
    assert message == ("Request: Oh, would you be a dear and pop the conch shell in the shoe box?\nPlain:")


def test_a_model_failure_or_an_empty_reply_gives_no_plain_form() -> None:
    failing = Restater(FakeLLM([BackendRequestError("server said 500")]))
    said = failing.restate("Pop the conch shell in the shoe box.")
    assert said.text == "" and "500" in said.problem
    assert Restater(FakeLLM(["  ...  "])).restate("Shells away, please.").text == ""


def test_empty_and_overlong_requests_are_not_sent() -> None:
    llm = FakeLLM([])  # any call would raise FakeExhaustedError
    restater = Restater(llm)
    assert restater.restate("   ").problem == "empty"
    assert restater.restate("shell " * MAX_REQUEST).problem == "too long to restate"
    assert llm.requests == []


def test_a_plain_form_copying_the_prompt_s_placeholder_is_no_plain_form() -> None:
    said = [
        Restater(FakeLLM([reply])).restate("Lunch?")
        for reply in ("Make D.", "Put everything W in the Y.", "Make a PB&J.")
    ]
    assert [s.text for s in said] == ["", "", "Make a PB&J."]
    assert said[0].problem == "the reply copies a placeholder of the prompt"


def _grams(text: str, n: int = 4) -> set[tuple[str, ...]]:
    words = re.findall(r"[a-z0-9'&-]+", text.lower())
    return {tuple(words[i : i + n]) for i in range(len(words) - n + 1)}


def test_the_prompt_examples_borrow_no_wording_from_the_test_split() -> None:
    examples = prompts.render("restate_system")
    requests = [
        line.removeprefix("Request: ") for line in examples.splitlines() if line.startswith("Request:")
    ]
    assert len(requests) >= 6
    test = set().union(*(_grams(t.request) for t in load_tasks(split="test")))
    assert {r: sorted(_grams(r) & test) for r in requests if _grams(r) & test} == {}
