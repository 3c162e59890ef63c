import pytest

from conceptbot.core.plan import Done, PickAndPlace
from conceptbot.core.scene import SceneObject
from conceptbot.pipeline import modes
from conceptbot.pipeline.affordance import (
    Gripper,
    affordance,
    bbox_score,
    property_score,
    relative_property_scores,
)
from conceptbot.pipeline.ope import ObjectProperties
from tests.pipeline.fakes import spill_scene


@pytest.mark.parametrize(
    ("width", "expected"),
    [(0.04, 1.0), (0.06, 1.0), (0.07, 0.75), (0.08, 0.5), (0.16, 0.25), (1.0, 0.1)],
)
def test_bbox_score_falls_as_width_nears_the_opening(width: float, expected: float) -> None:
    obj = SceneObject("x", size_m=(width, width, 0.1))
    assert bbox_score(obj, Gripper(0.08)) == pytest.approx(expected)


def test_bbox_from_pixels_and_unknown() -> None:
    assert bbox_score(SceneObject("x", bbox_px=(0, 0, 32, 100)), Gripper(0.08)) == 1.0  # 0.04 m
    assert bbox_score(SceneObject("x"), Gripper(0.08)) == 1.0


def test_yes_no_penalties_are_fixed_and_worse_for_people() -> None:
    props = {"knife": ObjectProperties("knife", modes.PROPERTIES, {"fragile": "Yes", "dangerous": "Yes"})}
    assert property_score("knife", "table", props) == pytest.approx(0.8 * 0.7)
    assert property_score("knife", "user", props) == pytest.approx(0.8 * 0.4)
    assert property_score("sponge", "user", props) == 1.0


def test_risk_scores_are_scaled_and_interactions_count_both_ways() -> None:
    props = {
        "tray": ObjectProperties(
            "tray", modes.RISK, {"dangerous": 2, "dangerous_with": [{"object": "oven", "score": 5}]}
        ),
        "bowl": ObjectProperties("bowl", modes.RISK, {"dangerous": 1, "dangerous_with": []}),
        "oven": ObjectProperties(
            "oven", modes.RISK, {"dangerous": 3, "dangerous_with": [{"object": "bowl", "score": 2}]}
        ),
    }
    assert property_score("tray", "oven", props) == pytest.approx(0.88 * 0.2)
    assert property_score("bowl", "oven", props) == pytest.approx(1.0 * 0.8)


def test_affordance_multiplies_factors_and_zeroes_repeats() -> None:
    scene = spill_scene()
    total, factors = affordance(PickAndPlace("knife", "user"), scene, {}, [])
    assert factors == {"pick": 0.9, "place": 1.0, "bbox": 1.0, "prop": 1.0} and total == pytest.approx(0.9)
    assert affordance(PickAndPlace("knife", "user"), scene, {}, [PickAndPlace("knife", "user")])[0] == 0.0
    assert affordance(Done(), scene, {}, []) == (1.0, {})


def test_property_scores_are_relative_to_the_safest_open_move() -> None:
    scored = [
        (0.1, {"pick": 1.0, "prop": 0.1}),
        (0.1, {"pick": 0.5, "prop": 0.2}),
        (0.0, {"prop": 0.5, "repeat": 0.0}),  # a repeat stays out and stays 0
        (1.0, {}),  # done()
    ]
    out = relative_property_scores(scored)
    assert out[0] == (pytest.approx(0.5), {"pick": 1.0, "prop": pytest.approx(0.5), "prop_abs": 0.1})
    assert out[1][0] == pytest.approx(0.5) and out[1][1]["prop"] == pytest.approx(1.0)
    assert out[2] == scored[2] and out[3] == (1.0, {})
    # When the safest move is not penalised, nothing changes.
    unchanged = [(0.7, {"prop": 0.7}), (1.0, {"prop": 1.0})]
    assert relative_property_scores(unchanged) == unchanged
