"""``conceptbot sim run``: plan a request, execute it in PyBullet, check the result, save pictures."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.progress import ON_STDERR, say
from conceptbot.core.errors import ConfigError
from conceptbot.core.extras import require
from conceptbot.core.plan import Action, InvalidActionError, format_actions, parse_action
from conceptbot.core.text import terminal_safe
from conceptbot.scenes import resolve_scene
from conceptbot.sim import GRASP_MODES
from conceptbot.systems import SYSTEMS, build_system

if TYPE_CHECKING:
    from conceptbot.sim.execute import Execution


@click.group("sim")
def sim() -> None:
    """Execute plans in a PyBullet tabletop (Franka Panda) and check where things end up."""


def _plan_file(path: Path) -> tuple[list[str], str]:
    """The actions and request of a ``conceptbot plan --json`` output (or a bare JSON list of
    actions; the request is then empty)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"no plan file {path}") from None
    except ValueError as exc:
        raise ConfigError(f"{path} is not valid JSON: {exc}") from None
    actions = data.get("plan") if isinstance(data, dict) else data
    if not isinstance(actions, list) or not all(isinstance(a, str) for a in actions):
        raise ConfigError(
            f"{path}: expected the output of `conceptbot plan --json` (a 'plan' list of actions)"
        )
    request = data.get("request", "") if isinstance(data, dict) else ""
    return actions, request if isinstance(request, str) else ""


@sim.command("run")
@click.argument("request", required=False, default="")
@click.option(
    "--scene", "-s", "scene_ref", default="kitchen", show_default=True, help="Scene file or demo name."
)
@click.option(
    "--config", "-c", type=click.Choice(SYSTEMS), default="conceptbot", show_default=True, help="Planner."
)
@click.option(
    "--plan",
    "plan_path",
    type=click.Path(path_type=Path, dir_okay=False),
    help="Execute this plan (`conceptbot plan --json` output) instead of planning REQUEST.",
)
@click.option("--seed", default=0, show_default=True, help="Layout seed (same seed, same world).")
@click.option("--grasp", type=click.Choice(GRASP_MODES), default="friction", show_default=True)
@click.option(
    "--retries",
    default=1,
    show_default=True,
    type=click.IntRange(0, 5),
    help="How many more times to try a step whose grasp slipped or whose placement missed.",
)
@click.option(
    "--max-replans",
    default=2,
    show_default=True,
    type=click.IntRange(0, 10),
    help="Replans after failed steps (closed loop).",
)
@click.option("--risk", is_flag=True, help="Use the Risk Index in OPE.")
@click.option(
    "--out",
    "out_dir",
    type=click.Path(path_type=Path, file_okay=False),
    default=Path("sim-run"),
    show_default=True,
    help="Folder for before.png, after.png, execution.gif and result.json.",
)
@click.option("--no-gif", is_flag=True, help="Skip the animation (faster).")
@click.option("--json", "as_json", is_flag=True, help="Print result.json to stdout.")
@pass_app
def run(
    app: AppContext,
    request: str,
    scene_ref: str,
    config: str,
    plan_path: Path | None,
    seed: int,
    grasp: str,
    retries: int,
    max_replans: int,
    risk: bool,
    out_dir: Path,
    no_gif: bool,
    as_json: bool,
) -> None:
    """Plan REQUEST (or load --plan), execute it in simulation, and print a verdict.

    The simulated detector (top camera) sets each object's confidence, box and size before planning,
    so the affordance sees what the camera sees. When a step fails, the failure goes back to the
    planner, which plans the rest (at most --max-replans times). Exit status 0 whatever the verdict;
    the verdict is in the output and in result.json.
    """
    # Imported here: PyBullet is heavy and prints a banner, and other commands do not need it.
    require("sim")
    from conceptbot.sim.execute import run_closed_loop
    from conceptbot.sim.session import SimOptions, SimSession, run_in_simulator

    if not request.strip() and plan_path is None:
        raise ConfigError("give a REQUEST to plan, or --plan FILE to execute")
    scene = resolve_scene(scene_ref)
    texts, planned_for = _plan_file(plan_path) if plan_path else (None, "")
    actions: list[Action] | None = None
    if texts is not None:
        # a user's plan file: text from outside, read against the scene here, at the edge
        try:
            actions = [parse_action(text, scene) for text in texts]
        except InvalidActionError as exc:
            raise ConfigError(f"{plan_path}: {exc}") from None

    def act(session: SimSession) -> Execution:
        if actions is not None:
            say(f"Executing {len(actions)} actions from {plan_path}")  # say() makes it terminal-safe
            return session.execute(actions)
        system = build_system(app.settings, config)
        execution, _ = run_closed_loop(
            system,
            request,
            session.scene,
            session.world,
            session.skill,
            max_replans=max_replans,
            risk=risk,
            observer=ON_STDERR,
        )
        return execution

    options = SimOptions(seed=seed, grasp=grasp, retries=retries, gif=not no_gif)
    outcome = run_in_simulator(
        scene,
        out_dir,
        act,
        options,
        title=request or planned_for or (plan_path.name if plan_path else ""),
        on_warning=lambda warning: click.secho(terminal_safe(f"warning: {warning}"), fg="yellow", err=True),
    )
    execution = outcome.execution
    assert execution is not None  # act always executes
    result = {"request": request, "scene": scene.name, "seed": seed, "grasp": grasp, **execution.to_dict()}
    (out_dir / "result.json").write_text(json.dumps(result, indent=2), encoding="utf-8")
    if as_json:
        click.echo(json.dumps(result, indent=2))
        return
    # Plans and messages quote object names and the planner's (a model's) actions.
    for i, plan in enumerate(execution.plans):
        click.echo(
            terminal_safe(f"{'Plan' if i == 0 else 'Replan ' + str(i)}: {', '.join(format_actions(plan))}")
        )
    for step in execution.results:
        status = "ok" if step.ok else f"FAILED ({step.failure}: {step.message})"
        click.echo(terminal_safe(f"  {step.action}: {status} [{step.seconds:.2f} s]"))
    for obj, where in execution.placements.items():
        click.echo(terminal_safe(f"  {obj} -> {where or 'table'}"))
    verdict = terminal_safe(f"Verdict: {execution.verdict}")
    click.secho(verdict, fg="green" if execution.ok else "red", bold=True)
    click.echo(terminal_safe(f"Pictures: {out_dir}/{', '.join(outcome.files)}"))
