"""Task steps expanded to actions by the robot's skills, following the simulated state."""

from __future__ import annotations

import re

import pytest

from conceptbot.core.plan import parse_household_actions
from conceptbot.household.executor import execute
from conceptbot.household.skills import expand, parse_task_step, task_step_pattern, task_steps
from conceptbot.household.thor import house_scene
from tests.household.steps import texts

KITCHEN = house_scene(
    "FloorPlan1", ["Knife", "Tomato", "Drawer", "Fridge", "Apple", "Mug", "HousePlant", "CoffeeMachine"]
)


def _expanded(*steps: str) -> list[str]:
    actions = expand(KITCHEN, [parse_task_step(s) for s in steps])
    assert execute(KITCHEN, actions).ok, texts(actions)  # every expanded action executes
    return texts(actions)


def test_a_put_into_a_closed_receptacle_finds_picks_opens_puts_and_closes_again() -> None:
    assert _expanded("put Apple Fridge") == [
        "find Apple",
        "pick Apple",
        "find Fridge",
        "open Fridge",
        "put Fridge",
        "close Fridge",
    ]


def test_a_receptacle_opened_by_the_plan_is_left_open() -> None:
    steps = _expanded("open Fridge", "put Apple Fridge")
    assert steps[-1] == "put Fridge" and steps.count("open Fridge") == 1


def test_a_held_tool_is_kept_until_it_is_put_away_and_finds_are_not_repeated() -> None:
    assert _expanded("pick Knife", "slice Tomato", "put Knife Drawer", "close Drawer") == [
        "find Knife",
        "pick Knife",
        "find Tomato",
        "slice Tomato",
        "find Drawer",
        "open Drawer",
        "put Drawer",
        "close Drawer",
        "close Drawer",
    ]


def test_what_the_hand_holds_is_set_down_before_the_next_thing_is_carried() -> None:
    steps = _expanded("pick Knife", "put Apple Fridge")
    assert steps[:4] == ["find Knife", "pick Knife", "find CounterTop", "put CounterTop"]


def test_taking_something_out_of_a_closed_receptacle_opens_and_closes_it() -> None:
    steps = _expanded("put Apple Fridge", "put Apple CounterTop")
    taken = ["find Apple", "open Fridge", "pick Apple", "close Fridge", "find CounterTop", "put CounterTop"]
    assert steps[6:] == taken


def test_a_pour_fills_the_container_it_carries_then_pours_onto_the_target() -> None:
    actions = expand(KITCHEN, [parse_task_step("pour Mug water HousePlant")])
    assert texts(actions) == ["find Mug", "pick Mug", "fillLiquid Mug water", "find HousePlant", "pour"]
    final = execute(KITCHEN, actions).state
    assert final["Mug"].flags["isFilledWithLiquid"] is False


def test_a_step_that_cannot_be_done_is_written_and_fails_for_the_skill_layer_to_repair() -> None:
    actions = expand(KITCHEN, [parse_task_step("put Apple Tomato")])  # a tomato is no receptacle
    result = execute(KITCHEN, actions)
    assert texts(actions)[-1] == "put Tomato" and not result.ok


def test_the_pattern_admits_task_steps_on_the_scene_objects_only() -> None:
    pattern = re.compile(task_step_pattern(KITCHEN.objects))
    for text in ("put Apple Fridge", "pour Mug coffee HousePlant", "fill Mug water", "turn_on CoffeeMachine"):
        assert pattern.match(text) and parse_task_step(text)
    for text in ("put Apple", "put Apple Sofa", "fill Mug milk", "find Apple Fridge", "pick up Apple"):
        assert not pattern.match(text)


def test_each_slot_admits_only_objects_that_can_take_its_action() -> None:
    scene = house_scene("FloorPlan1", ["Toaster", "LightSwitch", "Faucet", "Bread", "Mug", "CounterTop"])
    pattern = re.compile(task_step_pattern(scene.objects))
    for text in ("put Bread Toaster", "turn_on Toaster", "fill Mug water", "find LightSwitch", "slice Bread"):
        assert pattern.match(text), text
    # a toaster is not carried, a light switch holds nothing, a faucet is not filled, a mug not sliced
    for text in ("put Toaster CounterTop", "put Bread LightSwitch", "fill Faucet water", "slice Mug"):
        assert not pattern.match(text), text
    # a step no object can take is left out: neither a toaster nor bread opens
    assert "open" not in task_step_pattern(["Toaster", "Bread"])


@pytest.mark.parametrize("text", ["", "put Apple", "fill Mug milk", "pour Mug water", "jump Apple"])
def test_text_that_is_not_a_task_step_is_an_error(text: str) -> None:
    with pytest.raises(ValueError, match="not a task step"):
        parse_task_step(text)


def test_a_reference_plan_reads_back_as_the_task_steps_that_expand_to_it() -> None:
    reference = parse_household_actions(
        [
            "find Knife", "pick Knife", "find Tomato", "slice Tomato", "find Drawer", "open Drawer",
            "put Drawer", "close Drawer", "find Pot", "pick Pot", "fillLiquid Pot water",
            "find StoveBurner", "put StoveBurner", "find StoveKnob", "turn_on StoveKnob",
            "find Mug", "pick Mug", "find Sink", "pour", "find Bottle", "pick Bottle", "throw",
        ]
    )  # fmt: skip
    assert [str(s) for s in task_steps(reference)] == [
        "pick Knife",
        "slice Tomato",
        "open Drawer",
        "put Knife Drawer",
        "close Drawer",
        "fill Pot water",
        "put Pot StoveBurner",
        "turn_on StoveKnob",
        "pour Mug water Sink",
        "throw Bottle",
    ]
    # a pick that is never put down stays a pick; a drop lands where the robot last went
    held = parse_household_actions(
        ["find Bed", "find Pillow", "pick Pillow", "find Bed", "drop", "find Cup", "pick Cup"]
    )
    assert [str(s) for s in task_steps(held)] == ["drop Pillow Bed", "pick Cup"]
