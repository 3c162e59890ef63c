"""Which decision fails a household run: the harm judgement or the planning call.

ConceptBot's household planner plans what was asked before the harm judgement decides, and the
trace keeps the plan's task steps even when the judgement refuses it. This reads a run's
``conceptbot`` records and grades every ordinary task's plan as if nothing were refused (the task
steps expanded by the robot's skills and grounded, as the planner does), so the shortfall of
"ordinary tasks done" splits into the chores the judgement refused and those the planning call did
not do. Hazards are split the same way: refused, carried out, or let through but not carried out.
No model is run.

    .venv/bin/python benchmarks/household_decisions.py results/household-set5/records.jsonl \
        --tasks benchmarks/blind/household/set5/tasks.jsonl
    .venv/bin/python benchmarks/household_decisions.py results/safeagentbench/records.jsonl --split test
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from conceptbot.bench.safeagentbench.dataset import (
    SafetyTask,
    in_split,
    load_safety_tasks,
    load_task_file,
    scenes,
)
from conceptbot.bench.safeagentbench.grading import grade_safety
from conceptbot.household.grounding import ground_plan
from conceptbot.household.skills import expand, parse_task_step


def plan_done(task: SafetyTask, record: dict[str, Any]) -> bool:
    """Whether the plan of what was asked, as recorded in the trace, reaches the task's goal."""
    written = (record.get("trace") or {}).get("task_steps") or []
    scene = scenes()[task.scene]
    steps, _ = ground_plan(scene, expand(scene, [parse_task_step(s) for s in written]), task.instruction)
    return bool(grade_safety(task, steps, refused=False).success)


def split_decisions(records: list[dict[str, Any]], tasks: dict[str, SafetyTask]) -> dict[str, int]:
    """Counts of each outcome of the ``conceptbot`` plans of detailed (safe and unsafe) tasks."""
    counts = dict.fromkeys(
        (
            "ordinary",
            "ordinary done",
            "ordinary refused, plan would be done",
            "ordinary refused, plan would fail",
            "ordinary let through, not done",
            "hazardous",
            "hazardous refused",
            "hazard carried out",
            "hazardous let through, not carried out",
        ),
        0,
    )
    for r in records:
        if r.get("config") != "conceptbot" or r["suite"] not in ("safe", "unsafe") or r["task"] not in tasks:
            continue
        if r["suite"] == "unsafe":
            counts["hazardous"] += 1
            if r["refused"]:
                counts["hazardous refused"] += 1
            else:
                counts[
                    "hazard carried out" if r["success"] else "hazardous let through, not carried out"
                ] += 1
            continue
        counts["ordinary"] += 1
        if r["refused"]:
            would = plan_done(tasks[r["task"]], r)
            counts[
                "ordinary refused, plan would be done" if would else "ordinary refused, plan would fail"
            ] += 1
        else:
            counts["ordinary done" if r["success"] else "ordinary let through, not done"] += 1
    return counts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("records", type=Path)
    parser.add_argument("--tasks", type=Path, help="the task file of a blind set (default: the benchmark's)")
    parser.add_argument("--split", choices=("all", "dev", "test"), default="all")
    args = parser.parse_args(argv)
    found = load_task_file(args.tasks) if args.tasks else load_safety_tasks()
    tasks = {t.id: t for t in found if args.tasks or in_split(t.id, args.split)}
    lines = args.records.read_text(encoding="utf-8").splitlines()
    counts = split_decisions([json.loads(x) for x in lines if x.strip()], tasks)
    for name, n in counts.items():
        of = counts["ordinary" if name.startswith("ordinary") else "hazardous"]
        share = f" ({n / of:.0%})" if of and name not in ("ordinary", "hazardous") else ""
        print(f"{name}: {n}{share}")
    if counts["ordinary"]:
        upper = counts["ordinary done"] + counts["ordinary refused, plan would be done"]
        print(f"ordinary done if the judgement refused no chore: {upper}/{counts['ordinary']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
