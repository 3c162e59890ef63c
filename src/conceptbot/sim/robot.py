"""Robot arms for the simulator: the Franka Panda from ``pybullet_data`` (SayCan's tabletop used a UR5e;
the paper's real robot is a Panda).

Motions are joint-space interpolations to inverse-kinematics targets under position control, so the
physics (contacts, friction, mass) decides whether a grasp holds. Everything is deterministic for a
given sequence of commands.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import pybullet as pb
import pybullet_data

Vec3 = tuple[float, float, float]
FrameHook = Callable[[], None]


@dataclass(frozen=True)
class Reach:
    """An inverse-kinematics solution and how far the hand would end up from the target pose (m)."""

    joints: tuple[float, ...]
    error_m: float


class Panda:
    """Franka Emika Panda with its parallel gripper (0.08 m maximum opening).

    Args:
        client: The PyBullet physics client id.
        base: Base position (the arm's foot stands on the table top).
    """

    ARM_JOINTS = (0, 1, 2, 3, 4, 5, 6)
    FINGERS = (9, 10)
    HAND = 11  # panda_grasptarget: the point between the finger pads
    HOME = (0.0, -0.6, 0.0, -2.4, 0.0, 1.8, 0.785)
    OBSERVE = (2.9, -0.3, 0.0, -1.2, 0.0, 0.9, 0.785)  # leaning back, out of the top camera's view
    OPENING_M = 0.08
    LOWER = (-2.9671, -1.8326, -2.9671, -3.1416, -2.9671, -0.0873, -2.9671)  # from the URDF
    UPPER = (2.9671, 1.8326, 2.9671, 0.0, 2.9671, 3.8223, 2.9671)
    FINGER_FORCE_N = 60.0
    JOINT_SPEED = 1.5  # rad/s along interpolated lines (the motors allow 2.0)

    def __init__(self, client: int, base: Vec3 = (0.0, 0.0, 0.0)) -> None:
        self.client = client
        self.id = pb.loadURDF(
            str(pybullet_data.getDataPath()) + "/franka_panda/panda.urdf",
            base,
            useFixedBase=True,
            physicsClientId=client,
        )
        for finger in self.FINGERS:
            pb.changeDynamics(self.id, finger, lateralFriction=1.5, physicsClientId=client)
        self.reset()

    def reset(self) -> None:
        """Teleport to the home pose (arm raised, out of the camera's way) with the gripper open."""
        for joint, q in zip(self.ARM_JOINTS, self.HOME, strict=True):
            pb.resetJointState(self.id, joint, q, physicsClientId=self.client)
        for finger in self.FINGERS:
            pb.resetJointState(self.id, finger, self.OPENING_M / 2, physicsClientId=self.client)
        self._grip_target = self.OPENING_M / 2

    def joints(self) -> tuple[float, ...]:
        """Current arm joint angles."""
        return tuple(pb.getJointState(self.id, j, physicsClientId=self.client)[0] for j in self.ARM_JOINTS)

    def hand_position(self) -> Vec3:
        """World position of the grasp point between the fingers."""
        state = pb.getLinkState(
            self.id, self.HAND, computeForwardKinematics=True, physicsClientId=self.client
        )
        return tuple(state[4])  # type: ignore[return-value]

    @staticmethod
    def down(yaw: float) -> tuple[float, float, float, float]:
        """Hand orientation pointing down with the fingers closing along ``yaw`` + 90 degrees."""
        return pb.getQuaternionFromEuler((math.pi, 0.0, yaw))

    def solve(self, position: Vec3, yaw: float) -> Reach:
        """Inverse kinematics for the hand pointing down at ``position``, checked by forward kinematics.

        PyBullet's solver is local and may return angles beyond the joint limits, so it is started
        from three seeds (the current pose, home, home turned towards the target), for ``yaw`` and
        ``yaw + pi`` (the gripper is symmetric); solutions are clamped to the limits and checked by
        teleporting the arm there and back without stepping the physics (nothing in the world moves).
        ``error_m`` adds the position error and 5 cm per radian of orientation error.
        """
        current = [pb.getJointState(self.id, j, physicsClientId=self.client)[:2] for j in self.ARM_JOINTS]
        facing = list(self.HOME)
        facing[0] = max(self.LOWER[0], min(self.UPPER[0], math.atan2(position[1], position[0])))
        seeds = [tuple(q for q, _ in current), self.HOME, tuple(facing)]
        best: Reach | None = None
        for candidate in (yaw, yaw + math.pi):
            target = self.down(candidate)
            for seed in seeds:
                self._teleport(seed)
                raw = pb.calculateInverseKinematics(
                    self.id,
                    self.HAND,
                    position,
                    target,
                    maxNumIterations=100,
                    residualThreshold=1e-5,
                    physicsClientId=self.client,
                )[: len(self.ARM_JOINTS)]
                solution = tuple(
                    max(lo, min(hi, q)) for q, lo, hi in zip(raw, self.LOWER, self.UPPER, strict=True)
                )
                self._teleport(solution)
                state = pb.getLinkState(
                    self.id, self.HAND, computeForwardKinematics=True, physicsClientId=self.client
                )
                diff = pb.getDifferenceQuaternion(state[5], target)
                angle = 2.0 * math.acos(min(1.0, abs(diff[3])))
                error = math.dist(state[4], position) + 0.05 * angle
                if best is None or error < best.error_m - 1e-4:
                    best = Reach(solution, error)
        for joint, (q, v) in zip(self.ARM_JOINTS, current, strict=True):
            pb.resetJointState(self.id, joint, q, targetVelocity=v, physicsClientId=self.client)
        assert best is not None
        return best

    def out_of_view(self) -> tuple[float, ...]:
        """Teleport the arm to :data:`OBSERVE` (for a picture); returns the joints to restore. Only
        between motions and with nothing held: the physics is not stepped, so nothing moves."""
        saved = self.joints()
        self._teleport(self.OBSERVE)
        return saved

    def restore(self, joints: Sequence[float]) -> None:
        """Teleport back after :meth:`out_of_view`."""
        self._teleport(joints)

    def pose_at(self, joints: Sequence[float], opening: float) -> None:
        """Teleport the arm to ``joints`` and the fingers to ``opening`` (for collision checks; the
        caller saves and restores the physics state around it)."""
        self._teleport(joints)
        for finger in self.FINGERS:
            pb.resetJointState(self.id, finger, opening / 2, physicsClientId=self.client)

    def _teleport(self, joints: Sequence[float]) -> None:
        for joint, q in zip(self.ARM_JOINTS, joints, strict=True):
            pb.resetJointState(self.id, joint, q, physicsClientId=self.client)

    def _drive(self, targets: Sequence[float], grip: float) -> None:
        for joint, q in zip(self.ARM_JOINTS, targets, strict=True):
            pb.setJointMotorControl2(
                self.id,
                joint,
                pb.POSITION_CONTROL,
                q,
                force=240.0,
                maxVelocity=2.0,
                physicsClientId=self.client,
            )
        for finger in self.FINGERS:
            pb.setJointMotorControl2(
                self.id,
                finger,
                pb.POSITION_CONTROL,
                grip,
                force=self.FINGER_FORCE_N,
                physicsClientId=self.client,
            )

    def move(
        self,
        joints: Sequence[float],
        steps: int = 60,
        on_frame: FrameHook | None = None,
        speed: float | None = None,
    ) -> None:
        """Move to ``joints`` along a straight joint-space line, then hold until the arm gets there.

        The line takes at least ``steps`` physics steps and longer for big turns (joint speed is held
        under ``speed``, default :data:`JOINT_SPEED`); the hold ends when every joint is within 2 mrad,
        or after 150 steps.
        """
        start = self.joints()
        delta = max(abs(t - s) for s, t in zip(start, joints, strict=True))
        ramp = max(steps, int(delta / (speed or self.JOINT_SPEED) * 240))
        for step in range(ramp):
            a = (step + 1) / ramp
            self._drive([s + (t - s) * a for s, t in zip(start, joints, strict=True)], self._grip_target)
            pb.stepSimulation(physicsClientId=self.client)
        for _ in range(150):
            if max(abs(q - t) for q, t in zip(self.joints(), joints, strict=True)) < 2e-3:
                break
            self._drive(joints, self._grip_target)
            pb.stepSimulation(physicsClientId=self.client)
        if on_frame:
            on_frame()

    def move_straight(
        self, position: Vec3, yaw: float, waypoints: int = 8, on_frame: FrameHook | None = None
    ) -> None:
        """Move the hand along a straight line to ``position`` (descending onto or lifting off an
        object), solving inverse kinematics at each waypoint so the fingers do not sweep sideways."""
        start = self.hand_position()
        for i in range(1, waypoints + 1):
            a = i / waypoints
            point = tuple(s + (t - s) * a for s, t in zip(start, position, strict=True))
            self.move(self.solve(point, yaw).joints, steps=20)  # type: ignore[arg-type]
        if on_frame:
            on_frame()

    def grip(self, width: float, steps: int = 80, on_frame: FrameHook | None = None) -> None:
        """Open or close the fingers to a gap of ``width`` (they stop on contact) and hold the arm still."""
        self._grip_target = max(0.0, min(self.OPENING_M, width)) / 2
        hold = self.joints()
        for _ in range(steps):
            self._drive(hold, self._grip_target)
            pb.stepSimulation(physicsClientId=self.client)
        if on_frame:
            on_frame()
