"""A PyBullet tabletop built from a scene: a table, a Panda, and every object as a body.

Layout: the arm stands at the origin on the table top (z = 0); objects are placed by seeded rejection
sampling in the arm's reach (a half-ring in front and to the sides), destinations first on the outer
ring, without overlaps (footprint circles plus a margin). Same scene + same seed = same world.

Where things are: :meth:`World.locate` says, for an object, which destination it is in or on (a
container's floor, a zone pad, a plate, or the top of another object) or None (on the bare table).
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import NamedTuple

import pybullet as pb

from conceptbot.core.errors import ConfigError
from conceptbot.core.scene import Scene
from conceptbot.sim.catalogue import Catalogue, ObjectSpec
from conceptbot.sim.robot import Panda, Vec3

WALL_M = 0.008
POT_RGBA = (0.72, 0.42, 0.26, 1.0)  # terracotta, under a plant's foliage
REACH_MIN_M = 0.32
REACH_MAX_M = 0.78
SIDE_ANGLE_RAD = math.radians(150)
OUTER_EXTRA_ANGLE_RAD = math.radians(10)  # receptacles may stand a little behind the arm's sides
MARGIN_M = 0.015
ZONE_OVERHANG_M = 0.08
TABLE_HALF = (0.92, 0.95, 0.02)
BLOCKING_HEIGHT_M = 0.13  # things taller than this block the forearm's way down to what is behind them
ARM_CORRIDOR_M = 0.07  # half-width of the forearm's way from the arm to an object
BLOCKING_RANGE_M = 0.2  # how far before an object the forearm is low
TALL_M_LAYOUT = 0.2  # pickable things taller than this stand within TALL_REACH_M
TALL_REACH_M = 0.6
TABLE_CENTRE = (0.03, 0.0)


@dataclass
class Body:
    """One object in the world."""

    name: str
    spec: ObjectSpec
    id: int
    pickable: bool
    destination: bool


@dataclass
class World:
    """A running simulation built by :func:`build_world`. Call :meth:`close` when done."""

    client: int
    robot: Panda
    bodies: dict[str, Body]
    table_id: int
    seed: int
    warnings: list[str] = field(default_factory=list)

    # -- state -------------------------------------------------------------------------------------
    def pose(self, name: str) -> tuple[Vec3, tuple[float, float, float, float]]:
        """Position and orientation (quaternion) of a body."""
        pos, orn = pb.getBasePositionAndOrientation(self.bodies[name].id, physicsClientId=self.client)
        return tuple(pos), tuple(orn)  # type: ignore[return-value]

    def yaw(self, name: str) -> float:
        """Rotation of a body about the vertical axis (radians)."""
        return pb.getEulerFromQuaternion(self.pose(name)[1])[2]

    def aabb(self, name: str) -> tuple[Vec3, Vec3]:
        """Axis-aligned bounding box of a body (min corner, max corner)."""
        lo, hi = pb.getAABB(self.bodies[name].id, physicsClientId=self.client)
        return tuple(lo), tuple(hi)  # type: ignore[return-value]

    def snapshot(self) -> dict[str, tuple[float, ...]]:
        """Every body's position and orientation, rounded to 0.1 mm: compares two runs."""
        return {n: tuple(round(v, 4) for v in (*self.pose(n)[0], *self.pose(n)[1])) for n in self.bodies}

    def settle(self, steps: int = 120) -> None:
        """Step the physics with the arm holding still."""
        for _ in range(steps):
            pb.stepSimulation(physicsClientId=self.client)

    def floor_z(self, name: str) -> float:
        """Height things rest at when placed in/on ``name``."""
        body = self.bodies[name]
        lo, hi = self.aabb(name)
        if body.spec.shape == "container":
            return lo[2] + WALL_M
        return hi[2]

    def region(self, name: str) -> tuple[float, float, float, float]:
        """``(x0, y0, x1, y1)`` where things placed in/on ``name`` may rest (inside walls for containers)."""
        lo, hi = self.aabb(name)
        inset = WALL_M + 0.004 if self.bodies[name].spec.shape == "container" else 0.0
        return lo[0] + inset, lo[1] + inset, hi[0] - inset, hi[1] - inset

    def locate(self, name: str) -> str | None:
        """The destination ``name`` is in or on, or None (on the table, in no destination).

        A body counts as in/on a destination when its centre lies over the destination's footprint and
        its bottom rests between the destination's floor and top (containers) or on its top surface
        (zones, plates, other objects); the highest such destination wins (a block on a block on a plate
        is on the block).
        """
        if self.bodies[name].spec.shape == "zone":
            return None  # a pad on the table is never in/on something
        (x, y, _), _ = self.pose(name)
        lo, _ = self.aabb(name)
        best: tuple[float, str] | None = None
        for other, body in self.bodies.items():
            if other == name:
                continue
            olo, ohi = self.aabb(other)
            if not self._over(other, x, y, 0.005):
                continue
            if body.spec.shape == "container":
                resting = olo[2] - 0.01 <= lo[2] <= ohi[2] + 0.01
            else:
                resting = abs(lo[2] - ohi[2]) <= 0.02 and lo[2] > olo[2] + 0.001
            if resting and (best is None or ohi[2] > best[0]):
                best = (ohi[2], other)
        return best[1] if best else None

    def off_table(self, name: str) -> bool:
        """Whether ``name`` fell off the table (all of it below the table top, which is at z = 0)."""
        return self.aabb(name)[1][2] < -0.005

    def holders(self, name: str) -> list[str]:
        """Every destination ``name`` is in or on, innermost first: a fork on a plate in the dishwasher
        gives ``["plate", "dishwasher"]`` (things piled in a bin are in the bin)."""
        chain: list[str] = []
        current = self.locate(name)
        while current is not None and current not in chain:
            chain.append(current)
            current = self.locate(current)
        return chain

    def _over(self, name: str, x: float, y: float, margin: float) -> bool:
        """Whether the point ``(x, y)`` lies over ``name``'s footprint (in its own turned frame; an
        axis-aligned box would take in the corners beside a turned bin)."""
        (ox, oy, _), _ = self.pose(name)
        yaw = self.yaw(name)
        dx, dy = x - ox, y - oy
        lx = dx * math.cos(yaw) + dy * math.sin(yaw)
        ly = -dx * math.sin(yaw) + dy * math.cos(yaw)
        w, d, _ = self.bodies[name].spec.size_m
        return abs(lx) <= w / 2 + margin and abs(ly) <= d / 2 + margin

    def occupants(self, name: str) -> list[str]:
        """Bodies currently in or on ``name``."""
        return [other for other in self.bodies if other != name and self.locate(other) == name]

    def close(self) -> None:
        """Disconnect the physics client (idempotent)."""
        if pb.isConnected(self.client):
            pb.disconnect(self.client)

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _shapes(client: int, spec: ObjectSpec) -> tuple[int, int, float]:
    """Collision shape, visual shape and the centre height above the table for one spec."""
    w, d, h = spec.size_m
    colour = list(spec.rgba)
    if spec.shape == "sphere":
        r = w / 2
        return (
            pb.createCollisionShape(pb.GEOM_SPHERE, radius=r, physicsClientId=client),
            pb.createVisualShape(pb.GEOM_SPHERE, radius=r, rgbaColor=colour, physicsClientId=client),
            r,
        )
    if spec.shape == "cylinder" and spec.foliage_m > 0:
        # A potted plant: the pot is solid; the foliage above it is drawn only (see ObjectSpec).
        r = min(w, d) / 2
        visual = pb.createVisualShapeArray(
            [pb.GEOM_CYLINDER, pb.GEOM_CYLINDER],
            radii=[r, r],
            lengths=[h, spec.foliage_m],
            visualFramePositions=[[0, 0, 0], [0, 0, (h + spec.foliage_m) / 2]],
            rgbaColors=[list(POT_RGBA), colour],
            physicsClientId=client,
        )
        collision = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=r, height=h, physicsClientId=client)
        return collision, visual, h / 2
    if spec.shape == "cylinder":
        r = min(w, d) / 2
        return (
            pb.createCollisionShape(pb.GEOM_CYLINDER, radius=r, height=h, physicsClientId=client),
            pb.createVisualShape(
                pb.GEOM_CYLINDER, radius=r, length=h, rgbaColor=colour, physicsClientId=client
            ),
            h / 2,
        )
    if spec.shape == "container":
        t = WALL_M
        parts = [
            ((w / 2, d / 2, t / 2), (0, 0, -h / 2 + t / 2)),
            ((t / 2, d / 2, h / 2), (-w / 2 + t / 2, 0, 0)),
            ((t / 2, d / 2, h / 2), (w / 2 - t / 2, 0, 0)),
            ((w / 2 - t, t / 2, h / 2), (0, -d / 2 + t / 2, 0)),
            ((w / 2 - t, t / 2, h / 2), (0, d / 2 - t / 2, 0)),
        ]
        return (*_compound(client, parts, colour), h / 2)
    if spec.grip == "knob":
        knob = 0.012
        parts = [((w / 2, d / 2, h / 2), (0, 0, 0)), ((knob, knob, 0.015), (0, 0, h / 2 + 0.015))]
        return (*_compound(client, parts, colour), h / 2)
    half = (w / 2, d / 2, h / 2)
    return (
        pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, physicsClientId=client),
        pb.createVisualShape(pb.GEOM_BOX, halfExtents=half, rgbaColor=colour, physicsClientId=client),
        h / 2,
    )


