"""Which reading was meant, held out: the goal set's paraphrases of the dev requests, each planned
asking about every decision and reading (nobody answering), and where it reads two ways, labelled
as the plan-level calibration labels dev tasks (:func:`conceptbot.bench.conformal_fit.reading_label`:
each reading planned as the person's answer, the other questions answered from the dev task's gold).

Printed: how many paraphrases read two ways, which reading the plan passes with (the one taken, the
one dropped, a sampled one, none), and for the shipped reading threshold and the one threshold the
reading questions took before (``plan_qhat``), how many would be asked and how many sets hold the
reading meant.

``--write`` fits the reading decisions' own threshold on these labels and stores it in
``src/conceptbot/pipeline/conformal.json`` (``plan_qhat_reading``, for both which-one rules and both
combinations: the readings do not depend on either): split conformal's quantile of ``1 - P(the
reading meant)`` over the labelled paraphrases, each round's fit checked on the other round first.
The dev tasks' own requests are no calibration set for it: the reading rules were built on them, and
the reading taken was the one meant in all 21 of them that read two ways.

    .venv/bin/python benchmarks/bench_reading_labels.py [--rounds 11,12] [--category implicit]
        [--out results/parts/reading-labels-qwen2.5-coder-1.5b.jsonl] [--resume [--rescore]] [--write]

``--rescore`` gives the kept paraphrases' two readings the odds the planner gives them today (the
step's odds and the model's preference, :mod:`conceptbot.pipeline.goal.judge`) without planning them
again, so the threshold can be refit after the odds change.
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
from conceptbot.bench.provenance import stamp
from conceptbot.core.config import load_settings
from conceptbot.core.system import ASK_ALL, COVERAGES, PlannerSystem, SystemOptions
from conceptbot.core.trace import ReadingOption
from conceptbot.models.registry import open_llm
from conceptbot.pipeline.goal.judge import ReadingJudge, reading_odds
from conceptbot.pipeline.goal_planner.asking import reading_set
from conceptbot.pipeline.goal_planner.conformal import conformal_threshold, shipped
from conceptbot.systems import build_system

OUT = Path("results/parts/reading-labels-qwen2.5-coder-1.5b.jsonl")
CONFORMAL = Path(__file__).resolve().parents[1] / "src" / "conceptbot" / "pipeline" / "conformal.json"


def made() -> dict[str, object]:
    """What made each record: version, commit of the code, model (conceptbot.bench.provenance)."""
    return stamp({"llm": load_settings().llm})


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


def nonconformity(found: list[dict]) -> list[float]:
    """``1 - P(the reading meant)`` of each labelled paraphrase (a probability that is not one: 1)."""
    scores = []
    for f in found:
        if f["meant"] is None:
            continue
        p = f["readings"][f["meant"]]["p"]
        scores.append(1.0 - p if isinstance(p, int | float) and 0.0 <= p <= 1.0 else 1.0)
    return scores


def fit_reading(found: list[dict]) -> dict[float, float]:
    """The reading threshold per coverage: split conformal's quantile of :func:`nonconformity`."""
    scores = nonconformity(found)
    return {coverage: conformal_threshold(scores, coverage) for coverage in COVERAGES}


def write(found: list[dict], rounds: str) -> None:
    """Print each round's fit checked on the others, and store the fit on all of them."""
    by_round: dict[int, list[dict]] = {}
    for f in found:
        by_round.setdefault(f["round"], []).append(f)
    for held, rows in sorted(by_round.items()):
        rest = [f for f in found if f["round"] != held]
        if not nonconformity(rest) or not nonconformity(rows):
            continue
        fitted = fit_reading(rest)
        for coverage, qhat in fitted.items():
            scores = nonconformity(rows)
            kept = sum(round(1.0 - s, 4) >= round(1.0 - qhat, 4) for s in scores) / len(scores)
            print(f"fitted without round {held}: {coverage} qhat {qhat:.4f}, round {held} covered {kept:.1%}")
    fitted = fit_reading(found)
    data = json.loads(CONFORMAL.read_text(encoding="utf-8"))
    thresholds = {str(c): round(q, 4) for c, q in fitted.items()}
    for key in ("plan_qhat_reading", "plan_qhat_reading_fits"):
        data[key] = {"graph": thresholds, "nograph": thresholds}
    labelled = len(nonconformity(found))
    data["reading_fitted_on"] = (
        f"goal-set paraphrase rounds {rounds}: {labelled} labelled readings, {Path(__file__).name}"
    )
    CONFORMAL.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    print(f"wrote {CONFORMAL}: plan_qhat_reading {thresholds}")


def rescored(found: dict, judge: ReadingJudge) -> dict:
    """A labelled paraphrase with its two readings' odds as the planner now gives them (the step's
    odds moved by the model's preference, :func:`conceptbot.pipeline.goal.judge.reading_odds`), without
    planning it again: the labels depend on the readings' plans, not on their odds."""
    kinds = [r["kind"] for r in found["readings"]]
    if kinds != ["taken", "other"]:
        return found
    taken, other = (r["text"] for r in found["readings"])
    odds, judged_by = reading_odds(found["step"], found["request"], taken, other, judge)
    if judged_by is None:
        return found
    probabilities = (round(odds.taken, 4), round(odds.other, 4))
    readings = [{**r, "p": p} for r, p in zip(found["readings"], probabilities, strict=True)]
    return {**found, "readings": readings}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", default="11,12", help="comma-separated goal-set rounds (held out: 11,12)")
    parser.add_argument("--category", help="a dev category (implicit, risk, ...)")
    parser.add_argument("--out", type=Path, default=OUT, help="results file, a JSON line per paraphrase")
    parser.add_argument("--resume", action="store_true", help="keep the paraphrases already in --out")
    parser.add_argument(
        "--write", action="store_true", help=f"store the reading threshold in {CONFORMAL.name}"
    )
    parser.add_argument(
        "--rescore",
        action="store_true",
        help="with --resume: give the kept paraphrases' readings today's odds (no planning), rewrite --out",
    )
    args = parser.parse_args()
    if args.rescore and not args.resume:
        parser.error("--rescore works on the paraphrases kept by --resume")
    rows = chosen_rows(None, args.category, False, {int(r) for r in args.rounds.split(",")})
    tasks = {t.id: t for t in load_tasks(split="dev")}
    done: dict[str, dict] = {}
    if args.resume and args.out.exists():
        for line in args.out.read_text(encoding="utf-8").splitlines():
            if line.strip():
                found = json.loads(line)
                done[found["key"]] = found
    if args.rescore:
        judge = ReadingJudge(open_llm(load_settings(), module="reading"))
        done = {key: rescored(found, judge) for key, found in done.items()}
        args.out.write_text("".join(json.dumps(f) + "\n" for f in done.values()), encoding="utf-8")
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
            out.write(json.dumps({**found, **made()}) + "\n")
            out.flush()
            kinds = [r["kind"] for r in found["readings"]]
            print(
                f"[{n}/{len(rows)}] {row['task']}: {row['request']} -> {kinds} meant {found['meant']}",
                flush=True,
            )
    for coverage in COVERAGES:
        print(coverage, json.dumps(summary(results, coverage)))
    if args.write:
        write(results, args.rounds)


if __name__ == "__main__":
    main()
