"""Asking instead of guessing, measured (issue 35): each task of a split planned by the goal planner
with and without a simulated person who answers every question from the gold
(:func:`conceptbot.bench.grading.gold_answer`), at each coverage, through the answer cache.

Per split, system and coverage: success without questions and with the gold answers, the share of
tasks with a question (help rate), questions per task, and the empirical coverage of the calibrated
decisions' prediction sets against the gold. Rows go to ``results/asking/report.json`` (``--write``),
each naming the commit of the code that made it (:mod:`conceptbot.bench.provenance`).

    .venv/bin/python benchmarks/bench_asking.py --split dev [--systems conceptbot,nokg] [--write]

``--tasks id,id`` measures those tasks only and prints each one's outcome (alone, asked, the
questions); such rows are not written (they are not the split's figures).

With ``--write`` each task's outcome is also kept, as it is measured, in
``results/asking/records.jsonl``: the evidence behind the rows (which tasks fail, what was asked), and
what ``--write --resume`` continues from after a stop (outcomes of other code are planned again).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from conceptbot.bench.conformal_fit import labelled
from conceptbot.bench.grading import Task, gold_reading, gold_reply, grade, load_tasks, task_scene
from conceptbot.bench.provenance import stamp
from conceptbot.core.config import load_settings
from conceptbot.core.plan import Plan
from conceptbot.core.system import ASK_ALL, COVERAGES, LEVELS, READINGS, WHICH_ONE, SystemOptions
from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.pipeline.goal_planner.conformal import OLD_RULE, shipped
from conceptbot.systems import build_system

OUT = Path("results/asking/report.json")
FIGURE = Path("results/asking/asking.png")
RELIABILITY = Path("results/asking/reliability.png")
# Each task's outcome, one JSON line per task as it is measured (``--write``): the rows' evidence,
# and what ``--resume`` continues from after a stop.
TASKS = Path("results/asking/records.jsonl")
BINS = 10
# How the planner reads the request here (the default, SystemOptions.reading); the rows measured
# with the rules alone, before 2026-12-02, say "words".
READING = SystemOptions().reading


def outcome(system: Any, task: Task, readings: bool = True) -> dict[str, Any]:
    """One task planned without and with the simulated person: both grades, whether each calibrated
    decision's prediction set held the gold (``found``), and the questions asked with their answers.
    ``readings`` False: the person does not answer which reading of a request was meant, and such
    questions are not counted (the plan acts on the reading chosen, as before those were asked)."""
    scene = task_scene(task)
    alone = system.plan(task.request, scene)

    def person(question: ClarifyingQuestion) -> str:
        if question.kind != "reading":
            return gold_reply(task, question)
        if not readings:
            return ""  # not an answer: the reading chosen stands

        def plan_as(reading: str) -> Plan:
            def fixed(other: ClarifyingQuestion) -> str:
                return reading if other.kind == "reading" else gold_reply(task, other)

            return system.plan(task.request, scene, ask=fixed)

        return gold_reading(task, question, plan_as)

    answered = system.plan(task.request, scene, ask=person) if alone.questions else alone
    counted = [q for q in answered.questions if readings or q.kind != "reading"]
    return {
        "task": task.id,
        "alone": grade(task, alone.actions, alone.refused).ok,
        "asked": grade(task, answered.actions, answered.refused).ok,
        "found": [decision.covered for decision in labelled(task, alone)],
        "questions": [
            {"kind": q.kind, "text": q.text, "answer": q.answer, "objects": len(q.objects)} for q in counted
        ],
    }


def measure(
    split: str,
    system_name: str,
    coverage: float,
    level: str = "plan",
    ids: frozenset[str] = frozenset(),
    readings: bool = True,
    known: dict[str, dict[str, Any]] | None = None,
    keep: Callable[[dict[str, Any]], None] | None = None,
    which_one: str | None = None,
    reading: str = READING,
) -> dict[str, Any]:
    """One row: the split's tasks (``ids``: only those) planned with and without the gold answers
    (:func:`outcome`); with ``ids``, each task's outcome too (``per_task``). ``known`` holds outcomes
    of an earlier run by task id, taken instead of planning the task again (``--resume``); ``keep``
    gets each new outcome as it is found. ``which_one``: the which-one rule (None: the
    calibration's); ``reading``: how the planner reads the request (``SystemOptions.reading``)."""
    options = SystemOptions(coverage=coverage, level=level, which_one=which_one, reading=reading)
    system = build_system(load_settings(), system_name, options)
    rule = which_one or shipped().rule
    tasks = [t for t in load_tasks(split=split) if not ids or t.id in ids]
    found = []
    for done, task in enumerate(tasks):
        print(f"\r{split} {system_name} {coverage}: {done}/{len(tasks)}", end="", file=sys.stderr, flush=True)
        if known and task.id in known:
            found.append(known[task.id])
            continue
        found.append(outcome(system, task, readings))
        if keep:
            keep(found[-1])
    print(file=sys.stderr)
    return {
        "split": split,
        "system": system_name,
        "level": level,
        "coverage": coverage,
        **summary(found, level),
        "reading_asked": readings,
        "which_one": rule,
        "reading": reading,
        **({"per_task": found} if ids else {}),
    }


def summary(found: list[dict[str, Any]], level: str = "plan") -> dict[str, Any]:
    """The row's figures from its tasks' outcomes."""
    n = len(found)
    questions = [q for o in found for q in o["questions"]]
    decisions = [covered for o in found for covered in o["found"]]
    plans = [all(o["found"]) for o in found if o["found"]]
    return {
        "tasks": n,
        "success_without_questions": round(100 * sum(o["alone"] for o in found) / n, 1),
        "success": round(100 * sum(o["asked"] for o in found) / n, 1),
        "help_rate": round(100 * sum(bool(o["questions"]) for o in found) / n, 1),
        "questions_per_task": round(len(questions) / n, 3),
        "objects_per_question": (
            round(sum(q["objects"] for q in questions) / len(questions), 2) if questions else None
        ),
        "reading_questions": sum(q["kind"] == "reading" for q in questions),
        # At the calibrated level: plan (every calibrated decision of a task covered) or decision.
        "empirical_coverage": (
            round(sum(plans) / len(plans), 4)
            if level == "plan" and plans
            else (round(sum(decisions) / len(decisions), 4) if decisions else None)
        ),
        "tasks_with_calibrated_decisions": len(plans),
        "calibrated_decisions": len(decisions),
        "decision_coverage": round(sum(decisions) / len(decisions), 4) if decisions else None,
    }


def _key(r: dict[str, Any]) -> tuple[Any, ...]:
    """What a row (or a task's outcome) was measured as."""
    return (
        r["split"],
        r["system"],
        r.get("level", "decision"),
        r["coverage"],
        r.get("reading_asked", False),
        r.get("which_one") or OLD_RULE,  # rows before 2026-12-03 were all softmax
        r.get("reading", READING),  # how the request was read (rows of the rules alone say "words")
    )


def _outcomes(resume: bool, commit: str | None = None) -> list[dict[str, Any]]:
    """The per-task outcomes kept in :data:`TASKS` (none unless ``resume``; with ``commit``, only
    those made by that commit of the code)."""
    if not resume or not TASKS.exists():
        return []
    found = [json.loads(line) for line in TASKS.read_text(encoding="utf-8").splitlines() if line.strip()]
    return [o for o in found if commit is None or o.get("commit") == commit]


def _in_bin(pairs: list[tuple[float, float]], k: int, bins: int = BINS) -> list[tuple[float, float]]:
    """The pairs whose prediction falls in bin ``k`` of ``bins`` (1.0 in the last)."""
    return [(p, y) for p, y in pairs if k / bins <= p < (k + 1) / bins or (k == bins - 1 and p == 1.0)]


def expected_calibration_error(pairs: list[tuple[float, float]], bins: int = BINS) -> float:
    """ECE of ``(predicted probability, outcome 0/1)`` pairs over equal-width bins: the mean gap
    between a bin's predicted and observed rates, weighted by its share of the pairs."""
    total = 0.0
    for k in range(bins):
        inside = _in_bin(pairs, k, bins)
        if inside:
            gap = abs(sum(p for p, _ in inside) / len(inside) - sum(y for _, y in inside) / len(inside))
            total += gap * len(inside) / len(pairs)
    return total


def reliability(split: str, system_name: str) -> dict[str, Any]:
    """How honest the probabilities are without questions: each calibrated decision's P(yes) against
    the gold answer, and each plan's confidence against its grade."""
    system = build_system(load_settings(), system_name, SystemOptions())
    decisions: list[tuple[float, float]] = []
    plans: list[tuple[float, float]] = []
    for task in load_tasks(split=split):
        plan = system.plan(task.request, task_scene(task))
        decisions += [
            (found.p_yes, 1.0 if found.yes else 0.0)
            for found in labelled(task, plan)
            if found.p_yes is not None and found.p_yes == found.p_yes
        ]
        if plan.confidence is not None:
            plans.append((plan.confidence, 1.0 if grade(task, plan.actions, plan.refused).ok else 0.0))
    return {
        "split": split,
        "system": system_name,
        "decisions": len(decisions),
        "decision_ece": round(expected_calibration_error(decisions), 4),
        "plans": len(plans),
        "plan_ece": round(expected_calibration_error(plans), 4) if plans else None,
        "plan_mean_confidence": round(sum(p for p, _ in plans) / len(plans), 4) if plans else None,
        "plan_success": round(sum(y for _, y in plans) / len(plans), 4) if plans else None,
        "_pairs": {"decisions": decisions, "plans": plans},
    }


def plot_reliability(found: dict[str, Any]) -> None:
    """The reliability diagram of the decisions and the plans (observed rate per bin of predicted)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot([0, 1], [0, 1], color="grey", linestyle="--", linewidth=1)
    for key, label in (("decisions", "decisions: P(yes)"), ("plans", "plans: confidence")):
        pairs = found["_pairs"][key]
        xs, ys = [], []
        for k in range(BINS):
            inside = _in_bin(pairs, k)
            if inside:
                xs.append(sum(p for p, _ in inside) / len(inside))
                ys.append(sum(y for _, y in inside) / len(inside))
        ece = found["decision_ece" if key == "decisions" else "plan_ece"]
        ax.plot(xs, ys, marker="o", label=f"{label} (n={len(pairs)}, ECE {ece})")
    ax.set_xlabel("predicted")
    ax.set_ylabel("observed")
    ax.set_title(f"Reliability, {found['split']} split, {found['system']}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(RELIABILITY, dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--split", choices=("dev", "test"), default="dev")
    parser.add_argument("--systems", default="conceptbot,nokg")
    parser.add_argument("--level", choices=LEVELS, default="plan", help="what the coverage holds for")
    parser.add_argument("--write", action="store_true", help=f"add the rows to {OUT}")
    parser.add_argument(
        "--no-readings", action="store_true", help="the person does not say which reading was meant"
    )
    parser.add_argument(
        "--which-one", choices=WHICH_ONE, default=None, help="the which-one rule (default: the calibration's)"
    )
    parser.add_argument("--tasks", default="", help="only these task ids (comma-separated; not written)")
    parser.add_argument("--reading", choices=READINGS, default=READING, help="how the request is read")
    parser.add_argument(
        "--coverage",
        type=float,
        action="append",
        choices=(*COVERAGES, ASK_ALL),
        help="only this coverage (repeatable; default: every one)",
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help=f"take the tasks already measured from {TASKS} (same split, system, level, coverage) "
        "instead of planning them again",
    )
    parser.add_argument(
        "--reliability", action="store_true", help="only the reliability of the probabilities (no questions)"
    )
    args = parser.parse_args()
    ids = frozenset(t for t in args.tasks.split(",") if t)
    if ids and args.write:
        parser.error("--tasks measures a subset: its rows are not the split's, so --write is refused")
    if args.resume and not args.write:
        parser.error("--resume continues a written run: give --write too")
    if args.reliability:
        found = reliability(args.split, args.systems.split(",")[0])
        shown = {k: v for k, v in found.items() if not k.startswith("_")}
        print(json.dumps(shown, indent=2))
        if args.write:
            kept = json.loads(OUT.read_text()) if OUT.exists() else {"asking": []}
            kept["reliability"] = [
                *(
                    r
                    for r in kept.get("reliability", [])
                    if (r["split"], r["system"]) != (found["split"], found["system"])
                ),
                shown,
            ]
            OUT.write_text(json.dumps(kept, indent=2) + "\n", encoding="utf-8")
            plot_reliability(found)
            print(f"wrote {OUT} and {RELIABILITY}")
        return
    # ASK_ALL: every calibrated decision asked, the most the answers can do (the ceiling).
    coverages = tuple(args.coverage) if args.coverage else (*COVERAGES, ASK_ALL)
    readings = not args.no_readings
    rule = args.which_one or shipped().rule
    keys = [
        (args.split, s, args.level, c, readings, rule, args.reading)
        for s in args.systems.split(",")
        for c in coverages
    ]
    # What made each outcome and row: outcomes of other code are planned again on --resume.
    made = stamp({"level": args.level, "reading": args.reading, "which_one": rule, "asked": readings})
    earlier = _outcomes(args.resume, made["commit"])
    if args.write:
        TASKS.parent.mkdir(parents=True, exist_ok=True)
        # Without --resume, this run's keys start afresh; other keys' outcomes stay.
        kept = earlier if args.resume else [o for o in _outcomes(True) if _key(o) not in keys]
        TASKS.write_text("".join(json.dumps(o) + "\n" for o in kept), encoding="utf-8")
    rows = []
    for key in keys:
        split, system_name, level, coverage, _, _, _ = key
        known = {o["task"]: o for o in earlier if _key(o) == key}
        names = ("split", "system", "level", "coverage", "reading_asked", "which_one", "reading")
        fields = dict(zip(names, key, strict=True))

        def keep(found: dict[str, Any], fields: dict[str, Any] = fields) -> None:
            with TASKS.open("a", encoding="utf-8") as out:
                out.write(json.dumps({**fields, **made, **found}) + "\n")

        rows.append(
            made
            | measure(
                split,
                system_name,
                coverage,
                level,
                ids,
                readings,
                known,
                keep if args.write else None,
                rule,
                args.reading,
            )
        )
    columns = ("cover", "alone", "asked", "help", "q/task", "obj/q", "emp.cov", "dec.cov", "n task")
    print(f"{'system':10} {'level':8} " + " ".join(f"{c:>7}" for c in columns))
    for r in rows:
        print(
            f"{r['system']:10} {r['level']:8} {r['coverage']:>7} {r['success_without_questions']:>6}% "
            f"{r['success']:>6}% {r['help_rate']:>6}% {r['questions_per_task']:>7} "
            f"{r['objects_per_question']!s:>7} {r['empirical_coverage']!s:>7} {r['decision_coverage']!s:>7} "
            f"{r['tasks_with_calibrated_decisions']:>7}"
        )
        for found in r.get("per_task", []):
            print(f"    {found['task']}: alone {found['alone']}, asked {found['asked']}")
            for question in found["questions"]:
                print(f"        {question['text']} -> {question['answer']}")
    if args.write:
        document = json.loads(OUT.read_text()) if OUT.exists() else {"asking": []}
        done = {_key(r) for r in rows}
        kept = [r for r in document["asking"] if _key(r) not in done] + rows
        OUT.write_text(json.dumps({**document, "asking": kept}, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {OUT}")
        plot(kept)
        print(f"wrote {FIGURE}")


def plot(rows: list[dict[str, Any]]) -> None:
    """Success against help rate, one line per split and system through its coverages (KnowNo's
    figure), with the success without questions as the line's start and every decision asked
    (coverage 1.0) as its end."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 5))
    ax.set_prop_cycle(color=plt.cm.tab20.colors)  # more lines than the default ten colours

    def group(r: dict[str, Any]) -> tuple[str, str, str, bool, str, str]:
        readings = bool(r.get("reading_asked", False))
        rule = r.get("which_one") or OLD_RULE
        return r["split"], r["system"], r.get("level", "decision"), readings, rule, r.get("reading", READING)

    for key in sorted({group(r) for r in rows}):
        split, system, level, readings, rule, reading = key
        line = sorted((r for r in rows if group(r) == key), key=lambda r: r["coverage"])
        xs = [0.0] + [r["help_rate"] for r in line]
        ys = [line[0]["success_without_questions"]] + [r["success"] for r in line]
        asked = ", reading asked" if readings else ""
        which = f", which one by {rule}" if rule != OLD_RULE else ""
        read = ", the rules' reading" if reading == "words" else ""
        ax.plot(xs, ys, marker="o", label=f"{split}: {system}, {level} level{read}{asked}{which}")
        for r in line:
            ax.annotate(str(r["coverage"]), (r["help_rate"], r["success"]), fontsize=7)
    ax.scatter([40], [90], marker="*", s=120, color="red", label="issue 35's target (test, 0.9)")
    ax.set_xlabel("tasks with a question (%)")
    ax.set_ylabel("success with the answers (%)")
    ax.set_title("Asking instead of guessing (embedded 1.5B; labels: coverage)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))  # beside: the lines cross
    fig.tight_layout()
    fig.savefig(FIGURE, dpi=120)


if __name__ == "__main__":
    main()
