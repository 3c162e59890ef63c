"""Where does each object go in a sort by a property? One lettered choice per object over the places.

Measured on the materials and toxic tasks whose gold assigns objects to places (``assign``): for
every pickable object of the task's scene, the places it may go (``assign`` and ``optional``) or
"leave it" (any other object; an ``optional`` one may also stay). Each object is one question:
the request and the scene's places (every destination that is not a person) as lettered options,
"leave it where it is" last, then the object; the next token's log-probabilities over the letters
are the reading. The request and the places come first, so llama.cpp evaluates them once per task
and each object adds a few tokens.

It prints how many objects go to an accepted place, and how many tasks have every object right
(what the task's grade needs), for the best letter and for the best letter after a per-task
offset on "leave it" (the one free parameter: how readily an object is left), chosen by
leave-one-task-out. Readings are appended to the output as they come (resumable).

With ``--plans`` it also runs the default planner's reading and decisions on each task and keeps,
per object, where its choice of moves puts it (before the risk checks, which only drop moves) and
each target's decided score, so the same counts are printed for the planner as it is and for its
scores with a fitted "leave it" score in place of its thresholds (an object goes to its best
target or stays, whichever scores higher).

    .venv/bin/python benchmarks/bench_sort.py [--tasks DIR ...] [--plans]
        [--out results/parts/sort-MODEL.jsonl]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from conceptbot.bench.grading import load_split_scene
from conceptbot.core.config import load_settings
from conceptbot.core.observe import SILENT
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline.hazards import is_person
from conceptbot.systems import build_system

DEV = Path("src/conceptbot/bench/dev")
LETTERS = "ABCDEFGHIJKLMNOPQRSTUVWXYZ"
LEAVE = "leave it where it is"
SYSTEM = (
    "You help a household robot sort objects. You are shown what a person asked and the places, "
    "each with a letter, then one object. Answer with the letter of the place the object belongs "
    "in, or of leaving it where it is if it belongs in none of them."
)
OFFSETS = [i / 2 for i in range(-8, 9)]
LEAVES = [i / 2 for i in range(-12, 13)]
NAMED = 10.0


def items(folders: Sequence[Path]) -> list[dict]:
    """One item per sort task (materials or toxic, an ``assign`` gold) of the folders."""
    out = []
    for folder in folders:
        for category in ("materials", "toxic"):
            path = folder / "tasks" / f"{category}.json"
            if not path.exists():
                continue
            for task in json.loads(path.read_text(encoding="utf-8")):
                gold = task["gold"]
                if gold["type"] != "assign" or not gold.get("assign"):
                    continue
                scene = json.loads((folder / "scenes" / f"{task['scene']}.json").read_text(encoding="utf-8"))
                places = [d for d in scene["destinations"] if not is_person(d)]
                allowed = {}
                for obj in scene["pickable_objects"]:
                    ok = [*gold.get("assign", {}).get(obj, []), *gold.get("optional", {}).get(obj, [])]
                    if obj not in gold.get("assign", {}):
                        ok.append(LEAVE)
                    allowed[obj] = ok
                out.append(
                    {
                        "task": task["id"],
                        "request": task["request"],
                        "scene": task["scene"],
                        "folder": str(folder),
                        "places": places,
                        "allowed": allowed,
                    }
                )
    return out


def ask(llm: LLM, request: str, places: Sequence[str], obj: str) -> dict[str, float]:
    """The log-probability of each place's letter (``LEAVE`` last) for ``obj``."""
    options = [*places, LEAVE][: len(LETTERS)]
    listed = "\n".join(f"{LETTERS[i]}. {p}" for i, p in enumerate(options))
    user = (
        f'A person said: "{request}"\nPlaces:\n{listed}\n\n'
        f"Object: {obj}\nWhere should the robot put the {obj}? Answer with its letter."
    )
    scored = llm.score(
        ScoreRequest(
            options=tuple(LETTERS[: len(options)]),
            messages=(Message("system", SYSTEM), Message("user", user)),
        )
    )
    top = max(scored.logprobs)
    norm = top + math.log(sum(math.exp(v - top) for v in scored.logprobs))
    return {p: v - norm for p, v in zip(options, scored.logprobs, strict=True)}


def best(readings: dict[str, float], offset: float) -> str:
    """The place read first, "leave it" raised by ``offset``."""
    return max(readings, key=lambda p: readings[p] + (offset if p == LEAVE else 0.0))


def score(records: Sequence[dict], offset: float) -> tuple[int, int, int]:
    """Objects right, objects in all, tasks with every object right."""
    right = total = tasks = 0
    for record in records:
        marks = [best(record["readings"][o], offset) in ok for o, ok in record["allowed"].items()]
        right, total, tasks = right + sum(marks), total + len(marks), tasks + all(marks)
    return right, total, tasks


