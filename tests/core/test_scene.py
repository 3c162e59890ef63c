"""The scene format and loader (conceptbot.core.scene)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.core.scene import Scene, SceneObject, load_scene, scene_from_dict

MINIMAL: dict[str, Any] = {
    "objects": ["apple", "bowl", "user", "cup"],
    "pickable_objects": ["apple", "cup"],
    "destinations": ["bowl", "user"],
    "entity_states": {"cup": "contains a drink"},
}


def test_minimal_form_with_defaults() -> None:
    scene = scene_from_dict(MINIMAL)
    assert scene.names == ["apple", "bowl", "user", "cup"]
    assert scene.pickable == ["apple", "cup"]
    assert scene.destinations == ["bowl", "user"]
    assert scene.entity_states == {"cup": "contains a drink"}
    assert (scene.name, scene.description, dict(scene.extra)) == ("scene", "", {})
    apple = scene.get("apple")
    assert apple == SceneObject("apple", pickable=True)
    assert (apple.confidence, apple.bbox_px, apple.size_m, apple.state) == (1.0, None, None, None)


def test_names_only_under_pickable_or_destinations_are_added_in_order() -> None:
    scene = scene_from_dict(
        {"objects": ["apple"], "pickable_objects": ["apple", "pear"], "destinations": ["bowl", "pear"]}
    )
    assert scene.names == ["apple", "pear", "bowl"]
    pear = scene.get("pear")
    assert pear is not None and pear.pickable and pear.destination
    assert scene.destinations == ["pear", "bowl"]


def test_objects_key_may_be_left_out() -> None:
    scene = scene_from_dict({"pickable_objects": ["apple"], "destinations": ["user"]})
    assert scene.names == ["apple", "user"]


def test_names_are_stripped() -> None:
    scene = scene_from_dict(
        {"objects": [" apple "], "pickable_objects": ["apple"], "destinations": [" user"]}
    )
    assert scene.names == ["apple", "user"]
    assert scene.pickable == ["apple"]


def test_detections_are_parsed() -> None:
    data = dict(
        MINIMAL,
        detections={
            "apple": {"confidence": 0.93, "bbox_px": [120, 80, 170, 135], "size_m": [0.08, 0.08, 0.08]},
            "bowl": {"size_m": [0.15, 0.15, 0.07]},
        },
    )
    scene = scene_from_dict(data)
    apple, bowl = scene.get("apple"), scene.get("bowl")
    assert apple is not None and bowl is not None
    assert apple.confidence == 0.93
    assert apple.bbox_px == (120.0, 80.0, 170.0, 135.0)
    assert apple.size_m == (0.08, 0.08, 0.08)
    assert (bowl.confidence, bowl.bbox_px, bowl.size_m) == (1.0, None, (0.15, 0.15, 0.07))
    assert all(isinstance(v, float) for v in apple.bbox_px)


def test_get_prefers_exact_name_then_ignores_case() -> None:
    scene = scene_from_dict(
        {"objects": ["Coke", "coke can"], "pickable_objects": ["Coke"], "destinations": ["user"]}
    )
    assert scene.get("Coke") is scene.objects[0]
    assert scene.get(" COKE ") is scene.objects[0]
    assert scene.get("pepsi") is None


def test_name_description_and_extra_keys_are_kept() -> None:
    data = dict(MINIMAL, name="demo", description="a test scene", requests=["Bring me an apple."])
    scene = scene_from_dict(data)
    assert (scene.name, scene.description) == ("demo", "a test scene")
    assert scene.extra == {"requests": ["Bring me an apple."]}


def test_to_dict_round_trip() -> None:
    data = dict(
        MINIMAL,
        name="demo",
        description="round trip",
        detections={
            "apple": {"confidence": 0.5, "bbox_px": [1, 2, 3, 4], "size_m": [0.08, 0.08, 0.08]},
            "user": {"size_m": [0.5, 0.3, 1.7]},
        },
        requests=["Bring me an apple."],
    )
    scene = scene_from_dict(data)
    dumped = scene.to_dict()
    assert dumped["detections"] == {
        "apple": {"confidence": 0.5, "bbox_px": [1.0, 2.0, 3.0, 4.0], "size_m": [0.08, 0.08, 0.08]},
        "user": {"size_m": [0.5, 0.3, 1.7]},
    }
    assert dumped["requests"] == ["Bring me an apple."]
    again = scene_from_dict(json.loads(json.dumps(dumped)))
    assert again == scene


def test_to_dict_leaves_out_detections_when_all_default() -> None:
    dumped = scene_from_dict(MINIMAL).to_dict()
    assert "detections" not in dumped
    assert scene_from_dict(dumped) == scene_from_dict(MINIMAL)


def test_load_scene_reads_a_file(tmp_path: Path) -> None:
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(dict(MINIMAL, name="from-file")), encoding="utf-8")
    scene = load_scene(path)
    assert isinstance(scene, Scene)
    assert scene.name == "from-file"
    assert scene.pickable == ["apple", "cup"]


def _with(**changes: Any) -> dict[str, Any]:
    return {**MINIMAL, **changes}


@pytest.mark.parametrize(
    ("data", "fragment"),
    [
        (["apple"], "a scene must be a JSON object"),
        (_with(objects="apple"), "'objects' must be a list of names"),
        (_with(objects=["apple", ""]), "object names must not be empty"),
        (_with(objects=["apple", 3]), "'objects' must be a list of names"),
        (_with(pickable_objects=[" "]), "object names must not be empty"),
        (_with(destinations={"bowl": 1}), "'destinations' must be a list of names"),
        (_with(objects=["apple", "apple"]), "duplicate object names"),
        ({"objects": []}, "the scene has no objects"),
        ({}, "the scene has no objects"),
        (_with(entity_states=["cup"]), "entity_states and detections must be JSON objects"),
        (_with(detections=[1]), "entity_states and detections must be JSON objects"),
        (_with(entity_states={"kettle": "hot"}), "'kettle' has a state or detection but is not in the scene"),
        (_with(detections={"pear": {}}), "'pear' has a state or detection but is not in the scene"),
        (_with(detections={"apple": [0.9]}), "detections['apple'] must be a JSON object"),
        (_with(detections={"apple": {"confidence": 1.5}}), "confidence of 'apple' must be a number in"),
        (_with(detections={"apple": {"confidence": -0.1}}), "confidence of 'apple' must be a number in"),
        (_with(detections={"apple": {"confidence": "high"}}), "confidence of 'apple' must be a number in"),
        (_with(detections={"apple": {"bbox_px": [1, 2, 3]}}), "bbox_px of 'apple' must be a list of 4 num"),
        (_with(detections={"apple": {"bbox_px": "1,2,3,4"}}), "bbox_px of 'apple' must be a list of 4"),
        (_with(detections={"apple": {"size_m": [0.1, 0.1]}}), "size_m of 'apple' must be a list of 3 num"),
        (_with(detections={"apple": {"size_m": [0.1, "a", 0.1]}}), "size_m of 'apple' must be a list of 3"),
    ],
)
def test_invalid_scenes_raise_config_error(data: Any, fragment: str) -> None:
    with pytest.raises(ConfigError) as info:
        scene_from_dict(data, where="my.json")
    message = str(info.value)
    assert message.startswith("my.json: ")
    assert fragment in message


def test_load_scene_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.json"
    with pytest.raises(ConfigError, match=r"no scene file .*nope\.json"):
        load_scene(path)


def test_load_scene_invalid_json(tmp_path: Path) -> None:
    path = tmp_path / "broken.json"
    path.write_text('{"objects": ["apple",', encoding="utf-8")
    with pytest.raises(ConfigError, match=r"broken\.json is not valid JSON"):
        load_scene(path)


def test_load_scene_names_the_file_in_validation_errors(tmp_path: Path) -> None:
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"objects": ["apple"], "entity_states": {"kettle": "hot"}}), encoding="utf-8")
    with pytest.raises(ConfigError, match=r"bad\.json: 'kettle' has a state"):
        load_scene(path)


@pytest.mark.parametrize("bad", ["cup, red", "cup (red)", "bob's cup", 'the "cup"', "cup`", "cup\nplate"])
def test_names_the_action_format_cannot_carry_are_rejected(bad: str) -> None:
    with pytest.raises(ConfigError, match="which plans cannot carry") as info:
        scene_from_dict(_with(objects=["apple", bad]), where="my.json")
    assert info.value.hint and "letters, digits" in info.value.hint


def test_every_accepted_name_round_trips_through_the_action_format() -> None:
    from conceptbot.core.plan import parse_action, valid_actions

    names = ["red cup", "cup-2", "Bob’s mug", "café au lait", "x" * 80, "bowl_3", "a.b", "50% milk"]
    scene = scene_from_dict({"pickable_objects": names, "destinations": ["user"]})
    for action in valid_actions(scene, include_done=False):
        assert parse_action(str(action), scene) == action


@pytest.mark.parametrize(
    ("data", "fragment"),
    [
        ({"objects": ["apple", "bowl"], "destinations": ["bowl"]}, "no pickable_objects"),
        ({"objects": ["apple", "bowl"], "pickable_objects": ["apple"]}, "no destinations"),
        (_with(entity_states={"cup": False}), "the state of 'cup' must be a string, got false"),
        (_with(entity_states={"cup": None}), "the state of 'cup' must be a string, got null"),
        (_with(entity_states={"cup": 3}), "the state of 'cup' must be a string"),
        (_with(entity_states={"cup": "x" * 201}), "longer than 200 characters"),
        (_with(objects=["apple", "x" * 81]), "longer than 80 characters"),
        (_with(pickable_objects=[f"o{i}" for i in range(101)]), "at most 100"),
        (
            {"pickable_objects": [f"o{i}" for i in range(60)], "destinations": [f"d{i}" for i in range(41)]},
            "the scene has 101 objects; the limit is 100",
        ),
        (_with(detections={"apple": {"confidence": True}}), "confidence of 'apple' must be a number"),
        (_with(detections={"apple": {"size_m": [0.1, float("inf"), 0.1]}}), "size_m of 'apple' must be"),
        (_with(name=["kitchen"]), "'name' must be a string"),
        (_with(description={"a": 1}), "'description' must be a string"),
        (_with(extra=[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]), "nested more than 20 levels"),
    ],
)
def test_scene_limits_and_types(data: Any, fragment: str) -> None:
    with pytest.raises(ConfigError) as info:
        scene_from_dict(data, where="my.json")
    assert fragment in str(info.value)


def test_empty_state_means_no_state() -> None:
    assert scene_from_dict(_with(entity_states={"cup": "  "})).entity_states == {}


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (b"[" * 100_000 + b"]" * 100_000, "nested more than 20 levels"),
        (b'{"objects": ["caf\xe9"]}', "is not UTF-8 text"),
        (b" " * 1_000_001, "larger than 1,000,000 bytes"),
    ],
)
def test_hostile_scene_files_are_one_clear_error(tmp_path: Path, content: bytes, fragment: str) -> None:
    path = tmp_path / "hostile.json"
    path.write_bytes(content)
    with pytest.raises(ConfigError, match=fragment):
        load_scene(path)


def test_a_folder_is_not_a_scene_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="is a folder"):
        load_scene(tmp_path)
