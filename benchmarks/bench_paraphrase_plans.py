"""Plans for the goal set's paraphrases, graded by their dev task's gold: whether a planner's
design holds on wording it was not built on, at the level of the whole plan.

The goal set (``benchmarks/data/goal_set.json``) has, for each dev task, hand-written paraphrases
that mean exactly the same in the task's scene (same objects, same destinations), in rounds. Each
paraphrase is planned in the task's scene and graded against the task's gold, so a figure here is a
success rate like the dev split's, on requests no rule or prompt was written for.

    .venv/bin/python benchmarks/bench_paraphrase_plans.py --tasks dev-implicit-23,dev-implicit-24
    .venv/bin/python benchmarks/bench_paraphrase_plans.py --category implicit --out FILE.jsonl
    .venv/bin/python benchmarks/bench_paraphrase_plans.py --category implicit --rounds 11,12

Each plan is also graded without the moves of the things it took as used together with a need's
object (``companions`` in the trace; :mod:`conceptbot.pipeline.goal_planner.companions`), as
``without_companions``: the same plans with and without that step, on wording it was not built on.

A results file (``--out``) is written a line per plan as it is made and read back on ``--resume``,
so a long run can be stopped and continued. Answers come through the answer cache like any plan.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from conceptbot.bench.grading import grade, load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.core.plan import PickAndPlace, format_actions
from conceptbot.core.system import SystemOptions
from conceptbot.systems import build_system

GOAL_SET = Path(__file__).parent / "data" / "goal_set.json"


def chosen_rows(
    tasks: set[str] | None, category: str | None, originals: bool, rounds: set[int] | None = None
) -> list[dict]:
    """The goal set's rows for the chosen dev tasks (or category), paraphrases only unless
    ``originals``, of the chosen ``rounds`` only if given."""
    rows = json.loads(GOAL_SET.read_text(encoding="utf-8"))["requests"]
    return [
        r
        for r in rows
        if (tasks is None or r["task"] in tasks)
        and (category is None or r["task"].startswith(f"dev-{category}-"))
        and (originals or r["split"] == "paraphrase")
        and (rounds is None or r.get("round") in rounds)
    ]


def _without(actions: list, moves: set[tuple[str, str]]) -> list:
    """The plan's actions less ``moves`` (object, destination)."""
    return [a for a in actions if not (isinstance(a, PickAndPlace) and (a.obj, a.destination) in moves)]


def _key(row: dict) -> str:
    return f"{row['task']}|{row['request']}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tasks", help="comma-separated dev task ids")
    parser.add_argument("--category", help="a dev category (implicit, risk, ...)")
    parser.add_argument("--originals", action="store_true", help="plan the tasks' own requests too")
    parser.add_argument("--rounds", help="comma-separated goal-set rounds (e.g. the held-out 11,12)")
    parser.add_argument("--system", default="conceptbot")
    parser.add_argument("--out", type=Path, help="results file, a JSON line per plan")
    parser.add_argument("--resume", action="store_true", help="keep the plans already in --out")
    args = parser.parse_args()
    if not args.tasks and not args.category:
        parser.error("choose --tasks or --category")
    wanted = set(args.tasks.split(",")) if args.tasks else None
    rounds = {int(r) for r in args.rounds.split(",")} if args.rounds else None
    rows = chosen_rows(wanted, args.category, args.originals, rounds)
    tasks = {t.id: t for t in load_tasks(split="dev")}
    unknown = sorted({r["task"] for r in rows} - tasks.keys())
    if unknown:
        parser.error(f"not dev tasks: {', '.join(unknown)}")
    done: dict[str, dict] = {}
    if args.out and args.resume and args.out.exists():
        for line in args.out.read_text(encoding="utf-8").splitlines():
            if line.strip():
                found = json.loads(line)
                done[found["key"]] = found
    system = build_system(load_settings(), args.system, SystemOptions())
    out = args.out.open("a" if args.resume else "w", encoding="utf-8") if args.out else None
    results = []
    try:
        for n, row in enumerate(rows, 1):
            if _key(row) in done:
                results.append(done[_key(row)])
                continue
            task = tasks[row["task"]]
            started = time.perf_counter()
            plan = system.plan(row["request"], task_scene(task))
            verdict = grade(task, plan.actions, plan.refused)
            trace = plan.trace
            extra = {(c.object, c.place) for c in (trace.companions if trace else None) or () if c.used}
            without = grade(task, _without(plan.actions, extra), plan.refused).ok if extra else verdict.ok
            found = {
                "key": _key(row),
                "task": row["task"],
                "round": row.get("round"),
                "split": row["split"],
                "request": row["request"],
                "plan": format_actions(plan.actions),
                "refused": plan.refused,
                "success": verdict.ok,
                "why": verdict.reason,
                "companions": sorted(o for o, _ in extra),
                "without_companions": without,
                "seconds": round(time.perf_counter() - started, 1),
            }
            results.append(found)
            if out is not None:
                out.write(json.dumps(found) + "\n")
                out.flush()
            mark = "ok  " if verdict.ok else "FAIL"
            print(f"[{n}/{len(rows)}] {mark} {row['task']}: {row['request']} -> {found['plan']}", flush=True)
    finally:
        if out is not None:
            out.close()
    by_task: dict[str, list[bool]] = {}
    for r in results:
        by_task.setdefault(r["task"], []).append(r["success"])
    for task_id, found in sorted(by_task.items()):
        print(f"{task_id}: {sum(found)}/{len(found)}")
    right = sum(r["success"] for r in results)
    times = [r["seconds"] for r in results if r["seconds"]]
    median = f", median {statistics.median(times):.1f} s a plan" if times else ""
    print(f"all: {right}/{len(results)} plans right{median}")
    alone = sum(r.get("without_companions", r["success"]) for r in results)
    took = sum(bool(r.get("companions")) for r in results)
    print(f"without the things used together: {alone}/{len(results)} ({took} plans took one)")


if __name__ == "__main__":
    main()
