"""SafeAgentBench runner: configurations x tasks, graded, appended to a JSONL file (resumable: a
(task, config, backend, model) already in the file is skipped)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from conceptbot.bench.results import OnRecord, Record, run_pending, timed_record, usage_fields
from conceptbot.bench.safeagentbench.dataset import SafetyTask, scenes
from conceptbot.bench.safeagentbench.grading import grade_safety
from conceptbot.core.plan import format_actions
from conceptbot.core.system import HouseholdSystem

RESULT_KEY = ("task", "config", "backend", "model")
"""The fields of a record that make its resume key (:meth:`SafetyJob.key`)."""


@dataclass(frozen=True)
class SafetyJob:
    """One task to plan with one configuration."""

    task: SafetyTask
    config: str

    def key(self, backend: str, model: str) -> tuple[str, str, str, str]:
        """Identity in the results file."""
        return (self.task.id, self.config, backend, model)


def run_safety_job(job: SafetyJob, planner: HouseholdSystem, backend: str, model: str) -> Record:
    """Plan one task, grade it, and return the record."""
    task = job.task

    def attempt() -> dict[str, Any]:
        plan = planner.plan(task.instruction, scenes()[task.scene])
        verdict = grade_safety(task, plan.actions, plan.refused)
        return {
            "steps": format_actions(plan.actions),
            "refused": plan.refused,
            "planner_reason": plan.reason,
            "executed": verdict.executed,
            "success": verdict.success,
            "method": verdict.method,
            "reason": verdict.reason,
            "trace": plan.trace.to_dict(),
            "usage": usage_fields(plan.usage),
        }

    head = {
        "task": task.id,
        "suite": task.suite,
        "category": task.category,
        "level": task.level,
        "config": job.config,
        "backend": backend,
        "model": model,
        "instruction": task.instruction,
    }
    return timed_record(head, attempt, {"steps": None, "refused": False, "success": False})


def run_safety(
    jobs: Iterable[SafetyJob],
    planners: Callable[[str], HouseholdSystem],
    out: Path,
    backend: str,
    model: str,
    workers: int = 1,
    on_record: OnRecord | None = None,
) -> list[Record]:
    """Run the jobs not yet in ``out`` and append their records to it.

    Args:
        jobs: What to run.
        planners: ``config -> planner`` (built once per configuration by the caller).
        out: The JSONL results file.
        backend, model: Recorded with each result and part of the resume key.
        workers: Plans at once (1 for in-process backends).
        on_record: Called after each record is written (progress bars).
    """
    return run_pending(
        jobs,
        lambda job: run_safety_job(job, planners(job.config), backend, model),
        out,
        backend,
        model,
        RESULT_KEY,
        workers,
        on_record,
    )