def _compound(client: int, parts: list, colour: list[float]) -> tuple[int, int]:
    """Collision and visual shapes made of boxes (``parts``: half extents and offsets)."""
    halves = [list(p[0]) for p in parts]
    offsets = [list(p[1]) for p in parts]
    types = [pb.GEOM_BOX] * len(parts)
    collision = pb.createCollisionShapeArray(
        types, halfExtents=halves, collisionFramePositions=offsets, physicsClientId=client
    )
    visual = pb.createVisualShapeArray(
        types,
        halfExtents=halves,
        visualFramePositions=offsets,
        rgbaColors=[colour] * len(parts),
        physicsClientId=client,
    )
    return collision, visual


class _Placed(NamedTuple):
    """An object already laid out: centre, footprint radius, height, and whether the arm picks it."""

    x: float
    y: float
    radius: float
    height: float
    picked: bool


def _blocks(near: _Placed, far: _Placed) -> bool:
    """Whether ``near`` stands in the arm's way to ``far``: it is tall, nearer the arm, and within the
    forearm's corridor on the line from the arm to ``far``. Only objects to pick count as ``far``: a
    receptacle has room beside the blocker, and the skill picks a spot there."""
    reach = math.hypot(far.x, far.y)
    if not far.picked or near.height <= BLOCKING_HEIGHT_M or math.hypot(near.x, near.y) >= reach:
        return False
    along = (near.x * far.x + near.y * far.y) / reach
    across = abs(near.x * far.y - near.y * far.x) / reach
    # Only near the far object does the forearm come down low enough to hit something.
    return 0.0 < reach - along < BLOCKING_RANGE_M and across < near.radius + ARM_CORRIDOR_M


