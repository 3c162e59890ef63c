"""World building: layouts without overlaps, determinism, locating objects, errors."""

from __future__ import annotations

import itertools
import math

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.scenes import resolve_scene
from conceptbot.sim.world import build_world
from tests.sim.conftest import small_scene


def test_the_kitchen_is_laid_out_without_overlaps_and_nothing_is_in_a_destination_at_start() -> None:
    scene = resolve_scene("kitchen")
    with build_world(scene, seed=3) as world:
        assert set(world.bodies) == set(scene.names)
        centres = {n: world.pose(n)[0][:2] for n in world.bodies}
        for a, b in itertools.combinations(world.bodies, 2):
            gap = math.dist(centres[a], centres[b])
            assert gap >= world.bodies[a].spec.footprint_radius + world.bodies[b].spec.footprint_radius, (
                a,
                b,
            )
        assert all(world.locate(n) is None for n in scene.pickable)


def test_same_seed_same_world_other_seed_other_world() -> None:
    scene = small_scene()
    with build_world(scene, seed=1) as a, build_world(scene, seed=1) as b, build_world(scene, seed=2) as c:
        assert a.snapshot() == b.snapshot()
        assert a.snapshot() != c.snapshot()


def test_pinned_layout_and_its_errors() -> None:
    scene = small_scene({"layout": {"apple": [0.5, 0.1]}})
    with build_world(scene) as world:
        x, y, _ = world.pose("apple")[0]
        assert abs(x - 0.5) < 0.01 and abs(y - 0.1) < 0.01
    with pytest.raises(ConfigError, match="layout"):
        build_world(small_scene({"layout": {"ghost": [0.5, 0.1]}}))


def test_a_scene_too_big_for_the_table_is_a_clear_error() -> None:
    bins = [f"x{i} trash can" for i in range(40)]
    scene = small_scene(objects=bins, pickable=bins[:1], destinations=bins[1:])
    with pytest.raises(ConfigError, match="does not fit"):
        build_world(scene)


def test_unknown_objects_are_built_with_a_warning() -> None:
    scene = small_scene(objects=["gizmo", "user"], pickable=["gizmo"], destinations=["user"])
    with build_world(scene) as world:
        assert any("gizmo" in w for w in world.warnings)
