"""The ``pick_and_place(object, target)`` skill: inverse kinematics, a real friction grasp, and honest
failure reports.

Failure kinds (:data:`FAILURES`):

* ``unknown`` -- the object or target is not in the world, or the object is not pickable;
* ``too_wide`` -- the part to grasp is wider than the gripper opening (checked before moving);
* ``unreachable`` -- no arm pose puts the hand within 1.5 cm of a grasp or place pose;
* ``target_full`` -- no free spot in/on the target for the object's footprint;
* ``slipped`` -- the object was not held after lifting, or was lost on the way;
* ``missed`` -- released, but it did not end up in/on the target (bounced off, toppled out).

Grasp modes: ``friction`` (default) holds the object by finger contact and friction only; ``assisted``
adds a fixed constraint once both fingers touch it (deterministic carrying, for demos). Objects whose
grip is ``edge`` (sheets, a paper clip) are always held by a constraint once the closed fingers touch
them: that models a suction cup, since a parallel gripper cannot close on a sheet lying on a table.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import pybullet as pb

from conceptbot.sim.robot import FrameHook, Panda, Vec3
from conceptbot.sim.world import WALL_M, World

FAILURES = ("unknown", "too_wide", "unreachable", "target_full", "slipped", "missed")
GRASP_MODES = ("friction", "assisted")
REACH_TOLERANCE_M = 0.015
CLEARANCE_M = 0.06
CARRY_SPEED = 0.8  # rad/s while holding something: a fast swing shakes it loose
TRANSIT_Z_M = 0.32
TALL_M = 0.12
FINGER_MARGIN_M = 0.004


TABLE = "table"


def same_place(located: str | None, target: str) -> bool:
    """Whether an object found in/on ``located`` (None: the bare table) is where ``target`` says;
    "table" means anywhere on the table that is not in another destination, or its zone."""
    if target.lower() == TABLE:
        return located is None or located.lower() == TABLE
    return located == target


@dataclass
class SkillResult:
    """What happened when one action ran."""

    action: str
    ok: bool
    failure: str | None = None
    message: str = ""
    seconds: float = 0.0
    located: str | None = None
    details: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Grasp:
    """Where and how to hold an object: the hand position, its yaw, and the width to hold."""

    position: Vec3
    yaw: float
    width: float
    free_yaw: bool = False


def grasp_for(world: World, name: str) -> Grasp:
    """The grasp for ``name`` from its spec and current pose (see :mod:`conceptbot.sim.catalogue`)."""
    spec = world.bodies[name].spec
    (x, y, _z), _ = world.pose(name)
    yaw = world.yaw(name)
    w, d, h = spec.size_m
    lo, hi = world.aabb(name)
    top = hi[2]
    if spec.grip == "rim":
        # Hold the wall nearest the arm: fingers close across its thickness.
        walls = [(w / 2 - WALL_M / 2, 0.0, 0.0), (-(w / 2 - WALL_M / 2), 0.0, 0.0)]
        walls += [(0.0, d / 2 - WALL_M / 2, math.pi / 2), (0.0, -(d / 2 - WALL_M / 2), math.pi / 2)]
        best = None
        for ox, oy, wall_yaw in walls:
            wx = x + ox * math.cos(yaw) - oy * math.sin(yaw)
            wy = y + ox * math.sin(yaw) + oy * math.cos(yaw)
            if best is None or math.hypot(wx, wy) < math.hypot(best[0], best[1]):
                best = (wx, wy, wall_yaw)
        assert best is not None
        # The fingers close along the hand's y axis; a wall along local y needs the hand turned by 90.
        return Grasp((best[0], best[1], top - 0.02), yaw + best[2] + math.pi / 2, WALL_M)
    if spec.grip == "knob":
        return Grasp((x, y, top - 0.012), yaw, 0.024, free_yaw=True)
    if spec.grip == "edge":
        return Grasp((x, y, top + 0.015), yaw, 0.0, free_yaw=True)
    # Body: close across the narrower horizontal side, 2.5 cm below the top; low things at 1.7 cm,
    # where the finger pads reach the table top.
    narrow_is_x = w <= d
    width = min(w, d) if spec.shape not in ("sphere", "cylinder") else w
    across = yaw + (math.pi / 2 if narrow_is_x else 0.0)
    # Near the top: from above, the palm stops the hand about 4.5 cm below a tall object's top.
    grasp_z = max(top - 0.025, lo[2] + h / 2) if h > 0.05 else lo[2] + max(h / 2, 0.017)
    return Grasp((x, y, grasp_z), across, width, free_yaw=spec.shape in ("sphere", "cylinder"))


class PickAndPlace:
    """Runs ``pick_and_place`` in a world.

    Args:
        world: The simulation.
        grasp_mode: ``friction`` (default) or ``assisted`` (see the module docstring).
        on_frame: Called after each motion segment (for animations).
    """

    def __init__(self, world: World, grasp_mode: str = "friction", on_frame: FrameHook | None = None) -> None:
        if grasp_mode not in GRASP_MODES:
            raise ValueError(f"grasp_mode must be one of {GRASP_MODES}")
        self.world = world
        self.robot: Panda = world.robot
        self.grasp_mode = grasp_mode
        self.on_frame = on_frame

    # -- helpers -------------------------------------------------------------------------------------
    def _fail(self, action: str, kind: str, message: str, started: float) -> SkillResult:
        self.robot.grip(Panda.OPENING_M, steps=40)
        self._go_home()
        return SkillResult(action, False, kind, message, time.perf_counter() - started)

    def _go_home(self) -> None:
        self.robot.move(Panda.HOME, steps=100, on_frame=self.on_frame)

    def _reach(self, position: Vec3, yaw: float) -> tuple[float, ...] | None:
        solved = self.robot.solve(position, yaw)
        return solved.joints if solved.error_m <= REACH_TOLERANCE_M else None

    def _touching(self, name: str) -> bool:
        body = self.world.bodies[name].id
        return all(
            pb.getContactPoints(self.robot.id, body, linkIndexA=f, physicsClientId=self.world.client)
            for f in Panda.FINGERS
        )

    def _held(self, name: str, constraint: int | None) -> bool:
        """Held: attached, or touched by a finger and resting on nothing."""
        if constraint is not None:
            return True
        body = self.world.bodies[name].id
        touched = any(
            pb.getContactPoints(self.robot.id, body, linkIndexA=f, physicsClientId=self.world.client)
            for f in Panda.FINGERS
        )
        return touched and self.world.locate(name) is None

    def free_spots(self, obj: str, target: str) -> list[tuple[float, float, float]]:
        """Places ``(x, y, yaw)`` in/on ``target`` where ``obj``'s footprint (turned to ``yaw``: along
        the world axes or across them) overlaps nothing already there; nearest the arm first."""
        x0, y0, x1, y1 = self.world.region(target)
        w, d, h = self.world.bodies[obj].spec.size_m
        occupied = []
        for other in self.world.occupants(target):
            if other != obj:
                lo, hi = self.world.aabb(other)
                occupied.append((lo[0], lo[1], hi[0], hi[1]))
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        if self.world.bodies[target].spec.shape not in ("container", "zone", "flat"):
            # Stacking on an object: its top must be free; the footprint may overhang.
            return [] if occupied else [(cx, cy, 0.0), (cx, cy, math.pi / 2)]
        spots = []
        for yaw, (hx, hy) in ((0.0, (w / 2, d / 2)), (math.pi / 2, (d / 2, w / 2))):
            # A footprint bigger than the region may still rest on it (a banana across a plate).
            hx, hy = min(hx, (x1 - x0) / 2), min(hy, (y1 - y0) / 2)
            grid = 4
            candidates = [(cx, cy)] + [
                (x0 + hx + (x1 - x0 - 2 * hx) * i / grid, y0 + hy + (y1 - y0 - 2 * hy) * j / grid)
                for i in range(grid + 1)
                for j in range(grid + 1)
            ]
            for px, py in candidates:
                box = (px - hx - 0.005, py - hy - 0.005, px + hx + 0.005, py + hy + 0.005)
                if all(
                    box[2] <= o[0] or box[0] >= o[2] or box[3] <= o[1] or box[1] >= o[3] for o in occupied
                ):
                    spots.append((px, py, yaw))
        if h > TALL_M:
            # Tall things go to the centre, where they cannot topple over a wall or off a pad.
            spots.sort(key=lambda s: (round(math.hypot(s[0] - cx, s[1] - cy), 3), s[2]))
        else:
            # Fill from the side nearest the arm: keeps the far side free and packs several things.
            spots.sort(key=lambda s: (round(math.hypot(s[0], s[1]), 3), s[2]))
        return spots

    # -- the skill -----------------------------------------------------------------------------------
    def run(self, obj: str, target: str) -> SkillResult:
        """Pick ``obj`` and place it in/on ``target``; never raises for a failed manipulation."""
        action = f"pick_and_place({obj}, {target})"
        started = time.perf_counter()
        world = self.world
        if obj not in world.bodies or target not in world.bodies or obj == target:
            return SkillResult(action, False, "unknown", "object or target not in the world", 0.0)
        if not world.bodies[obj].pickable:
            return SkillResult(action, False, "unknown", f"{obj} is not something the robot may pick", 0.0)
        grasp = grasp_for(world, obj)
        if grasp.width > Panda.OPENING_M - FINGER_MARGIN_M:
            return SkillResult(
                action,
                False,
                "too_wide",
                f"{obj} is {grasp.width * 100:.1f} cm across; the gripper opens "
                f"{Panda.OPENING_M * 100:.0f} cm",
                time.perf_counter() - started,
            )
        spots = self.free_spots(obj, target)
        if not spots:
            return SkillResult(action, False, "target_full", f"no free spot for {obj} in/on {target}", 0.0)
        gx, gy, gz = grasp.position
        (ox, oy, _), _ = world.pose(obj)
        obj_lo, obj_hi = world.aabb(obj)
        hand_above_bottom = gz - obj_lo[2]
        floor = world.floor_z(target)
        _, target_hi = world.aabb(target)
        # Travel high enough that the held object clears everything on the way (tallest things 0.25 m).
        transit = max(TRANSIT_Z_M, target_hi[2] + hand_above_bottom + CLEARANCE_M, obj_hi[2] + CLEARANCE_M)
        pick = self._pick_poses(grasp, transit)
        if pick is None:
            return SkillResult(action, False, "unreachable", f"the arm cannot reach {obj}", 0.0)
        yaw, above_obj = pick
        offset = (gx - ox, gy - oy)
        object_yaw = world.yaw(obj)
        place = None
        for spot in spots[:12]:
            place = self._place_poses(
                spot, offset, yaw, object_yaw, transit, floor + hand_above_bottom + 0.004
            )
            if place is not None:
                break
        if place is None:
            return SkillResult(action, False, "unreachable", f"the arm cannot reach {target}", 0.0)
        above_target, drop, drop_yaw = place

        robot = self.robot
        robot.grip(Panda.OPENING_M, steps=20)
        robot.move(above_obj, on_frame=self.on_frame)
        robot.move_straight(grasp.position, yaw, on_frame=self.on_frame)
        robot.grip(0.0, steps=90, on_frame=self.on_frame)  # squeeze: the fingers stop on the object
        constraint = None
        if grasp.width == 0.0 or self.grasp_mode == "assisted":
            if not (self._touching(obj) or self._near_hand(obj)):
                return self._fail(action, "slipped", f"the fingers did not touch {obj}", started)
            constraint = self._attach(obj)
        start_z = world.pose(obj)[0][2]
        robot.move_straight((gx, gy, transit), yaw, on_frame=self.on_frame)
        lifted = world.pose(obj)[0][2] - start_z
        if lifted < 0.03 or not self._held(obj, constraint):
            self._detach(constraint)
            return self._fail(action, "slipped", f"{obj} was not lifted ({lifted * 100:.1f} cm)", started)
        robot.move(above_target, on_frame=self.on_frame, speed=CARRY_SPEED)
        if not self._held(obj, constraint):
            self._detach(constraint)
            return self._fail(action, "slipped", f"{obj} slipped out on the way", started)
        robot.move_straight(drop, drop_yaw, on_frame=self.on_frame)
        self._detach(constraint)
        # Open only a little wider than the object: a wide-open hand pushes its neighbours away.
        robot.grip(min(Panda.OPENING_M, grasp.width + 0.02), steps=50, on_frame=self.on_frame)
        robot.move_straight((drop[0], drop[1], transit), drop_yaw, waypoints=3)
        self._go_home()
        world.settle(60)
        located = world.locate(obj)
        seconds = time.perf_counter() - started
        if not same_place(located, target):
            where = f"in/on {located}" if located else "on the table"
            message = f"{obj} ended up {where}, not in/on {target}"
            return SkillResult(action, False, "missed", message, seconds, located)
        return SkillResult(action, True, None, "ok", seconds, located, {"lifted_m": round(lifted, 3)})

    def _yaws(self, base: float, free: bool) -> list[float]:
        """Hand yaws to try: only ``base`` when the grasp fixes it, else eight around it."""
        return [base + k * math.pi / 8 for k in range(8)] if free else [base]

    def _pick_poses(self, grasp: Grasp, transit: float) -> tuple[float, tuple[float, ...]] | None:
        """``(yaw, joints above the object)`` where the grasp pose is also reachable, or None."""
        gx, gy, _ = grasp.position
        for yaw in self._yaws(grasp.yaw, grasp.free_yaw):
            above = self._reach((gx, gy, transit), yaw)
            at = self._reach(grasp.position, yaw)
            if above is not None and at is not None:
                return yaw, above  # the grasp pose is checked here, reached by a straight descent
        return None

    def _place_poses(
        self,
        spot: tuple[float, float, float],
        offset: tuple[float, float],
        yaw: float,
        object_yaw: float,
        transit: float,
        release_z: float,
    ) -> tuple[tuple[float, ...], Vec3, float] | None:
        """``(joints above the spot, hand position at the release, hand yaw)``, or None.

        The hand turns the held object from ``object_yaw`` to the spot's yaw (or that plus pi, the same
        footprint); the grasp offset turns with it.
        """
        for extra in (0.0, math.pi):
            turn = spot[2] - object_yaw + extra
            dx = offset[0] * math.cos(turn) - offset[1] * math.sin(turn)
            dy = offset[0] * math.sin(turn) + offset[1] * math.cos(turn)
            x, y = spot[0] + dx, spot[1] + dy
            above = self._reach((x, y, transit), yaw + turn)
            drop = self._reach((x, y, release_z), yaw + turn)
            if above is not None and drop is not None:
                return above, (x, y, release_z), yaw + turn
        return None

    def _near_hand(self, obj: str) -> bool:
        points = pb.getClosestPoints(
            self.robot.id, self.world.bodies[obj].id, 0.02, physicsClientId=self.world.client
        )
        return bool(points)

    def _attach(self, obj: str) -> int:
        client = self.world.client
        hand = pb.getLinkState(self.robot.id, Panda.HAND, physicsClientId=client)
        pos, orn = self.world.pose(obj)
        inv_pos, inv_orn = pb.invertTransform(hand[4], hand[5])
        rel_pos, rel_orn = pb.multiplyTransforms(inv_pos, inv_orn, pos, orn)
        return pb.createConstraint(
            self.robot.id,
            Panda.HAND,
            self.world.bodies[obj].id,
            -1,
            pb.JOINT_FIXED,
            (0, 0, 0),
            rel_pos,
            (0, 0, 0),
            rel_orn,
            physicsClientId=client,
        )

    def _detach(self, constraint: int | None) -> None:
        if constraint is not None:
            pb.removeConstraint(constraint, physicsClientId=self.world.client)
