"""Untrusted text made safe for a terminal (conceptbot.core.text)."""

import json

import pytest

from conceptbot.core.text import safe_json_dumps, terminal_safe

# What a hostile server or model emits: retitle (OSC ... BEL), clear, recolour, 8-bit CSI, NUL,
# backspace, a lone CR that overwrites the line, DEL, a right-to-left override.
HOSTILE = "\x1b]0;pwned\x07\x1b[2J\x1b[31mred\x9b1m\x00\x08\rover\x7f\u202eevil"
RAW_CONTROLS = [chr(c) for c in (*range(0x00, 0x09), *range(0x0B, 0x20), *range(0x7F, 0xA0))]


def test_control_characters_become_visible_escapes() -> None:
    assert terminal_safe("\x1b[2J") == "\\x1b[2J"
    assert terminal_safe("a\x07b") == "a\\x07b"
    assert terminal_safe("\x9b") == "\\x9b"
    assert terminal_safe("\u202eabc") == "\\u202eabc"
    safe = terminal_safe(HOSTILE)
    assert not any(c in safe for c in [*RAW_CONTROLS, "\u202e"])
    assert "pwned" in safe and "red" in safe and "evil" in safe  # nothing is lost, only disarmed


@pytest.mark.parametrize("char", RAW_CONTROLS)
def test_every_c0_and_c1_control_but_newline_and_tab_is_escaped(char: str) -> None:
    assert terminal_safe(f"a{char}b") == f"a\\x{ord(char):02x}b"


def test_layout_and_ordinary_text_are_kept() -> None:
    text = "line one\n\tline two: crème brûlée, 日本語, [bold] :knife: \\x1b"
    assert terminal_safe(text) == text
    assert terminal_safe("windows\r\nline") == "windows\nline"  # CRLF is a line end, not an overwrite
    assert terminal_safe(42) == "42"


def test_safe_json_dumps_is_the_same_json_without_raw_controls() -> None:
    value = {"request": HOSTILE, "name": "crème brûlée", "n": 1.5}
    text = safe_json_dumps(value)
    assert json.loads(text) == value
    assert not any(c in text for c in [*RAW_CONTROLS, "\u202e"])
    assert "crème brûlée" in text  # non-ASCII text stays readable
