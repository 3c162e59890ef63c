"""A detector's Scene message as the planner's scene, and the latest one kept with its age."""

from __future__ import annotations

from typing import Any

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.ros2.detections import LatestScene, scene_from_msg

msg = pytest.importorskip("conceptbot_interfaces.msg", reason="scripts/build_interfaces.sh not run")


def _scene(
    *detections: Any, destinations: tuple[str, ...] = ("tray", "user"), pickable: tuple[str, ...] = ()
) -> Any:
    return msg.Scene(detections=list(detections), destinations=list(destinations), pickable=list(pickable))


MUG = msg.Detection(
    name="mug", confidence=0.8, box_px=[1.0, 2.0, 30.0, 40.0], size_m=[0.1, 0.1, 0.12], state="hot"
)
TRAY = msg.Detection(name="tray", confidence=0.9)


def test_detections_become_objects_with_their_scores_and_the_rest_are_destinations() -> None:
    scene = scene_from_msg(_scene(MUG, TRAY))
    assert scene.names == ["mug", "tray", "user"]
    assert scene.pickable == ["mug"] and scene.destinations == ["tray", "user"]
    mug = scene.get("mug")
    assert mug is not None and mug.confidence == pytest.approx(0.8) and mug.bbox_px == (1, 2, 30, 40)
    assert mug.size_m == pytest.approx((0.1, 0.1, 0.12)) and mug.state == "hot"
    tray = scene.get("tray")
    assert tray is not None and tray.bbox_px is None and tray.size_m is None  # all-zero: not given


@pytest.mark.parametrize(
    ("scene", "message"),
    [
        (_scene(), "no detections"),
        (_scene(MUG, MUG), "detected twice: mug"),
        (_scene(msg.Detection(name="mug", confidence=1.5)), "not in [0, 1]"),
        (_scene(MUG, pickable=("knife",)), "pickable but not detected: knife"),
        (_scene(msg.Detection(name="mug", confidence=0.5, box_px=[30.0, 2.0, 1.0, 40.0])), "is not x0 < x1"),
    ],
)
def test_a_malformed_scene_is_one_clear_error(scene: Any, message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        scene_from_msg(scene)
    assert message in caught.value.message


def test_the_latest_scene_is_refused_before_any_comes_when_stale_and_when_malformed() -> None:
    now = [100.0]
    latest = LatestScene(max_age_s=5.0, clock=lambda: now[0])
    with pytest.raises(ConfigError, match="no detections have come"):
        latest.current()
    latest.put(_scene(MUG, TRAY))
    assert latest.current().pickable == ["mug"]
    now[0] = 106.0
    with pytest.raises(ConfigError, match=r"6\.0 s old \(at most 5 s\)"):
        latest.current()
    stamped = _scene(MUG, TRAY)
    stamped.stamp.sec = 105  # the detector's own time wins over when it came
    latest.put(stamped)
    assert latest.current().names[0] == "mug"
    latest.put(_scene())
    with pytest.raises(ConfigError, match="the latest detections are malformed: the scene has no detections"):
        latest.current()
