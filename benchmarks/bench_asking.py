"""Asking instead of guessing, measured (issue 35): each task of a split planned by the goal planner
with and without a simulated person who answers every question from the gold
(:func:`conceptbot.bench.grading.gold_answer`), at each coverage, through the answer cache.

Per split, system and coverage: success without questions and with the gold answers, the share of
tasks with a question (help rate), questions per task, and the empirical coverage of the calibrated
decisions' prediction sets against the gold. Rows go to ``results/asking.json`` (``--write``).

    .venv/bin/python benchmarks/bench_asking.py --split dev [--systems conceptbot,nokg] [--write]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from conceptbot.bench.grading import gold_answer, grade, load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.core.system import COVERAGES, SystemOptions
from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.systems import build_system

OUT = Path("results/asking.json")
FIGURE = Path("results/asking.png")


def measure(split: str, system_name: str, coverage: float) -> dict[str, Any]:
    """One row: the split's tasks planned with and without the gold answers."""
    system = build_system(load_settings(), system_name, SystemOptions(coverage=coverage))
    tasks = load_tasks(split=split)
    solo = helped = asked_tasks = questions = covered = calibrated = 0
    for task in tasks:
        scene = task_scene(task)
        alone = system.plan(task.request, scene)
        solo += grade(task, alone.actions, alone.refused).ok
        for decision in alone.trace.decisions or ():
            for judgement in decision.objects:
                if judgement.answers is not None:
                    calibrated += 1
                    covered += gold_answer(task, judgement.object, decision.target.to) in judgement.answers

        def person(question: ClarifyingQuestion, task=task) -> str:
            return gold_answer(task, question.object, question.target)

        answered = system.plan(task.request, scene, ask=person) if alone.questions else alone
        helped += grade(task, answered.actions, answered.refused).ok
        questions += len(answered.questions)
        asked_tasks += bool(answered.questions)
    n = len(tasks)
    return {
        "split": split,
        "system": system_name,
        "coverage": coverage,
        "tasks": n,
        "success_without_questions": round(100 * solo / n, 1),
        "success": round(100 * helped / n, 1),
        "help_rate": round(100 * asked_tasks / n, 1),
        "questions_per_task": round(questions / n, 3),
        "calibrated_decisions": calibrated,
        "empirical_coverage": round(covered / calibrated, 4) if calibrated else None,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--split", choices=("dev", "test"), default="dev")
    parser.add_argument("--systems", default="conceptbot,nokg")
    parser.add_argument("--write", action="store_true", help=f"add the rows to {OUT}")
    args = parser.parse_args()
    rows = [measure(args.split, s, c) for s in args.systems.split(",") for c in COVERAGES]
    columns = ("cover", "alone", "asked", "help", "q/task", "emp.cov", "n dec")
    print(f"{'system':10} " + " ".join(f"{c:>7}" for c in columns))
    for r in rows:
        print(
            f"{r['system']:10} {r['coverage']:>7} {r['success_without_questions']:>6}% {r['success']:>6}% "
            f"{r['help_rate']:>6}% {r['questions_per_task']:>7} {r['empirical_coverage']!s:>7} "
            f"{r['calibrated_decisions']:>7}"
        )
    if args.write:
        kept = json.loads(OUT.read_text())["asking"] if OUT.exists() else []
        done = {(r["split"], r["system"], r["coverage"]) for r in rows}
        kept = [r for r in kept if (r["split"], r["system"], r["coverage"]) not in done] + rows
        OUT.write_text(json.dumps({"asking": kept}, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {OUT}")
        plot(kept)
        print(f"wrote {FIGURE}")


def plot(rows: list[dict[str, Any]]) -> None:
    """Success against help rate, one line per split and system through its coverages (KnowNo's
    figure), with the success without questions as the line's start."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for split, system in sorted({(r["split"], r["system"]) for r in rows}):
        line = sorted(
            (r for r in rows if (r["split"], r["system"]) == (split, system)), key=lambda r: r["coverage"]
        )
        xs = [0.0] + [r["help_rate"] for r in line]
        ys = [line[0]["success_without_questions"]] + [r["success"] for r in line]
        ax.plot(xs, ys, marker="o", label=f"{split}: {system}")
        for r in line:
            ax.annotate(str(r["coverage"]), (r["help_rate"], r["success"]), fontsize=7)
    ax.set_xlabel("tasks with a question (%)")
    ax.set_ylabel("success with the answers (%)")
    ax.set_title("Asking instead of guessing (embedded 1.5B; labels: coverage)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(FIGURE, dpi=120)


if __name__ == "__main__":
    main()
