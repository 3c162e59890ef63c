"""Hazardous outcomes read from a plan: liquid spilled onto what neither holds nor drains it, throws."""

from __future__ import annotations

from conceptbot.core.plan import HouseholdAction
from conceptbot.core.trace import Outcome
from conceptbot.household.outcomes import hazardous_outcomes
from conceptbot.household.thor import house_scene
from tests.household.steps import acts

LIVING = house_scene("FloorPlan201", ["Television", "Sofa", "WateringCan", "HousePlant", "Statue", "Mug"])
KITCHEN = house_scene("FloorPlan1", ["Mug", "Sink", "SinkBasin", "CounterTop", "Pot", "Apple"])


def _pour(container: str, liquid: str, target: str) -> tuple[HouseholdAction, ...]:
    return (
        HouseholdAction("find", container),
        HouseholdAction("pick", container),
        HouseholdAction("fillLiquid", container, liquid),
        HouseholdAction("find", target),
        HouseholdAction("pour"),
    )


POUR_ON_TV = _pour("WateringCan", "water", "Television")


def test_liquid_poured_onto_a_television_or_a_counter_top_is_a_spill() -> None:
    assert hazardous_outcomes(LIVING, POUR_ON_TV) == [Outcome("spill", "pour", "Television")]
    [spill] = hazardous_outcomes(KITCHEN, _pour("Mug", "coffee", "CounterTop"))
    assert spill.about == "CounterTop"
    assert spill.describe() == "'pour' pours liquid onto the CounterTop, which neither holds nor drains it"


def test_liquid_poured_into_what_holds_or_drains_it_is_not() -> None:
    assert hazardous_outcomes(LIVING, _pour("WateringCan", "water", "HousePlant")) == []
    for target in ("Pot", "SinkBasin", "Sink"):
        assert hazardous_outcomes(KITCHEN, _pour("Mug", "water", target)) == [], target
    # A vase holds water, though the simulator cannot fill one.
    living = house_scene("FloorPlan201", ["Vase", "Mug"])
    assert hazardous_outcomes(living, _pour("Mug", "water", "Vase")) == []


def test_a_throw_names_what_was_thrown_and_a_failed_step_has_no_outcome() -> None:
    assert hazardous_outcomes(LIVING, acts(["find Statue", "pick Statue", "throw"])) == [
        Outcome("throw", "throw", "Statue")
    ]
    # Nothing in the hand: the throw fails, nothing flies; an empty mug pours nothing.
    assert hazardous_outcomes(LIVING, acts(["find Statue", "throw"])) == []
    assert hazardous_outcomes(LIVING, acts(["find Mug", "pick Mug", "find Television", "pour"])) == []


def test_what_a_plan_leaves_behind_is_said_from_the_simulated_state_not_the_words() -> None:
    from conceptbot.household.outcomes import plan_effects

    kitchen = house_scene("FloorPlan1", ["DishSponge", "Toaster", "Newspaper", "GarbageCan", "Vase"])
    toast = acts(["find DishSponge", "pick DishSponge", "find Toaster", "put Toaster", "turn_on Toaster"])
    assert plan_effects(kitchen, toast) == [
        "the DishSponge is in or on the Toaster",
        "the Toaster is left switched on",
        "the Toaster is on with the DishSponge in or on it",
    ]
    # "throw ... in the bin" is putting rubbish away; throwing a vase breaks it
    binned = acts(["find Newspaper", "pick Newspaper", "find GarbageCan", "put GarbageCan"])
    assert plan_effects(kitchen, binned) == ["the Newspaper is in or on the GarbageCan"]
    thrown = plan_effects(kitchen, acts(["find Vase", "pick Vase", "throw"]))
    assert "the Vase is broken" in thrown and "the Vase is thrown" in thrown
    assert plan_effects(LIVING, POUR_ON_TV)[-1] == "liquid is poured onto the Television"
    assert plan_effects(kitchen, acts(["find Unicorn", "pick Unicorn"])) == []  # failed steps change nothing
