"""How often the goal is read right when the model first says the request plainly
(``pipeline/goal/restate.py``), against the rules reading the request's own words, on rounds of
the goal set (``benchmarks/data/goal_set.json``).

For each request it records the rules' reading of the words, the model's plain form and the rules'
reading of that, each compared with the gold (exact match, :func:`conceptbot.pipeline.goal.same_goal`),
and prints per round: each reading's accuracy, how often the two agree and how often they are right
when they do, how often the gold is one of the two (what a question choosing between them can reach),
and each of :mod:`conceptbot.pipeline.goal.aided`'s policies.

The rows go to ``--out`` (JSON lines) as they are read; a second run skips rows already there and
read with the same prompt (its hash is part of each row's key), so a long run resumes. The model's
calls go through the answer cache.

    .venv/bin/python benchmarks/bench_restated_reading.py --rounds 9 10 --out results/parts/restate-dev.jsonl

``--changed test|dev`` instead lists the split's tasks whose goal the restated reading changes (with
the graph's dish checks, and without them, as the no-graph ablation reads), so that only those are
planned again: it reads no gold and tunes nothing.

``--fit-odds`` counts, per step of the grounded choice (:data:`conceptbot.pipeline.goal.aided.STEPS`),
how often the reading kept and the reading dropped are the gold, on the records of the tuning rounds
(0, 8, 9 and 10; round 11 is held out), and prints them beside the held-out round's counts; with
``--write`` they go to ``src/conceptbot/pipeline/goal/reading_odds.json``, which the goal planner
reads to decide whether to ask which reading was meant. No model is run.

    .venv/bin/python benchmarks/bench_restated_reading.py --fit-odds --out results/parts/goal-set.jsonl

``--fit-judge`` asks the model which of the two readings was meant (:mod:`conceptbot.pipeline.goal.judge`,
through the answer cache) on every record that reads two ways with the gold one of them, fits how
much its preference moves each step's odds on the tuning rounds (:func:`fit_judge`), and prints the
ranking of the meant reading (AUC) with the steps' odds alone and with the preference, on the tuning
rounds and on the held-out rounds 11 and 12; with ``--write`` the weights go into the odds file's
``judge``.

    .venv/bin/python benchmarks/bench_restated_reading.py --fit-judge --out results/parts/goal-set.jsonl
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path
from typing import Any

from conceptbot.bench.grading import load_dev_scene, load_tasks, task_scene
from conceptbot.bench.provenance import stamp
from conceptbot.core.config import load_settings
from conceptbot.models.registry import open_llm
from conceptbot.pipeline import prompts
from conceptbot.pipeline.goal import Goal, GoalReader, same_goal
from conceptbot.pipeline.goal.aided import POLICIES, AidedReader, choose
from conceptbot.pipeline.goal.doubt import JudgeWeights, Odds, describe, judged
from conceptbot.pipeline.goal.judge import ReadingJudge
from conceptbot.pipeline.goal.restate import Restater


def made() -> dict[str, object]:
    """What made each record: version, commit of the code, model (conceptbot.bench.provenance)."""
    return stamp({"llm": load_settings().llm})


def _sibling(name: str) -> Any:
    """A sibling benchmark script as a module (the scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_GOAL_BENCH = _sibling("bench_goal_reading")
GOAL_SET: Path = _GOAL_BENCH.GOAL_SET
graph_reader = _GOAL_BENCH.graph_reader


def _key(row: dict[str, Any]) -> str:
    return f"{row['task']}|{row.get('round', 0)}|{row['request']}|{PROMPT}"


def _prompt_version() -> str:
    """The restating prompt's hash: rows read with another prompt are read again."""
    text = prompts.render("restate_system") + prompts.fill("restate_user", request="")
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:12]


PROMPT = _prompt_version()


