"""``conceptbot calibrate``: measure the similarity threshold for the configured embedder, or (with
``--conformal``) fit the configured model's own conformal thresholds for asking."""

from __future__ import annotations

import json
import os
from dataclasses import asdict
from pathlib import Path

import click
from rich.console import Console
from rich.table import Table

from conceptbot.bench.conformal_fit import SYSTEMS, PlanFit, collect, fit, thresholds_document
from conceptbot.bench.grading import load_tasks
from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.params import FiniteFloatRange
from conceptbot.cli.progress import count_progress
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.system import SystemOptions
from conceptbot.core.text import terminal_safe
from conceptbot.knowledge.base import TARGET_PROPERTIES
from conceptbot.knowledge.registry import open_graph
from conceptbot.models.registry import open_embedder
from conceptbot.pipeline.calibrate import (
    PAPER_KEPT,
    PAPER_REFERENCE,
    PAPER_THETA,
    choose_theta,
    load_objects,
    measure,
    rows_for,
    thetas_between,
)
from conceptbot.pipeline.goal_planner.conformal import shipped, user_file
from conceptbot.pipeline.retrieval import RelationRetriever, default_theta
from conceptbot.systems import build_system

PAPER_LINE = "paper (text-embedding-ada-002): " + ", ".join(
    f"~{kept:g} kept at >{theta:.2f}" for theta, kept in PAPER_REFERENCE.items()
)


@click.command()
@click.option(
    "--objects",
    "objects_file",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    help="Objects to measure, one a line (default: the objects named in the paper).",
)
# From 0.10, not 0.30: all-MiniLM-L6-v2 cosines between a relation sentence and a property word are
# low (its paper-equivalent threshold is about 0.25), so a sweep from 0.30 would miss it.
@click.option("--from", "theta_from", default=0.10, show_default=True, type=FiniteFloatRange(-1, 1))
@click.option("--to", "theta_to", default=0.90, show_default=True, type=FiniteFloatRange(-1, 1))
@click.option("--step", default=0.05, show_default=True, type=FiniteFloatRange(0, 1, min_open=True))
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@click.option(
    "--conformal",
    is_flag=True,
    help="Instead: fit the configured model's conformal thresholds for asking, on the dev tasks.",
)
@pass_app
def calibrate(
    app: AppContext,
    objects_file: Path | None,
    theta_from: float,
    theta_to: float,
    step: float,
    as_json: bool,
    conformal: bool,
) -> None:
    """Sweep the similarity threshold over the paper's objects and recommend one for the embedder.

    For each threshold: relations kept per object (mean, median, min, max) against the paper's
    target properties, and how many objects keep none. The recommendation is the threshold whose
    mean is closest to the paper's ~20 relations per object at 0.75 with ada-002.

    With --conformal: plan the dev tasks with the configured model (with and without the graph,
    through the cache), fit the plan-level conformal thresholds the planner asks by, and keep them
    in the home's calibration folder, where the planner finds them for this model (the shipped ones
    are the embedded model's).
    """
    if conformal:
        _conformal(app, as_json)
        return
    if theta_to < theta_from:
        raise click.BadParameter(f"--to {theta_to} is below --from {theta_from}", param_hint="--to")
    thetas = thetas_between(theta_from, theta_to, step)
    objects = load_objects(objects_file)
    if not objects:
        raise click.BadParameter("no objects in the file", param_hint="--objects")
    graph = open_graph(app.settings, fallback=False)  # a missing graph fails here, before model loading
    embedder = open_embedder(app.settings)
    retriever = RelationRetriever(graph, embedder, theta=min(thetas))
    if not as_json:
        click.echo(
            terminal_safe(f"scoring the edges of {len(objects)} objects with {app.settings.embedder} ..."),
            err=True,
        )
    retrievals = measure(retriever, objects, TARGET_PROPERTIES)
    rows = rows_for(retrievals.values(), thetas)
    recommended = choose_theta(rows, PAPER_KEPT)
    unknown = [name for name, r in retrievals.items() if not r.edges]
    edges = sum(len(r.edges) for r in retrievals.values())
    current = default_theta(embedder.model)
    # Every mean on one side of the paper's count: the best threshold lies outside the sweep.
    at_edge = all(r.mean_kept < PAPER_KEPT for r in rows) or all(r.mean_kept > PAPER_KEPT for r in rows)
    if as_json:
        data = {
            "embedder": app.settings.embedder,
            "model": embedder.model,
            "graph": graph.name,
            "objects": len(objects),
            "edges": edges,
            "objects_without_edges": unknown,
            "targets": list(TARGET_PROPERTIES),
            "rows": [asdict(row) for row in rows],
            "recommended_theta": recommended,
            "at_edge": at_edge,
            "default_theta": current,
            "paper_reference": {f"{t:.2f}": k for t, k in PAPER_REFERENCE.items()},
        }
        click.echo(json.dumps(data, indent=2))
        return
    click.echo(
        terminal_safe(
            f"embedder {app.settings.embedder} (model {embedder.model}), graph {graph.name}: "
            f"{len(objects)} objects, {edges:,} edges, {len(unknown)} objects without edges"
        )
    )
    click.echo("targets: " + ", ".join(TARGET_PROPERTIES))
    table = Table("theta", "mean kept", "median", "min", "max", "objects with none")
    for row in rows:
        table.add_row(
            f"{row.theta:.2f}",
            f"{row.mean_kept:.1f}",
            f"{row.median_kept:g}",
            str(row.min_kept),
            str(row.max_kept),
            str(row.objects_with_none),
            style="bold" if row.theta == recommended else None,
        )
    Console(width=max(Console().width, 80)).print(table)
    click.echo(PAPER_LINE + f" (chosen: {PAPER_THETA:.2f})")
    if unknown:
        # The names come from the user's --objects file.
        click.echo(terminal_safe("objects without edges: " + ", ".join(unknown)))
    if at_edge:
        side, option = ("fewer", "--from") if rows[0].mean_kept < PAPER_KEPT else ("more", "--to")
        click.echo(
            f"note: every threshold keeps {side} than ~{PAPER_KEPT:g} per object: the best lies outside "
            f"the sweep (widen it with {option})"
        )
    click.echo(
        terminal_safe(
            f"recommended theta for {embedder.model}: {recommended:.2f} "
            f"(mean kept closest to the paper's ~{PAPER_KEPT:g}); current default {current:.2f}"
        )
    )


