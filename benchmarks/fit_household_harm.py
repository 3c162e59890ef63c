"""Fit the household harm judgement (:mod:`conceptbot.household.harm`) on tuning tasks only.

The tuning tasks are SafeAgentBench's dev split (its detailed safe and unsafe tasks) and the blind
household sets folded into dev (:data:`FOLDED`).

``collect``: for each task, the signals of the judgement. The harm judge's readings of the
instruction come from the task's recorded ``conceptbot`` run where there is one (the judge's
prompts are unchanged since), else they are read now; the plan of what was asked is
made now with ConceptBot's planning call, the outcome judge reads what it leaves behind, and its
symbolic effects are counted. An ordinary task's plan is also graded (would it be done if let
through). Rows are appended as they come (resumable).

``fit``: a logistic model over the signals, 5 folds by task for held-out scores (AUC; at each
threshold the share of hazardous tasks refused, of ordinary ones refused and done; the threshold
with the best harmonic mean of hazardous refused and ordinary done), then fitted on every task.
Its conformal thresholds come from the held-out probabilities. ``--write`` stores
``src/conceptbot/household/harm_model.json``.

``fit`` first gives every row the similar cases' reading (:mod:`conceptbot.household.similar`),
cross-fitted over the rows' instructions; ``--write`` also stores those labelled instructions
(``harm_examples.json``), which the planner fits the reading on.

``fold``: a blind set planned once with ConceptBot is folded in from its records, without running
a model: its recorded signals, and each ordinary task's plan graded as if let through.

``blind-check``: one folded set scored as if it were new (the reading and the harm model fitted
on the tasks written before it), with and without the similar cases' reading.

    .venv/bin/python benchmarks/fit_household_harm.py collect [--out FILE] [--limit N] [--reuse FILE]
    .venv/bin/python benchmarks/fit_household_harm.py fold --records RECORDS --tasks TASKS
    .venv/bin/python benchmarks/fit_household_harm.py fit [--out FILE] [--write]
    .venv/bin/python benchmarks/fit_household_harm.py blind-check --set hh5-
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from conceptbot.bench.provenance import code_commit
from conceptbot.bench.safeagentbench.dataset import SafetyTask, load_task_file, scenes, select
from conceptbot.bench.safeagentbench.grading import grade_safety
from conceptbot.core.config import load_settings
from conceptbot.core.observe import SILENT
from conceptbot.core.plan import format_actions
from conceptbot.core.trace import HouseholdTrace
from conceptbot.core.usage import Usage
from conceptbot.household.harm import FEATURES, READINGS, HarmModel
from conceptbot.household.planner import ConceptBotHouseholdPlanner
from conceptbot.household.similar import cross_fitted, fit_logistic
from conceptbot.household.skills import expand, task_steps
from conceptbot.household.thor import catalogue
from conceptbot.models.embedder import Embedder
from conceptbot.models.registry import open_embedder
from conceptbot.systems import build_household_system

V4 = Path("results/parts/safeagentbench-v4-qwen2.5-coder-1.5b.jsonl")
"""The dev split's recorded runs (the judge's readings)."""
FOLDED = (
    (Path("benchmarks/blind/household/set1/tasks.jsonl"), Path("results/household-set1/records.jsonl")),
    (Path("benchmarks/blind/household/set2/tasks.jsonl"), Path("results/household-set2/records.jsonl")),
    (Path("benchmarks/blind/household/set3/tasks.jsonl"), Path("results/household-set3/records.jsonl")),
    (Path("benchmarks/blind/household/set4/tasks.jsonl"), Path("results/household-set4/records.jsonl")),
    (Path("benchmarks/blind/household/set5/tasks.jsonl"), Path("results/household-set5/records.jsonl")),
    (Path("benchmarks/blind/household/set6/tasks.jsonl"), Path("results/household-set6/records.jsonl")),
)
"""Blind household sets folded into dev: (tasks, their recorded runs). A later blind set's report
replaces an earlier one's: set 1's records are in git history at ``ceaf6b0``, set 2's at ``35de0b0``,
set 3's at ``cabc46c``, set 4's at ``55c9cc7``, set 5's at ``21d6e60``
(``git show COMMIT:PATH > PATH``); without them (and without ``--reuse`` rows) their readings are
read now."""
OUT = Path("results/parts/household-harm-qwen2.5-coder-1.5b.jsonl")
MODEL = Path("src/conceptbot/household/harm_model.json")
EXAMPLES = Path("src/conceptbot/household/harm_examples.json")
PARTS = {"dev": ("safe-", "unsafe-")} | {f"blind set {n}": (f"hh{n}-",) for n in range(1, 7)}
COVERAGES = (0.8, 0.9, 0.95)


def tuning_tasks() -> list[tuple[SafetyTask, dict[str, Any]]]:
    """Every tuning task with its recorded ``conceptbot`` run ({} where none)."""
    found: list[tuple[SafetyTask, dict[str, Any]]] = []
    sources = [(select(("safe", "unsafe"), split="dev"), V4)]
    sources += [(load_task_file(tasks), records) for tasks, records in FOLDED]
    for tasks, path in sources:
        text = path.read_text(encoding="utf-8") if path.exists() else ""  # none: all read now
        rows = [json.loads(x) for x in text.splitlines() if x.strip()]
        runs = {r["task"]: r for r in rows if r["config"] == "conceptbot"}
        found += [(t, runs.get(t.id, {})) for t in tasks]
    return found


def recorded(run: dict[str, Any]) -> dict[str, float] | None:
    """The judge's readings that the judgement weighs, in a recorded run (None: it has none)."""
    readings = ((run.get("trace") or {}).get("judge") or {}).get("readings") or {}
    if not all(k in readings for k in READINGS):
        return None
    return {k: float(readings[k]) for k in READINGS}


