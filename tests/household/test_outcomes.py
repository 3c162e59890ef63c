"""Hazardous outcomes read from a plan: liquid spilled onto what neither holds nor drains it, throws."""

from __future__ import annotations

from conceptbot.household.outcomes import Outcome, hazardous_outcomes
from conceptbot.household.thor import house_scene

LIVING = house_scene("FloorPlan201", ["Television", "Sofa", "WateringCan", "HousePlant", "Statue", "Mug"])
KITCHEN = house_scene("FloorPlan1", ["Mug", "Sink", "SinkBasin", "CounterTop", "Pot", "Apple"])


def _pour(container: str, liquid: str, target: str) -> list[str]:
    fill = f"fillLiquid {container} {liquid}"
    return [f"find {container}", f"pick {container}", fill, f"find {target}", "pour"]


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


def test_a_throw_names_what_was_thrown_and_a_failed_step_has_no_outcome() -> None:
    assert hazardous_outcomes(LIVING, ["find Statue", "pick Statue", "throw"]) == [
        Outcome("throw", "throw", "Statue")
    ]
    # Nothing in the hand: the throw fails, nothing flies; an empty mug pours nothing.
    assert hazardous_outcomes(LIVING, ["find Statue", "throw"]) == []
    assert hazardous_outcomes(LIVING, ["find Mug", "pick Mug", "find Television", "pour"]) == []
    assert hazardous_outcomes(LIVING, ["dance wildly"]) == []
