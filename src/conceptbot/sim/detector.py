"""The simulated detector: render the top camera, segment, and report per object a pixel box, a
confidence and a size. It replaces the paper's ViLD/YOLO and feeds the Planner's affordance through
the scene's detections (``confidence``, ``bbox_px``, ``size_m``).

* ``bbox_px``: the box around the object's visible pixels in the segmentation mask.
* ``confidence``: the visible fraction -- visible pixels over the pixels its top face would cover
  unoccluded (its footprint projected at its distance from the camera), capped at 1. A thing under
  the arm or inside a deep box scores low; a thing out of view is not detected at all.
* ``size_m``: the mask's extents along the sides of its smallest enclosing rectangle, in metres at
  the object's distance (what an RGB-D detector measures), narrow side first, and its height; the
  affordance compares the narrow side with the gripper opening.

Any other detector plugs in through :class:`Detector`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from conceptbot.core.scene import Scene
from conceptbot.sim.render import TOP, Camera, capture
from conceptbot.sim.world import World


@dataclass(frozen=True)
class Detection:
    """One detected object."""

    name: str
    confidence: float
    bbox_px: tuple[float, float, float, float]
    size_m: tuple[float, float, float]


class Detector(Protocol):
    """Reports what a camera sees in a world."""

    def detect(self, world: World) -> dict[str, Detection]:
        """Detections by object name (objects not seen are absent)."""
        ...


def _footprint_area(shape: str, width: float, depth: float) -> float:
    if shape in ("sphere", "cylinder"):
        return math.pi * (width / 2) ** 2
    return width * depth


def _extents(rows: np.ndarray, cols: np.ndarray) -> tuple[float, float]:
    """Long and short extents (pixels) of a pixel set along the sides of its smallest-area enclosing
    rectangle (turns tried every 3 degrees; principal axes alone are arbitrary for a square)."""
    points = np.stack([rows, cols], axis=1).astype(float)
    if len(points) < 3:
        return 1.0, 1.0
    centred = points - points.mean(axis=0)
    angles = np.radians(np.arange(0.0, 90.0, 3.0))
    axes = np.stack([np.cos(angles), np.sin(angles)], axis=1)  # (turns, 2)
    along = centred @ axes.T  # first side of each rectangle
    across = centred @ np.stack([-axes[:, 1], axes[:, 0]], axis=1).T
    spans_a = along.max(axis=0) - along.min(axis=0) + 1.0
    spans_b = across.max(axis=0) - across.min(axis=0) + 1.0
    best = int(np.argmin(spans_a * spans_b))
    return float(max(spans_a[best], spans_b[best])), float(min(spans_a[best], spans_b[best]))


class SimDetector:
    """Detector from the top camera's segmentation mask (see the module docstring).

    Args:
        camera: The camera (default: straight down over the workspace).
    """

    def __init__(self, camera: Camera = TOP) -> None:
        self.camera = camera

    def detect(self, world: World) -> dict[str, Detection]:
        """Detections of every body with at least one visible pixel."""
        saved = world.robot.out_of_view()
        try:
            _, mask = capture(world, self.camera)
        finally:
            world.robot.restore(saved)
        by_id = {body.id: name for name, body in world.bodies.items()}
        found: dict[str, Detection] = {}
        ids, counts = np.unique(mask[mask >= 0] & ((1 << 24) - 1), return_counts=True)
        for body_id, count in zip(ids.tolist(), counts.tolist(), strict=True):
            name = by_id.get(body_id)
            if name is None:
                continue
            rows, cols = np.nonzero((mask & ((1 << 24) - 1)) == body_id)
            bbox = (float(cols.min()), float(rows.min()), float(cols.max() + 1), float(rows.max() + 1))
            lo, hi = world.aabb(name)
            centre = ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, hi[2])
            _, _, depth = self.camera.project(centre)
            metres_per_px = depth / self.camera.focal_px
            spec = world.bodies[name].spec
            expected_px = _footprint_area(spec.shape, spec.size_m[0], spec.size_m[1]) / metres_per_px**2
            confidence = min(1.0, count / expected_px) if expected_px > 0 else 1.0
            # Extents along the mask's own smallest rectangle: a turned object is as wide as it is,
            # not as wide as its axis-aligned box.
            long_px, short_px = _extents(rows, cols)
            size = (
                round(short_px * metres_per_px, 3),
                round(long_px * metres_per_px, 3),
                round(hi[2] - lo[2], 3),
            )
            found[name] = Detection(name, round(confidence, 3), bbox, size)
        return found


def observe(scene: Scene, world: World, detector: Detector) -> Scene:
    """``scene`` with its detections replaced by what ``detector`` sees in ``world``.

    An object the detector does not see keeps its name but gets confidence 0 (the affordance then
    rules out acting on it); people and furniture zones are always "seen" (confidence 1).
    """
    seen = detector.detect(world)
    objects = []
    for obj in scene.objects:
        det = seen.get(obj.name)
        if det is not None:
            objects.append(replace(obj, confidence=det.confidence, bbox_px=det.bbox_px, size_m=det.size_m))
        elif obj.name in world.bodies and world.bodies[obj.name].spec.shape == "zone":
            objects.append(replace(obj, confidence=1.0))
        else:
            objects.append(replace(obj, confidence=0.0))
    return replace(scene, objects=tuple(objects))