def signals_now(planner: ConceptBotHouseholdPlanner, task: SafetyTask) -> dict[str, float]:
    """The judge's readings, read now."""
    assert planner.judge is not None
    verdict, _ = planner.judge.judge(task.instruction, scenes()[task.scene], "")
    return dict(verdict.readings)


def earlier_readings(path: Path | None) -> dict[str, dict[str, float]]:
    """The judge's readings per task in an earlier collect's rows: they depend on the instruction
    alone, so a new planning call reuses them."""
    if path is None or not path.exists():
        return {}
    rows = [json.loads(x) for x in path.read_text(encoding="utf-8").splitlines() if x.strip()]
    return {r["task"]: {k: r["signals"][k] for k in READINGS} for r in rows}


def collect(out: Path, limit: int | None, reuse: Path | None = None) -> None:
    """Append a row per tuning task not in ``out`` yet (``reuse``: an earlier collect's rows whose
    readings stand in for a recorded run's)."""
    done = (
        {json.loads(x)["task"] for x in out.read_text().splitlines() if x.strip()} if out.exists() else set()
    )
    settings = load_settings()
    planner = build_household_system(settings, "conceptbot")
    assert isinstance(planner, ConceptBotHouseholdPlanner)
    todo = [(t, r) for t, r in tuning_tasks() if t.id not in done][:limit]
    earlier = earlier_readings(reuse)
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("a", encoding="utf-8") as sink:
        for number, (task, run) in enumerate(todo, 1):
            scene = scenes()[task.scene]
            signals = recorded(run) or earlier.get(task.id)
            fresh = signals is None
            signals = signals if signals is not None else signals_now(planner, task)
            usage: dict[str, Usage] = {}
            reply, trace = planner.draft(task.instruction, scene, HouseholdTrace(), SILENT, usage)
            signals.update(planner.read_plan(scene, reply.steps, SILENT, usage))
            graded = grade_safety(task, reply.steps, refused=False)
            row = {
                "task": task.id,
                "unsafe": task.should_refuse,
                "signals": signals,
                "readings_now": fresh,
                "steps": format_actions(reply.steps),
                "done": bool(graded.success) and not task.should_refuse,
                "repaired": bool(trace.repair and trace.repair.kept),
                "seconds": round(sum(u.latency_s for u in usage.values()), 2),
                "model": settings.llm,
                "commit": code_commit(),
            }
            sink.write(json.dumps(row) + "\n")
            sink.flush()
            print(
                f"{number}/{len(todo)} {task.id} outcome {signals['outcome']:+.2f} done {row['done']}",
                file=sys.stderr,
            )


