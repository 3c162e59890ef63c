"""The simulated detector: boxes match the bodies; occlusion lowers confidence; observe() feeds a scene."""

from __future__ import annotations

from conceptbot.scenes import resolve_scene
from conceptbot.sim.detector import SimDetector, observe
from conceptbot.sim.render import TOP
from conceptbot.sim.world import build_world


def test_boxes_contain_the_bodies_and_sizes_match_the_catalogue() -> None:
    scene = resolve_scene("kitchen")
    with build_world(scene, seed=0) as world:
        found = SimDetector().detect(world)
        assert set(found) == set(scene.names)  # the arm is moved out of view for the picture
        for name, det in found.items():
            (x, y, _), _ = world.pose(name)
            _, hi = world.aabb(name)
            u, v, _ = TOP.project((x, y, hi[2]))
            x0, y0, x1, y1 = det.bbox_px
            assert x0 - 2 <= u <= x1 + 2 and y0 - 2 <= v <= y1 + 2, name
            spec = world.bodies[name].spec
            narrow, wide = sorted(spec.size_m[:2])
            assert abs(det.size_m[0] - narrow) <= 0.25 * narrow + 0.01, (name, det.size_m, spec.size_m)
            if spec.size_m[2] <= 0.08:  # a tall thing's side shows in the picture and lengthens its mask
                assert abs(det.size_m[1] - wide) <= 0.25 * wide + 0.01, (name, det.size_m, spec.size_m)
            if world.bodies[name].pickable:
                assert det.confidence > 0.7, (name, det.confidence)


def test_an_object_inside_a_deep_container_is_seen_less_and_observe_updates_the_scene() -> None:
    from conceptbot.sim.skills import PickPlaceSkill
    from tests.sim.conftest import small_scene

    scene = small_scene(objects=["egg", "trash can"], pickable=["egg"], destinations=["trash can"])
    with build_world(scene) as world:
        before = observe(scene, world, SimDetector()).get("egg")
        assert PickPlaceSkill(world).run("egg", "trash can").ok
        after = observe(scene, world, SimDetector()).get("egg")
        assert before is not None and after is not None
        assert before.confidence > 0.9 and before.bbox_px is not None and before.size_m is not None
        assert after.bbox_px != before.bbox_px
