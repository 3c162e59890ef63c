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
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError


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
    if not isinstance(value, list) or not all(isinstance(v, str) and v.strip() for v in value):
        raise ConfigError(f"{where}: {key!r} must be a list of non-empty names")
    return [v.strip() for v in value]


def _floats(value: Any, n: int, label: str, where: str) -> tuple[float, ...] | None:
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != n or not all(isinstance(v, int | float) for v in value):
        raise ConfigError(f"{where}: {label} must be a list of {n} numbers")
    return tuple(float(v) for v in value)


def scene_from_dict(data: Mapping[str, Any], where: str = "scene") -> Scene:
    """Build and validate a scene from its JSON form.

    Raises:
        ConfigError: Wrong types, duplicate names, no objects, a state or detection for an unknown
            object, or a confidence outside [0, 1].
    """
    if not isinstance(data, Mapping):
        raise ConfigError(f"{where}: a scene must be a JSON object")
    objects = _names(data, "objects", where)
    pickable = _names(data, "pickable_objects", where)
    destinations = _names(data, "destinations", where)
    ordered = list(dict.fromkeys(objects + pickable + destinations))
    if len(set(objects)) != len(objects):
        raise ConfigError(f"{where}: duplicate object names in 'objects'")
    if not ordered:
        raise ConfigError(f"{where}: the scene has no objects")
    states = data.get("entity_states", {}) or {}
    detections = data.get("detections", {}) or {}
    if not isinstance(states, Mapping) or not isinstance(detections, Mapping):
        raise ConfigError(f"{where}: entity_states and detections must be JSON objects")
    for key in list(states) + list(detections):
        if key not in ordered:
            raise ConfigError(f"{where}: {key!r} has a state or detection but is not in the scene")
    built = []
    for name in ordered:
        det = detections.get(name, {})
        if not isinstance(det, Mapping):
            raise ConfigError(f"{where}: detections[{name!r}] must be a JSON object")
        confidence = det.get("confidence", 1.0)
        if not isinstance(confidence, int | float) or not 0.0 <= confidence <= 1.0:
            raise ConfigError(f"{where}: confidence of {name!r} must be a number in [0, 1]")
        state = states.get(name)
        built.append(
            SceneObject(
                name=name,
                pickable=name in pickable,
                destination=name in destinations,
                confidence=float(confidence),
                bbox_px=_floats(det.get("bbox_px"), 4, f"bbox_px of {name!r}", where),  # type: ignore[arg-type]
                size_m=_floats(det.get("size_m"), 3, f"size_m of {name!r}", where),  # type: ignore[arg-type]
                state=str(state) if state else None,
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
    return Scene(tuple(built), str(data.get("name", "scene")), str(data.get("description", "")), extra)


def load_scene(path: Path) -> Scene:
    """Read a scene file (JSON).

    Raises:
        ConfigError: Missing file, invalid JSON, or an invalid scene.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"no scene file {path}") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{path} is not valid JSON: {exc}") from None
    return scene_from_dict(data, where=str(path))
