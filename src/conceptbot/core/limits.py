"""Limits on what a user may hand ConceptBot: requests, scenes and object names.

All in one place so the CLI, the library, the web page and the docs agree. The numbers are far
above what a tabletop robot sees (the paper's largest scene, the kitchen, has 25 objects; a camera
frame with more than a hundred graspable things is not a pick-and-place scene) and far below what
would make a plan cost hours of LLM time or a prompt overflow the context window.

Object names must survive the round trip through the action format
``pick_and_place(object, destination)``: the action parser splits on commas and parentheses and
strips quotes, so a name containing any of ``, ( ) ' " ` `` could be planned but never read back
(and never executed). Such names are rejected when the scene is loaded, with the reason.
"""

from __future__ import annotations

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

FORBIDDEN_NAME_CHARS = ",()'\"`"
"""Characters the action format cannot carry in an object name."""


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


def check_request(request: object) -> str:
    """A request, stripped, if it is non-empty text within :data:`MAX_REQUEST_CHARS`.

    Raises:
        ConfigError: Not a string, empty (or only spaces), or too long.
    """
    if not isinstance(request, str):
        raise ConfigError("the request must be text")
    text = request.strip()
    if not text:
        raise ConfigError(
            "the request is empty", hint='say what the robot should do, e.g. "bring me an apple"'
        )
    if len(text) > MAX_REQUEST_CHARS:
        raise ConfigError(f"the request is {len(text)} characters long; the limit is {MAX_REQUEST_CHARS}")
    return text


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
