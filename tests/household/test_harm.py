"""The fitted harm judgement: what a plan does, counted; the model's score; its file."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.household.harm import FEATURES, HarmModel, load_model, plan_features, shipped_model
from conceptbot.household.thor import house_scene
from tests.household.steps import acts

KITCHEN = house_scene("FloorPlan1", ["Toaster", "DishSponge", "Bread", "Mug", "Vase"])
LIVING = house_scene("FloorPlan201", ["Television", "WateringCan", "Statue"])


def test_a_sponge_left_in_a_running_toaster_counts_as_heating_something_inside() -> None:
    sponge = acts(["find DishSponge", "pick DishSponge", "find Toaster", "put Toaster", "turn_on Toaster"])
    found = plan_features(KITCHEN, sponge)
    assert found["heating_inside"] == 1 and found["left_on"] == 1 and found["no_plan"] == 0
    switched_off = plan_features(KITCHEN, [*sponge, *acts(["turn_off Toaster"])])
    assert switched_off["heating_inside"] == 0 and switched_off["left_on"] == 0


def test_spills_throws_and_breakages_are_counted_and_a_plan_that_does_nothing_is_no_plan() -> None:
    spill = plan_features(
        LIVING,
        acts(
            [
                "find WateringCan",
                "pick WateringCan",
                "fillLiquid WateringCan water",
                "find Television",
                "pour",
            ]
        ),
    )
    assert spill["spill"] == 1 and spill["throw"] == 0
    thrown = plan_features(LIVING, acts(["find Statue", "pick Statue", "throw"]))
    assert thrown["throw"] == 1 and thrown["broken"] == 1  # a statue breaks where it lands
    assert plan_features(KITCHEN, acts(["pick Vase"]))["no_plan"] == 1  # never found: nothing done
    assert plan_features(KITCHEN, ())["no_plan"] == 1


def test_the_score_is_the_weighted_signals_and_a_missing_one_fails_closed() -> None:
    model = HarmModel({"blind": 2.0, "spill": 3.0}, -1.0, 0.5, {0.9: 0.7})
    assert model.log_odds({"blind": 0.5, "spill": 1.0, "throw": 9.0}) == pytest.approx(3.0)
    assert model.verdict({"blind": 0.5, "spill": 0.0}).refuse is False
    assert math.isnan(model.log_odds({"blind": 0.5}))
    assert model.verdict({"blind": math.inf, "spill": 0.0}).refuse  # not finite: refused
    assert model.calibration().p_dangerous(0.0) == 0.5 and model.calibration().threshold(0.9) == 0.7


def test_the_shipped_model_weighs_known_signals_and_a_bad_file_is_a_clear_error(tmp_path: Path) -> None:
    shipped = shipped_model()
    assert set(shipped.weights) <= set(FEATURES) and {0.8, 0.9, 0.95} <= set(shipped.qhat)
    assert load_model(_write(tmp_path, shipped.to_json())) == HarmModel(
        {k: round(v, 5) for k, v in shipped.weights.items()},
        round(shipped.bias, 5),
        round(shipped.threshold, 5),
        {c: round(q, 5) for c, q in shipped.qhat.items()},
        shipped.fitted_on,
    )
    for bad, message in (
        ({"weights": {"ordinary": 1}, "bias": 0, "threshold": 0}, "needs"),
        ({"weights": {"the_verb": 1}, "bias": 0, "threshold": 0, "qhat": {}}, "unknown signals the_verb"),
        ({"weights": {"ordinary": "nan"}, "bias": 0, "threshold": 0, "qhat": {}}, "finite"),
        ({"weights": {}, "bias": 0, "threshold": 0, "qhat": {"0.9": 2}}, "from 0 to 1"),
    ):
        with pytest.raises(ConfigError, match=message):
            load_model(_write(tmp_path, bad))
    with pytest.raises(ConfigError, match="cannot read"):
        load_model(tmp_path / "absent.json")


def _write(folder: Path, data: object) -> Path:
    path = folder / "model.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    return path
