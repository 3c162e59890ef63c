"""How well the model judges a household plan by what it leaves behind (issue 68), on its own.

For each detailed task of the SafeAgentBench dev split (or of a task file, ``--tasks``), the
reference plan and the plain planner's own plan (from ``results/parts/safeagentbench-v4-*.jsonl``,
none where it refused) are run in the executor; what each leaves behind is put in words
(:func:`conceptbot.household.outcomes.plan_effects`) and the outcome question is asked
(:class:`conceptbot.household.judge.OutcomeJudge`). Printed: the AUC of unsafe against safe for
the outcome reading of either plan, for the instruction judge's v4 score (from the same records),
and for the two together (a logistic fit, 5 folds by task), with no word of the request read by a
rule. Readings are appended as they come (resumable).

    .venv/bin/python benchmarks/bench_outcome_judge.py [--tasks FILE] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from conceptbot.bench.safeagentbench.dataset import load_task_file, scenes, select
from conceptbot.core.config import load_settings
from conceptbot.core.plan import parse_household_actions
from conceptbot.household.judge import OutcomeJudge
from conceptbot.household.outcomes import plan_effects
from conceptbot.models.registry import open_llm

V4 = Path("results/parts/safeagentbench-v4-qwen2.5-coder-1.5b.jsonl")


def auc(pos: list[float], neg: list[float]) -> float:
    """P(a positive scores above a negative), ties half."""
    if not pos or not neg:
        return float("nan")
    wins = sum((p > n) + 0.5 * (p == n) for p in pos for n in neg)
    return wins / (len(pos) * len(neg))


def cross_fit(x: np.ndarray, y: np.ndarray, folds: int = 5) -> np.ndarray:
    """Held-out logistic scores (5 folds in task order, L2 1.0, standardised features)."""
    from sklearn.linear_model import LogisticRegression

    out = np.zeros(len(y))
    fold = np.arange(len(y)) % folds
    for k in range(folds):
        train, test = fold != k, fold == k
        mean, std = x[train].mean(0), x[train].std(0) + 1e-9
        model = LogisticRegression(C=1.0).fit((x[train] - mean) / std, y[train])
        out[test] = model.decision_function((x[test] - mean) / std)
    return out


def v4_records() -> dict[tuple[str, str], dict[str, Any]]:
    """(task, config) -> the v4 record."""
    rows = [json.loads(line) for line in V4.read_text(encoding="utf-8").splitlines() if line.strip()]
    return {(r["task"], r["config"]): r for r in rows}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", type=Path, help="a task file (benchmarks/blind/household/...)")
    parser.add_argument("--out", type=Path, default=Path("results/parts/outcome-qwen2.5-coder-1.5b.jsonl"))
    args = parser.parse_args(argv)
    tasks = load_task_file(args.tasks) if args.tasks else select(("safe", "unsafe"), split="dev")
    done = {}
    if args.out.exists():
        done = {json.loads(x)["task"]: json.loads(x) for x in args.out.read_text().splitlines() if x.strip()}
    v4 = v4_records()
    judge = OutcomeJudge(open_llm(load_settings(), module="judge"))
    with args.out.open("a", encoding="utf-8") as sink:
        for number, task in enumerate(tasks, 1):
            if task.id in done:
                continue
            scene = scenes()[task.scene]
            plain = v4.get((task.id, "plain"), {})
            planned = parse_household_actions(plain.get("steps") or [])
            row: dict[str, Any] = {"task": task.id, "unsafe": task.should_refuse}
            for name, steps in (("reference", task.steps), ("planned", planned)):
                effects = plan_effects(scene, steps)
                row[name], _ = judge.reading(scene, effects)
                row[f"{name}_effects"] = effects
            judged = (v4.get((task.id, "conceptbot"), {}).get("trace") or {}).get("judge")
            row["judge"] = judged["log_odds"] if judged else None
            row["plain_refused"] = bool(plain.get("refused"))
            sink.write(json.dumps(row) + "\n")
            sink.flush()
            done[task.id] = row
            print(
                f"{number}/{len(tasks)} {task.id}: {row['reference']:+.2f} / {row['planned']:+.2f}",
                file=sys.stderr,
            )
    rows = [done[t.id] for t in tasks if t.id in done]
    pos = [r for r in rows if r["unsafe"]]
    neg = [r for r in rows if not r["unsafe"]]
    print(f"{len(pos)} unsafe, {len(neg)} safe tasks")
    for name in ("reference", "planned"):
        print(f"AUC outcome of the {name} plan: {auc([r[name] for r in pos], [r[name] for r in neg]):.3f}")
    judged = [r for r in rows if r["judge"] is not None]
    if judged:
        jp = [r["judge"] for r in judged if r["unsafe"]]
        jn = [r["judge"] for r in judged if not r["unsafe"]]
        print(f"AUC instruction judge (v4, {len(judged)} tasks it read): {auc(jp, jn):.3f}")
        y = np.array([r["unsafe"] for r in judged], dtype=int)
        for name in ("reference", "planned"):
            x = np.array([[r["judge"], r[name]] for r in judged])
            fitted = cross_fit(x, y)
            print(
                f"AUC judge + outcome of the {name} plan (held out): "
                f"{auc(list(fitted[y == 1]), list(fitted[y == 0])):.3f}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
