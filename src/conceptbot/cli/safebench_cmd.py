"""``conceptbot safebench``: SafeAgentBench with the 17 household actions, and its report."""

from __future__ import annotations

from pathlib import Path

import click

from conceptbot.bench.provenance import stamp
from conceptbot.bench.results import built_once, load_records, pending, read_records
from conceptbot.bench.safeagentbench.dataset import (
    SPLITS,
    SUITES,
    SafetyTask,
    in_split,
    interleaved,
    load_task_file,
    select,
)
from conceptbot.bench.safeagentbench.report import (
    RECORD,
    RUN_FIRST,
    markdown_safety,
    summarise_safety,
    write_safety_report,
)
from conceptbot.bench.safeagentbench.runner import (
    RESULT_KEY,
    SafetyJob,
    asking_label,
    parse_label,
    run_safety,
)
from conceptbot.cli.bench_options import (
    allow_mixed_option,
    backend_and_model,
    echo_report,
    effective_workers,
    out_dir_option,
    record_progress,
    results_option,
    workers_option,
)
from conceptbot.cli.context import AppContext, pass_app
from conceptbot.systems import DEFAULT_HOUSEHOLD_SYSTEMS, HOUSEHOLD_SYSTEMS, build_household_system

DEFAULT_OUT = Path("results/safeagentbench/records.jsonl")

split_option = click.option(
    "--split",
    type=click.Choice(SPLITS),
    default="all",
    show_default=True,
    help="dev: the third of each suite to tune on (data/dev_split.txt); test: the other two thirds.",
)


@click.group()
def safebench() -> None:
    """SafeAgentBench: refuse hazardous household tasks, complete safe ones (harmonic mean)."""


@safebench.command("run")
@click.option(
    "--config",
    "-c",
    "configs",
    multiple=True,
    type=click.Choice(HOUSEHOLD_SYSTEMS),
    help="Configuration(s) to run (repeatable; default: plain, conceptbot; conceptbot-joint is the "
    "first design, where the planning call also judges).",
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
@click.option(
    "--task",
    "ids",
    multiple=True,
    help="Only these task ids, whatever the split (e.g. unsafe-12, abstract-3-L2).",
)
@click.option(
    "--coverage",
    type=click.Choice(["0.8", "0.9", "0.95", "1"]),
    help="Ask where the harm judge is unsure at this coverage (conceptbot only; the simulated person "
    "answers from the gold: unsafe and abstract tasks are dangerous). Its records are "
    "conceptbot@COVERAGE. Default: no questions, the judge's threshold decides.",
)
@click.option(
    "--tasks",
    "task_file",
    type=click.Path(path_type=Path, dir_okay=False),
    help="A task file of our own (JSONL; benchmarks/blind/household/check.py gives the format) instead "
    "of the benchmark's tasks; results default to results/household-<its folder>/records.jsonl.",
)
@split_option
@workers_option
@results_option(DEFAULT_OUT)
@pass_app
def run_cmd(
    app: AppContext,
    configs: tuple[str, ...],
    suites: tuple[str, ...],
    levels: tuple[int, ...],
    limit: int | None,
    ids: tuple[str, ...],
    coverage: str | None,
    task_file: Path | None,
    split: str,
    workers: int,
    out: Path,
) -> None:
    """Plan and grade each task with each configuration; results go to --out."""
    settings = app.settings
    backend, model = backend_and_model(settings.llm)
    workers = effective_workers(backend, workers)
    if task_file is not None:
        split = "all"
        out = (
            Path("results") / f"household-{task_file.parent.name}" / "records.jsonl"
            if out == DEFAULT_OUT
            else out
        )
    # The run ends with a report of the whole file: a file it cannot report on is refused now,
    # before any planning is appended to it.
    read_records(out, RECORD)
    tasks = _tasks(task_file, suites, levels, limit, ids, split)
    if not tasks:
        raise click.UsageError("no task matches the given suites, levels, ids and split")
    configs = configs or DEFAULT_HOUSEHOLD_SYSTEMS
    if coverage is not None and "conceptbot" not in configs:
        raise click.UsageError("--coverage asks where conceptbot's harm judge is unsure: add -c conceptbot")
    asking = float(coverage) if coverage is not None else None
    configs = tuple(asking_label(c, asking) for c in configs)
    # Task-major, so an interrupted run still compares the configurations on the same tasks; safe
    # and unsafe tasks alternate (safe-1, unsafe-1, safe-2, ...) and abstract ones come last, so a
    # partial run already gives the headline harmonic mean.
    jobs = [SafetyJob(t, c) for t in interleaved(tasks) for c in configs]
    # What made each record, and what changes its plans; records of other code are planned again.
    made = stamp({"coverage": asking, "cache": settings.use_cache})
    todo = pending(jobs, out, backend, model, RESULT_KEY, made["commit"])
    click.echo(
        f"{len(jobs)} plans ({len(tasks)} tasks x {len(configs)} configs); "
        f"{len(jobs) - len(todo)} already in {out}"
    )

    def describe(record: dict) -> str:
        verdict = "refused" if record["refused"] else ("done" if record["success"] else "not done")
        return f"{record['config']} {record['task']}: {verdict}"

    planner = built_once(lambda label: build_household_system(settings, *parse_label(label)))
    with record_progress(len(todo), describe) as on_record:
        run_safety(todo, planner, out, backend, model, workers, on_record, made)
    records = [r for r in load_records(out, hint=RUN_FIRST, shape=RECORD) if in_split(r["task"], split)]
    click.echo(markdown_safety(summarise_safety(records, allow_mixed=True)))


def _tasks(
    task_file: Path | None,
    suites: tuple[str, ...],
    levels: tuple[int, ...],
    limit: int | None,
    ids: tuple[str, ...],
    split: str,
) -> list[SafetyTask]:
    """The benchmark's tasks chosen by the options, or a task file's (by --suite, --limit, --task)."""
    if task_file is None:
        return select(suites or SUITES, levels or (1, 2, 3, 4), limit, ids, split)
    try:
        found = load_task_file(task_file)
    except ValueError as exc:
        raise click.UsageError(f"{task_file}: {exc}") from None
    chosen = [t for t in found if (not suites or t.suite in suites) and (not ids or t.id in ids)]
    if limit is not None:
        counts: dict[str, int] = {}
        for task in list(chosen):
            counts[task.suite] = counts.get(task.suite, 0) + 1
            if counts[task.suite] > limit:
                chosen.remove(task)
    return chosen


@safebench.command("report")
@click.argument("results", type=click.Path(path_type=Path))
@split_option
@out_dir_option
@allow_mixed_option
def report_cmd(results: Path, split: str, out_dir: Path | None, allow_mixed: bool) -> None:
    """Write safeagentbench.md/.json/.png (``-dev``/``-test`` in the names for a split) for a results
    file, and print the tables.

    A configuration whose records come from several commits of the code is refused unless
    --allow-mixed is given (the report then says which)."""
    echo_report(write_safety_report(results, out_dir or results.parent, split, allow_mixed))
