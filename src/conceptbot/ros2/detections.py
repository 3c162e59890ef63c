"""Scenes from the robot's detector: ``conceptbot_interfaces/msg/Scene`` to the planner's scene.

A detection's confidence and box feed the affordance as a scene file's ``detections`` do (the
paper's detector scores); a size and a state are kept where the detector gives them. The message is
turned into a scene file's fields and read by the scene loader, so a detector's scene is checked
exactly as a file is (one error message for a bad name, box or confidence).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Sequence
from typing import Any

from conceptbot.core.errors import ConfigError
from conceptbot.core.scene import Scene, scene_from_dict


def _given(values: Sequence[float]) -> list[float] | None:
    """A fixed-size field of the message, or None where the detector left it all zero."""
    found = [float(v) for v in values]
    return None if all(v == 0.0 for v in found) else found


def scene_dict(msg: Any) -> dict[str, Any]:
    """A ``conceptbot_interfaces/msg/Scene`` as a scene file's fields (see :mod:`conceptbot.core.scene`).

    Destinations that were not detected ("user", a table the detector does not box) are added as
    objects; an empty ``pickable`` makes every detection that is not a destination pickable.
    """
    names = [str(d.name) for d in msg.detections]
    destinations = [str(n) for n in msg.destinations]
    pickable = [str(n) for n in msg.pickable] or [n for n in names if n not in destinations]
    detections: dict[str, dict[str, Any]] = {}
    states: dict[str, str] = {}
    for found in msg.detections:
        entry: dict[str, Any] = {"confidence": float(found.confidence)}
        if (box := _given(found.box_px)) is not None:
            entry["bbox_px"] = box
        if (size := _given(found.size_m)) is not None:
            entry["size_m"] = size
        detections[str(found.name)] = entry
        if str(found.state).strip():
            states[str(found.name)] = str(found.state)
    objects = list(dict.fromkeys([*names, *(d for d in destinations if d not in names)]))
    return {
        "name": "detections",
        "objects": objects,
        "pickable_objects": pickable,
        "destinations": destinations,
        "entity_states": states,
        "detections": detections,
    }


def scene_from_msg(msg: Any) -> Scene:
    """The planner's scene from a detector's ``Scene`` message.

    Raises:
        ConfigError: No detections, a name twice, a confidence outside [0, 1], a bad box or size, or
            a pickable or destination name that was not detected (the scene loader's message).
    """
    if not msg.detections:
        raise ConfigError("the scene has no detections", hint="a Scene lists what the detector sees")
    names = [str(d.name) for d in msg.detections]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ConfigError(f"detected twice: {', '.join(twice)}", hint="give each object one detection")
    for found in msg.detections:
        if not math.isfinite(found.confidence) or not 0.0 <= found.confidence <= 1.0:
            raise ConfigError(f"detection {found.name!r}: confidence {found.confidence} is not in [0, 1]")
        box = _given(found.box_px)
        if box is not None and not (box[0] < box[2] and box[1] < box[3]):
            raise ConfigError(f"detection {found.name!r}: box_px {box} is not x0 < x1, y0 < y1")
    missing = sorted(set(map(str, msg.pickable)) - set(names) - set(map(str, msg.destinations)))
    if missing:
        raise ConfigError(f"pickable but not detected: {', '.join(missing)}")
    return scene_from_dict(scene_dict(msg), where="scene")


def stamp_seconds(msg: Any) -> float | None:
    """The message's header time in seconds, or None when the detector left it zero."""
    seconds = msg.stamp.sec + msg.stamp.nanosec * 1e-9
    return seconds if seconds > 0 else None


class LatestScene:
    """The detector's latest scene and when it came (thread-safe: the subscription writes it, the
    planner's worker reads it).

    Args:
        max_age_s: How old the latest scene may be when a goal is planned against it.
        clock: Seconds now (the node's ROS clock in seconds, so a stamped scene is aged on the same
            clock as its stamp).
    """

    def __init__(self, max_age_s: float, clock: Any = time.time) -> None:
        self.max_age_s = max_age_s
        self.clock = clock
        self._lock = threading.Lock()
        self._latest: tuple[Scene | ConfigError, float] | None = None

    def put(self, msg: Any) -> None:
        """Keep ``msg`` as the latest scene (a bad one is kept as its error, to be reported)."""
        try:
            found: Scene | ConfigError = scene_from_msg(msg)
        except ConfigError as exc:
            found = exc
        with self._lock:
            self._latest = (found, stamp_seconds(msg) or self.clock())

    def current(self) -> Scene:
        """The latest scene.

        Raises:
            ConfigError: None has come, it is older than ``max_age_s``, or it was malformed.
        """
        with self._lock:
            latest = self._latest
        if latest is None:
            raise ConfigError(
                "no detections have come from the detector yet",
                hint="publish a conceptbot_interfaces/msg/Scene on the detections topic, or send the scene",
            )
        found, at = latest
        age = self.clock() - at
        if age > self.max_age_s:
            raise ConfigError(
                f"the latest detections are {age:.1f} s old (at most {self.max_age_s:g} s)",
                hint="is the detector running? (or raise the detections_max_age_s parameter)",
            )
        if isinstance(found, ConfigError):
            raise ConfigError(f"the latest detections are malformed: {found.message}", hint=found.hint)
        return found
