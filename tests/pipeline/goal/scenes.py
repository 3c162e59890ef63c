"""Small scenes for the goal reader's tests (ours: no benchmark scene, no benchmark object)."""

from __future__ import annotations

from conceptbot.core.scene import Scene, scene_from_dict


def scene(pickable: list[str], destinations: list[str]) -> Scene:
    """A scene of names only."""
    return scene_from_dict(
        {
            "name": "test",
            "objects": pickable + destinations,
            "pickable_objects": pickable,
            "destinations": destinations,
        }
    )


SHELLS = scene(
    ["cowrie shell", "scallop shell", "conch shell", "sand dollar"], ["shoe box", "biscuit tin", "user"]
)
NURSERY = scene(["rattle", "wooden duck", "nappy cream", "safety pins"], ["kids chair", "top shelf", "user"])
WORKSHOP = scene(
    ["steel nail", "oak dowel", "brass hinge", "felt pad", "rubber mallet"],
    ["wood crate", "metal crate", "felt crate", "odds crate"],
)
PANTRY = scene(["avocado", "lime", "cracker", "bowl of olives"], ["serving bowl", "chopping board", "user"])
KENNEL = scene(["dog brush", "squeaky bone", "dog lead", "tin of biscuits"], ["dog", "basket", "user"])
