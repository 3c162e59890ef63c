"""The ``pick_and_place(object, target)`` skill: inverse kinematics, a real friction grasp, and honest
failure reports.

Failure kinds (:data:`FAILURES`):

* ``unknown`` -- the object or target is not in the world, or the object is not pickable;
* ``too_wide`` -- the part to grasp is wider than the gripper opening (checked before moving);
* ``unreachable`` -- no arm pose puts the hand within 1.5 cm of a grasp or place pose;
* ``target_full`` -- no free spot in/on the target for the object's footprint;
* ``slipped`` -- the object was not held after lifting, or was lost on the way;
* ``missed`` -- released, but it did not end up in/on the target (bounced off, toppled out).

A grasp that slips or a placement that misses is tried again from where the object now lies, as a
robot that checks its work would (``retries``, default 1); the result then says how many attempts
it took (``details["attempts"]``); when every attempt failed, the failure is the first one (what went
wrong with the step) and the message tells what the others ran into.

Grasp modes: ``friction`` (default) holds the object by finger contact and friction only; ``assisted``
adds a fixed constraint once both fingers touch it (deterministic carrying, for demos). Objects whose
grip is ``edge`` (sheets, a paper clip) are always held by a constraint once the closed fingers touch
them: that models a suction cup, since a parallel gripper cannot close on a sheet lying on a table.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import pybullet as pb

from conceptbot.core.plan import PickAndPlace, format_action
from conceptbot.sim import GRASP_MODES
from conceptbot.sim.robot import FrameHook, Panda, Vec3
from conceptbot.sim.world import REACH_MAX_M, WALL_M, World

FAILURES = ("unknown", "too_wide", "unreachable", "target_full", "slipped", "missed")
RETRYABLE = ("slipped", "missed")  # the physics went wrong, not the plan: the same step may work again
REACH_TOLERANCE_M = 0.015
CLEARANCE_M = 0.04
CARRY_SPEED = 0.8  # rad/s while holding something: a fast swing shakes it loose
TRANSIT_Z_M = 0.32
TALL_M = 0.12
FINGER_MARGIN_M = 0.004
MAX_PILE_M = 0.08  # the highest pile on a pad or plate
HEAP_M = 0.03  # how far a heap may rise over a container's rim
DROP_M = 0.04  # the highest a thing is let go above where it comes to rest
AIM_TOLERANCE_M = 0.01  # a held object this close to the planned grasp is released as planned
FINGER_CLEARANCE_M = 0.02  # room kept beside a placed object for the fingers and their opening


TABLE = "table"


def same_place(holders: Sequence[str], target: str) -> bool:
    """Whether an object in/on ``holders`` (from :meth:`World.holders`; empty: the bare table) is
    where ``target`` says: in/on it directly or on top of something in/on it; "table" means anywhere
    on the table that is not in another destination, or its zone."""
    if target.lower() == TABLE:
        return not holders or TABLE in (h.lower() for h in holders)
    return target in holders


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
class Spot:
    """Where to set an object down: centre ``(x, y)``, its yaw, and the height its bottom rests at."""

    x: float
    y: float
    yaw: float
    floor_z: float


@dataclass(frozen=True)
class Grasp:
    """Where and how to hold an object: the hand position, its yaw, and the width to hold."""

    position: Vec3
    yaw: float
    width: float
    free_yaw: bool = False


Place = tuple[tuple[float, ...], Vec3, float, tuple[float, ...]]
"""A release: joints above the spot, hand position at the release, hand yaw, joints at the release."""


@dataclass(frozen=True)
class _Motion:
    """A pick and place worked out before the arm moves: the grasp and the hand's yaw at it, the
    joints above the object, the release (None while it is looked for), the grasp point's offset
    from the object's centre and height above its bottom, and the height the hand travels at."""

    grasp: Grasp
    yaw: float
    above_obj: tuple[float, ...]
    place: Place | None
    offset: tuple[float, float]
    hand_above_bottom: float
    transit: float


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