def _auc(pos: np.ndarray, neg: np.ndarray) -> float:
    if not len(pos) or not len(neg):
        return math.nan
    return float(((pos[:, None] > neg[None, :]) + 0.5 * (pos[:, None] == neg[None, :])).mean())


def _fit(x: np.ndarray, y: np.ndarray, c: float) -> tuple[np.ndarray, float]:
    """Weights and bias in the signals' own units (standardised for the L2 fit)."""
    from sklearn.linear_model import LogisticRegression

    mean, std = x.mean(0), x.std(0) + 1e-9
    model = LogisticRegression(C=c).fit((x - mean) / std, y)
    weights = model.coef_[0] / std
    return weights, float(model.intercept_[0] - (weights * mean).sum())


def _matrix(rows: list[dict[str, Any]], columns: Sequence[str] = FEATURES) -> tuple[np.ndarray, np.ndarray]:
    """The rows' signals (a missing one is 0) and whether each task is hazardous."""
    x = np.array([[r["signals"].get(f, 0.0) for f in columns] for r in rows], dtype=float)
    return x, np.array([int(r["unsafe"]) for r in rows])


def _harmonic(a: float, b: float) -> float:
    return 2 * a * b / (a + b) if a + b else 0.0


def _threshold(score: np.ndarray, y: np.ndarray, done: np.ndarray) -> tuple[float, str]:
    """The threshold with the best harmonic mean of hazardous refused and ordinary done, and a
    table of it and its neighbours."""
    best, lines = (-1.0, 0.0), []
    for t in np.unique(np.round(score, 2)):
        refused = score >= t
        hm = _harmonic(refused[y == 1].mean(), (done & ~refused)[y == 0].mean())
        best = max(best, (hm, float(t)))
    for t in (best[1] - 1, best[1] - 0.5, best[1], best[1] + 0.5, best[1] + 1):
        refused = score >= t
        lines.append(
            f"  threshold {t:+.2f}: hazardous refused {refused[y == 1].mean():.0%}, ordinary refused "
            f"{refused[y == 0].mean():.0%}, ordinary done {(done & ~refused)[y == 0].mean():.0%}, "
            f"harmonic mean {_harmonic(refused[y == 1].mean(), (done & ~refused)[y == 0].mean()):.1%}"
        )
    return best[1], "\n".join(lines)


def _qhat(p: np.ndarray, y: np.ndarray, coverage: float) -> float:
    """Split-conformal threshold on P(true answer): nonconformity 1 - P(true)."""
    nonconformity = np.sort(1.0 - np.where(y == 1, p, 1.0 - p))
    n = len(nonconformity)
    k = min(n - 1, math.ceil((n + 1) * coverage) - 1)
    return float(1.0 - nonconformity[k])


def instructions() -> dict[str, str]:
    """Each tuning task's instruction, by task id."""
    return {task.id: task.instruction for task, _ in tuning_tasks()}


def reference_steps(task: SafetyTask) -> list[str]:
    """The task's reference plan as task steps with the scene's names, where those steps reach
    what the reference plan reaches (else none: a few references fail in the simulator)."""
    cat = catalogue()
    steps = [
        replace(
            s, obj=cat.canonical(s.obj) or s.obj, target=s.target and (cat.canonical(s.target) or s.target)
        )
        for s in task_steps(task.steps)
    ]
    scene = scenes()[task.scene]
    reached = grade_safety(task, expand(scene, steps), refused=False).success
    return [str(s) for s in steps] if reached else []


def with_similar(rows: list[dict[str, Any]], embedder: Embedder) -> list[dict[str, Any]]:
    """The rows with the similar cases' reading of each task's instruction, cross-fitted (each
    from a fit on the other folds' instructions), as a new task would get it."""
    texts = instructions()
    x = embedder.embed([texts[r["task"]] for r in rows])
    readings = cross_fitted(x, np.array([int(r["unsafe"]) for r in rows]))
    return [
        {**r, "signals": {**r["signals"], "similar": float(v)}} for r, v in zip(rows, readings, strict=True)
    ]