def _layout(specs: list[tuple[ObjectSpec, bool]], rng: random.Random) -> dict[str, tuple[float, float]]:
    """Positions without overlaps: receptacles and zones on the outer ring first, then the rest.

    Tall objects stand within :data:`TALL_REACH_M` (the arm lifts them higher than it can reach far
    out) and never in the forearm's way to another object (a bottle in front of an egg leaves no way
    down to the egg)."""
    placed: list[_Placed] = []
    positions: dict[str, tuple[float, float]] = {}
    order = sorted(specs, key=lambda item: (not item[1], -item[0].footprint_radius))
    for spec, outer in order:
        radius = spec.footprint_radius
        height = spec.size_m[2]
        lo = (REACH_MIN_M + REACH_MAX_M) / 2 if outer else REACH_MIN_M
        hi = REACH_MAX_M if outer else REACH_MAX_M - 0.06
        if spec.shape == "zone":
            hi += ZONE_OVERHANG_M  # only the near part of a large pad must be in reach
        elif not outer and height > TALL_M_LAYOUT:
            hi = min(hi, TALL_REACH_M)
        for attempt in range(10000):
            if attempt == 3000:
                lo = REACH_MIN_M  # crowded: let it use the whole ring
            corridors = attempt < 8000  # very crowded: give up keeping the forearm's ways free
            r = rng.uniform(lo + radius * 0.5, hi - radius * 0.5) if hi - lo > radius else (lo + hi) / 2
            side = SIDE_ANGLE_RAD + (OUTER_EXTRA_ANGLE_RAD if outer else 0.0)
            a = rng.uniform(-side, side)
            x, y = r * math.cos(a), r * math.sin(a)
            here = _Placed(x, y, radius, height, not outer)
            if all(math.hypot(x - p.x, y - p.y) >= radius + p.radius + MARGIN_M for p in placed) and not (
                corridors and any(_blocks(here, other) or _blocks(other, here) for other in placed)
            ):
                placed.append(here)
                positions[spec.name] = (x, y)
                break
        else:
            raise ConfigError(
                f"the scene does not fit on the simulated table ({len(specs)} objects); "
                "remove some objects or use smaller receptacles"
            )
    return positions


