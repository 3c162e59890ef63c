"""Cameras and pictures: TinyRenderer images (no GPU, no display), labelled PNGs and animated GIFs.

Two cameras: :data:`TOP` looks straight down on the workspace (the simulated detector uses it), and
:data:`VIEW` looks from in front of the table at an angle (pictures for people).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet as pb
from PIL import Image, ImageDraw

from conceptbot.sim.world import World


@dataclass(frozen=True)
class Camera:
    """A pinhole camera looking at ``target`` from ``eye``."""

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float]
    fov_deg: float
    width: int = 640
    height: int = 480

    def view(self) -> list[float]:
        """The view matrix."""
        return pb.computeViewMatrix(self.eye, self.target, self.up)

    def projection(self) -> list[float]:
        """The projection matrix."""
        return pb.computeProjectionMatrixFOV(self.fov_deg, self.width / self.height, 0.05, 5.0)

    def scaled(self, width: int, height: int) -> Camera:
        """The same camera at another resolution."""
        return Camera(self.eye, self.target, self.up, self.fov_deg, width, height)

    def project(self, point: tuple[float, float, float]) -> tuple[float, float, float]:
        """Pixel ``(u, v)`` and depth (m along the optical axis) of a world point."""
        view = np.array(self.view()).reshape(4, 4).T
        proj = np.array(self.projection()).reshape(4, 4).T
        cam = view @ np.array([*point, 1.0])
        clip = proj @ cam
        ndc = clip[:3] / clip[3]
        u = (ndc[0] + 1) / 2 * self.width
        v = (1 - ndc[1]) / 2 * self.height
        return float(u), float(v), float(-cam[2])

    @property
    def focal_px(self) -> float:
        """Focal length in pixels (vertical field of view)."""
        return self.height / (2 * math.tan(math.radians(self.fov_deg) / 2))


TOP = Camera(eye=(0.03, 0.0, 2.1), target=(0.03, 0.0, 0.0), up=(1.0, 0.0, 0.0), fov_deg=50.0)
VIEW = Camera(eye=(1.55, 0.0, 1.25), target=(0.1, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov_deg=60.0)


def capture(world: World, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """RGB image (H x W x 3, uint8) and segmentation mask (body id per pixel, -1 for background)."""
    _, _, rgba, _, seg = pb.getCameraImage(
        camera.width,
        camera.height,
        camera.view(),
        camera.projection(),
        renderer=pb.ER_TINY_RENDERER,
        lightDirection=(0.4, -0.3, 1.0),
        physicsClientId=world.client,
    )
    rgb = np.asarray(rgba, dtype=np.uint8).reshape(camera.height, camera.width, 4)[:, :, :3]
    mask = np.asarray(seg, dtype=np.int64).reshape(camera.height, camera.width)
    return rgb, mask


def picture(world: World, camera: Camera = VIEW, labels: bool = True, title: str = "") -> Image.Image:
    """A picture of the world, with object names written at their positions."""
    rgb, _ = capture(world, camera)
    image = Image.fromarray(rgb)
    draw = ImageDraw.Draw(image)
    if labels:
        for name in world.bodies:
            (x, y, _z), _ = world.pose(name)
            _, hi = world.aabb(name)
            u, v, _ = camera.project((x, y, hi[2] + 0.01))
            if 0 <= u < camera.width and 0 <= v < camera.height:
                text_w = draw.textlength(name)
                draw.rectangle((u - text_w / 2 - 2, v - 12, u + text_w / 2 + 2, v), fill=(255, 255, 255))
                draw.text((u - text_w / 2, v - 12), name, fill=(0, 0, 0))
    if title:
        draw.rectangle((0, 0, camera.width, 16), fill=(0, 0, 0))
        draw.text((4, 2), title, fill=(255, 255, 255))
    return image


def save_gif(frames: list[Image.Image], path: Path, ms_per_frame: int = 120) -> None:
    """Write frames as an animated GIF (looping); nothing is written for no frames."""
    if not frames:
        return
    frames[0].save(
        path, save_all=True, append_images=frames[1:], duration=ms_per_frame, loop=0, optimize=True
    )
