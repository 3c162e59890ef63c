"""Simulator benchmark: execute the gold (reference) plan of every benchmark task in PyBullet and
report the execution success rate and the wall seconds per pick_and_place.

This measures the simulator itself (layout, grasping, placing, the final-state check), not a planner:
a gold plan that fails here is a simulator failure, unless the failure is a real physical limit
(``too_wide``: an object wider than the gripper), which is reported separately.

A slipped or missed step is tried again once (``--retries``, as ``conceptbot sim run`` does); the
figures say how many steps needed it. ``--retries 0`` measures single attempts.

Run: .venv/bin/python benchmarks/bench_sim.py [--seeds 0 1 2] [--grasp friction|assisted] [--retries N]
     [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections import Counter

from conceptbot.bench.grading import load_tasks, reference_plan, task_scene
from conceptbot.sim.execute import execute_plan
from conceptbot.sim.skills import PickAndPlace
from conceptbot.sim.world import build_world


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--grasp", choices=("friction", "assisted"), default="friction")
    parser.add_argument("--retries", type=int, default=1, help="more tries of a slipped or missed step")
    parser.add_argument("--category", default=None)
    parser.add_argument("--json", default=None, help="write per-run records here")
    args = parser.parse_args(argv)
    records = []
    started = time.perf_counter()
    for task in load_tasks():
        if args.category and task.category != args.category:
            continue
        plan = reference_plan(task)
        if plan == ["done()"]:
            continue  # refusals: nothing to execute
        scene = task_scene(task)
        for seed in args.seeds:
            with build_world(scene, seed=seed) as world:
                execution = execute_plan(
                    world, scene, plan, PickAndPlace(world, args.grasp, retries=args.retries)
                )
            records.append(
                {
                    "task": task.id,
                    "seed": seed,
                    "ok": execution.ok,
                    "verdict": execution.verdict,
                    "failures": [r.failure for r in execution.results if not r.ok],
                    "seconds": execution.seconds_per_action,
                    "retried": [r.ok for r in execution.results if r.details.get("attempts", 1) > 1],
                    "warnings": world.warnings,
                }
            )
            mark = "ok  " if execution.ok else "FAIL"
            print(f"{mark} {task.id:15s} seed {seed}: {execution.verdict}", flush=True)
    if not records:
        print("no tasks with placements", file=sys.stderr)
        return 1
    ok = sum(r["ok"] for r in records)
    seconds = [s for r in records for s in r["seconds"]]
    kinds = Counter(k for r in records for k in r["failures"])
    wrong_place = sum(1 for r in records if not r["ok"] and not r["failures"])
    print()
    print(
        f"gold plans executed: {len(records)} (tasks x seeds), grasp mode {args.grasp}, "
        f"retries {args.retries}"
    )
    print(f"execution success: {ok}/{len(records)} = {100 * ok / len(records):.1f}%")
    print(f"failures by kind: {dict(kinds)}; disturbed after placing: {wrong_place}")
    retried = [ok for r in records for ok in r["retried"]]
    print(f"steps tried again: {len(retried)} of {len(seconds)}, of which {sum(retried)} then succeeded")
    print(
        f"seconds per pick_and_place: median {statistics.median(seconds):.2f}, "
        f"p90 {sorted(seconds)[int(0.9 * (len(seconds) - 1))]:.2f} over {len(seconds)} actions"
    )
    print(f"wall time: {time.perf_counter() - started:.0f} s")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump(records, handle, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