def build_world(scene: Scene, seed: int = 0, catalogue: Catalogue | None = None) -> World:
    """Create the simulation for ``scene`` (headless, DIRECT mode).

    Args:
        scene: The scene; names, pickable/destination flags and (for objects the catalogue does not
            know) sizes are used. A scene entry ``"layout": {"name": [x, y], ...}`` pins positions
            (metres, robot at the origin) instead of sampling them.
        seed: Layout seed.
        catalogue: Object catalogue (default: the shipped one).

    Raises:
        ConfigError: The objects do not fit on the table, or a pinned position is malformed.
    """
    catalogue = catalogue or Catalogue.load()
    catalogue.warnings.clear()
    client = pb.connect(pb.DIRECT)
    try:
        pb.setGravity(0, 0, -9.81, physicsClientId=client)
        pb.setTimeStep(1 / 240, physicsClientId=client)
        table = pb.createMultiBody(
            0,
            pb.createCollisionShape(pb.GEOM_BOX, halfExtents=TABLE_HALF, physicsClientId=client),
            pb.createVisualShape(
                pb.GEOM_BOX, halfExtents=TABLE_HALF, rgbaColor=[0.62, 0.5, 0.38, 1], physicsClientId=client
            ),
            [TABLE_CENTRE[0], TABLE_CENTRE[1], -TABLE_HALF[2]],
            physicsClientId=client,
        )
        pb.changeDynamics(table, -1, lateralFriction=0.8, physicsClientId=client)
        robot = Panda(client)
        specs = [(catalogue.spec(o.name, o.size_m), o.destination and not o.pickable) for o in scene.objects]
        rng = random.Random(seed)
        positions = _layout(specs, rng)
        pinned = scene.extra.get("layout", {}) or {}
        for name, xy in pinned.items():
            if name not in positions or not (isinstance(xy, list) and len(xy) == 2):
                raise ConfigError(f"layout: {name!r} must be a scene object with [x, y] in metres")
            positions[name] = (float(xy[0]), float(xy[1]))
        bodies: dict[str, Body] = {}
        for obj, (spec, _) in zip(scene.objects, specs, strict=True):
            collision, visual, z = _shapes(client, spec)
            x, y = positions[obj.name]
            # Face the arm: a long object lies across the reach direction so the gripper closes on its
            # narrow side without twisting the wrist far.
            # Receptacles stay square to the table: their regions are then their bounding boxes.
            yaw = math.atan2(y, x) if spec.shape in ("box", "cylinder", "sphere") else 0.0
            # Receptacles and zones the robot may not pick are fixed in place: a bump does not slide a
            # bin across the table (real ones are heavy or stand beside it).
            mass = spec.mass_kg if obj.pickable else 0.0
            body_id = pb.createMultiBody(
                mass,
                collision,
                visual,
                [x, y, z + 0.0005],
                pb.getQuaternionFromEuler((0, 0, yaw)),
                physicsClientId=client,
            )
            pb.changeDynamics(
                body_id,
                -1,
                lateralFriction=1.0,
                spinningFriction=0.002,
                rollingFriction=0.01 if spec.shape == "sphere" else 0.0001,  # fruit is not a ball bearing
                physicsClientId=client,
            )
            bodies[obj.name] = Body(obj.name, spec, body_id, obj.pickable, obj.destination)
        world = World(client, robot, bodies, table, seed, list(catalogue.warnings))
        world.settle(60)
        return world
    except Exception:
        pb.disconnect(client)
        raise
