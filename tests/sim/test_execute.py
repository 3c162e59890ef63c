"""Plan execution, the final-state check, and closed-loop replanning with feedback."""

from __future__ import annotations

import pybullet as pb

from conceptbot.core.plan import Done, Feedback, PickAndPlace, Plan
from conceptbot.core.scene import Scene
from conceptbot.sim.execute import _check, execute_plan, run_closed_loop
from conceptbot.sim.world import build_world
from tests.sim.conftest import small_scene


def test_a_good_plan_succeeds_and_a_failing_one_stops_at_the_failure() -> None:
    scene = small_scene()
    with build_world(scene) as world:
        good = execute_plan(world, scene, [PickAndPlace("apple", "user"), Done()])
        assert good.ok and good.placements == {"apple": "user"} and "success" in good.verdict
    brick = small_scene(
        objects=["brick", "apple", "user"], pickable=["brick", "apple"], destinations=["user"]
    )
    with build_world(brick) as world:
        bad = execute_plan(
            world, brick, [PickAndPlace("brick", "user"), PickAndPlace("apple", "user"), Done()]
        )
        assert not bad.ok and len(bad.results) == 1 and "too_wide" in bad.verdict
        assert world.locate("apple") is None


class ScriptedSystem:
    """A planner that proposes the brick first and, told it failed, the apple."""

    def __init__(self) -> None:
        self.feedbacks: list[Feedback | None] = []

    def plan(self, request: str, scene: Scene, risk: bool = False, feedback=None, observer=None) -> Plan:
        self.feedbacks.append(feedback)
        if feedback is None:
            return Plan([PickAndPlace("energy bar", "user"), PickAndPlace("brick", "user"), Done()])
        assert PickAndPlace("brick", "user") in feedback.failed_actions
        return Plan([*feedback.executed, PickAndPlace("apple", "user"), Done()])


def test_closed_loop_gives_the_failure_back_and_replans_from_there() -> None:
    scene = small_scene(
        objects=["energy bar", "brick", "apple", "user"],
        pickable=["energy bar", "brick", "apple"],
        destinations=["user"],
    )
    system = ScriptedSystem()
    with build_world(scene) as world:
        execution, plans = run_closed_loop(system, "give me something", scene, world, max_replans=2)
    assert len(plans) == 2 and system.feedbacks[0] is None
    feedback = system.feedbacks[1]
    assert feedback is not None and list(feedback.executed) == [PickAndPlace("energy bar", "user")]
    assert [r.action for r in execution.results] == [
        "pick_and_place(energy bar, user)",
        "pick_and_place(brick, user)",
        "pick_and_place(apple, user)",
    ]
    assert execution.placements["apple"] == "user" and execution.placements["energy bar"] == "user"
    assert not execution.ok  # the brick step failed; the verdict says so even after the replan
    assert "too_wide" in execution.verdict


def test_replanning_is_bounded() -> None:
    class Stubborn:
        calls = 0

        def plan(self, request, scene, risk=False, feedback=None, observer=None):
            Stubborn.calls += 1
            return Plan([*(feedback.executed if feedback else []), PickAndPlace("brick", "user"), Done()])

    scene = small_scene(objects=["brick", "user"], pickable=["brick"], destinations=["user"])
    with build_world(scene) as world:
        _, plans = run_closed_loop(Stubborn(), "r", scene, world, max_replans=1)
    assert len(plans) == 2 and Stubborn.calls == 2


def test_an_object_knocked_off_the_table_is_not_on_the_table() -> None:
    # "table" means anywhere on the table; a thing that fell off it is nowhere the plan put it.
    scene = small_scene(
        objects=["apple", "user", "table"], pickable=["apple"], destinations=["user", "table"]
    )
    with build_world(scene) as world:
        execution = execute_plan(world, scene, [PickAndPlace("apple", "table"), Done()])
        assert execution.ok and not world.off_table("apple")
        pb.resetBasePositionAndOrientation(
            world.bodies["apple"].id, (1.5, 1.5, 0.3), (0, 0, 0, 1), physicsClientId=world.client
        )
        world.settle(240)
        assert world.off_table("apple")
        _check(world, execution)
        assert not execution.ok and "apple fell off the table" in execution.verdict