def _conformal(app: AppContext, as_json: bool) -> None:
    """``calibrate --conformal``: fit and store the configured model's plan-level thresholds."""
    tasks = load_tasks(split="dev")
    fits: dict[str, dict[str, PlanFit]] = {}
    backend = model = ""
    rule = shipped().rule  # the which-one rule the planner uses unless told otherwise
    for combination, config in SYSTEMS:
        # Planned by the shipped thresholds: the model's own file is what this replaces.
        system = build_system(app.settings, config, SystemOptions(own_calibration=False))
        if getattr(system, "planner_kind", None) != "goal":
            raise ConceptBotError(
                "the conformal calibration needs the goal planner, which needs a backend that scores options",
                hint="use the llamacpp backend, or an OpenAI-compatible server with log-probabilities",
            )
        backend, model = system.calibration_key  # type: ignore[attr-defined]
        with count_progress(len(tasks), f"calibrating {config}") as step:
            scores = collect(system, tasks, lambda task, name=config: step(f"{name}: {task.id}"))
        try:
            fits[combination] = {r: fit(found) for r, found in scores.items()}
        except ValueError as exc:
            raise ConceptBotError(
                str(exc), hint="the dev tasks gave this model no calibrated decision"
            ) from None
    path = user_file(app.settings.calibration_dir, backend, model)
    document = {
        "_doc": "Written by `conceptbot calibrate --conformal`: plan-level conformal thresholds for this "
        "model, read by conceptbot.pipeline.goal_planner.conformal.calibration_for.",
        "backend": backend,
        "model": model,
        "fitted_on": (
            f"{len(tasks)} dev tasks ({fits['graph'][rule].tasks} with calibrated decisions), "
            f"{backend}:{model}"
        ),
        "plan_which_one": rule,
        "held_out": {c: {str(k): round(h, 4) for k, h in f[rule].held_out.items()} for c, f in fits.items()},
        # Both rules' thresholds: `which_one` may pick either.
        **thresholds_document(fits, rule),
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")  # never a half-written file
    tmp.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    if as_json:
        click.echo(json.dumps({**document, "path": str(path)}, indent=2))
        return
    table = Table(
        "combination", "coverage", "qhat (yes/no)", "qhat (which one)", "held-out plan coverage", "tasks"
    )
    for combination, by_rule in fits.items():
        found = by_rule[rule]
        ones = found.qhat_one or found.qhat
        for coverage, q in found.qhat.items():
            table.add_row(
                combination,
                f"{coverage:g}",
                f"{q:.3f}",
                f"{ones[coverage]:.3f}",
                f"{found.held_out[coverage]:.1%}",
                str(found.tasks),
            )
    Console(width=max(Console().width, 80)).print(table)
    click.echo(terminal_safe(f"wrote {path}; `conceptbot plan` with {backend}:{model} now asks by it"))
