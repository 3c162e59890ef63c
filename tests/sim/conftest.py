"""Small scenes for simulator tests."""

from __future__ import annotations

from conceptbot.core.scene import Scene, scene_from_dict


def small_scene(extra: dict | None = None, **lists: list[str]) -> Scene:
    """A scene with a few objects; ``extra`` adds keys such as ``layout``."""
    data = {
        "objects": lists.get("objects", ["apple", "energy bar", "ceramic bowl", "user"]),
        "pickable_objects": lists.get("pickable", ["apple", "energy bar"]),
        "destinations": lists.get("destinations", ["ceramic bowl", "user"]),
    }
    data.update(extra or {})
    return scene_from_dict(data)
