"""Which reading was meant, held out: the goal set's paraphrases of the dev requests, each planned
asking about every decision and reading (nobody answering), and where it reads two ways, labelled
as the plan-level calibration labels dev tasks (:func:`conceptbot.bench.conformal_fit.reading_label`:
each reading planned as the person's answer, the other questions answered from the dev task's gold).

Printed: how many paraphrases read two ways, which reading the plan passes with (the one taken, the
one dropped, a sampled one, none), and for the shipped reading threshold and the one threshold the
reading questions took before (``plan_qhat``), how many would be asked and how many sets hold the
reading meant. The dev tasks' own requests fitted the threshold; the paraphrases did not.

    .venv/bin/python benchmarks/bench_reading_labels.py [--rounds 11,12] [--category implicit]
        [--out results/reading-labels-qwen2.5-coder-1.5b.jsonl] [--resume]
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

from bench_paraphrase_plans import chosen_rows
from conceptbot.bench.conformal_fit import reading_label
from conceptbot.bench.grading import Task, load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.core.system import ASK_ALL, PlannerSystem, SystemOptions
from conceptbot.core.trace import ReadingOption
from conceptbot.pipeline.goal_planner.asking import reading_set
from conceptbot.pipeline.goal_planner.conformal import shipped
from conceptbot.systems import build_system

OUT = Path("results/reading-labels-qwen2.5-coder-1.5b.jsonl")


def label(system: PlannerSystem, task: Task, request: str) -> dict:
    """One paraphrase: its readings with their odds and the step, and which the plan passes with."""
    said = replace(task, request=request)
    plan = system.plan(request, task_scene(said))
    readings, meant = reading_label(said, plan, system)
    goal = plan.trace.goal if plan.trace is not None else None
    return {
        "step": goal.step if goal is not None else "",
        "readings": [r.to_dict() for r in readings],
        "meant": meant,
    }


def summary(found: list[dict], coverage: float) -> dict:
    """How the reading sets of ``found`` fare at ``coverage`` with the shipped reading threshold and
    with the one threshold the reading questions took before."""
    calibration = shipped()
    out: dict = {"paraphrases": len(found), "two_ways": sum(len(f["readings"]) > 1 for f in found)}
    labelled = [f for f in found if f["meant"] is not None]
    out["labelled"] = len(labelled)
    out["meant"] = dict(Counter(f["readings"][f["meant"]]["kind"] for f in labelled))
    for name, qhat in (
        ("reading threshold", calibration.threshold_reading(coverage)),
        ("one threshold (before)", calibration.threshold(coverage)),
    ):
        asked = covered = 0
        for f in labelled:
            options = [
                ReadingOption(r["text"], r["p"] if r["p"] is not None else float("nan"), r["kind"])
                for r in f["readings"]
            ]
            kept = reading_set(options, qhat)
            asked += len(kept) > 1
            covered += options[f["meant"]].text in {o.text for o in kept}
        out[name] = {"qhat": qhat, "asked": asked, "covered": covered}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", default="11,12", help="comma-separated goal-set rounds (held out: 11,12)")
    parser.add_argument("--category", help="a dev category (implicit, risk, ...)")
    parser.add_argument("--out", type=Path, default=OUT, help="results file, a JSON line per paraphrase")
    parser.add_argument("--resume", action="store_true", help="keep the paraphrases already in --out")
    args = parser.parse_args()
    rows = chosen_rows(None, args.category, False, {int(r) for r in args.rounds.split(",")})
    tasks = {t.id: t for t in load_tasks(split="dev")}
    done: dict[str, dict] = {}
    if args.resume and args.out.exists():
        for line in args.out.read_text(encoding="utf-8").splitlines():
            if line.strip():
                found = json.loads(line)
                done[found["key"]] = found
    system = build_system(load_settings(), "conceptbot", SystemOptions(coverage=ASK_ALL))
    results = []
    with args.out.open("a" if args.resume else "w", encoding="utf-8") as out:
        for n, row in enumerate(rows, 1):
            key = f"{row['task']}|{row['request']}"
            if key in done:
                results.append(done[key])
                continue
            started = time.perf_counter()
            found = {"key": key, "task": row["task"], "round": row.get("round"), "request": row["request"]}
            found.update(label(system, tasks[row["task"]], row["request"]))
            found["seconds"] = round(time.perf_counter() - started, 1)
            results.append(found)
            out.write(json.dumps(found) + "\n")
            out.flush()
            kinds = [r["kind"] for r in found["readings"]]
            print(
                f"[{n}/{len(rows)}] {row['task']}: {row['request']} -> {kinds} meant {found['meant']}",
                flush=True,
            )
    for coverage in (0.8, 0.9, 0.95):
        print(coverage, json.dumps(summary(results, coverage)))


if __name__ == "__main__":
    main()
