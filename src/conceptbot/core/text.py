"""Untrusted text made safe to print on a terminal.

Requests, object names, model replies and servers' error bodies reach the CLI's output. A terminal
obeys the control characters in what it prints: ``ESC ] 0 ; title BEL`` retitles the window,
``ESC [ 2 J`` clears it, ``ESC [ 31 m`` recolours what follows, ``CR`` overwrites the start of the
line, and the bidirectional overrides (U+202E, ...) reorder what the user reads. A served model or
a proxy can emit any of them, so everything untrusted passes through :func:`terminal_safe` before
it is printed: the characters stay visible (``\\x1b``), they just lose their power.
"""

from __future__ import annotations

import json
import re

# Every control character (C0, DEL, C1) except newline and tab, which lay text out and do nothing
# else, plus the bidirectional embedding, override and isolate controls.
_UNSAFE = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")
# What json.dumps(ensure_ascii=False) leaves raw: it escapes only U+0000-U+001F itself.
_UNSAFE_IN_JSON = re.compile(r"[\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def _visible(match: re.Match[str]) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def terminal_safe(text: object) -> str:
    """``text`` as a string whose control characters are shown as escapes, not obeyed.

    Newlines and tabs are kept (and ``CRLF`` line ends become ``LF``: harmless, unlike a lone
    ``CR``, which overwrites the line); every other C0 control, DEL, every C1 control and the
    bidirectional embedding/override/isolate controls become ``\\xNN`` / ``\\uNNNN``, so
    ``"\\x1b[2J"`` prints as the six characters ``\\x1b[2J`` instead of clearing the screen.

    Args:
        text: Anything; non-strings are converted with ``str()`` first.

    Returns:
        The text, unchanged when it held nothing unsafe.
    """
    value = text if isinstance(text, str) else str(text)
    return _UNSAFE.sub(_visible, value.replace("\r\n", "\n"))


def safe_json_dumps(value: object, *, indent: int | None = 2) -> str:
    """``json.dumps`` for a terminal: readable non-ASCII text, no raw control character.

    ``ensure_ascii=False`` keeps "crème brûlée" readable but would let DEL, the C1 controls and the
    bidirectional overrides through raw; they are written as ``\\uNNNN`` escapes instead, which any
    JSON parser reads back as the same string (they can only occur inside strings).
    """
    text = json.dumps(value, indent=indent, ensure_ascii=False)
    return _UNSAFE_IN_JSON.sub(lambda m: f"\\u{ord(m.group()):04x}", text)
