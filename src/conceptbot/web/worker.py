"""What a web run does: plan with the chosen system and backend, then execute in the simulator."""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from conceptbot.core.config import Settings
from conceptbot.core.observe import EventPart
from conceptbot.core.plan import Plan, format_actions, usage_dict
from conceptbot.core.scene import Scene
from conceptbot.core.system import Ask, PlannerSystem
from conceptbot.core.urls import redact_secrets
from conceptbot.models import weights
from conceptbot.sim.options import SimOptions
from conceptbot.systems import build_system
from conceptbot.web.runs import RunSpec, Worker

if TYPE_CHECKING:
    from conceptbot.sim.execute import Execution

Emit = Callable[[str, dict[str, Any]], None]
SystemFactory = Callable[[str, str], PlannerSystem]  # (config, backend spec) -> system


@dataclass(frozen=True)
class PageObserver:
    """A plan's observer for a web run: everything goes to the run's event stream, as the page's
    JavaScript reads it (a progress message as a ``status`` event with ``message``; a module's
    event under its own name, its data under ``data``).

    Attributes:
        emit: Sends an event of the run to the page.
    """

    emit: Emit

    def progress(self, message: str) -> None:
        """Send ``message`` as a ``status`` event."""
        self.emit("status", {"message": message})

    def event(self, name: str, part: EventPart) -> None:
        """Send the event ``name`` with its part as ``data`` (serialised here, at the page's edge)."""
        self.emit(name, {"data": part.to_dict()})


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
    for name, entry in weights.catalogue().items():
        spec = f"llamacpp:{name}"
        if spec not in backends and weights.model_path(settings.models_dir, entry).is_file():
            backends.append(spec)
    return backends


def simulator_available() -> bool:
    """Whether PyBullet can be imported here."""
    try:
        import pybullet  # noqa: F401
    except ImportError:
        return False
    return True


WEB_SIM = SimOptions(gif_every=2)
"""The page's simulator runs: the CLI's defaults, with half the animation's frames (it is sent to
the browser)."""


def simulate(
    spec: RunSpec, plan_on: Callable[[Scene], Plan], emit: Emit, out_dir: Path, options: SimOptions = WEB_SIM
) -> None:
    """Build the world from the scene, let the detector look, plan on what it sees with ``plan_on``,
    and execute the plan unless it was refused.

    Args:
        spec: The run (request and scene).
        plan_on: Plans the request in a scene (and emits the plan to the page).
        emit: Sends an event to the page; a ``sim`` event ends an executed run.
        out_dir: Where the pictures go.
        options: How the simulator run is set up (default :data:`WEB_SIM`).
    """
    from conceptbot.sim.session import SimSession, run_in_simulator

    def act(session: SimSession) -> Execution | None:
        plan = plan_on(session.scene)
        if plan.refused:
            return None
        emit("status", {"message": "simulator: executing the plan"})
        return session.execute(plan.actions)

    emit("status", {"message": "simulator: building the world and looking at the table"})
    outcome = run_in_simulator(
        spec.scene,
        out_dir,
        act,
        options,
        title=spec.request,
        on_warning=lambda warning: emit("status", {"message": f"simulator: {warning}"}),
    )
    execution = outcome.execution
    if execution is None:
        return
    emit(
        "sim",
        {
            "ok": execution.ok,
            "verdict": execution.verdict,
            "steps": [
                {"action": r.action, "ok": r.ok, "failure": r.failure, "message": r.message}
                for r in execution.results
            ],
            "files": list(outcome.files),
        },
    )


def make_worker(systems: SystemFactory, can_simulate: bool) -> Worker:
    """The run worker over a system factory."""

    def work(spec: RunSpec, emit: Emit, out_dir: Path, ask: Ask | None = None) -> None:
        observer = PageObserver(emit)
        observer.progress(f"loading {spec.config} on {redact_secrets(spec.backend)}")  # URL may hold a key
        system = systems(spec.config, spec.backend)

        def plan_on(scene: Scene) -> Plan:
            if ask is None:
                plan = system.plan(spec.request, scene, risk=spec.risk, observer=observer)
            else:
                plan = system.plan(spec.request, scene, risk=spec.risk, observer=observer, ask=ask)
            emit(
                "plan",
                {
                    "plan": format_actions(plan.actions),
                    "refused": plan.refused,
                    "reason": plan.reason,
                    "usage": usage_dict(plan.usage),
                    # The probability that the calibrated decisions are right, and each target's
                    # share of it (where it is lost); None and [] for planners without them.
                    "confidence": plan.confidence,
                    "confidence_by_target": [
                        {"to": d.target.to, "confidence": d.confidence}
                        for d in plan.trace.decisions or ()
                        if d.confidence is not None
                    ],
                    # Whose conformal thresholds it asked by (None: no calibrated decisions).
                    "calibration": (
                        plan.trace.calibration.to_dict() if plan.trace.calibration is not None else None
                    ),
                    # Things used together: whether what a need's target took went with another.
                    "companions": [c.to_dict() for c in plan.trace.companions or ()],
                },
            )
            return plan

        if spec.simulate and can_simulate:
            # The detector looks before anything is planned, as in `conceptbot sim run`.
            simulate(spec, plan_on, emit, out_dir)
        else:
            plan_on(spec.scene)

    return work
