"""Results files, shared by both benchmarks (the paper's tasks and SafeAgentBench).

A run appends one JSON line per graded plan to a results file and is resumable: a job whose key (the
values of a record's key fields, e.g. task, config, backend, model) is already in the file is skipped,
so an interrupted run continues where it stopped. A report reads the file back (a torn last line is
skipped) and writes Markdown, JSON and a chart beside it.

The runners (:mod:`conceptbot.bench.runner`, :mod:`conceptbot.bench.safeagentbench.runner`) supply
only what differs: a job's key and how a job becomes a record. The reports supply the summary, its
Markdown and its chart.
"""

from __future__ import annotations

import json
import threading
import time
import traceback
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, Protocol, TypeVar

from conceptbot.core.errors import ConceptBotError, ConfigError
from conceptbot.core.usage import Usage

J = TypeVar("J")
T = TypeVar("T")
Record = dict[str, Any]
OnRecord = Callable[[Record], None]


class Keyed(Protocol):
    """A job with an identity in the results file."""

    def key(self, backend: str, model: str) -> tuple[Any, ...]: ...


K = TypeVar("K", bound=Keyed)


# -- reading -----------------------------------------------------------------------------------------
def _records(path: Path) -> Iterable[Record]:
    """The parsed lines of a results file; a line that is not JSON (a torn last line) is skipped."""
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            yield json.loads(line)
        except ValueError:
            continue


def load_records(path: Path, hint: str = "run `conceptbot bench run` first") -> list[Record]:
    """The records of a results file (torn lines skipped).

    Args:
        path: The JSONL results file.
        hint: How to make one, shown when there is none.

    Raises:
        ConfigError: The file does not exist or holds no records.
    """
    if not Path(path).is_file():
        raise ConfigError(f"no results file {path}", hint=hint)
    records = list(_records(Path(path)))
    if not records:
        raise ConfigError(f"{path} holds no benchmark records")
    return records


def done_keys(path: Path, fields: tuple[str, ...]) -> set[tuple[Any, ...]]:
    """Keys (the values of ``fields``) of the records already in a results file (a torn last line,
    or a record without one of the fields, is ignored)."""
    if not path.is_file():
        return set()
    keys: set[tuple[Any, ...]] = set()
    for r in _records(path):
        try:
            keys.add(tuple(r[f] for f in fields))
        except (KeyError, TypeError):
            continue
    return keys


def pending(jobs: Iterable[K], out: Path, backend: str, model: str, fields: tuple[str, ...]) -> list[K]:
    """The jobs whose key (``fields`` of a record) is not yet in the results file ``out``."""
    seen = done_keys(out, fields)
    return [j for j in jobs if j.key(backend, model) not in seen]


# -- writing -----------------------------------------------------------------------------------------
def append_results(
    todo: Iterable[J],
    make_record: Callable[[J], Record],
    out: Path,
    workers: int = 1,
    on_record: OnRecord | None = None,
) -> list[Record]:
    """Make a record per job and append each to the JSONL file ``out`` as soon as it exists (an
    interrupted run loses at most the job in progress); ``workers`` jobs at once."""
    out.parent.mkdir(parents=True, exist_ok=True)
    lock = threading.Lock()
    records: list[Record] = []

    def work(job: J) -> None:
        record = make_record(job)
        with lock, open(out, "a", encoding="utf-8") as handle:
            handle.write(json.dumps(record, ensure_ascii=False) + "\n")
            records.append(record)
        if on_record:
            on_record(record)

    if workers <= 1:
        for job in todo:
            work(job)
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(work, todo))
    return records


def run_pending(
    jobs: Iterable[K],
    make_record: Callable[[K], Record],
    out: Path,
    backend: str,
    model: str,
    fields: tuple[str, ...],
    workers: int = 1,
    on_record: OnRecord | None = None,
) -> list[Record]:
    """Run the jobs whose key is not yet in ``out`` and append their records to it.

    Args:
        jobs: What to run.
        make_record: Plans and grades one job (it must not raise: see :func:`timed_record`).
        out: The JSONL results file.
        backend, model: Part of the resume key (and recorded by ``make_record``).
        fields: The record fields that make the resume key, in the order of ``Job.key``.
        workers: Jobs at once (1 for in-process backends).
        on_record: Called after each record is written (progress bars).

    Returns:
        The new records, in the order they were written.
    """
    return append_results(pending(jobs, out, backend, model, fields), make_record, out, workers, on_record)


def built_once(build: Callable[[str], T]) -> Callable[[str], T]:
    """``build(config)`` memoised per configuration (a system loads its model once per run), safe to
    call from several workers at once."""
    built: dict[str, T] = {}
    lock = threading.Lock()

    def get(config: str) -> T:
        with lock:
            if config not in built:
                built[config] = build(config)
            return built[config]

    return get


# -- record fields -----------------------------------------------------------------------------------
def usage_fields(usage: dict[str, Usage]) -> dict[str, dict[str, Any]]:
    """Per-module usage as stored in a results record."""
    return {
        m: {
            "latency_s": round(u.latency_s, 3),
            "prompt_tokens": u.prompt_tokens,
            "completion_tokens": u.completion_tokens,
            "cost_usd": u.cost_usd,
            "calls": u.calls,
        }
        for m, u in usage.items()
    }


def failure_fields(exc: Exception) -> dict[str, str]:
    """``reason`` and ``error`` of a record whose planning raised: a user-facing error by its
    message, anything else (a bug) with its traceback."""
    if isinstance(exc, ConceptBotError):
        return {"reason": f"error: {exc.message}", "error": str(exc)}
    return {"reason": f"crash: {type(exc).__name__}: {exc}", "error": traceback.format_exc(limit=5)}


def timed_record(head: Record, attempt: Callable[[], Record], on_failure: Record) -> Record:
    """A results record: ``head``, then the fields ``attempt()`` returns (plan and verdict), or
    ``on_failure`` and the error when it raises, then the seconds it took and when it finished."""
    record = dict(head)
    started = time.perf_counter()
    try:
        record.update(attempt())
    except Exception as exc:  # a bug must not lose the rest of a long run; it is recorded and reported
        record.update(on_failure, **failure_fields(exc))
    record["seconds"] = round(time.perf_counter() - started, 3)
    record["finished_at"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    return record


# -- reports -----------------------------------------------------------------------------------------
def write_report_files(
    summary: dict[str, Any],
    out_dir: Path,
    names: tuple[str, str, str],
    markdown: Callable[[dict[str, Any]], str],
    chart: Callable[[dict[str, Any], Path], None],
) -> dict[str, Path]:
    """Write a summary's Markdown, JSON and chart into ``out_dir``.

    Args:
        summary: The report's data (JSON-able; sets are written as lists).
        out_dir: Where the files go (created if needed).
        names: File names of the Markdown, the JSON and the chart.
        markdown: Renders the summary as Markdown.
        chart: Draws the summary into a PNG at the given path.

    Returns:
        The paths written, by kind: ``markdown``, ``json``, ``chart``.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = dict(zip(("markdown", "json", "chart"), (out_dir / name for name in names), strict=True))
    paths["markdown"].write_text(markdown(summary), encoding="utf-8")
    paths["json"].write_text(json.dumps(summary, indent=2, default=list), encoding="utf-8")
    chart(summary, paths["chart"])
    return paths