def planned(system: object, item: dict, folder: str) -> dict:
    """The default planner's decisions on ``item``: each target's scores per object, and where its
    choice of moves puts each object before the risk checks (which only ever drop a move)."""
    scene = load_split_scene(folder, item["scene"])
    planner = system.goal_planner  # type: ignore[attr-defined]
    read = planner.targets.read(item["request"], scene)
    ranked, decisions, _ = planner._decide(item["request"], scene, read.targets, read.stack, SILENT)
    moves = planner._choose(read.targets, ranked, set(), scene.pickable) if not read.stack else []
    placed = dict(moves)
    scores: dict[str, dict[str, float]] = {o: {} for o in item["allowed"]}
    for decision in decisions:
        for judged in decision.objects:
            if judged.object in scores:
                scores[judged.object][decision.target.to] = judged.score
        for obj in decision.target.named:
            if obj in scores:
                scores[obj][decision.target.to] = NAMED
    return {"placed": {o: placed.get(o, LEAVE) for o in item["allowed"]}, "scores": scores}


def leave_score(records: Sequence[dict], leave: float) -> tuple[int, int, int]:
    """Objects right, objects in all, tasks all right: each object to its best-scored target, or
    left where no target scores above ``leave``."""
    right = total = tasks = 0
    for record in records:
        marks = []
        for obj, ok in record["allowed"].items():
            options = {**record["planned"]["scores"][obj], LEAVE: leave}
            marks.append(max(options, key=lambda p: options[p]) in ok)
        right, total, tasks = right + sum(marks), total + len(marks), tasks + all(marks)
    return right, total, tasks


def report_plans(records: Sequence[dict]) -> None:
    """The planner as it is, and its scores with a "leave it" score chosen leave-one-task-out (on
    every other task of all the folders), over all the tasks and per folder."""
    with_plans = [r for r in records if "planned" in r]
    held: dict[str, bool] = {}
    for n, record in enumerate(with_plans):
        others = with_plans[:n] + with_plans[n + 1 :]
        chosen = max(LEAVES, key=lambda b: (leave_score(others, b)[0], -abs(b)))
        held[record["task"]] = leave_score([record], chosen)[2] == 1
    chosen = max(LEAVES, key=lambda b: (leave_score(with_plans, b)[0], -abs(b)))
    for folder in [None, *dict.fromkeys(r["folder"] for r in with_plans)]:
        group = [r for r in with_plans if folder is None or r["folder"] == folder]
        marks = [[r["planned"]["placed"][o] in ok for o, ok in r["allowed"].items()] for r in group]
        right, total, tasks = leave_score(group, chosen)
        print(
            f"{folder or 'all'}: {len(group)} tasks; planner as it is: objects {sum(map(sum, marks))}/"
            f"{sum(map(len, marks))}, tasks {sum(map(all, marks))}; leave at {chosen}: objects "
            f"{right}/{total}, tasks {tasks}; leave-one-task-out tasks {sum(held[r['task']] for r in group)}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", type=Path, action="append", default=[], help="a folder of tasks/, scenes/")
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--plans", action="store_true", help="also run the default planner's decisions")
    parser.add_argument(
        "--no-letters", action="store_true", help="only the planner's decisions (with --plans)"
    )
    args = parser.parse_args(argv)
    settings = load_settings()
    out: Path = args.out or Path(f"results/parts/sort-{settings.llm.split(':', 1)[-1]}.jsonl")
    system = build_system(settings, "conceptbot")
    llm = system.goal_planner.decider.llm  # type: ignore[attr-defined]
    done = {}
    if out.exists():
        done = {r["task"]: r for r in map(json.loads, out.read_text(encoding="utf-8").splitlines()) if r}
    todo = items([*args.tasks, DEV])  # the given folders first: dev last
    started = time.perf_counter()
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("a", encoding="utf-8") as sink:
        for number, item in enumerate(todo, 1):
            record = done.get(item["task"])
            if record is not None and ("planned" in record or not args.plans):
                continue
            if record is None:
                readings = (
                    {}
                    if args.no_letters
                    else {o: ask(llm, item["request"], item["places"], o) for o in item["allowed"]}
                )
                record = {**item, "readings": readings}
            if args.plans:
                folder = "dev" if item["folder"] == str(DEV) else item["folder"]
                record["planned"] = planned(system, item, folder)
            done[item["task"]] = record
            sink.write(json.dumps(record) + "\n")
            sink.flush()
            print(f"{number}/{len(todo)} {time.perf_counter() - started:.0f} s", file=sys.stderr)
    records = [done[i["task"]] for i in todo if i["task"] in done]
    report_letters([r for r in records if r["readings"]])
    if any("planned" in r for r in records):
        report_plans(records)
    return 0


def report_letters(records: Sequence[dict]) -> None:
    """The lettered choice: the best letter, and with a leave-one-task-out offset on "leave it"."""
    right, total, tasks = score(records, 0.0)
    print(f"{len(records)} sort tasks, {total} objects")
    print(f"best letter: objects {right}/{total}, tasks all right {tasks}/{len(records)}")
    held = 0
    for n, record in enumerate(records):
        others = records[:n] + records[n + 1 :]
        chosen = max(OFFSETS, key=lambda o: (score(others, o)[0], -abs(o)))
        held += score([record], chosen)[2]
    chosen = max(OFFSETS, key=lambda o: (score(records, o)[0], -abs(o)))
    right, total, tasks = score(records, chosen)
    print(
        f"'leave it' offset {chosen}: objects {right}/{total}, tasks {tasks}; leave-one-task-out tasks {held}"
    )


if __name__ == "__main__":
    raise SystemExit(main())