def read_rows(rows: Sequence[dict[str, Any]], out: Path, reader: GoalReader, restater: Restater) -> None:
    """Read each row not yet in ``out`` and append its record."""
    done = set()
    if out.exists():
        done = {json.loads(line)["key"] for line in out.read_text(encoding="utf-8").splitlines() if line}
    todo = [r for r in rows if _key(r) not in done]
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("a", encoding="utf-8") as sink:
        for i, row in enumerate(todo, 1):
            scene = load_dev_scene(row["scene"])
            gold = Goal.from_dict(row["goal"])
            started = time.perf_counter()
            words = reader.read(row["request"], scene)
            said = restater.restate(row["request"])
            plain = reader.read(said.text, scene) if said.text else None
            record = {
                "key": _key(row),
                "task": row["task"],
                "round": row.get("round", 0),
                "request": row["request"],
                "plain": said.text,
                "problem": said.problem,
                "words_goal": words.to_dict(),
                "plain_goal": plain.to_dict() if plain else None,
                "gold": row["goal"],
                "words_ok": same_goal(words, gold).ok,
                "plain_ok": plain is not None and same_goal(plain, gold).ok,
                "agree": plain is not None and same_goal(words, plain).ok,
                "seconds": round(time.perf_counter() - started, 2),
                "model_calls": said.usage.calls,
            }
            sink.write(json.dumps({**record, **made()}) + "\n")
            sink.flush()
            print(f"\r{i}/{len(todo)} read", end="", file=sys.stderr, flush=True)
    if todo:
        print(file=sys.stderr)


def report(records: Sequence[dict[str, Any]]) -> None:
    """Print the figures per round."""
    rounds = sorted({r["round"] for r in records})
    names = list(POLICIES)
    print(f"{'round':>6} {'n':>4} {'words':>7} {'plain':>7} {'agree':>7} {'ok|agr':>7} {'either':>7} "
          + " ".join(f"{n:>9}" for n in names))  # fmt: skip

    def line(label: str, rows: list[dict[str, Any]]) -> None:
        n = len(rows)
        agree = [r for r in rows if r["agree"]]
        cells = [
            sum(r["words_ok"] for r in rows) / n,
            sum(r["plain_ok"] for r in rows) / n,
            len(agree) / n,
            (sum(r["words_ok"] for r in agree) / len(agree)) if agree else 0.0,
            sum(r["words_ok"] or r["plain_ok"] for r in rows) / n,
        ]
        for name in names:
            cells.append(sum(_policy_ok(r, name) for r in rows) / n)
        print(f"{label:>6} {n:>4} " + " ".join(f"{100 * c:6.1f}%" for c in cells[:5]) + " "
              + " ".join(f"{100 * c:8.1f}%" for c in cells[5:]))  # fmt: skip

    for number in rounds:
        line(str(number) if number else "orig", [r for r in records if r["round"] == number])
    line("all", list(records))


def _policy_ok(record: dict[str, Any], policy: str) -> bool:
    words = Goal.from_dict(record["words_goal"])
    plain = Goal.from_dict(record["plain_goal"]) if record["plain_goal"] else None
    chosen = choose(words, plain, policy, record["request"], record["plain"], _names(record["task"])).goal
    return same_goal(chosen, Goal.from_dict(record["gold"])).ok


@cache
def _names(task_id: str) -> tuple[str, ...]:
    """The objects of a dev task's scene, as the planner gives them to the choice of reading."""
    found = {t.id: t for t in load_tasks(split="dev")}.get(task_id)
    return tuple(task_scene(found).names) if found is not None else ()


ODDS = Path("src/conceptbot/pipeline/goal/reading_odds.json")
#: The goal-set rounds the odds are counted on; the last round is held out to check them.
TUNING_ROUNDS = (0, 8, 9, 10)
HELD_OUT = 11
#: The goal-set rounds the judge's weights are checked on (never fitted on).
HELD_OUT_ROUNDS = (11, 12)