def _held_out(x: np.ndarray, y: np.ndarray, c: float) -> np.ndarray:
    """Each row's score from a fit on the other 4 folds (rows dealt round-robin)."""
    held = np.zeros(len(y))
    fold = np.arange(len(y)) % 5
    for k in range(5):
        w, b = _fit(x[fold != k], y[fold != k], c)
        held[fold == k] = x[fold == k] @ w + b
    return held


def fit(out: Path, write: bool, c: float = 1.0) -> None:
    """Print held-out figures; with ``write``, store the model fitted on every row and the
    labelled instructions the similar cases' reading is fitted on."""
    texts = instructions()
    tasks = {task.id: task for task, _ in tuning_tasks()}
    rows = with_similar(_rows(out), open_embedder(load_settings()))
    x, y = _matrix(rows)
    done = np.array([bool(r["done"]) for r in rows])
    print(
        f"{len(rows)} tasks: {y.sum()} hazardous, {(1 - y).sum()} ordinary; plans of ordinary ones done: "
        f"{done[y == 0].mean():.0%}"
    )
    held = _held_out(x, y, c)
    print(f"held-out AUC {_auc(held[y == 1], held[y == 0]):.3f}")
    for part, prefixes in PARTS.items():
        mask = np.array([r["task"].startswith(prefixes) for r in rows])
        if (y[mask] == 1).any() and (y[mask] == 0).any():
            print(f"  {part}: held-out AUC {_auc(held[mask & (y == 1)], held[mask & (y == 0)]):.3f}")
    for i, name in enumerate(FEATURES):
        print(f"  {name:15s} alone AUC {_auc(x[y == 1, i], x[y == 0, i]):.3f}")
    threshold, table = _threshold(held, y, done)
    print(table)
    p = 1.0 / (1.0 + np.exp(-held))
    qhat = {cov: _qhat(p, y, cov) for cov in COVERAGES}
    w, b = _fit(x, y, c)
    model = HarmModel(
        dict(zip(FEATURES, map(float, w), strict=True)),
        b,
        threshold,
        qhat,
        f"{len(rows)} tuning tasks (SafeAgentBench dev split, folded blind household sets) by "
        "benchmarks/fit_household_harm.py; threshold and conformal thresholds from 5-fold held-out scores",
    )
    print(json.dumps(model.to_json(), indent=1))
    if write:
        MODEL.write_text(json.dumps(model.to_json(), indent=1) + "\n", encoding="utf-8")
        examples = [
            {
                "task": r["task"],
                "instruction": texts[r["task"]],
                "dangerous": bool(r["unsafe"]),
                "steps": steps,
            }
            for r in rows
            for steps in [reference_steps(tasks[r["task"]])]
        ]
        about = f"{len(rows)} labelled tuning instructions (benchmarks/fit_household_harm.py fit --write)"
        listed = ",\n".join(json.dumps(e) for e in examples)  # one example a line, for diffs
        EXAMPLES.write_text(
            f'{{"about": {json.dumps(about)}, "examples": [\n{listed}\n]}}\n', encoding="utf-8"
        )
        print(f"wrote {MODEL} and {EXAMPLES}")


def _rows(out: Path) -> list[dict[str, Any]]:
    return [json.loads(x) for x in out.read_text(encoding="utf-8").splitlines() if x.strip()]


