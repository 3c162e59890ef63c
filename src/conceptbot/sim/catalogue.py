"""The object catalogue: what each named object looks like physically (shape, size, mass, colour).

The data is ``sim/data/objects.json`` (every object in the paper's tables and the demo scenes). Look-up
order for a name: exact, case-insensitive, then the longest matching tail of its words ("stainless steel
spoon" -> "spoon", "Green Hellebore" -> "green hellebore"), then the scene's own ``size_m`` on the
default shape, then the default (a 6 cm grey box) -- the last two with a warning, so a user sees which
objects were guessed.

Receptacles are scaled to fit one tabletop: footprints of containers and zones are capped at
:data:`MAX_RECEPTACLE_FOOTPRINT_M` and container heights at :data:`MAX_CONTAINER_HEIGHT_M` (a real
kitchen bin stands beside the table; here the arm reaches into a tub on it). Grip modes follow from the
shape (see :func:`grip_mode`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError

SHAPES = ("box", "cylinder", "sphere", "container", "flat", "zone")
GRIPS = ("body", "rim", "knob", "edge")
MAX_RECEPTACLE_FOOTPRINT_M = 0.28
MAX_ZONE_FOOTPRINT_M = 0.3
MAX_CONTAINER_HEIGHT_M = 0.12
THIN_M = 0.016  # objects thinner than this lie flat: picked by the edge (see grip_mode)


@dataclass(frozen=True)
class ObjectSpec:
    """Physical description of one object.

    Attributes:
        name: The scene's name for it.
        shape: One of :data:`SHAPES`.
        size_m: ``(width, depth, height)`` in metres (after receptacle capping).
        mass_kg: Mass; 0 for static zones.
        rgba: Colour.
        grip: How the gripper holds it, one of :data:`GRIPS`.
        source: ``catalogue``, ``scene`` (the scene's size on the default shape) or ``default``.
        foliage_m: Height of soft growth drawn above the rigid body (potted plants: ``size_m`` is the
            pot, which is what collides and what the gripper holds; leaves bend around a hand, so
            they are visual only).
    """

    name: str
    shape: str
    size_m: tuple[float, float, float]
    mass_kg: float
    rgba: tuple[float, float, float, float]
    grip: str
    source: str = "catalogue"
    foliage_m: float = 0.0

    @property
    def footprint_radius(self) -> float:
        """Half the footprint diagonal: the radius that keeps layouts free of overlaps."""
        w, d, _ = self.size_m
        return 0.5 * (w * w + d * d) ** 0.5


def grip_mode(shape: str, size_m: tuple[float, float, float], override: str | None = None) -> str:
    """How the gripper holds an object.

    ``rim`` for containers (the fingers close on one wall), ``edge`` for flat things thinner than
    :data:`THIN_M` (sheets, a paper clip; held as a suction cup would hold them -- a parallel gripper
    cannot close on a sheet lying on a table), ``body`` otherwise (top-down across the narrower side).
    A catalogue entry may say ``knob`` (a teapot is lifted by its lid knob).
    """
    if override:
        return override
    if shape == "container":
        return "rim"
    if shape == "flat" or size_m[2] < THIN_M:
        return "edge"
    return "body"


def _check(key: str, entry: dict[str, Any]) -> None:
    """Raise ConfigError unless ``entry`` is a complete, valid object description."""
    try:
        valid = (
            entry["shape"] in SHAPES
            and entry.get("grip", "body") in GRIPS
            and len(entry["size"]) == 3
            and min(float(v) for v in entry["size"]) > 0
            and len(entry["rgba"]) == 4
            and float(entry["mass"]) >= 0
            and float(entry.get("pot", 1.0)) > 0
        )
    except (KeyError, TypeError, ValueError):
        valid = False
    if not valid:
        raise ConfigError(
            f"object catalogue: {key!r} needs a known shape and grip, a positive 3-number size, "
            "a mass and an rgba"
        )


class Catalogue:
    """Object specs by name; see the module docstring for the look-up order.

    Args:
        data: The parsed catalogue (``{"kinds": ..., "objects": ...}``).
    """

    def __init__(self, data: dict[str, Any]) -> None:
        kinds = data.get("kinds", {})
        if "default" not in kinds:
            raise ConfigError("object catalogue: a 'default' kind is required")
        self._kinds: dict[str, dict[str, Any]] = kinds
        self._objects: dict[str, dict[str, Any]] = {k.lower(): v for k, v in data.get("objects", {}).items()}
        self.warnings: list[str] = []
        _check("default", kinds["default"])
        for name in self._objects:
            self._entry(name)  # validate eagerly: a bad data file fails on load, not mid-run

    @classmethod
    def load(cls, path: Path | None = None) -> Catalogue:
        """The shipped catalogue, or a JSON file in the same format.

        Raises:
            ConfigError: Missing or invalid file.
        """
        try:
            if path is None:
                text = files("conceptbot.sim").joinpath("data/objects.json").read_text(encoding="utf-8")
            else:
                text = Path(path).read_text(encoding="utf-8")
            return cls(json.loads(text))
        except FileNotFoundError:
            raise ConfigError(f"no object catalogue {path}") from None
        except ValueError as exc:
            raise ConfigError(f"object catalogue {path or 'objects.json'}: {exc}") from None

    def names(self) -> list[str]:
        """Every object name the catalogue knows (lower case)."""
        return sorted(self._objects)

    def _entry(self, key: str) -> dict[str, Any]:
        entry = dict(self._kinds["default"])
        raw = self._objects[key]
        kind = raw.get("kind")
        if kind is not None:
            if kind not in self._kinds:
                raise ConfigError(f"object catalogue: {key!r} names unknown kind {kind!r}")
            entry.update(self._kinds[kind])
        entry.update({k: v for k, v in raw.items() if k != "kind"})
        _check(key, entry)
        return entry

    def _find(self, name: str) -> str | None:
        key = name.strip().lower()
        if key in self._objects:
            return key
        words = key.replace("-", " ").split()
        for start in range(1, len(words)):
            tail = " ".join(words[start:])
            if tail in self._objects:
                return tail
        return None

    def spec(self, name: str, scene_size: tuple[float, float, float] | None = None) -> ObjectSpec:
        """The spec for ``name`` (warnings for guessed objects go to :attr:`warnings`)."""
        key = self._find(name)
        if key is not None:
            entry, source = self._entry(key), "catalogue"
        else:
            entry = dict(self._kinds["default"])
            if scene_size is not None:
                entry["size"], source = list(scene_size), "scene"
                self.warnings.append(f"{name!r} is not in the object catalogue: a box of the scene's size")
            else:
                source = "default"
                self.warnings.append(f"{name!r} is not in the object catalogue: a 6 cm grey box")
        shape = entry["shape"]
        w, d, h = (float(v) for v in entry["size"])
        if shape in ("container", "zone"):
            cap = MAX_ZONE_FOOTPRINT_M if shape == "zone" else MAX_RECEPTACLE_FOOTPRINT_M
            w, d = min(w, cap), min(d, cap)
            h = min(h, MAX_CONTAINER_HEIGHT_M) if shape == "container" else 0.005
        foliage = 0.0
        if "pot" in entry and h > float(entry["pot"]):
            foliage, h = h - float(entry["pot"]), float(entry["pot"])
        size = (w, d, h)
        return ObjectSpec(
            name=name,
            shape=shape,
            size_m=size,
            mass_kg=0.0 if shape == "zone" else float(entry["mass"]),
            rgba=tuple(float(v) for v in entry["rgba"]),  # type: ignore[arg-type]
            grip=grip_mode(shape, size, entry.get("grip")),
            source=source,
            foliage_m=foliage,
        )