def step_counts(records: Sequence[dict[str, Any]]) -> dict[str, list[int]]:
    """Per step of the grounded choice: [rows, the reading kept is the gold, the reading dropped is]."""
    counts: dict[str, list[int]] = {}
    for record in records:
        words = Goal.from_dict(record["words_goal"])
        plain = Goal.from_dict(record["plain_goal"]) if record["plain_goal"] else None
        gold = Goal.from_dict(record["gold"])
        chosen = choose(words, plain, "grounded", record["request"], record["plain"], _names(record["task"]))
        row = counts.setdefault(chosen.step or "words only", [0, 0, 0])
        row[0] += 1
        row[1] += same_goal(chosen.goal, gold).ok
        row[2] += chosen.other is not None and same_goal(chosen.other, gold).ok
    return counts


def fit_odds(records: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The odds per step from the tuning rounds' records, add-one smoothed over the three outcomes
    (kept right, dropped right, neither): a step seen on few rows stays near a third each, so the
    planner asks there."""
    counts = step_counts([r for r in records if r["round"] in TUNING_ROUNDS])
    steps = {
        step: {
            "rows": n,
            "taken": round((kept + 1) / (n + 3), 4),
            "other": round((dropped + 1) / (n + 3), 4),
        }
        for step, (n, kept, dropped) in sorted(counts.items())
        # "agree": one reading, but sampled plain forms may offer others (--reading sampled).
        if step != "words only"  # nothing to ask there: the words alone were read
    }
    return {
        "_doc": (
            "Per step of the grounded choice between the two readings of a request "
            "(conceptbot.pipeline.goal.aided.STEPS): P(the reading kept is the one meant) and P(the "
            "reading dropped is), add-one smoothed, counted on the goal set's tuning rounds by "
            "benchmarks/bench_restated_reading.py --fit-odds --write. Read by "
            "conceptbot.pipeline.goal.doubt. Refit for another model or prompt."
        ),
        "fitted_on": f"goal set rounds {', '.join(map(str, TUNING_ROUNDS))}: "
        f"{sum(r['round'] in TUNING_ROUNDS for r in records)} rows, restate prompt {PROMPT}",
        "steps": steps,
    }


def show_odds(records: Sequence[dict[str, Any]], fitted: dict[str, Any]) -> None:
    """The fitted odds beside the held-out round's counts."""
    held = step_counts([r for r in records if r["round"] == HELD_OUT])
    print(f"{'step':12} {'rows':>5} {'P(kept)':>8} {'P(other)':>8}   round {HELD_OUT}: rows kept other")
    for step, found in fitted["steps"].items():
        n, kept, dropped = held.get(step, [0, 0, 0])
        print(f"{step:12} {found['rows']:>5} {found['taken']:>8} {found['other']:>8}   "
              f"{n:>14} {kept:>4} {dropped:>5}")  # fmt: skip


def judged_rows(records: Sequence[dict[str, Any]], judge: ReadingJudge) -> list[dict[str, Any]]:
    """The records that read two ways (in words too) and whose gold is one of the two, each with the
    step, which reading the gold is (``taken`` or ``other``) and the model's preference for the
    reading taken (:class:`ReadingJudge`, through the answer cache)."""
    rows = []
    for i, record in enumerate(records, 1):
        words = Goal.from_dict(record["words_goal"])
        plain = Goal.from_dict(record["plain_goal"]) if record["plain_goal"] else None
        gold = Goal.from_dict(record["gold"])
        chosen = choose(words, plain, "grounded", record["request"], record["plain"], _names(record["task"]))
        if chosen.other is None:
            continue
        taken, other = describe(chosen.goal), describe(chosen.other)
        label = (
            "taken"
            if same_goal(chosen.goal, gold).ok
            else "other"
            if same_goal(chosen.other, gold).ok
            else None
        )
        if label is None or taken == other:
            continue
        preference = judge.prefer(record["request"], taken, other).log_odds
        rows.append({"round": record["round"], "step": chosen.step, "label": label, "preference": preference})
        print(f"\r{i}/{len(records)} judged", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return rows


def _offset(step: str, steps: dict[str, Any]) -> float:
    found = steps.get(step) or {}
    taken, other = found.get("taken", 0.5), found.get("other", 0.5)
    return math.log(other / taken)


def fit_judge(rows: Sequence[dict[str, Any]], steps: dict[str, Any], ridge: float = 0.01) -> dict[str, float]:
    """The weights of :func:`conceptbot.pipeline.goal.doubt.judged`: a logistic regression of "the
    reading dropped was meant" on the model's preference against it, offset by the step's log-odds
    (``steps``, the shipped odds), with a light ridge; Newton's method."""
    w = b = 0.0
    for _ in range(100):
        grad = [ridge * w, ridge * b]
        hess = [[ridge, 0.0], [0.0, ridge]]
        for row in rows:
            x = -row["preference"]
            p = 1.0 / (1.0 + math.exp(-(_offset(row["step"], steps) + b + w * x)))
            err = p - (row["label"] == "other")
            v = p * (1.0 - p)
            grad[0] += err * x
            grad[1] += err
            hess[0][0] += v * x * x
            hess[0][1] += v * x
            hess[1][1] += v
        det = hess[0][0] * hess[1][1] - hess[0][1] ** 2
        dw = (hess[1][1] * grad[0] - hess[0][1] * grad[1]) / det
        db = (hess[0][0] * grad[1] - hess[0][1] * grad[0]) / det
        w, b = w - dw, b - db
        if abs(dw) + abs(db) < 1e-9:
            break
    return {"weight": round(w, 4), "bias": round(b, 4)}


def auc(rows: Sequence[dict[str, Any]], score: Callable[[dict[str, Any]], float]) -> float:
    """How often a row whose dropped reading was meant scores above one whose taken reading was
    (ties half): the area under the ROC curve of ``score`` as P(the dropped reading was meant)."""
    pos = [score(r) for r in rows if r["label"] == "other"]
    neg = [score(r) for r in rows if r["label"] == "taken"]
    if not pos or not neg:
        return float("nan")
    return sum((p > n) + 0.5 * (p == n) for p in pos for n in neg) / (len(pos) * len(neg))


def show_judge(rows: Sequence[dict[str, Any]], steps: dict[str, Any], weights: dict[str, float]) -> None:
    """The fit's ranking beside the steps' alone, on the tuning rounds and on the held-out ones."""
    fitted = JudgeWeights(weights["weight"], weights["bias"])

    def combined(row: dict[str, Any]) -> float:
        found = odds_of(row["step"], steps)
        return judged(found, row["preference"], fitted).other

    print(f"weight {weights['weight']}, bias {weights['bias']}")
    print(f"{'rounds':14} {'rows':>5} {'dropped meant':>14} {'AUC steps':>10} {'AUC judged':>11}")
    for name, wanted in (("tuning", TUNING_ROUNDS), ("held out", HELD_OUT_ROUNDS)):
        these = [r for r in rows if r["round"] in wanted]
        dropped = sum(r["label"] == "other" for r in these)
        steps_auc = auc(these, lambda r: _offset(r["step"], steps))
        print(f"{name:14} {len(these):>5} {dropped:>14} {steps_auc:>10.3f} {auc(these, combined):>11.3f}")


def odds_of(step: str, steps: dict[str, Any]) -> Odds:
    """A step's odds from an odds file's ``steps``."""
    found = steps.get(step) or {}
    return Odds(found.get("taken", 0.5), found.get("other", 0.5), found.get("rows", 0))


def changed(split: str, restater: Restater) -> None:
    """Print, per reader (graph, no graph), the tasks of ``split`` whose goal reads differently."""
    readers = {
        "graph": AidedReader(graph_reader(), restater),
        "no graph": AidedReader(GoalReader(), restater),
    }
    for task in load_tasks(split=split):
        scene = task_scene(task)
        for name, reader in readers.items():
            reading = reader.read(task.request, scene)
            if not same_goal(reading.goal, reading.words).ok:
                print(f"{name}\t{task.id}\t{task.request}\t{reading.plain}")


def main() -> None:
    """Read the chosen rounds and print the figures (and, with --failures, the misread rows)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", nargs="+", type=int, default=[], help="0 for the originals")
    parser.add_argument("--out", type=Path, help="JSON lines, resumed")
    parser.add_argument("--changed", choices=["test", "dev"], help="list the tasks whose reading changes")
    parser.add_argument("--no-graph", action="store_true", help="read without the graph's dish checks")
    parser.add_argument("--failures", choices=["words", "plain", "both", "none"], default="none")
    parser.add_argument("--limit", type=int, default=0, help="read only the first N rows of each round")
    parser.add_argument("--fit-odds", action="store_true", help="count each choice step's odds from --out")
    parser.add_argument(
        "--fit-judge", action="store_true", help="fit the model's reading preference's weights from --out"
    )
    parser.add_argument("--write", action="store_true", help=f"with --fit-odds or --fit-judge: write {ODDS}")
    args = parser.parse_args()
    if args.fit_odds or args.fit_judge:
        if args.out is None or not args.out.exists():
            parser.error("--fit-odds and --fit-judge read the records of --out (a file this script wrote)")
        records = [json.loads(x) for x in args.out.read_text(encoding="utf-8").splitlines() if x]
        records = [r for r in records if r["key"].endswith(f"|{PROMPT}")]
        shipped = json.loads(ODDS.read_text(encoding="utf-8"))
        if args.fit_odds:
            fitted = fit_odds(records)
            show_odds(records, fitted)
            fitted.update({k: v for k, v in shipped.items() if k == "judge"})  # the judge's fit stays
        else:
            judge = ReadingJudge(open_llm(load_settings(), module="reading"))
            rows = judged_rows(records, judge)
            tuning = [r for r in rows if r["round"] in TUNING_ROUNDS]
            weights = fit_judge(tuning, shipped["steps"])
            show_judge(rows, shipped["steps"], weights)
            fitted = {
                **shipped,
                "judge": {
                    **weights,
                    "fitted_on": f"goal set rounds {', '.join(map(str, TUNING_ROUNDS))}: {len(tuning)} rows "
                    f"read two ways with the gold one of them, restate prompt {PROMPT}",
                },
            }
        if args.write:
            ODDS.write_text(json.dumps(fitted, indent=2) + "\n", encoding="utf-8")
            print(f"wrote {ODDS}")
        return
    if args.changed:
        changed(args.changed, Restater(open_llm(load_settings(), module="restate")))
        return
    if not args.rounds or args.out is None:
        parser.error("--rounds and --out are needed (or --changed)")
    rows = json.loads(GOAL_SET.read_text(encoding="utf-8"))["requests"]
    chosen: list[dict[str, Any]] = []
    for number in args.rounds:
        these = [r for r in rows if r.get("round", 0) == number]
        chosen += these[: args.limit] if args.limit else these
    reader = GoalReader() if args.no_graph else graph_reader()
    restater = Restater(open_llm(load_settings(), module="restate"))
    read_rows(chosen, args.out, reader, restater)
    keys = {_key(r) for r in chosen}
    records = [json.loads(x) for x in args.out.read_text(encoding="utf-8").splitlines() if x]
    records = [r for r in records if r["key"] in keys]
    report(records)
    for record in records:
        wrong = (args.failures in ("words", "both") and not record["words_ok"]) or (
            args.failures in ("plain", "both") and not record["plain_ok"]
        )
        if wrong:
            print(f"\n{record['task']} [{record['round']}] {record['request']}\n  plain: {record['plain']}"
                  f"\n  words {'ok' if record['words_ok'] else 'WRONG'}: {json.dumps(record['words_goal'])}"
                  f"\n  plain {'ok' if record['plain_ok'] else 'WRONG'}: {json.dumps(record['plain_goal'])}"
                  f"\n  gold: {json.dumps(record['gold'])}")  # fmt: skip


if __name__ == "__main__":
    main()
