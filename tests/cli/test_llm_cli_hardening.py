"""`conceptbot llm` against hostile input: odd numbers, bad schema files, escapes in replies.

(Also the other commands' float options: ``nan`` passes a plain ``click.FloatRange``.)"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from tests.cli.inprocess import assert_terminal_safe, invoke
from tests.loopback import LoopbackServer, Request
from tests.misbehaving import MisbehavingServer
from tests.scripted import write_replies

ESCAPES = "hello \x1b]0;pwned\x07\x1b[2J\x1b[31mred\x9b1m [/x] [bold] :knife:"


@pytest.mark.parametrize("value", ["nan", "NaN", "inf", "-1", "-inf"])
def test_a_temperature_that_is_not_a_finite_number_in_range_is_one_clear_error(
    tmp_path: Path, value: str
) -> None:
    spec = write_replies(tmp_path / "r.json", ["hi"])
    outcome = invoke("--llm", spec, "llm", "hi", "-t", value)
    assert_terminal_safe(outcome)
    assert outcome.code == 2
    assert "--temperature" in outcome.errors()[0]


def _deep_schema_text(depth: int) -> str:
    return '{"type": "object", "properties": {"a": ' * depth + "{}" + "}}" * depth


class _SchemaHost(LoopbackServer):
    def respond(self, request: Request) -> tuple[int, dict[str, Any]]:
        return 200, {"type": "integer"}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[1, 2]", "must be a JSON object"),
        ('{"type": "objet"}', "not a valid JSON Schema"),
        ('{"$ref": "#"}', "refers to itself without end"),
        (_deep_schema_text(3000), "nested too deeply"),  # past the JSON decoder's recursion limit
        (_deep_schema_text(100), "nested 201 levels deep"),
        ("{not json", "is not valid JSON"),
    ],
)
def test_an_unusable_schema_file_is_one_config_error(tmp_path: Path, text: str, message: str) -> None:
    schema = tmp_path / "s.json"
    schema.write_text(text)
    spec = write_replies(tmp_path / "r.json", ['{"a": 1}', '{"a": 1}'])
    outcome = invoke("--no-cache", "--llm", spec, "llm", "q", "--schema", str(schema))
    assert_terminal_safe(outcome)
    assert outcome.code == 2 and message in outcome.errors()[0]
    assert str(schema) in outcome.errors()[0]


def test_a_remote_reference_in_a_schema_is_refused_and_never_fetched(tmp_path: Path) -> None:
    spec = write_replies(tmp_path / "r.json", ['{"a": 1}', '{"a": 1}'])
    with _SchemaHost() as host:
        schema = tmp_path / "s.json"
        schema.write_text(json.dumps({"type": "object", "properties": {"a": {"$ref": f"{host.base_url}/x"}}}))
        outcome = invoke("--no-cache", "--llm", spec, "llm", "q", "--schema", str(schema))
        assert host.received == []
    assert_terminal_safe(outcome)
    assert outcome.code == 2 and "references are never fetched" in outcome.errors()[0]


def test_escapes_in_a_model_reply_are_shown_not_obeyed(tmp_path: Path) -> None:
    spec = write_replies(tmp_path / "r.json", [ESCAPES, ESCAPES + " 2"])
    outcome = invoke("--no-cache", "--llm", spec, "llm", "hi", "-n", "2")
    assert_terminal_safe(outcome)
    assert outcome.code == 0
    assert "hello \\x1b]0;pwned\\x07\\x1b[2J\\x1b[31mred\\x9b1m [/x] [bold] :knife:" in outcome.stdout
    as_json = invoke("--no-cache", "--llm", spec, "llm", "hi", "--json")
    assert_terminal_safe(as_json)
    assert json.loads(as_json.stdout)["choices"] == [ESCAPES]


def test_escapes_in_a_servers_error_body_are_shown_not_obeyed(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CONCEPTBOT_MAX_RETRIES", "0")
    with MisbehavingServer() as server:
        outcome = invoke("--no-cache", "--llm", f"openai-compatible:{server.url('ansi')}#m", "llm", "hi")
    assert_terminal_safe(outcome)
    assert outcome.code != 0
    assert "\\x1b]0;pwned\\x07\\x1b[2J\\x1b[31mevil [/x] [bold]" in outcome.errors()[0]


def test_a_nan_temperature_never_reaches_an_http_backend(monkeypatch: pytest.MonkeyPatch) -> None:
    # The reproduction: the OpenAI client raised "Out of range float values are not JSON compliant".
    monkeypatch.setenv("CONCEPTBOT_MAX_RETRIES", "0")
    with MisbehavingServer() as server:
        outcome = invoke(
            "--no-cache", "--llm", f"openai-compatible:{server.url('ok')}#m", "llm", "hi", "-t", "nan"
        )
        assert [r.path for r in server.received if r.method == "POST"] == []
    assert_terminal_safe(outcome)
    assert outcome.code == 2 and "not a finite number" in outcome.errors()[0]


@pytest.mark.parametrize("option", ["--from", "--to", "--step"])
def test_calibrate_refuses_a_nan_sweep_bound(option: str) -> None:
    outcome = invoke("--embedder", "fake", "calibrate", option, "nan")
    assert_terminal_safe(outcome)
    assert outcome.code == 2 and "not a finite number" in outcome.errors()[0]


def test_a_prompt_with_bytes_that_are_not_utf8_is_one_clear_error(tmp_path: Path) -> None:
    spec = write_replies(tmp_path / "r.json", ["hi"])
    for args in (("hi \udcff",), ("hi", "--system", "be \udcff")):
        outcome = invoke("--llm", spec, "llm", *args)
        assert_terminal_safe(outcome)
        assert outcome.code == 2 and "undecodable bytes" in outcome.errors()[0], outcome.stderr
