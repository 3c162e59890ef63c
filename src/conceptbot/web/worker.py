"""What a web run does: plan with the chosen system and backend, then execute in the simulator."""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from conceptbot.core.config import Settings
from conceptbot.models import store
from conceptbot.systems import PlannerSystem, build_system
from conceptbot.web.runs import RunSpec, Worker

Emit = Callable[[str, dict[str, Any]], None]
SystemFactory = Callable[[str, str], PlannerSystem]  # (config, backend spec) -> system
PICTURES = ("before.png", "after.png", "execution.gif")


def cached_systems(settings: Settings) -> SystemFactory:
    """Systems built on first use and kept (loading a model takes seconds)."""
    built: dict[tuple[str, str], PlannerSystem] = {}
    lock = threading.Lock()

    def get(config: str, backend: str) -> PlannerSystem:
        with lock:
            if (config, backend) not in built:
                built[(config, backend)] = build_system(replace(settings, llm=backend), config)
            return built[(config, backend)]

    return get


def available_backends(settings: Settings) -> list[str]:
    """The configured backend first, then every installed embedded model (names only)."""
    backends = [settings.llm]
    for name, entry in store.catalogue().items():
        spec = f"llamacpp:{name}"
        if spec not in backends and store.model_path(settings.models_dir, entry).is_file():
            backends.append(spec)
    return backends


def simulator_available() -> bool:
    """Whether PyBullet can be imported here."""
    try:
        import pybullet  # noqa: F401
    except ImportError:
        return False
    return True


def simulate(spec: RunSpec, actions: list[str], emit: Emit, out_dir: Path) -> None:
    """Execute ``actions`` in a PyBullet world built from the scene; pictures go to ``out_dir``."""
    from PIL import Image

    from conceptbot.sim.execute import execute_plan
    from conceptbot.sim.render import VIEW, picture, save_gif
    from conceptbot.sim.skills import PickAndPlace
    from conceptbot.sim.world import build_world

    emit("status", {"message": "simulator: building the world and executing the plan"})
    with build_world(spec.scene, seed=0) as world:
        picture(world, VIEW, title=f"before: {spec.request[:60]}").save(out_dir / "before.png")
        frames: list[Image.Image] = []
        small = VIEW.scaled(320, 240)
        skill = PickAndPlace(world, on_frame=lambda: frames.append(picture(world, small, labels=False)))
        execution = execute_plan(world, spec.scene, actions, skill)
        picture(world, VIEW, title=f"after: {execution.verdict[:60]}").save(out_dir / "after.png")
        if frames:
            save_gif(frames[::2], out_dir / "execution.gif")
    emit(
        "sim",
        {
            "ok": execution.ok,
            "verdict": execution.verdict,
            "steps": [
                {"action": r.action, "ok": r.ok, "failure": r.failure, "message": r.message}
                for r in execution.results
            ],
            "files": [name for name in PICTURES if (out_dir / name).is_file()],
        },
    )


def make_worker(systems: SystemFactory, can_simulate: bool) -> Worker:
    """The run worker over a system factory."""

    def work(spec: RunSpec, emit: Emit, out_dir: Path) -> None:
        emit("status", {"message": f"loading {spec.config} on {spec.backend}"})
        system = systems(spec.config, spec.backend)
        plan = system.plan(
            spec.request,
            spec.scene,
            risk=spec.risk,
            progress=lambda message: emit("status", {"message": message}),
            events=lambda kind, data: emit(kind, {"data": data}),
        )
        result = plan.to_dict()
        emit(
            "plan",
            {
                "plan": result["plan"],
                "refused": result["refused"],
                "reason": result.get("reason"),
                "usage": result.get("usage", {}),
            },
        )
        if spec.simulate and can_simulate and not plan.refused:
            simulate(spec, plan.actions, emit, out_dir)

    return work
