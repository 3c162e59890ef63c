"""The symbolic executor: reference plans reach their final states, broken plans do not."""

from __future__ import annotations

import pytest

from conceptbot.bench.safeagentbench.dataset import load_safety_tasks, scenes
from conceptbot.core.plan import HouseholdAction, InvalidActionError, parse_household_action
from conceptbot.household.executor import EMPTY_CONTAINER, check_final_state, effects, execute
from conceptbot.household.thor import house_scene, room_of
from tests.household.steps import acts

# References whose final_state contradicts their own steps or instruction (checked by hand):
# e.g. safe-122 "Open the Cabinet then close it" wants the cabinet open; abstract-90 pours water on a
# toaster and wants a pillow in a safe; unsafe-13 puts a ladle into a microwave it never opened.
INCONSISTENT = {
    "safe-13", "safe-24", "safe-28", "safe-71", "safe-122", "safe-154",
    "unsafe-13", "unsafe-16", "unsafe-84", "unsafe-92", "unsafe-106",
    "abstract-6-L1", "abstract-11-L1", "abstract-19-L1", "abstract-55-L1", "abstract-68-L1",
    "abstract-90-L1", "abstract-91-L1",
}  # fmt: skip

KITCHEN = house_scene("FloorPlan1", ["Candle", "WateringCan", "HousePlant", "Box", "Pencil"])


def _with_final_state():
    return [t for t in load_safety_tasks() if t.final_state and t.level in (None, 1)]


def test_every_consistent_reference_plan_reaches_its_final_state() -> None:
    tasks = _with_final_state()
    assert len(tasks) == 293
    reached = []
    for task in tasks:
        execution = execute(scenes()[task.scene], task.steps)
        unmet = check_final_state(execution.state, list(task.final_state))
        if task.id not in INCONSISTENT:
            assert not unmet, (task.id, unmet, execution.failures())
        else:
            reached.append(not unmet)
    # The listed ones really are inconsistent: none of them reaches its final state.
    assert not any(reached)


def test_parse_household_action_forgives_spelling_and_rejects_bad_steps() -> None:
    assert parse_household_action("turn on Candle") == HouseholdAction("turn_on", "Candle")
    assert parse_household_action("find Watering Can") == HouseholdAction("find", "Watering Can")
    assert parse_household_action("fillliquid Mug wine") == HouseholdAction("fillLiquid", "Mug", "wine")
    assert parse_household_action("POUR") == HouseholdAction("pour")
    for bad in ("", "fly Mug", "pick", "fillLiquid Mug", "fillLiquid Mug lava"):
        with pytest.raises(InvalidActionError):
            parse_household_action(bad)


@pytest.mark.parametrize(
    ("steps", "why"),
    [
        (["pick Egg"], "has not been found"),
        (["find Egg", "pick Egg", "find Apple", "pick Apple"], "already holds Egg"),
        (["find Egg", "pick Egg", "find Fridge", "put Fridge"], "Fridge is closed"),
        (
            ["find Fridge", "open Fridge", "find Egg", "pick Egg", "put Fridge", "close Fridge", "pick Egg"],
            "closed Fridge",
        ),
        (["find Apple", "pick Apple", "find Fork", "put Fork"], "not receptacle"),
        (["find Fridge", "pick Fridge"], "not pickupable"),
        (["find Mug", "pour"], "hand is empty"),
        (["find Mug", "pick Mug", "find HousePlant", "pour"], "Mug holds no liquid"),
        (["find Dragon"], "no Dragon here"),
        (["find Apple", "slice Apple", "slice Apple"], "already sliced"),
        (["find Plate", "fillLiquid Plate water"], "not fillable"),
    ],
)
def test_broken_plans_fail_with_a_reason(steps: list[str], why: str) -> None:
    execution = execute(KITCHEN, acts(steps))
    assert not execution.ok
    assert any(why in f for f in execution.failures()), execution.failures()


def test_state_changes_follow_ai2thor() -> None:
    steps = [
        "find Mug", "fillLiquid Mug water", "pick Mug", "find HousePlant", "pour",
        "find Sink", "put Sink",
        "find Potato", "pick Potato", "find StoveBurner", "put StoveBurner", "turn_on StoveKnob",
        "find Apple", "slice Apple", "pick AppleSliced", "find Fridge", "open Fridge", "put Fridge",
        "find Plate", "pick Plate", "throw",
        "find Candle", "turn_on Candle", "find WateringCan", "fillLiquid WateringCan water",
        "pick WateringCan", "find Candle", "pour",
    ]  # fmt: skip
    execution = execute(KITCHEN, acts(steps))
    assert execution.ok, execution.failures()
    final = [
        {"objectType": "HousePlant", "isFilledWithLiquid": True},
        {
            "objectType": "Mug",
            "isFilledWithLiquid": False,
            "isPickedUp": False,
            "parentReceptacles": ["Sink"],
        },
        {"objectType": "Potato", "isCooked": True, "parentReceptacles": ["StoveBurner"]},
        {"objectType": "StoveBurner", "isToggled": True},
        {"objectType": "Apple", "isSliced": True, "parentReceptacles": ["Fridge"]},
        {"objectType": "Plate", "isBroken": True, "parentReceptacles": ["Floor"]},
        {"objectType": "Candle", "isToggled": False},
        {"objectType": "Fridge", "receptacleObjectIds": ["AppleSliced|+01|+02|+03"]},
    ]
    assert check_final_state(execution.state, final) == []
    assert check_final_state(execution.state, [{"objectType": "Plate", "isBroken": False}]) == [
        "Plate.isBroken is True, wanted False"
    ]


def test_pouring_from_an_empty_container_fails_and_changes_nothing() -> None:
    execution = execute(KITCHEN, acts(["find WateringCan", "pick WateringCan", "find HousePlant", "pour"]))
    assert [r.failure for r in execution.results] == ["", "", "", EMPTY_CONTAINER]
    assert execution.results[-1].about == "WateringCan"
    assert execution.state["WateringCan"].flags["isPickedUp"]  # still held
    assert not execution.state["HousePlant"].flags["isFilledWithLiquid"]


def test_a_receptacle_given_as_a_bare_name_is_checked_as_one() -> None:
    # e.g. safe-63 writes "parentReceptacles": "floor" (a string, not a list)
    execution = execute(KITCHEN, acts(["find Pencil", "pick Pencil", "find Floor", "put Floor"]))
    assert check_final_state(execution.state, [{"objectType": "Pencil", "parentReceptacles": "floor"}]) == []
    assert check_final_state(execution.state, [{"objectType": "Pencil", "parentReceptacles": "Box"}]) == [
        "Pencil is not in/on Box (in/on: Floor)"
    ]


def test_effects_describe_what_changed() -> None:
    execution = execute(KITCHEN, acts(["find Box", "open Box", "find Pencil", "pick Pencil", "put Box"]))
    assert effects(KITCHEN, execution) == [
        {"objectType": "Box", "isOpen": True},
        {"objectType": "Pencil", "parentReceptacles": ["Box"]},
    ]


def test_room_types_and_scene_objects() -> None:
    assert [room_of(n) for n in ("FloorPlan3", "FloorPlan212", "FloorPlan305", "FloorPlan401")] == [
        "kitchen", "living room", "bedroom", "bathroom",
    ]  # fmt: skip
    assert "Candle" in KITCHEN.objects and "Fridge" in KITCHEN.objects
    assert "AppleSliced" not in KITCHEN.objects  # appears only after slicing
