"""The demo scenes shipped with the package, and loading scenes by name or path."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.core.scene import Scene
from conceptbot.scenes import demo_scene_names, load_demo_scene, resolve_scene

EXPECTED = {
    "kitchen",
    *(f"materials-{i}" for i in range(1, 8)),
    *(f"toxic-{i}" for i in range(1, 6)),
    "example-spill",
    "example-dirty-plate",
    "example-scissors",
    "example-stack",
    "example-paper",
}


def test_names_are_sorted_and_include_the_paper_scenes() -> None:
    names = demo_scene_names()
    assert names == sorted(names)
    assert set(names) >= EXPECTED
    risk = [n for n in names if n.startswith("risk-")]
    assert [n.split("-")[1] for n in risk] == [str(i) for i in range(1, 9)]


@pytest.mark.parametrize("name", demo_scene_names())
def test_every_demo_scene_is_usable(name: str) -> None:
    scene = load_demo_scene(name)
    assert isinstance(scene, Scene)
    assert scene.name == name
    assert scene.description
    assert scene.pickable, "no pickable object"
    assert scene.destinations, "no destination"
    for obj in scene.objects:
        assert obj.pickable or obj.destination, f"{obj.name!r} can be neither picked nor placed at"
        assert obj.size_m is not None, f"{obj.name!r} has no size"
        assert all(0.0 < v <= 2.0 for v in obj.size_m), f"{obj.name!r} has an implausible size"
    requests = scene.extra.get("requests")
    assert isinstance(requests, list) and requests and all(isinstance(r, str) and r for r in requests)


def test_a_demo_scene_has_the_papers_objects() -> None:
    scene = load_demo_scene("example-dirty-plate")
    assert scene.names == ["plate", "sponge", "apple", "carrot", "banana", "coke", "user"]
    assert set(scene.destinations) == {"plate", "user"}
    assert scene.entity_states == {"plate": "dirty"}
    kitchen = load_demo_scene("kitchen")
    assert {"mustard", "egg", "butter", "lemon", "ceramic bowl", "7up", "Rivella"} <= set(kitchen.names)
    assert "cup" in kitchen.pickable and "cup" not in kitchen.destinations


def test_demo_names_ignore_case_spaces_and_suffix() -> None:
    assert load_demo_scene(" Kitchen.json ").name == "kitchen"


def test_unknown_demo_name_lists_the_known_ones() -> None:
    with pytest.raises(ConfigError) as info:
        load_demo_scene("living-room")
    message = str(info.value)
    assert "unknown demo scene 'living-room'" in message
    for name in demo_scene_names():
        assert name in message


def test_resolve_scene_takes_a_name() -> None:
    assert resolve_scene("risk-2-microwave") == load_demo_scene("risk-2-microwave")


def test_resolve_scene_takes_a_path(tmp_path: Path) -> None:
    path = tmp_path / "mine.json"
    path.write_text(json.dumps({"pickable_objects": ["pear"], "destinations": ["user"], "name": "mine"}))
    scene = resolve_scene(str(path))
    assert (scene.name, scene.names) == ("mine", ["pear", "user"])


def test_an_existing_file_wins_over_a_demo_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    scene = {"objects": ["pear"], "pickable_objects": ["pear"], "destinations": ["user"]}
    Path("kitchen").write_text(json.dumps(scene))
    assert resolve_scene("kitchen").names == ["pear", "user"]


def test_resolve_scene_reports_an_invalid_file(tmp_path: Path) -> None:
    path = tmp_path / "bad.json"
    path.write_text("{not json")
    with pytest.raises(ConfigError, match="not valid JSON"):
        resolve_scene(str(path))


def test_resolve_scene_missing_path_says_so(tmp_path: Path) -> None:
    missing = tmp_path / "missing.json"
    with pytest.raises(ConfigError) as info:
        resolve_scene(str(missing))
    assert f"no scene file {missing}" in str(info.value)
    assert "kitchen" in str(info.value)


def test_resolve_scene_unknown_name_lists_the_known_ones() -> None:
    with pytest.raises(ConfigError) as info:
        resolve_scene("garage")
    message = str(info.value)
    assert "unknown demo scene 'garage'" in message
    assert all(name in message for name in demo_scene_names())
