"""Does the model, asked to choose between the two likeliest candidates of a "which one" decision,
tell whether the planner's first choice is acceptable better than the decision's own ``p_one``?

Each which-one decision (a target taking one object from two or more candidates) of the dev tasks,
and of the goal set's held-out paraphrases of them (rounds 11 and 12), is planned without asking
(through the answer cache). The two candidates with the highest ``p_one`` are put to the model as
"A" and "B", once in each order ('Which one should the robot give to the user? A: the pencil B: the
ballpoint pen'), and the two log-odds are averaged (the model leans to the option shown first).
Printed per set: how many decisions, how often exactly one of the two is acceptable to the gold and
which of the two rankings picks it, and the AUC of ``p_one`` and of the preference for "the first
choice is acceptable". Measured, not shipped (``docs/asking.md``).

    .venv/bin/python benchmarks/bench_one_pairwise.py \
        [--out results/parts/one-pairwise-qwen2.5-coder-1.5b.jsonl]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from bench_paraphrase_plans import chosen_rows
from conceptbot.bench.grading import Task, gold_answer, load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.core.system import PlannerSystem, SystemOptions
from conceptbot.models.llm import LLM
from conceptbot.models.registry import open_llm
from conceptbot.pipeline.goal.judge import both_orders
from conceptbot.pipeline.goal_planner.asking import move_words
from conceptbot.systems import build_system

OUT = Path("results/parts/one-pairwise-qwen2.5-coder-1.5b.jsonl")
SYSTEM = "You help a household robot understand people. Answer with A or B only."
USER = (
    'A person said to the robot: "{request}"\n'
    "Which one should the robot {move}?\nA: the {a}\nB: the {b}\nAnswer A or B."
)
#: The dev categories whose targets may take one of several objects.
CATEGORIES = ("ambiguous", "implicit", "risk", "materials")


def preference(llm: LLM, request: str, move: str, first: str, second: str) -> float:
    """The model's log-odds for ``first`` over ``second``, averaged over both orders."""

    def user(a: str, b: str) -> str:
        return USER.format(request=request, move=move, a=a, b=b)

    return both_orders(llm, SYSTEM, user, first, second)[0]


def decisions(system: PlannerSystem, llm: LLM, task: Task, where: str) -> list[dict[str, Any]]:
    """The task's which-one decisions as rows: the two likeliest candidates, their ``p_one``, the
    model's preference and which the gold accepts."""
    plan = system.plan(task.request, task_scene(task))
    rows = []
    for decision in (plan.trace.decisions if plan.trace is not None else None) or ():
        chances = {j.object: j.p_one for j in decision.objects if j.p_one is not None}
        if len(chances) < 2:
            continue
        (a, pa), (b, pb) = sorted(chances.items(), key=lambda kv: -kv[1])[:2]
        to = decision.target.to
        rows.append(
            {
                "set": where,
                "task": task.id,
                "request": task.request,
                "to": to,
                "first": a,
                "second": b,
                "p_first": pa,
                "p_second": pb,
                "preference": preference(llm, task.request, move_words(to), a, b),
                "first_ok": gold_answer(task, a, to) == "yes",
                "second_ok": gold_answer(task, b, to) == "yes",
            }
        )
    return rows


def auc(pos: Sequence[float], neg: Sequence[float]) -> float:
    """P(a positive scores above a negative), ties half; NaN without both."""
    if not pos or not neg:
        return float("nan")
    return sum((p > n) + 0.5 * (p == n) for p in pos for n in neg) / (len(pos) * len(neg))


def report(rows: Sequence[dict[str, Any]]) -> None:
    """The figures per set (see the module docstring)."""
    for where in sorted({r["set"] for r in rows}):
        these = [r for r in rows if r["set"] == where]
        one = [r for r in these if r["first_ok"] != r["second_ok"]]
        good = [r for r in these if r["first_ok"]]
        bad = [r for r in these if not r["first_ok"]]
        print(
            f"{where}: {len(these)} decisions, first choice acceptable in {len(good)}; "
            f"exactly one of the two in {len(one)}: "
            f"p_one picks it {sum(r['first_ok'] for r in one)}, the model "
            f"{sum((r['preference'] > 0) == r['first_ok'] for r in one)}; AUC for the first choice "
            f"acceptable: p_one {auc([r['p_first'] for r in good], [r['p_first'] for r in bad]):.3f}, "
            f"preference {auc([r['preference'] for r in good], [r['preference'] for r in bad]):.3f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=OUT, help="the rows, JSON lines (rewritten)")
    args = parser.parse_args()
    settings = load_settings()
    system = build_system(settings, "conceptbot", SystemOptions(coverage=0.9))
    llm = open_llm(settings, module="decide")
    tasks = {t.id: t for t in load_tasks(split="dev")}
    todo = [("dev", t) for t in tasks.values() if t.category in CATEGORIES]
    todo += [
        ("paraphrases", replace(tasks[r["task"]], request=r["request"]))
        for r in chosen_rows(None, None, False, {11, 12})
        if tasks[r["task"]].category in CATEGORIES
    ]
    rows: list[dict[str, Any]] = []
    for n, (where, task) in enumerate(todo, 1):
        rows += decisions(system, llm, task, where)
        print(f"\r{n}/{len(todo)} planned", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    args.out.write_text("".join(json.dumps(r) + "\n" for r in rows), encoding="utf-8")
    report(rows)


if __name__ == "__main__":
    main()
