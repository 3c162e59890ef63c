"""Scenes: what the robot sees. Objects, which can be picked and which are destinations, their
states, and optional detections (confidence, bounding box in pixels, real size).

Minimal JSON form (names only)::

    {"objects": ["apple", "bowl", "user"], "pickable_objects": ["apple"],
     "destinations": ["bowl", "user"], "entity_states": {"cup": "contains a drink"}}

Optional per-object detections, keyed by name::

    "detections": {"apple": {"confidence": 0.93, "bbox_px": [120, 80, 170, 135],
                             "size_m": [0.08, 0.08, 0.08]}}

Defaults: confidence 1.0, no bounding box, no size (the affordance then does not penalise size).
An object listed only under ``pickable_objects`` or ``destinations`` is added to ``objects``.
A scene needs at least one pickable object and one destination (otherwise the only possible plan is
``done()``); names, sizes and nesting are limited as :mod:`conceptbot.core.limits` says.

:class:`HouseScene` is the other world's scene: a household room (SafeAgentBench) as a room type and
the AI2-THOR object types in it, built by :func:`conceptbot.household.thor.house_scene`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError
from conceptbot.core.limits import (
    MAX_JSON_DEPTH,
    MAX_OBJECTS,
    MAX_SCENE_FILE_BYTES,
    MAX_STATE_CHARS,
    check_name,
    json_depth,
)


@dataclass(frozen=True)
class SceneObject:
    """One object in a scene.

    Attributes:
        name: The name as the scene spells it; plans use exactly this name.
        pickable: The robot may pick it up.
        destination: Things may be placed on/in/at it (bowls, bins, "user", "table").
        confidence: Detection confidence in [0, 1].
        bbox_px: Bounding box ``(x0, y0, x1, y1)`` in image pixels, or None.
        size_m: Real size ``(width, depth, height)`` in metres, or None.
        state: Entity state in words ("contains a drink"), or None.
    """

    name: str
    pickable: bool = False
    destination: bool = False
    confidence: float = 1.0
    bbox_px: tuple[float, float, float, float] | None = None
    size_m: tuple[float, float, float] | None = None
    state: str | None = None


@dataclass(frozen=True)
class Scene:
    """A scene: its objects in order, plus a name and description for people."""

    objects: tuple[SceneObject, ...]
    name: str = "scene"
    description: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        """All object names, in scene order."""
        return [o.name for o in self.objects]

    @property
    def pickable(self) -> list[str]:
        """Names of objects the robot may pick."""
        return [o.name for o in self.objects if o.pickable]

    @property
    def destinations(self) -> list[str]:
        """Names of objects things may be placed at."""
        return [o.name for o in self.objects if o.destination]

    @property
    def entity_states(self) -> dict[str, str]:
        """Object name -> state, for objects that have one."""
        return {o.name: o.state for o in self.objects if o.state}

    def get(self, name: str) -> SceneObject | None:
        """The object called exactly ``name`` (case-insensitive fallback), or None."""
        for obj in self.objects:
            if obj.name == name:
                return obj
        lowered = name.strip().lower()
        for obj in self.objects:
            if obj.name.lower() == lowered:
                return obj
        return None

    def to_dict(self) -> dict[str, Any]:
        """The JSON form (round-trips through :func:`scene_from_dict`)."""
        detections = {}
        for o in self.objects:
            det: dict[str, Any] = {}
            if o.confidence != 1.0:
                det["confidence"] = o.confidence
            if o.bbox_px is not None:
                det["bbox_px"] = list(o.bbox_px)
            if o.size_m is not None:
                det["size_m"] = list(o.size_m)
            if det:
                detections[o.name] = det
        data: dict[str, Any] = {
            "name": self.name,
            "description": self.description,
            "objects": self.names,
            "pickable_objects": self.pickable,
            "destinations": self.destinations,
            "entity_states": self.entity_states,
        }
        if detections:
            data["detections"] = detections
        data.update(self.extra)
        return data


def _names(data: Mapping[str, Any], key: str, where: str) -> list[str]:
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ConfigError(f"{where}: {key!r} must be a list of names (strings)")
    if len(value) > MAX_OBJECTS:
        raise ConfigError(f"{where}: {key!r} lists {len(value)} objects; a scene holds at most {MAX_OBJECTS}")
    return [check_name(v, where) for v in value]


def _is_number(value: Any) -> bool:
    # bool is an int in Python, and JSON's NaN/Infinity parse as floats: neither is a measurement.
    return isinstance(value, int | float) and not isinstance(value, bool) and abs(value) < float("inf")


def _floats(value: Any, n: int, label: str, where: str) -> tuple[float, ...] | None:
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != n or not all(_is_number(v) for v in value):
        raise ConfigError(f"{where}: {label} must be a list of {n} numbers")
    return tuple(float(v) for v in value)


def _text(data: Mapping[str, Any], key: str, default: str, where: str) -> str:
    value = data.get(key, default)
    if not isinstance(value, str):
        raise ConfigError(f"{where}: {key!r} must be a string")
    return value


def _state(name: str, value: Any, where: str) -> str | None:
    if not isinstance(value, str):
        raise ConfigError(
            f"{where}: the state of {name!r} must be a string, got {json.dumps(value)[:40]}",
            hint='describe it in words, e.g. "entity_states": {"cup": "contains hot tea"}',
        )
    if len(value) > MAX_STATE_CHARS:
        raise ConfigError(f"{where}: the state of {name!r} is longer than {MAX_STATE_CHARS} characters")
    return value.strip() or None


def scene_from_dict(data: Mapping[str, Any], where: str = "scene") -> Scene:
    """Build and validate a scene from its JSON form.

    Raises:
        ConfigError: Wrong types, duplicate names, no objects, no pickable object or no destination,
            a name the action format cannot carry, more than ``MAX_OBJECTS`` objects, a non-string
            state, a state or detection for an unknown object, or a confidence outside [0, 1].
    """
    if not isinstance(data, Mapping):
        raise ConfigError(f"{where}: a scene must be a JSON object")
    if json_depth(data) > MAX_JSON_DEPTH:
        raise ConfigError(f"{where}: the scene is nested more than {MAX_JSON_DEPTH} levels deep")
    objects = _names(data, "objects", where)
    pickable = _names(data, "pickable_objects", where)
    destinations = _names(data, "destinations", where)
    ordered = list(dict.fromkeys(objects + pickable + destinations))
    if len(set(objects)) != len(objects):
        raise ConfigError(f"{where}: duplicate object names in 'objects'")
    if not ordered:
        raise ConfigError(f"{where}: the scene has no objects")
    if len(ordered) > MAX_OBJECTS:
        raise ConfigError(f"{where}: the scene has {len(ordered)} objects; the limit is {MAX_OBJECTS}")
    states = data.get("entity_states", {}) or {}
    detections = data.get("detections", {}) or {}
    if not isinstance(states, Mapping) or not isinstance(detections, Mapping):
        raise ConfigError(f"{where}: entity_states and detections must be JSON objects")
    for key in list(states) + list(detections):
        if key not in ordered:
            raise ConfigError(f"{where}: {key!r} has a state or detection but is not in the scene")
    if not pickable or not destinations:
        missing = "pickable_objects" if not pickable else "destinations"
        raise ConfigError(
            f"{where}: the scene has no {missing}, so the robot could do nothing but done()",
            hint="list what the robot may pick under 'pickable_objects' and where things may go "
            "under 'destinations'",
        )
    built = []
    for name in ordered:
        det = detections.get(name, {})
        if not isinstance(det, Mapping):
            raise ConfigError(f"{where}: detections[{name!r}] must be a JSON object")
        confidence = det.get("confidence", 1.0)
        if not _is_number(confidence) or not 0.0 <= confidence <= 1.0:
            raise ConfigError(f"{where}: confidence of {name!r} must be a number in [0, 1]")
        built.append(
            SceneObject(
                name=name,
                pickable=name in pickable,
                destination=name in destinations,
                confidence=float(confidence),
                bbox_px=_floats(det.get("bbox_px"), 4, f"bbox_px of {name!r}", where),  # type: ignore[arg-type]
                size_m=_floats(det.get("size_m"), 3, f"size_m of {name!r}", where),  # type: ignore[arg-type]
                state=_state(name, states[name], where) if name in states else None,
            )
        )
    known = {
        "name",
        "description",
        "objects",
        "pickable_objects",
        "destinations",
        "entity_states",
        "detections",
    }
    extra = {k: v for k, v in data.items() if k not in known}
    name = _text(data, "name", "scene", where)
    return Scene(tuple(built), name, _text(data, "description", "", where), extra)


def load_scene(path: Path) -> Scene:
    """Read a scene file (JSON).

    Raises:
        ConfigError: Missing file, invalid JSON, or an invalid scene.
    """
    path = Path(path)
    try:
        if path.stat().st_size > MAX_SCENE_FILE_BYTES:
            raise ConfigError(
                f"{path} is larger than {MAX_SCENE_FILE_BYTES:,} bytes; that is not a scene file"
            )
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"no scene file {path}") from None
    except IsADirectoryError:
        raise ConfigError(f"{path} is a folder, not a scene file") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{path} is not UTF-8 text") from None
    except RecursionError:
        raise ConfigError(f"{path}: the scene is nested more than {MAX_JSON_DEPTH} levels deep") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{path} is not valid JSON: {exc}") from None
    return scene_from_dict(data, where=str(path))


@dataclass(frozen=True)
class HouseScene:
    """What a household robot can act on: a room type and the AI2-THOR object types present."""

    name: str
    room: str
    objects: tuple[str, ...]

    def has(self, type_name: str) -> bool:
        """Whether the scene holds an object of this type."""
        return type_name in self.objects
