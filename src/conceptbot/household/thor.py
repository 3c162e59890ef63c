"""AI2-THOR object types (actionable properties) and household scenes built from them.

The data file ``data/thor.json`` holds every iTHOR object type with its abilities (pickupable,
receptacle, openable, toggleable, breakable, sliceable, cookable, dirtyable, fillable, usedup), the
types assumed in every scene of a room type, aliases people use ("counter" for CounterTop), and what
slicing or cracking makes ("Apple" -> "AppleSliced", "Egg" -> "EggCracked").

AI2-THOR itself (a Unity program) is not available offline, so a scene here is a set of object types,
not a 3-D room: see :func:`house_scene`.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

from conceptbot.core.scene import HouseScene


def key(name: str) -> str:
    """Comparison key of an object name: lower case, no spaces, underscores or hyphens."""
    return re.sub(r"[\s_\-]+", "", name).lower()


ROOM_BY_HUNDREDS = {0: "kitchen", 2: "living room", 3: "bedroom", 4: "bathroom"}


@dataclass(frozen=True)
class ThorCatalogue:
    """AI2-THOR's object-type table."""

    types: dict[str, frozenset[str]]
    derived: dict[str, str]
    rooms: dict[str, tuple[str, ...]]
    aliases: dict[str, str]
    liquids: tuple[str, ...]
    default_parent: dict[str, str]
    by_key: dict[str, str]  # comparison key (see key) -> type

    def canonical(self, name: str) -> str | None:
        """The object type a name means (case, spaces and a plural 's' forgiven), or None."""
        k = key(name)
        for candidate in (k, k[:-1] if k.endswith("s") else k):
            if candidate in self.by_key:
                return self.by_key[candidate]
            if candidate in self.aliases:
                return self.aliases[candidate]
        return None

    def has(self, type_name: str, ability: str) -> bool:
        """Whether objects of a type have an ability (unknown types have none)."""
        return ability in self.types.get(type_name, frozenset())


@cache
def catalogue() -> ThorCatalogue:
    """The bundled object-type table."""
    raw: dict[str, Any] = json.loads(
        resources.files("conceptbot.household").joinpath("data/thor.json").read_text(encoding="utf-8")
    )
    return ThorCatalogue(
        types={t: frozenset(a) for t, a in raw["types"].items()},
        derived=dict(raw["derived"]),
        rooms={r: tuple(ts) for r, ts in raw["rooms"].items()},
        aliases={key(a): t for a, t in raw["aliases"].items()},
        liquids=tuple(raw["liquids"]),
        default_parent=dict(raw["default_parent"]),
        by_key={key(t): t for t in raw["types"]},
    )


def room_of(scene_name: str) -> str:
    """The room type of an iTHOR scene name (FloorPlan1-30 kitchens, 201-230 living rooms, 301-330
    bedrooms, 401-430 bathrooms); ``kitchen`` for names without a number."""
    match = re.search(r"(\d+)$", scene_name)
    if not match:
        return "kitchen"
    return ROOM_BY_HUNDREDS.get(int(match.group(1)) // 100, "kitchen")


def house_scene(name: str, mentioned: Sequence[str] = ()) -> HouseScene:
    """The scene ``name``: its room type's usual objects plus every type in ``mentioned`` (the
    objects its tasks name). Unknown names in ``mentioned`` are skipped."""
    cat = catalogue()
    room = room_of(name)
    objects = list(cat.rooms[room])
    for m in mentioned:
        t = cat.canonical(m)
        if t and t not in objects and t not in cat.derived.values():
            objects.append(t)
    return HouseScene(name, room, tuple(sorted(objects)))
