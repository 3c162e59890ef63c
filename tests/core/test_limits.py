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
