"""Limits on what a user may hand ConceptBot: requests, scenes and object names.

All in one place so the CLI, the library, the web page and the docs agree. The numbers are far
above what a tabletop robot sees (the paper's largest scene, the kitchen, has 25 objects; a camera
frame with more than a hundred graspable things is not a pick-and-place scene) and far below what
would make a plan cost hours of LLM time or a prompt overflow the context window.

Object names must survive the round trip through the action format
``pick_and_place(object, destination)``: the action parser splits on commas and parentheses and
strips quotes, so a name containing any of ``, ( ) ' " ` `` could be planned but never read back
(and never executed). Such names are rejected when the scene is loaded, with the reason.

Requests are free text, but they are printed on terminals and pages, so they may not carry control
characters (a request holding ``ESC ] 0 ; ... BEL`` would retitle the terminal of whoever reads the
trace); line breaks and tabs, which a pasted request often holds, become spaces instead.
"""

from __future__ import annotations

import re
import unicodedata

from conceptbot.core.errors import ConfigError

MAX_OBJECTS = 100
"""Objects in one scene (pickable and destinations together)."""
MAX_NAME_CHARS = 80
"""Characters in one object name."""
MAX_STATE_CHARS = 200
"""Characters in one entity state ("contains hot tea")."""
MAX_REQUEST_CHARS = 500
"""Characters in one request."""
MAX_SCENE_FILE_BYTES = 1_000_000
"""Size of a scene file."""
MAX_JSON_DEPTH = 20
"""Nesting of a scene file's JSON (a scene needs 3 levels; deeper is not a scene)."""
MAX_SCHEMA_DEPTH = 64
"""Nesting of a JSON Schema given to ``conceptbot llm --schema`` (each object level of the reply
takes two: ``properties`` and the property's schema; validation recurses, so depth is bounded)."""

FORBIDDEN_NAME_CHARS = ",()'\"`"
"""Characters the action format cannot carry in an object name."""

# Layout a pasted request carries (line breaks, tabs, form feeds, Unicode line separators): one
# space per run, so "bring me\r\n  an apple" reads as it was meant.
_REQUEST_LAYOUT = re.compile(r"[\t\n\r\v\f\x85\u2028\u2029]+")
# Formatting controls that reorder how text is displayed (the "Trojan Source" characters).
_BIDI_CONTROLS = frozenset("\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069")
# Control characters, and lone surrogates: Python decodes bytes that are not UTF-8 (an argument
# holding \xff) to U+DC80..U+DCFF, which no file, cache key or HTTP body can encode.
_UNPRINTABLE = ("Cc", "Cs")


def check_text(text: str, what: str) -> str:
    """``text`` as it is, if it holds no lone surrogate (bytes that were not UTF-8).

    For free text that is not a request (a prompt, a concept to look up): its layout is kept.

    Raises:
        ConfigError: A lone surrogate, named by its escape.
    """
    bad = sorted({c for c in text if unicodedata.category(c) == "Cs"})
    if bad:
        shown = " ".join(repr(c) for c in bad)
        raise ConfigError(
            f"the {what} contains undecodable bytes {shown} (text that is not UTF-8?)",
            hint=f"give the {what} as UTF-8 text",
        )
    return text


def check_name(name: str, where: str) -> str:
    """An object name, stripped, if the action format can carry it.

    Raises:
        ConfigError: Empty, too long, a control character, or one of :data:`FORBIDDEN_NAME_CHARS`.
    """
    text = name.strip()
    if not text:
        raise ConfigError(f"{where}: object names must not be empty")
    if len(text) > MAX_NAME_CHARS:
        raise ConfigError(f"{where}: object name {text[:40]!r}... is longer than {MAX_NAME_CHARS} characters")
    bad = sorted({c for c in text if c in FORBIDDEN_NAME_CHARS or not c.isprintable()})
    if bad:
        shown = " ".join(repr(c) for c in bad)
        raise ConfigError(
            f"{where}: object name {text!r} contains {shown}, which plans cannot carry",
            hint="name objects with letters, digits, spaces, '-' or '_' (e.g. 'red cup', 'cup-2')",
        )
    return text


class CheckedRequest(str):
    """A request that :func:`check_request` has checked: where it goes next it is not checked again
    (the CLI checks what the person typed, the system it goes to takes it as it is)."""

    __slots__ = ()


def check_request(request: object) -> CheckedRequest:
    """A request, stripped, if it is non-empty plain text within :data:`MAX_REQUEST_CHARS`; one
    checked already (a :class:`CheckedRequest`) as it is.

    Line breaks and tabs are not refused: each run of them becomes one space (a request pasted from
    an editor or a chat window keeps its meaning). Every other control character (ESC, BEL, CSI,
    NUL, DEL, C1 controls) and the bidirectional override controls are refused: they have no
    meaning to the robot and would be obeyed by the terminal that shows the request.

    Raises:
        ConfigError: Not a string, empty (or only spaces), too long, a control character or a
            lone surrogate (bytes that were not UTF-8).
    """
    if isinstance(request, CheckedRequest):
        return request
    if not isinstance(request, str):
        raise ConfigError("the request must be text")
    text = _REQUEST_LAYOUT.sub(" ", request).strip()
    if not text:
        raise ConfigError(
            "the request is empty", hint='say what the robot should do, e.g. "bring me an apple"'
        )
    if len(text) > MAX_REQUEST_CHARS:
        raise ConfigError(f"the request is {len(text)} characters long; the limit is {MAX_REQUEST_CHARS}")
    bad = sorted({c for c in text if unicodedata.category(c) in _UNPRINTABLE or c in _BIDI_CONTROLS})
    if bad:
        # repr() shows each one as an escape ('\x1b', '\udcff'), so the message itself is safe to print.
        shown = " ".join(repr(c) for c in bad)
        raise ConfigError(
            f"the request contains the control characters or undecodable bytes {shown}"
            " (a terminal escape sequence, or text that is not UTF-8?)",
            hint="type the request as plain UTF-8 text, without colour codes or other escape sequences",
        )
    return CheckedRequest(text)


def json_depth(value: object) -> int:
    """Containers nested in a parsed JSON value: 0 for a scalar, 1 for a flat list or object.

    Iterative, so a hostile file cannot overflow the stack."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, depth = stack.pop()
        children = item.values() if isinstance(item, dict) else item if isinstance(item, list) else None
        if children is not None:
            deepest = max(deepest, depth)
            stack.extend((v, depth + 1) for v in children)
    return deepest
