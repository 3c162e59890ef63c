"""``conceptbot bench``: run the paper's benchmark and report it."""

from __future__ import annotations

from pathlib import Path

import click

from conceptbot.baselines.factory import SYSTEMS, build_system
from conceptbot.bench.grading import CATEGORIES, load_tasks
from conceptbot.bench.report import load_records, markdown, summarise, write_report
from conceptbot.bench.runner import Job, pending, run
from conceptbot.cli.bench_options import (
    echo_report,
    effective_workers,
    out_dir_option,
    results_option,
    workers_option,
)
from conceptbot.cli.main import AppContext, pass_app
from conceptbot.cli.progress import count_progress
from conceptbot.models.registry import split_spec


@click.group()
def bench() -> None:
    """Run the paper's 47-task benchmark (ConceptBot vs SayCan, ablations) and report it."""


@bench.command("run")
@click.option(
    "--config",
    "-c",
    "configs",
    multiple=True,
    type=click.Choice(SYSTEMS),
    help="Configuration(s) to run (repeatable; default: saycan, nokg, conceptbot).",
)
@click.option(
    "--category", "categories", multiple=True, type=click.Choice(CATEGORIES), help="Only these categories."
)
@click.option("--limit", type=click.IntRange(1), help="At most this many tasks (after the category filter).")
@click.option("--trials", default=1, show_default=True, type=click.IntRange(1, 20))
@click.option(
    "--temperature",
    default=0.0,
    show_default=True,
    type=click.FloatRange(0.0, 2.0),
    help="Sampling temperature of the vote planner (log-probability scoring ignores it).",
)
@click.option("--seed", default=0, show_default=True, type=int, help="Base seed (trial i uses seed + i).")
@workers_option
@results_option(Path("results/bench.jsonl"))
@pass_app
def run_cmd(
    app: AppContext,
    configs: tuple[str, ...],
    categories: tuple[str, ...],
    limit: int | None,
    trials: int,
    temperature: float,
    seed: int,
    workers: int,
    out: Path,
) -> None:
    """Plan and grade every task with each configuration; results go to --out."""
    settings = app.settings
    backend, model = split_spec(settings.llm)
    workers = effective_workers(backend, workers)
    tasks = load_tasks(list(categories) or None)[:limit]
    configs = configs or ("saycan", "nokg", "conceptbot")
    # Task-major order: an interrupted run still compares every configuration on the same tasks.
    jobs = [Job(t, c, i) for t in tasks for c in configs for i in range(trials)]
    systems: dict[str, object] = {}

    def system(config: str):
        if config not in systems:
            options = {} if config == "saycan" else {"n": 5}
            systems[config] = build_system(settings, config, **options)
        return systems[config]

    todo = len(pending(jobs, out, backend, model or ""))
    click.echo(
        f"{len(jobs)} plans ({len(tasks)} tasks x {len(configs)} configs x {trials} trials); "
        f"{len(jobs) - todo} already in {out}"
    )
    ok = 0
    with count_progress(todo) as step:

        def advance(record: dict) -> None:
            nonlocal ok
            ok += bool(record["ok"])
            verdict = "ok" if record["ok"] else "fail"
            step(f"{record['config']} {record['task']}: {verdict} ({ok} ok)")

        run(jobs, system, out, backend, model or "", workers, advance)
    click.echo(markdown(summarise(load_records(out))))


@bench.command("report")
@click.argument("results", type=click.Path(path_type=Path))
@out_dir_option
def report_cmd(results: Path, out_dir: Path | None) -> None:
    """Write report.md, report.json and success.png for a results file, and print the table."""
    echo_report(write_report(results, out_dir or results.parent))