def fold(out: Path, records: Path, tasks_file: Path) -> None:
    """Append the rows of a blind set planned with ConceptBot, from its records: the signals as
    recorded, and whether each ordinary task's plan of what was asked is done (for a refused one,
    its recorded task steps graded as if let through). No model is run."""
    from household_decisions import plan_done  # a sibling script

    tasks = {t.id: t for t in load_task_file(tasks_file)}
    have = {r["task"] for r in _rows(out)} if out.exists() else set()
    added = 0
    with out.open("a", encoding="utf-8") as sink:
        for line in records.read_text(encoding="utf-8").splitlines():
            run = json.loads(line) if line.strip() else {}
            signals = ((run.get("trace") or {}).get("judge") or {}).get("readings") or {}
            wanted = [f for f in FEATURES if f != "similar"]
            if (
                run.get("config") != "conceptbot"
                or run["task"] in have
                or not all(f in signals for f in wanted)
            ):
                continue
            task = tasks[run["task"]]
            done = not task.should_refuse and (
                plan_done(task, run) if run["refused"] else bool(run["success"])
            )
            row = {
                "task": task.id,
                "unsafe": task.should_refuse,
                "signals": {f: float(signals[f]) for f in wanted},
                "readings_now": False,
                "steps": run["steps"],
                "done": done,
                "seconds": run["seconds"],
                "model": f"{run['backend']}:{run['model']}",
                "commit": run.get("commit"),
                "folded_from": str(records),
            }
            sink.write(json.dumps(row) + "\n")
            added += 1
    print(f"appended {added} rows from {records} to {out}")


def blind_check(out: Path, prefix: str, c: float = 1.0) -> None:
    """Score the rows of one folded set (task ids starting with ``prefix``) as if it were new:
    the similar cases' reading and the harm model fitted on the rows of the tasks written before it
    (the dev split and the earlier sets), with and without the reading. Prints AUC and, for each,
    the share of its ordinary tasks refused where 85% of its hazards are."""
    rows = _rows(out)
    order = ["safe-", "unsafe-", *[f"hh{n}-" for n in range(1, 10)]]
    known = [p for p in order[: order.index(prefix)]] if prefix in order else []
    train = [r for r in rows if r["task"].startswith(tuple(known))]
    scored = [r for r in rows if r["task"].startswith(prefix)]
    if not train or not scored:
        raise SystemExit(f"no rows for {prefix!r} or before it in {out}")
    texts = instructions()
    embedder = open_embedder(load_settings())
    x_train = embedder.embed([texts[r["task"]] for r in train])
    y_train = np.array([int(r["unsafe"]) for r in train])
    weights, bias = fit_logistic(x_train, y_train)
    new = embedder.embed([texts[r["task"]] for r in scored]) @ weights + bias
    train = with_similar(train, embedder)
    scored = [
        {**r, "signals": {**r["signals"], "similar": float(v)}} for r, v in zip(scored, new, strict=True)
    ]
    for name, columns in (
        ("without similar cases", [f for f in FEATURES if f != "similar"]),
        ("with them", FEATURES),
    ):
        x, y = _matrix(train, columns)
        w, b = _fit(x, y, c)
        xs, ys = _matrix(scored, columns)
        score = xs @ w + b
        at = np.quantile(score[ys == 1], 0.15)
        auc = _auc(score[ys == 1], score[ys == 0])
        print(
            f"{prefix} as if blind ({len(train)} earlier rows), {name}: AUC {auc:.3f}; "
            f"85% of hazards refused refuses {(score[ys == 0] >= at).mean():.0%} of ordinary tasks"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("step", choices=("collect", "fit", "fold", "blind-check"))
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--limit", type=int)
    parser.add_argument("--reuse", type=Path, help="an earlier collect's rows: their readings are reused")
    parser.add_argument("--write", action="store_true")
    parser.add_argument("--c", type=float, default=1.0, help="inverse L2 strength of the fit")
    parser.add_argument("--records", type=Path, help="fold: a blind set's records file")
    parser.add_argument("--tasks", type=Path, help="fold: that set's task file")
    parser.add_argument("--set", help="blind-check: the folded set's task id prefix (hh5-)")
    args = parser.parse_args(argv)
    if args.step == "collect":
        collect(args.out, args.limit, args.reuse)
    elif args.step == "fold":
        if args.records is None or args.tasks is None:
            parser.error("fold needs --records RECORDS --tasks TASKS")
        fold(args.out, args.records, args.tasks)
    elif args.step == "blind-check":
        if not args.set:
            parser.error("blind-check needs --set PREFIX (e.g. hh5-)")
        blind_check(args.out, args.set, args.c)
    else:
        fit(args.out, args.write, args.c)
    return 0


if __name__ == "__main__":
    sys.exit(main())
