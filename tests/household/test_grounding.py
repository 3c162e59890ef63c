"""The skill layer: failed steps repaired by the action rules, one change per failure."""

from __future__ import annotations

import pytest

from conceptbot.household.executor import execute
from conceptbot.household.grounding import ground_plan, liquid_named
from conceptbot.household.thor import house_scene
from tests.household.steps import acts, texts

KITCHEN = house_scene("FloorPlan1", ["Candle", "WateringCan", "HousePlant", "Book", "Mug", "Fridge", "Apple"])
BEDROOM = house_scene("FloorPlan301", ["Pillow", "Drawer", "Book", "Shelf"])


def _changes(plan: list[str], scene=KITCHEN, instruction: str = "") -> tuple[list[str], list[str]]:
    grounded, repairs = ground_plan(scene, acts(plan), instruction)
    assert execute(scene, grounded).ok, grounded  # whatever was repaired, every step now executes
    return texts(grounded), [r.change for r in repairs]


def test_a_plan_that_executes_is_left_alone() -> None:
    plan = ["find Mug", "pick Mug", "find Fridge", "open Fridge", "put Fridge"]
    assert _changes(plan) == (plan, [])


def test_a_forgotten_pick_goes_right_after_the_find_and_impossible_steps_are_dropped() -> None:
    grounded, changes = _changes(["find Book", "find Shelf", "put Shelf", "close Shelf"], BEDROOM)
    assert grounded == ["find Book", "pick Book", "find Shelf", "put Shelf"]
    assert changes == ["inserted pick Book", "dropped the step"]


def test_a_put_naming_the_object_picks_it_and_puts_it_in_the_receptacle_last_found() -> None:
    plan = ["find Drawer", "open Drawer", "find Pillow", "put Pillow", "close Drawer"]
    grounded, changes = _changes(plan, BEDROOM)
    assert grounded == [
        "find Drawer",
        "open Drawer",
        "find Pillow",
        "pick Pillow",
        "put Drawer",
        "close Drawer",
    ]
    assert changes == ["inserted pick Pillow", "put on Drawer instead"]


def test_pouring_with_an_empty_hand_picks_the_filled_container() -> None:
    plan = ["find WateringCan", "fillLiquid WateringCan water", "find Mug", "find HousePlant", "pour"]
    grounded, changes = _changes(plan)
    assert changes == ["inserted pick WateringCan"] and grounded[1] == "pick WateringCan"
    assert execute(KITCHEN, acts(grounded)).state["HousePlant"].flags["isFilledWithLiquid"]


def test_when_the_hand_is_busy_in_between_the_pick_goes_just_before_the_step() -> None:
    plan = [
        "find Book",
        "find Apple",
        "pick Apple",
        "find Fridge",
        "open Fridge",
        "put Fridge",
        "find Mug",
        "drop",
    ]
    grounded, changes = _changes(plan)
    assert changes == ["inserted pick Mug"] and grounded[-2:] == ["pick Mug", "drop"]


@pytest.mark.parametrize(
    ("plan", "expected", "change"),
    [
        (["pick Mug"], ["find Mug", "pick Mug"], "inserted find Mug"),
        (
            ["find Mug", "pick Mug", "find Fridge", "put Fridge"],
            ["find Mug", "pick Mug", "find Fridge", "open Fridge", "put Fridge"],
            "inserted open Fridge",
        ),
        (
            ["find Mug", "pick Mug", "find Apple", "pick Apple"],
            ["find Mug", "pick Mug", "find Apple"],
            "dropped the step",
        ),
        (["find Mug", "slice Mug", "pick Mug"], ["find Mug", "pick Mug"], "dropped the step"),
    ],
)
def test_one_change_per_kind_of_failure(plan: list[str], expected: list[str], change: str) -> None:
    assert _changes(plan) == (expected, [change])


def test_an_apple_in_the_closed_fridge_is_taken_out_after_opening_it() -> None:
    plan = ["find Apple", "pick Apple", "find Fridge", "open Fridge", "put Fridge", "close Fridge"]
    plan += ["find Apple", "pick Apple"]
    grounded, changes = _changes(plan)
    assert (
        changes == ["inserted open Fridge"]
        and grounded[-3:] == ["open Fridge", "pick Apple"][:0] + grounded[-3:]
    )
    assert grounded[-2:] == ["open Fridge", "pick Apple"]


def test_unknown_objects_and_impossible_steps_are_dropped_and_the_rounds_end() -> None:
    grounded, changes = _changes(["find Dragon", "find Mug", "pick Mug", "close Mug", "drop"])
    assert grounded == ["find Mug", "pick Mug", "drop"] and changes == ["dropped the step"] * 2
    long_plan = ["put Fridge"] * 30  # nothing to carry anywhere: the puts go, in bounded rounds
    assert _changes(long_plan) == (["find Fridge"], ["inserted find Fridge"] + ["dropped the step"] * 30)


def test_an_empty_container_is_filled_with_the_liquid_the_instruction_names_before_pouring() -> None:
    plan = ["find Mug", "pick Mug", "find HousePlant", "pour"]
    grounded, changes = _changes(plan, instruction="Pour coffee from the mug onto the plant.")
    assert grounded == ["find Mug", "pick Mug", "find HousePlant", "fillLiquid Mug coffee", "pour"]
    assert changes == ["inserted fillLiquid Mug coffee"]
    assert execute(KITCHEN, acts(grounded)).state["HousePlant"].flags["isFilledWithLiquid"]


def test_pouring_from_something_that_holds_no_liquid_is_dropped() -> None:
    grounded, changes = _changes(["find Book", "pick Book", "find HousePlant", "pour"])
    assert grounded == ["find Book", "pick Book", "find HousePlant"]
    assert changes == ["dropped the step"]


@pytest.mark.parametrize(
    ("instruction", "liquid"),
    [
        ("Pour wine into the bowl, then coffee", "wine"),
        ("Water the plant", "water"),
        ("Pour it out", "water"),
    ],
)
def test_the_liquid_is_the_first_one_named(instruction: str, liquid: str) -> None:
    assert liquid_named(instruction) == liquid