class PickPlaceSkill:
    """Runs ``pick_and_place`` in a world.

    Args:
        world: The simulation.
        grasp_mode: ``friction`` (default) or ``assisted`` (see the module docstring).
        on_frame: Called after each motion segment (for animations).
        retries: How many more times a slipped or missed step is tried (0: never).
    """

    def __init__(
        self,
        world: World,
        grasp_mode: str = "friction",
        on_frame: FrameHook | None = None,
        retries: int = 1,
    ) -> None:
        if grasp_mode not in GRASP_MODES:
            raise ValueError(f"grasp_mode must be one of {GRASP_MODES}")
        if retries < 0:
            raise ValueError("retries must be 0 or more")
        self.retries = retries
        self.world = world
        self.robot: Panda = world.robot
        self.grasp_mode = grasp_mode
        self.on_frame = on_frame

    # -- helpers -------------------------------------------------------------------------------------
    def _fail(self, action: str, obj: str, kind: str, message: str, started: float) -> SkillResult:
        self.robot.grip(Panda.OPENING_M, steps=40)
        self._go_home()
        if self.world.off_table(obj):
            message += "; it fell off the table"
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

    def free_spots(self, obj: str, target: str) -> list[Spot]:
        """Places in/on ``target`` for ``obj``, best first (see :class:`Spot`).

        Floor spots first: the object's footprint (turned along the world axes or across them) plus
        :data:`FINGER_CLEARANCE_M` for the open fingers overlaps nothing already there (without the
        clearance when nothing fits with it). Receptacles whose floor is full (a bin, a dishwasher)
        take things on top of what is in them, lowest pile first, as a person would drop a brochure
        onto a journal in the paper bin. A plain object (stacking) takes one thing on its top.
        """
        x0, y0, x1, y1 = self.world.region(target)
        floor = self.world.floor_z(target)
        w, d, h = self.world.bodies[obj].spec.size_m
        inside = [other for other in self.world.occupants(target) if other != obj]
        occupied = []
        for other in inside:
            lo, hi = self.world.aabb(other)
            occupied.append((lo[0], lo[1], hi[0], hi[1], hi[2]))
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        if self.world.bodies[target].spec.shape not in ("container", "zone", "flat"):
            # Stacking on an object: its top must be free; the footprint may overhang.
            return [] if occupied else [Spot(cx, cy, 0.0, floor), Spot(cx, cy, math.pi / 2, floor)]
        for pad in (FINGER_CLEARANCE_M, 0.005):
            spots = self._floor_spots((x0, y0, x1, y1), (w, d), pad, occupied, floor)
            if spots:
                break
        if h > TALL_M and self.world.bodies[target].spec.shape == "container":
            # Tall things go to a container's centre, where they cannot topple over a wall.
            spots.sort(key=lambda s: (round(math.hypot(s.x - cx, s.y - cy), 3), s.yaw))
        elif h > TALL_M:
            # On a pad or plate, to the far side: the hand then has room in front for the next thing.
            spots.sort(key=lambda s: (-round(math.hypot(s.x, s.y), 3), s.yaw))
        else:
            # Fill from the side nearest the arm: keeps the far side free and packs several things.
            spots.sort(key=lambda s: (round(math.hypot(s.x, s.y), 3), s.yaw))
        # Zone pads may stick out past the arm's sure reach (they are laid out at the ring's edge);
        # a release out there lands short, so those spots come last (the sort is stable).
        spots.sort(key=lambda s: math.hypot(s.x, s.y) > REACH_MAX_M)
        if spots:
            return spots
        piles = []
        for px, py in [(cx, cy)] + [((o[0] + o[2]) / 2, (o[1] + o[3]) / 2) for o in occupied]:
            for yaw, (hx, hy) in ((0.0, (w / 2, d / 2)), (math.pi / 2, (d / 2, w / 2))):
                under = [
                    o[4]
                    for o in occupied
                    if not (px + hx <= o[0] or px - hx >= o[2] or py + hy <= o[1] or py - hy >= o[3])
                ]
                piles.append(Spot(px, py, yaw, max(under, default=floor)))
        # A pile stays in a container (heaped at most a little over its rim) and low on a pad or plate.
        _, hi = self.world.aabb(target)
        container = self.world.bodies[target].spec.shape == "container"
        limit = hi[2] + HEAP_M if container else floor + MAX_PILE_M
        piles = [s for s in piles if s.floor_z <= limit]
        piles.sort(key=lambda s: (round(s.floor_z, 3), round(math.hypot(s.x - cx, s.y - cy), 3)))
        return piles

    @staticmethod
    def _floor_spots(
        region: tuple[float, float, float, float],
        size: tuple[float, float],
        pad: float,
        occupied: list[tuple[float, float, float, float, float]],
        floor: float,
    ) -> list[Spot]:
        """Grid positions in ``region`` where the footprint ``size`` plus ``pad`` is clear."""
        x0, y0, x1, y1 = region
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        spots = []
        for yaw, (hx, hy) in ((0.0, (size[0] / 2, size[1] / 2)), (math.pi / 2, (size[1] / 2, size[0] / 2))):
            # A footprint bigger than the region may still rest on it (a banana across a plate).
            hx, hy = min(hx + pad, (x1 - x0) / 2), min(hy + pad, (y1 - y0) / 2)
            grid = 4
            candidates = [(cx, cy)] + [
                (x0 + hx + (x1 - x0 - 2 * hx) * i / grid, y0 + hy + (y1 - y0 - 2 * hy) * j / grid)
                for i in range(grid + 1)
                for j in range(grid + 1)
            ]
            for px, py in candidates:
                box = (px - hx, py - hy, px + hx, py + hy)
                if all(
                    box[2] <= o[0] or box[0] >= o[2] or box[3] <= o[1] or box[1] >= o[3] for o in occupied
                ):
                    spots.append(Spot(px, py, yaw, floor))
        return spots

    # -- the skill -----------------------------------------------------------------------------------
    def run(self, obj: str, target: str) -> SkillResult:
        """Pick ``obj`` and place it in/on ``target``; never raises for a failed manipulation.

        A slipped or missed attempt is repeated from the object's new pose, up to ``retries`` times;
        ``seconds`` covers every attempt."""
        started = time.perf_counter()
        result = self._attempt(obj, target)
        attempts = 1
        first, retried = result, list[SkillResult]()
        while not result.ok and result.failure in RETRYABLE and attempts <= self.retries:
            self.world.settle(120)  # a dropped thing comes to rest (or falls off the table) first
            if self.world.off_table(obj):
                if "fell off the table" not in result.message:
                    result.message += "; it fell off the table"
                break
            attempts += 1
            result = self._attempt(obj, target)
            retried.append(result)
        if attempts > 1 and not result.ok:
            # The first failure says what went wrong with the step; the retries start from the mess.
            tried = "; ".join(f"{r.failure}: {r.message}" for r in retried)
            result = replace(first, message=f"{first.message} (tried again: {tried})", located=result.located)
        result.seconds = time.perf_counter() - started
        if attempts > 1:
            result.details["attempts"] = attempts
        return result

    def _attempt(self, obj: str, target: str) -> SkillResult:
        """One try at :meth:`run`, from the world as it is now."""
        action = format_action(PickAndPlace(obj, target))
        started = time.perf_counter()
        motion = self._plan_motion(action, obj, target, started)
        if isinstance(motion, SkillResult):
            return motion  # refused before the arm moved
        return self._carry_out(action, obj, target, motion, started)

    def _plan_motion(self, action: str, obj: str, target: str, started: float) -> _Motion | SkillResult:
        """Work out the whole pick and place before the arm moves, or say why it cannot be done."""
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
        _, target_hi = world.aabb(target)
        # Travel high enough that the held object clears everything on the way (tallest things 0.25 m)
        # and what already stands in/on the target, which it passes above on the way in.
        standing = [world.aabb(o)[1][2] for o in world.occupants(target) if o != obj]
        top = max([target_hi[2]] + [spot.floor_z for spot in spots[:12]] + standing)
        transit = max(TRANSIT_Z_M, top + hand_above_bottom + CLEARANCE_M, obj_hi[2] + CLEARANCE_M)
        pick = self._pick_poses(grasp, obj, transit)
        if pick is None:
            return SkillResult(action, False, "unreachable", f"the arm cannot reach {obj}", 0.0)
        yaw, above_obj = pick
        motion = _Motion(grasp, yaw, above_obj, None, (gx - ox, gy - oy), hand_above_bottom, transit)
        place, reachable = self._find_place(obj, spots, motion)
        if not reachable:
            return SkillResult(action, False, "unreachable", f"the arm cannot reach {target}", 0.0)
        if place is None:
            message = f"no spot in/on {target} leaves room for the hand beside what is there"
            return SkillResult(action, False, "target_full", message, 0.0)
        return replace(motion, place=place)

    def _find_place(self, obj: str, spots: list[Spot], motion: _Motion) -> tuple[Place | None, bool]:
        """The first place where the hand at the release touches nothing (the palm is 21 cm wide:
        beside a bin's wall it would land on the wall, beside a bottle it would knock it over), and
        whether any spot was reachable at all."""
        object_yaw = self.world.yaw(obj)
        round_body = self.world.bodies[obj].spec.shape in ("sphere", "cylinder")
        reachable = False
        # Where the hand cannot go all the way down (fingers on a bowl's rim), it lets go a little
        # higher, as people do: the thing drops at most DROP_M.
        for lift in (0.0, DROP_M / 2, DROP_M):
            for spot in spots:
                release_z = spot.floor_z + motion.hand_above_bottom + 0.004 + lift
                poses = self._place_poses(
                    spot, motion.offset, motion.yaw, object_yaw, motion.transit, release_z, round_body
                )
                for candidate in poses:
                    reachable = True
                    if self._clear(candidate[3], obj, motion.grasp.width):
                        return candidate, True
            if not reachable:
                break
        return None, reachable

    def _carry_out(self, action: str, obj: str, target: str, motion: _Motion, started: float) -> SkillResult:
        """Move the arm through a planned pick and place, and check where the object ended up."""
        world, robot, grasp, transit = self.world, self.robot, motion.grasp, motion.transit
        assert motion.place is not None
        robot.grip(Panda.OPENING_M, steps=20)
        robot.move(motion.above_obj, on_frame=self.on_frame)
        robot.move_straight(grasp.position, motion.yaw, on_frame=self.on_frame)
        robot.grip(0.0, steps=90, on_frame=self.on_frame)  # squeeze: the fingers stop on the object
        constraint = None
        if grasp.width == 0.0 or self.grasp_mode == "assisted":
            if not (self._touching(obj) or self._near_hand(obj)):
                return self._fail(action, obj, "slipped", f"the fingers did not touch {obj}", started)
            constraint = self._attach(obj)
        start_z = world.pose(obj)[0][2]
        robot.move_straight(
            (grasp.position[0], grasp.position[1], transit), motion.yaw, on_frame=self.on_frame
        )
        lifted = world.pose(obj)[0][2] - start_z
        if lifted < 0.03 or not self._held(obj, constraint):
            self._detach(constraint)
            message = f"{obj} was not lifted ({lifted * 100:.1f} cm)"
            return self._fail(action, obj, "slipped", message, started)
        # The squeeze moves the object in the hand (a cup held by its wall slides along the fingers),
        # so the release is aimed from where the hand holds it now, as a robot would after looking.
        drop_yaw = motion.place[2]
        above_target, drop = self._aim(
            obj, motion.place, motion.yaw, motion.offset, motion.hand_above_bottom, transit
        )
        robot.move(above_target, on_frame=self.on_frame, speed=CARRY_SPEED)
        if not self._held(obj, constraint):
            self._detach(constraint)
            return self._fail(action, obj, "slipped", f"{obj} slipped out on the way", started)
        robot.move_straight(drop, drop_yaw, on_frame=self.on_frame)
        self._detach(constraint)
        # Open into the clearance free_spots kept beside it (not wide open: that would push the
        # neighbours away), and let it stand on its own before the fingers leave.
        robot.grip(
            min(Panda.OPENING_M, grasp.width + 2 * FINGER_CLEARANCE_M), steps=50, on_frame=self.on_frame
        )
        world.settle(30)
        robot.move_straight((drop[0], drop[1], transit), drop_yaw, waypoints=3)
        self._go_home()
        world.settle(60)
        return self._where_it_ended(action, obj, target, lifted, started)

    def _where_it_ended(
        self, action: str, obj: str, target: str, lifted: float, started: float
    ) -> SkillResult:
        """The result of a completed motion: ok when ``obj`` rests in/on ``target``, else missed."""
        located = self.world.locate(obj)
        seconds = time.perf_counter() - started
        if self.world.off_table(obj):
            return SkillResult(action, False, "missed", f"{obj} fell off the table", seconds, located)
        if not same_place(self.world.holders(obj), target):
            where = f"in/on {located}" if located else "on the table"
            message = f"{obj} ended up {where}, not in/on {target}"
            return SkillResult(action, False, "missed", message, seconds, located)
        return SkillResult(action, True, None, "ok", seconds, located, {"lifted_m": round(lifted, 3)})

    def _yaws(self, grasp: Grasp) -> list[float]:
        """Hand yaws to try: ``grasp.yaw`` and its turn by pi (the same finger line, another arm pose),
        or eight around it when the grasp may turn (round things, knobs, sheets)."""
        if grasp.free_yaw:
            return [grasp.yaw + k * math.pi / 8 for k in range(8)]
        return [grasp.yaw, grasp.yaw + math.pi]

    def _pick_poses(self, grasp: Grasp, obj: str, transit: float) -> tuple[float, tuple[float, ...]] | None:
        """``(yaw, joints above the object)`` where the grasp pose is also reachable, or None.

        A yaw where the open hand at the grasp pose touches no other body wins (the palm is 21 cm
        wide along the finger line: beside a bottle it would land on it); else the first reachable.
        """
        gx, gy, _ = grasp.position
        first = None
        for yaw in self._yaws(grasp):
            above = self._reach((gx, gy, transit), yaw)
            at = self._reach(grasp.position, yaw)
            if above is None or at is None:
                continue
            if self._clear(at, obj):
                return yaw, above  # the grasp pose is checked here, reached by a straight descent
            first = first or (yaw, above)
        return first

    def _clear(self, joints: tuple[float, ...], obj: str, opening: float = Panda.OPENING_M) -> bool:
        """Whether the hand at ``joints``, fingers ``opening`` apart, keeps 3 mm from every body but
        ``obj`` and the table.

        Checked by putting the arm there without stepping the physics, then restoring the state."""
        client = self.world.client
        state = pb.saveState(physicsClientId=client)
        try:
            self.robot.pose_at(joints, opening)
            held = self.world.bodies[obj].id
            return not any(
                pb.getClosestPoints(self.robot.id, body.id, 0.003, physicsClientId=client)
                for body in self.world.bodies.values()
                if body.id != held
            )
        finally:
            pb.restoreState(state, physicsClientId=client)
            pb.removeState(state, physicsClientId=client)

    def _place_poses(
        self,
        spot: Spot,
        offset: tuple[float, float],
        yaw: float,
        object_yaw: float,
        transit: float,
        release_z: float,
        round_body: bool = False,
    ) -> list[Place]:
        """Reachable ``(joints above the spot, hand position at the release, hand yaw, joints at the
        release)`` for one spot.

        The hand turns the held object from ``object_yaw`` to the spot's yaw (or that plus pi, the same
        footprint); a round body may turn any way (eight turns tried), which lets the wide palm
        avoid a wall or a tall neighbour. The grasp offset turns with it.
        """
        found = []
        for extra in [k * math.pi / 4 for k in range(8)] if round_body else (0.0, math.pi):
            turn = spot.yaw - object_yaw + extra
            dx = offset[0] * math.cos(turn) - offset[1] * math.sin(turn)
            dy = offset[0] * math.sin(turn) + offset[1] * math.cos(turn)
            x, y = spot.x + dx, spot.y + dy
            above = self._reach((x, y, transit), yaw + turn)
            drop = self._reach((x, y, release_z), yaw + turn)
            if above is not None and drop is not None:
                found.append((above, (x, y, release_z), yaw + turn, drop))
        return found

    def _aim(
        self,
        obj: str,
        place: Place,
        pick_yaw: float,
        planned_offset: tuple[float, float],
        planned_height: float,
        transit: float,
    ) -> tuple[tuple[float, ...], Vec3]:
        """``(joints above the release, release position)`` for the held ``obj``, corrected by how far
        it sits from where the grasp was planned (offset from the hand, height under it).

        The planned poses stay when the object is held within :data:`AIM_TOLERANCE_M` of the plan
        (they were checked for collisions), and when the corrected release is out of reach or needs
        another arm configuration."""
        above, drop, drop_yaw, _ = place
        hand = self.robot.hand_position()
        (ox, oy, _), _ = self.world.pose(obj)
        lo, _ = self.world.aabb(obj)
        ex, ey = (hand[0] - ox) - planned_offset[0], (hand[1] - oy) - planned_offset[1]
        turn = drop_yaw - pick_yaw  # the hand turns the offset with it
        dx = ex * math.cos(turn) - ey * math.sin(turn)
        dy = ex * math.sin(turn) + ey * math.cos(turn)
        dz = (hand[2] - lo[2]) - planned_height
        if max(math.hypot(dx, dy), abs(dz)) < AIM_TOLERANCE_M:
            return above, drop  # held as planned: keep the checked poses
        aimed = (drop[0] + dx, drop[1] + dy, drop[2] + dz)
        aimed_above = self._reach((aimed[0], aimed[1], transit), drop_yaw)
        # Another arm configuration (elbow flipped) would swing the held thing through the scene.
        if (
            aimed_above is None
            or max(abs(a - b) for a, b in zip(aimed_above, above, strict=True)) > 0.3
            or self._reach(aimed, drop_yaw) is None
        ):
            return above, drop
        return aimed_above, aimed

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
