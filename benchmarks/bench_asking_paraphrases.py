"""Asking on held-out wording: the goal set's paraphrases of the dev requests (rounds 11 and 12, which
no rule, odds or threshold was fitted on but the reading threshold), each planned as its dev task
with and without a simulated person who answers from the gold (:func:`bench_asking.outcome`), with
the shipped reading odds (the step's odds moved by the model's preference, ``pipeline/goal/judge.py``)
and with the step's odds alone and the reading threshold fitted for them before (``--variant steps``).

Printed per variant and coverage: success without and with the answers, the share of paraphrases
with a question, and how many got a reading question. Rows go to ``--out`` as they are found (one
JSON line per variant, coverage and paraphrase), so a run resumes.

    .venv/bin/python benchmarks/bench_asking_paraphrases.py [--variant judged,steps] [--coverage 0.9]
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from bench_asking import outcome, summary
from bench_paraphrase_plans import chosen_rows
from conceptbot.bench.grading import load_tasks
from conceptbot.core.config import load_settings
from conceptbot.core.system import SystemOptions
from conceptbot.systems import build_system

OUT = Path("results/parts/asking-paraphrases-qwen2.5-coder-1.5b.jsonl")
ROUNDS = frozenset({11, 12})
#: The reading threshold fitted for the step's odds alone (eighteenth session), per coverage.
STEPS_READING = {0.8: 0.35, 0.9: 0.8788, 0.95: 0.9048}
VARIANTS = ("judged", "steps")


def system_for(variant: str, coverage: float) -> Any:
    """The shipped system at ``coverage``; ``steps``: without the model's preference, with the
    reading threshold fitted for the steps' odds."""
    system = build_system(load_settings(), "conceptbot", SystemOptions(coverage=coverage))
    if variant == "steps":
        planner = system.goal_planner
        planner.targets.judge = None
        planner.calibration = replace(planner.calibration, qhat_reading=dict(STEPS_READING))
    return system


def figures(found: list[dict[str, Any]]) -> dict[str, Any]:
    """:func:`bench_asking.summary` and the paraphrases asked which reading."""
    return {
        **summary(found),
        "reading_questions": sum(any(q["kind"] == "reading" for q in f["questions"]) for f in found),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variant", default=",".join(VARIANTS), help="comma-separated: judged, steps")
    parser.add_argument("--coverage", type=float, action="append", choices=sorted(STEPS_READING))
    parser.add_argument("--out", type=Path, default=OUT, help="JSON lines, resumed")
    args = parser.parse_args()
    variants = [v for v in args.variant.split(",") if v]
    if any(v not in VARIANTS for v in variants):
        parser.error(f"--variant takes {', '.join(VARIANTS)}")
    tasks = {t.id: t for t in load_tasks(split="dev")}
    rows = chosen_rows(None, None, False, set(ROUNDS))
    done: dict[str, dict[str, Any]] = {}
    if args.out.exists():
        for line in args.out.read_text(encoding="utf-8").splitlines():
            if line.strip():
                found = json.loads(line)
                done[found["key"]] = found
    for coverage in args.coverage or [0.9]:
        for variant in variants:
            system = system_for(variant, coverage)
            found = []
            with args.out.open("a", encoding="utf-8") as sink:
                for n, row in enumerate(rows, 1):
                    key = f"{variant}|{coverage}|{row['task']}|{row['request']}"
                    if key not in done:
                        task = replace(tasks[row["task"]], request=row["request"])
                        done[key] = {"key": key, "round": row.get("round"), **outcome(system, task)}
                        sink.write(json.dumps(done[key]) + "\n")
                        sink.flush()
                    found.append(done[key])
                    print(f"\r{variant} {coverage}: {n}/{len(rows)}", end="", file=sys.stderr, flush=True)
            print(file=sys.stderr)
            print(variant, coverage, json.dumps(figures(found)))


if __name__ == "__main__":
    main()
