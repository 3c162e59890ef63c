"""Demo scenes from the ConceptBot paper, shipped as package data, and a loader by name or path.

The scenes live in ``conceptbot/scenes/data/*.json`` (one file per scene, the file stem is its name; see
``data/README.md`` for where each comes from in the paper). Each is an ordinary scene file in the format
of :mod:`conceptbot.core.scene`; most also carry a ``requests`` list (the paper's instructions for that
scene), kept in :attr:`Scene.extra <conceptbot.core.scene.Scene.extra>`.

Example::

    from conceptbot.scenes import demo_scene_names, resolve_scene

    demo_scene_names()                 # ['example-dirty-plate', ..., 'kitchen', ..., 'toxic-5']
    resolve_scene("kitchen")           # a demo scene by name
    resolve_scene("my_scene.json")     # or any scene file
"""

from __future__ import annotations

import json
from importlib.resources import files
from importlib.resources.abc import Traversable
from pathlib import Path

from conceptbot.core.errors import ConfigError
from conceptbot.core.scene import Scene, load_scene, scene_from_dict

__all__ = ["demo_scene_names", "load_demo_scene", "resolve_scene"]


def _data_dir() -> Traversable:
    """The folder of demo scene files inside the installed package."""
    return files(__name__).joinpath("data")


def _demo_files() -> dict[str, Traversable]:
    """Demo scene name -> its JSON resource."""
    return {
        entry.name.removesuffix(".json"): entry
        for entry in _data_dir().iterdir()
        if entry.is_file() and entry.name.endswith(".json")
    }


def demo_scene_names() -> list[str]:
    """Names of the demo scenes shipped with the package, sorted.

    Returns:
        Names such as ``"kitchen"``, ``"risk-1-hot-tea"``, ``"materials-3"``, ``"example-spill"``.
    """
    return sorted(_demo_files())


def _unknown(name: str) -> ConfigError:
    """The error for a name that is neither a demo scene nor a file."""
    known = ", ".join(demo_scene_names())
    return ConfigError(
        f"unknown demo scene {name!r}; known demo scenes: {known}",
        hint="pass one of these names, or the path of a scene JSON file",
    )


def load_demo_scene(name: str) -> Scene:
    """Load a demo scene by name.

    Args:
        name: A name from :func:`demo_scene_names` (surrounding spaces, letter case and a trailing
            ``.json`` are ignored).

    Returns:
        The validated scene.

    Raises:
        ConfigError: No demo scene has that name (the message lists the known ones), or the shipped file
            is invalid.
    """
    key = name.strip().lower().removesuffix(".json")
    resource = _demo_files().get(key)
    if resource is None:
        raise _unknown(name)
    where = f"demo scene {key!r}"
    try:
        data = json.loads(resource.read_text(encoding="utf-8"))
    except ValueError as exc:
        raise ConfigError(f"{where} is not valid JSON: {exc}") from None
    return scene_from_dict(data, where=where)


def resolve_scene(name_or_path: str) -> Scene:
    """Load a scene given either a file path or a demo scene name.

    An existing file is always loaded as a scene file (so a local ``kitchen`` file wins over the demo
    scene of that name); anything else is looked up among the demo scenes.

    Args:
        name_or_path: Path of a scene JSON file, or a name from :func:`demo_scene_names`.

    Returns:
        The validated scene.

    Raises:
        ConfigError: The file is not a valid scene; or there is no such file and no demo scene of that
            name (the message lists the demo scenes).
    """
    path = Path(name_or_path).expanduser()
    if path.is_file():
        return load_scene(path)
    key = name_or_path.strip().lower().removesuffix(".json")
    if key in _demo_files():
        return load_demo_scene(key)
    if path.suffix.lower() == ".json" or "/" in name_or_path or "\\" in name_or_path:
        known = ", ".join(demo_scene_names())
        raise ConfigError(
            f"no scene file {name_or_path} (and no demo scene of that name)",
            hint=f"check the path, or use a demo scene: {known}",
        )
    raise _unknown(name_or_path)
