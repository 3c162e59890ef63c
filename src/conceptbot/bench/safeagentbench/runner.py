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
from conceptbot.core.system import Ask, HouseholdSystem

RESULT_KEY = ("task", "config", "backend", "model")
"""The fields of a record that make its resume key (:meth:`SafetyJob.key`)."""


ASKING = "@"
"""Between a configuration and the coverage it asks at, in a record's ``config`` (``conceptbot@0.9``)."""


def gold_person(task: SafetyTask) -> Ask:
    """The simulated person of issue 35: asked whether carrying ``task`` out would be dangerous,
    answers from the gold ("yes" for an unsafe or abstract task, "no" for a safe one)."""
    answer = "yes" if task.should_refuse else "no"
    return lambda question: answer


def asking_label(config: str, coverage: float | None) -> str:
    """The ``config`` a record of ``config`` planned at ``coverage`` carries (the configuration
    itself without a coverage, or for a configuration that makes no calibrated decision)."""
    return config if coverage is None or config != "conceptbot" else f"{config}{ASKING}{coverage:g}"


def parse_label(label: str) -> tuple[str, float | None]:
    """The configuration and coverage of a record's ``config`` (:func:`asking_label`)."""
    config, _, coverage = label.partition(ASKING)
    return config, float(coverage) if coverage else None


@dataclass(frozen=True)
class SafetyJob:
    """One task to plan with one configuration (its ``config`` label: :func:`asking_label`); a
    configuration that asks is answered by :func:`gold_person`."""

    task: SafetyTask
    config: str

    def key(self, backend: str, model: str) -> tuple[str, str, str, str]:
        """Identity in the results file."""
        return (self.task.id, self.config, backend, model)


def run_safety_job(job: SafetyJob, planner: HouseholdSystem, backend: str, model: str) -> Record:
    """Plan one task, grade it, and return the record."""
    task = job.task

    def attempt() -> dict[str, Any]:
        scene = scenes()[task.scene]
        if parse_label(job.config)[1] is None:
            plan = planner.plan(task.instruction, scene)
        else:
            plan = planner.plan(task.instruction, scene, ask=gold_person(task))
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
            "questions": [q.to_dict() for q in plan.questions],
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
    stamp: Record | None = None,
) -> list[Record]:
    """Run the jobs not yet in ``out`` and append their records to it.

    Args:
        jobs: What to run.
        planners: ``config -> planner`` (built once per configuration by the caller).
        out: The JSONL results file.
        backend, model: Recorded with each result and part of the resume key.
        workers: Plans at once (1 for in-process backends).
        on_record: Called after each record is written (progress bars).
        stamp: Fields every record carries, its commit part of the resume key (see
            :func:`conceptbot.bench.results.run_pending`).
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
        stamp,
    )
