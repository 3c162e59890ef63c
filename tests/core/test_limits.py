"""Input limits (conceptbot.core.limits)."""

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.core.limits import MAX_REQUEST_CHARS, check_name, check_request, json_depth


@pytest.mark.parametrize("request_text", ["", "   ", "\n\t"])
def test_empty_requests_are_refused(request_text: str) -> None:
    with pytest.raises(ConfigError, match="the request is empty"):
        check_request(request_text)


def test_requests_are_stripped_and_capped() -> None:
    assert check_request("  bring me an apple \n") == "bring me an apple"
    assert check_request("a" * MAX_REQUEST_CHARS) == "a" * MAX_REQUEST_CHARS
    with pytest.raises(ConfigError, match="the limit is 500"):
        check_request("a" * (MAX_REQUEST_CHARS + 1))
    with pytest.raises(ConfigError, match="must be text"):
        check_request(None)


def test_names() -> None:
    assert check_name("  red cup ", "s") == "red cup"
    with pytest.raises(ConfigError, match=r"'\(' '\)'"):
        check_name("cup (red)", "s")


def test_json_depth_is_iterative() -> None:
    deep: list = []
    node = deep
    for _ in range(50_000):  # far beyond Python's recursion limit
        node.append([])
        node = node[0]
    assert json_depth(deep) == 50_001
    assert json_depth({"a": [1, {"b": 2}]}) == 3
    assert json_depth("x") == 0


@pytest.mark.parametrize(
    "request_text",
    [
        "bring me an apple \x1b]0;pwned\x07",  # OSC: retitles the terminal
        "bring me \x1b[2J an apple",  # CSI: clears the screen
        "bring me an apple\x07",  # BEL
        "bring me an apple \x9b31m",  # 8-bit CSI (C1)
        "bring me\x00 an apple",
        "bring me an apple\x7f",
        "bring me an \u202eelppa",  # right-to-left override
    ],
)
def test_requests_with_control_characters_are_refused(request_text: str) -> None:
    with pytest.raises(ConfigError, match="control characters") as info:
        check_request(request_text)
    # The message names the characters as escapes, so printing it is safe too.
    assert info.value.message.isprintable()
    assert "escape sequences" in (info.value.hint or "")


def test_line_breaks_and_tabs_in_a_request_become_spaces() -> None:
    assert check_request("bring me\r\n  an apple\tplease\n") == "bring me   an apple please"
    assert check_request("bring me\u2028an apple") == "bring me an apple"
    assert check_request("une crème brûlée, s'il te plaît") == "une crème brûlée, s'il te plaît"


def test_bytes_that_were_not_utf8_are_refused_with_the_control_characters() -> None:
    from conceptbot.core.limits import check_text

    with pytest.raises(ConfigError, match=r"control characters or undecodable bytes '\\x1b' '\\udcff'"):
        check_request("bring me an apple \udcff \x1b")
    with pytest.raises(ConfigError, match=r"the prompt contains undecodable bytes '\\ud800'"):
        check_text("hi \ud800", "prompt")
    assert check_text("crème\nbrûlée", "prompt") == "crème\nbrûlée"
