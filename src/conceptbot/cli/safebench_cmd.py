"""``conceptbot safebench``: SafeAgentBench with the 17 household actions, and its report."""

from __future__ import annotations

from pathlib import Path

import click
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from conceptbot.bench.report import load_records
from conceptbot.bench.safeagentbench.dataset import SUITES, select
from conceptbot.bench.safeagentbench.report import markdown_safety, summarise_safety, write_safety_report
from conceptbot.bench.safeagentbench.runner import SafetyJob, pending, run_safety
from conceptbot.cli.main import AppContext, pass_app
from conceptbot.household.factory import build_household_planner
from conceptbot.household.planner import HOUSEHOLD_CONFIGS, HouseholdPlanner
from conceptbot.models.registry import split_spec


@click.group()
def safebench() -> None:
    """SafeAgentBench: refuse hazardous household tasks, complete safe ones (harmonic mean)."""


@safebench.command("run")
@click.option(
    "--config",
    "-c",
    "configs",
    multiple=True,
    type=click.Choice(HOUSEHOLD_CONFIGS),
    help="Configuration(s) to run (repeatable; default: plain, conceptbot).",
)
@click.option(
    "--suite",
    "suites",
    multiple=True,
    type=click.Choice(SUITES),
    help="Task suites (repeatable; default: safe, unsafe, abstract).",
)
@click.option(
    "--level",
    "levels",
    multiple=True,
    type=click.IntRange(1, 4),
    help="Abstract tasks: phrasing levels, 1 concrete to 4 abstract (repeatable; default: all).",
)
@click.option("--limit", type=click.IntRange(1), help="At most this many tasks of each suite.")
@click.option("--task", "ids", multiple=True, help="Only these task ids (e.g. unsafe-12, abstract-3-L2).")
@click.option(
    "--workers",
    default=1,
    show_default=True,
    type=click.IntRange(1, 16),
    help="Plans at once (HTTP backends only; the embedded model runs one at a time).",
)
@click.option(
    "--out",
    type=click.Path(dir_okay=False, path_type=Path),
    default=Path("results/safeagentbench.jsonl"),
    show_default=True,
    help="JSONL results file; finished runs in it are skipped (resume).",
)
@pass_app
def run_cmd(
    app: AppContext,
    configs: tuple[str, ...],
    suites: tuple[str, ...],
    levels: tuple[int, ...],
    limit: int | None,
    ids: tuple[str, ...],
    workers: int,
    out: Path,
) -> None:
    """Plan and grade each task with each configuration; results go to --out."""
    settings = app.settings
    backend, model = split_spec(settings.llm)
    if backend == "llamacpp":
        workers = 1
    tasks = select(suites or SUITES, levels or (1, 2, 3, 4), limit, ids)
    if not tasks:
        raise click.UsageError("no task matches the given suites, levels and ids")
    configs = configs or HOUSEHOLD_CONFIGS
    # Task-major, so an interrupted run still compares the configurations on the same tasks; safe
    # and unsafe tasks alternate (safe-1, unsafe-1, safe-2, ...) and abstract ones come last, so a
    # partial run already gives the headline harmonic mean.
    detailed = [t for t in tasks if t.suite != "abstract"]
    order = sorted(detailed, key=lambda t: (int(t.id.rsplit("-", 1)[1]), t.suite))
    order += [t for t in tasks if t.suite == "abstract"]
    jobs = [SafetyJob(t, c) for t in order for c in configs]
    todo = pending(jobs, out, backend, model or "")
    click.echo(
        f"{len(jobs)} plans ({len(tasks)} tasks x {len(configs)} configs); "
        f"{len(jobs) - len(todo)} already in {out}"
    )
    planners: dict[str, HouseholdPlanner] = {}

    def planner(config: str) -> HouseholdPlanner:
        if config not in planners:
            planners[config] = build_household_planner(settings, config)
        return planners[config]

    with Progress(
        TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn()
    ) as bar:
        bar_id = bar.add_task("planning", total=len(todo))

        def advance(record: dict) -> None:
            verdict = "refused" if record["refused"] else ("done" if record["success"] else "not done")
            bar.update(bar_id, advance=1, description=f"{record['config']} {record['task']}: {verdict}")

        run_safety(todo, planner, out, backend, model or "", workers, advance)
    click.echo(markdown_safety(summarise_safety(load_records(out))))


@safebench.command("report")
@click.argument("results", type=click.Path(path_type=Path))
@click.option("--out-dir", type=click.Path(file_okay=False, path_type=Path), help="Default: beside RESULTS.")
def report_cmd(results: Path, out_dir: Path | None) -> None:
    """Write safeagentbench.md/.json/.png for a results file, and print the tables."""
    paths = write_safety_report(results, out_dir or results.parent)
    click.echo(paths["markdown"].read_text(encoding="utf-8"))
    click.echo("written: " + ", ".join(str(p) for p in paths.values()))
