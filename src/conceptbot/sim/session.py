"""One simulator run, written once for the CLI (``conceptbot sim run``) and the web page.

:func:`run_in_simulator` builds a PyBullet world from a scene, lets the simulated detector look at
the table (so a planner sees what the camera sees: confidence, box and size of each object), saves
``before.png``, hands a :class:`SimSession` to the caller's ``act`` (plan, execute, replan: whatever
the caller does), then saves ``after.png`` and the animation ``execution.gif``.

Example::

    options = SimOptions(seed=0, gif_size=(320, 240))
    outcome = run_in_simulator(scene, Path("sim-run"), lambda s: s.execute(actions), options)
    print(outcome.execution.verdict, outcome.files)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from PIL import Image

from conceptbot.core.plan import Action
from conceptbot.core.scene import Scene
from conceptbot.sim import AFTER_PNG, BEFORE_PNG, EXECUTION_GIF
from conceptbot.sim.detector import SimDetector, observe
from conceptbot.sim.execute import Execution, execute_plan
from conceptbot.sim.options import SimOptions
from conceptbot.sim.render import VIEW, picture, save_gif
from conceptbot.sim.skills import PickPlaceSkill
from conceptbot.sim.world import World, build_world

TITLE_CHARS = 70
"""Longest title written over a picture: the default font fits about 100 characters in 640 px,
and the prefix ("before: ", "after: ") takes some of them."""


@dataclass(frozen=True)
class SimSession:
    """What ``act`` gets: the running world, the scene as the detector saw it, and the skill.

    Attributes:
        world: The simulation (closed when ``act`` returns).
        scene: The scene with the detector's confidences, boxes and sizes (plan on this one).
        skill: Pick-and-place in ``world`` (it records the animation's frames).
    """

    world: World
    scene: Scene
    skill: PickPlaceSkill

    def execute(self, actions: Sequence[Action]) -> Execution:
        """Execute a plan's actions open loop (stop at the first failure) and check the final state."""
        return execute_plan(self.world, self.scene, actions, self.skill)


@dataclass(frozen=True)
class SimOutcome:
    """What a simulator run left.

    Attributes:
        execution: What ``act`` returned (None: nothing was executed, e.g. the plan was refused).
        scene: The scene as the detector saw it.
        files: Names of the pictures written in the output folder, in the order
            before, after, animation.
        warnings: What the world builder could not honour (an unknown object drawn as a box, ...).
    """

    execution: Execution | None
    scene: Scene
    files: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()


Act = Callable[[SimSession], Execution | None]
"""The caller's part of a run: plan and execute in the session; None when nothing was executed."""


def _frame_hook(world: World, options: SimOptions, frames: list[Image.Image]) -> Callable[[], None] | None:
    """A hook that keeps one small picture in ``options.gif_every`` motion segments (None: no GIF).
    Segments that are left out are not rendered at all (a picture costs more than the motion)."""
    if not options.gif:
        return None
    camera = VIEW.scaled(*options.gif_size)
    segments = 0

    def hook() -> None:
        nonlocal segments
        if segments % options.gif_every == 0:
            frames.append(picture(world, camera, labels=False))
        segments += 1

    return hook


def run_in_simulator(
    scene: Scene,
    out_dir: Path,
    act: Act,
    options: SimOptions | None = None,
    title: str = "",
    on_warning: Callable[[str], None] | None = None,
) -> SimOutcome:
    """Build the world, look, picture, ``act``, picture, animation (see the module docstring).

    Args:
        scene: The scene to build (objects laid out on a table with a Franka Panda).
        out_dir: Folder for ``before.png``, ``after.png`` and ``execution.gif`` (created if needed).
        act: Plans and executes in the session; returns the execution, or None when it executed
            nothing (then no ``after.png`` or animation is written).
        options: Seed, grasp, retries, detector and animation settings (default :class:`SimOptions`).
        title: Written over ``before.png`` (the request, usually).
        on_warning: Told each thing the world builder could not honour, before ``act`` runs.

    Returns:
        The execution, the scene as seen, the pictures written and the builder's warnings.
    """
    options = options or SimOptions()
    out_dir.mkdir(parents=True, exist_ok=True)
    frames: list[Image.Image] = []
    with build_world(scene, seed=options.seed) as world:
        for warning in world.warnings:
            if on_warning:
                on_warning(warning)
        seen = observe(scene, world, SimDetector()) if options.detect else scene
        picture(world, VIEW, title=f"before: {title[:TITLE_CHARS]}").save(out_dir / BEFORE_PNG)
        files = [BEFORE_PNG]
        hook = _frame_hook(world, options, frames)
        skill = PickPlaceSkill(world, options.grasp, on_frame=hook, retries=options.retries)
        execution = act(SimSession(world, seen, skill))
        if execution is not None:
            after = f"after: {execution.verdict[:TITLE_CHARS]}"
            picture(world, VIEW, title=after).save(out_dir / AFTER_PNG)
            files.append(AFTER_PNG)
            if frames:
                save_gif(frames, out_dir / EXECUTION_GIF)
                files.append(EXECUTION_GIF)
        warnings = tuple(world.warnings)
    return SimOutcome(execution, seen, tuple(files), warnings)
