"""Benchmark runner: configurations x tasks x trials, graded, appended to a JSONL file.

Resumable: a run whose (task, config, trial, backend, model) is already in the results file is
skipped, so an interrupted run continues where it stopped. The embedded llama.cpp model runs in
this process, one plan at a time; HTTP backends can run several plans at once (``workers``).
Trials differ only where the planner samples (``--temperature`` > 0 with the vote method); with
log-probability scoring every trial of a task is the same plan.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from conceptbot.bench.grading import Task, grade, task_scene
from conceptbot.bench.results import OnRecord, Record, run_pending, timed_record, usage_fields
from conceptbot.core.plan import format_actions
from conceptbot.core.system import PlannerSystem


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
"""The fields of a record that make its resume key (:meth:`Job.key`)."""


def run_job(job: Job, system: PlannerSystem, backend: str, model: str, scoring: str = "") -> Record:
    """Plan one task with one system, grade it, and return the record (``scoring``: how the backend
    scores options, recorded as is)."""
    scene = task_scene(job.task)

    def attempt() -> dict[str, Any]:
        plan = system.plan(job.task.request, scene)
        verdict = grade(job.task, plan.actions, plan.refused)
        return {
            "plan": format_actions(plan.actions),
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
    on_record: OnRecord | None = None,
    scoring: str = "",
    stamp: Record | None = None,
) -> list[Record]:
    """Run the jobs not yet in ``out`` and append their records to it.

    Args:
        jobs: What to run.
        systems: ``config -> system`` (built once per configuration by the caller).
        out: The JSONL results file.
        backend, model: Recorded with each result and part of the resume key.
        workers: Plans at once (1 for in-process backends).
        on_record: Called after each record is written (progress bars).
        scoring: How the backend scores options (:func:`conceptbot.models.registry.scoring_method`).
        stamp: Fields every record carries, its commit part of the resume key (see
            :func:`conceptbot.bench.results.run_pending`).
    """
    return run_pending(
        jobs,
        lambda job: run_job(job, systems(job.config), backend, model, scoring),
        out,
        backend,
        model,
        RESULT_KEY,
        workers,
        on_record,
        stamp,
    )
