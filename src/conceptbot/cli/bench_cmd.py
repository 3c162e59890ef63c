"""``conceptbot bench``: run the paper's benchmark (or the dev split, to tune on) and report it."""

from __future__ import annotations

from pathlib import Path

import click

from conceptbot.bench.grading import CATEGORIES, load_tasks
from conceptbot.bench.provenance import stamp
from conceptbot.bench.report import RECORD, markdown, summarise, write_report
from conceptbot.bench.results import built_once, load_records, pending, read_records
from conceptbot.bench.runner import RESULT_KEY, Job, run
from conceptbot.cli.bench_options import (
    allow_mixed_option,
    backend_and_model,
    echo_report,
    effective_workers,
    out_dir_option,
    record_progress,
    workers_option,
)
from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.params import FiniteFloatRange, reading_option
from conceptbot.core.system import SystemOptions
from conceptbot.models.registry import scoring_method
from conceptbot.systems import SYSTEMS, build_system

DEFAULT_RESULTS = {"test": Path("results/paper47/records.jsonl"), "dev": Path("results/dev/records.jsonl")}
"""Results file of each task split when --out is not given."""


@click.group()
def bench() -> None:
    """Run the paper's 47-task benchmark (ConceptBot vs SayCan, ablations) and report it.

    Tune on the dev split (`bench run --split dev`: our own tasks in new scenes), measure on the
    test split (the paper's 47 tasks, the default).
    """


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
@click.option(
    "--split",
    default="test",
    show_default=True,
    help="Task split: test (the paper's 47 tasks), dev (our own tasks to tune on, in new scenes), "
    "or the path of a task folder laid out as the dev split (tasks/<category>.json, scenes/).",
)
@click.option("--limit", type=click.IntRange(1), help="At most this many tasks (after the category filter).")
@click.option("--trials", default=1, show_default=True, type=click.IntRange(1, 20))
@click.option(
    "--temperature",
    default=0.0,
    show_default=True,
    type=FiniteFloatRange(0.0, 2.0),
    help="Sampling temperature of the vote planner (log-probability scoring ignores it).",
)
@click.option("--seed", default=0, show_default=True, type=int, help="Base seed (trial i uses seed + i).")
@workers_option
@reading_option
@click.option(
    "--out",
    type=click.Path(dir_okay=False, path_type=Path),
    help="JSONL results file; finished runs in it are skipped (resume). "
    f"Default: {DEFAULT_RESULTS['test']}, {DEFAULT_RESULTS['dev']} with --split dev, "
    "results/<folder name>/records.jsonl with a folder.",
)
@pass_app
def run_cmd(
    app: AppContext,
    configs: tuple[str, ...],
    categories: tuple[str, ...],
    split: str,
    limit: int | None,
    trials: int,
    temperature: float,
    seed: int,
    workers: int,
    reading: str,
    out: Path | None,
) -> None:
    """Plan and grade every task of the split with each configuration; results go to --out."""
    settings = app.settings
    backend, model = backend_and_model(settings.llm)
    workers = effective_workers(backend, workers)
    out = out or DEFAULT_RESULTS.get(split) or Path("results", Path(split).name, "records.jsonl")
    # The run ends with a report of the whole file: a file it cannot report on is refused now,
    # before hours of planning are appended to it.
    read_records(out, RECORD)
    tasks = load_tasks(list(categories) or None, split=split)[:limit]
    configs = configs or ("saycan", "nokg", "conceptbot")
    # Task-major order: an interrupted run still compares every configuration on the same tasks.
    jobs = [Job(t, c, i) for t in tasks for c in configs for i in range(trials)]

    def system(config: str):
        return build_system(settings, config, SystemOptions(n=5, reading=reading))  # SayCan ignores them

    scoring = scoring_method(settings)
    # What made each record, and what changes its plans; records of other code are planned again.
    made = stamp(
        {
            "scoring": scoring,
            "reading": reading,
            "n": 5,
            "temperature": temperature,
            "seed": seed,
            "cache": settings.use_cache,
        }
    )
    todo = len(pending(jobs, out, backend, model, RESULT_KEY, made["commit"]))
    if scoring and scoring != "logprob":
        click.echo(f"options scored by {scoring} ({backend})")
    if split == "dev":
        click.echo("split: dev (our own tasks for tuning, not the paper's 47)")
    elif split != "test":
        click.echo(f"tasks: {split} (not the paper's 47)")
    click.echo(
        f"{len(jobs)} plans ({len(tasks)} tasks x {len(configs)} configs x {trials} trials); "
        f"{len(jobs) - todo} already in {out}"
    )
    ok = 0

    def describe(record: dict) -> str:
        nonlocal ok
        ok += bool(record["ok"])
        return f"{record['config']} {record['task']}: {'ok' if record['ok'] else 'fail'} ({ok} ok)"

    with record_progress(todo, describe) as on_record:
        run(jobs, built_once(system), out, backend, model, workers, on_record, scoring, made)
    click.echo(markdown(summarise(load_records(out, shape=RECORD), allow_mixed=True)))


@bench.command("report")
@click.argument("results", type=click.Path(path_type=Path))
@out_dir_option
@allow_mixed_option
def report_cmd(results: Path, out_dir: Path | None, allow_mixed: bool) -> None:
    """Write report.md, report.json and success.png for a results file, and print the table.

    A configuration whose records come from several commits of the code is refused unless
    --allow-mixed is given (the report then says which)."""
    echo_report(write_report(results, out_dir or results.parent, allow_mixed))
