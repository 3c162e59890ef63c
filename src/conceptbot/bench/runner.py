"""Benchmark runner: configurations x tasks x trials, graded, appended to a JSONL file.

Resumable: a run whose (task, config, trial, backend, model) is already in the results file is
skipped, so an interrupted run continues where it stopped. The embedded llama.cpp model runs in
this process, one plan at a time; HTTP backends can run several plans at once (``workers``).
Trials differ only where the planner samples (``--temperature`` > 0 with the vote method); with
log-probability scoring every trial of a task is the same plan.
"""

from __future__ import annotations

import json
import threading
import time
import traceback
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, TypeVar

from conceptbot.bench.grading import Task, grade, task_scene
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.usage import Usage
from conceptbot.systems import PlannerSystem

J = TypeVar("J")


@dataclass(frozen=True)
class Job:
    """One plan to make and grade."""

    task: Task
    config: str
    trial: int

    def key(self, backend: str, model: str) -> tuple[str, str, int, str, str]:
        """Identity in the results file."""
        return (self.task.id, self.config, self.trial, backend, model)


RESULT_KEY = ("task", "config", "trial", "backend", "model")


def done_keys(path: Path, fields: tuple[str, ...] = RESULT_KEY) -> set[tuple[Any, ...]]:
    """Keys (the values of ``fields``) of the records already in a results file (a torn last line
    is ignored)."""
    keys: set[tuple[Any, ...]] = set()
    if not path.is_file():
        return keys
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            r = json.loads(line)
            keys.add(tuple(r[f] for f in fields))
        except (ValueError, KeyError, TypeError):
            continue
    return keys


class Keyed(Protocol):
    """A job with an identity in the results file."""

    def key(self, backend: str, model: str) -> tuple[Any, ...]: ...


K = TypeVar("K", bound=Keyed)


def pending(
    jobs: Iterable[K], out: Path, backend: str, model: str, fields: tuple[str, ...] = RESULT_KEY
) -> list[K]:
    """The jobs whose key (``fields`` of a record) is not yet in the results file ``out``."""
    seen = done_keys(out, fields)
    return [j for j in jobs if j.key(backend, model) not in seen]


def append_results(
    todo: Iterable[J],
    make_record: Callable[[J], dict[str, Any]],
    out: Path,
    workers: int = 1,
    on_record: Callable[[dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:
    """Make a record per job and append each to the JSONL file ``out`` as soon as it exists (an
    interrupted run loses at most the job in progress); ``workers`` jobs at once."""
    out.parent.mkdir(parents=True, exist_ok=True)
    lock = threading.Lock()
    records: list[dict[str, Any]] = []

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


def timed_record(
    head: dict[str, Any], attempt: Callable[[], dict[str, Any]], on_failure: dict[str, Any]
) -> dict[str, Any]:
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


def run_job(job: Job, system: PlannerSystem, backend: str, model: str, scoring: str = "") -> dict[str, Any]:
    """Plan one task with one system, grade it, and return the record (``scoring``: how the backend
    scores options, recorded as is)."""
    scene = task_scene(job.task)

    def attempt() -> dict[str, Any]:
        plan = system.plan(job.task.request, scene)
        verdict = grade(job.task, plan.actions, plan.refused)
        return {
            "plan": plan.actions,
            "refused": plan.refused,
            "refusal_reason": plan.reason,
            "ok": verdict.ok,
            "reason": verdict.reason,
            "usage": usage_fields(plan.usage),
        }

    head = {
        "task": job.task.id,
        "category": job.task.category,
        "split": job.task.split,
        "config": job.config,
        "trial": job.trial,
        "backend": backend,
        "model": model,
        "scoring": scoring,
        "request": job.task.request,
    }
    return timed_record(head, attempt, {"plan": None, "refused": False, "ok": False})


def run(
    jobs: Iterable[Job],
    systems: Callable[[str], PlannerSystem],
    out: Path,
    backend: str,
    model: str,
    workers: int = 1,
    on_record: Callable[[dict[str, Any]], None] | None = None,
    scoring: str = "",
) -> list[dict[str, Any]]:
    """Run the jobs not yet in ``out`` and append their records to it.

    Args:
        jobs: What to run.
        systems: ``config -> system`` (built once per configuration by the caller).
        out: The JSONL results file.
        backend, model: Recorded with each result and part of the resume key.
        workers: Plans at once (1 for in-process backends).
        on_record: Called after each record is written (progress bars).
        scoring: How the backend scores options (:func:`conceptbot.models.registry.scoring_method`).
    """
    return append_results(
        pending(jobs, out, backend, model),
        lambda job: run_job(job, systems(job.config), backend, model, scoring),
        out,
        workers,
        on_record,
    )
