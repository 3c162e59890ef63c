"""Which question picks the object a need calls for? Measured on the judgement set's ``need`` rows
(156 objects in 39 groups, each a request such as "I can't make out this tiny print" and the
objects asked about it), asked the way the goal planner can ask them: with the request's words only
(the rows' human-written criterion, "helps me read tiny print", is what the planner does not have).

Readings, each per group (one calibration question per group, as in the planner):

* ``move``: the planner's question, "to do what the person asked, should the robot give the X to
  the user?", with the object's graph facts (the default system);
* ``move_plain``: the same without graph facts (the no-graph ablation);
* ``names``: the name ranking, "which object should the robot give to the user?" over the group's
  objects, against a neutral request (``Decider.name_scores``);
* ``help``: "would the X help with what the person said?" (``prompts/help_user.txt``, no graph
  facts; ``Decider.helps``);
* ``use``: no model; the highest cosine between the request and what the graph states the object
  is for (its ``UsedFor`` and ``CapableOf`` edges and its gloss; ``FactFinder.uses``).

For each reading and for rankings that add readings (each standardised within its group), the
script prints the AUC of those scores, pooled over the groups, and how often the group's best
object is one the gold accepts (top-1; what a target taking one object gets). Readings are
appended to the output file as they come and read back on a rerun (resumable).

``--scenes`` asks the same about the dev tasks that want one object for a need or a kind of thing
("I can't make out this tiny print", "something to write with"), over every pickable object of
the task's scene (9 to 12; the judgement set's groups hold 3 to 7), with the objects the gold
accepts as the answer: nearer to what the planner faces.

    .venv/bin/python benchmarks/bench_need_questions.py [--scenes] \
        [--out results/parts/need-questions-MODEL.jsonl]
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import time
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path

from conceptbot.core.config import load_settings
from conceptbot.core.scene import Scene
from conceptbot.pipeline.goal_planner.decide import Decider
from conceptbot.systems import build_system

SET = Path("benchmarks/data/judgement_set.jsonl")
DEV = Path("src/conceptbot/bench/dev")
MOVE = re.compile(r"^pick_and_place\((.+), user\)$")
READINGS = ("move", "move_plain", "names", "help", "use")
RANKINGS: dict[str, dict[str, float]] = {
    "move + names (shipped)": {"move": 1.0, "names": 1.0},
    "move_plain + names (no-graph shipped)": {"move_plain": 1.0, "names": 1.0},
    "help + names": {"help": 1.0, "names": 1.0},
    "move + help + names": {"move": 1.0, "help": 1.0, "names": 1.0},
    "move + names + use": {"move": 1.0, "names": 1.0, "use": 1.0},
    "move + names + 0.5 use": {"move": 1.0, "names": 1.0, "use": 0.5},
    "help + names + 0.5 use": {"help": 1.0, "names": 1.0, "use": 0.5},
    "help + names + use": {"help": 1.0, "names": 1.0, "use": 1.0},
    "help + 0.5 names": {"help": 1.0, "names": 0.5},
    "move + help": {"move": 1.0, "help": 1.0},
    "move_plain + names + 0.5 use": {"move_plain": 1.0, "names": 1.0, "use": 0.5},
    "move_plain + names + use": {"move_plain": 1.0, "names": 1.0, "use": 1.0},
    "move_plain + 0.5 use": {"move_plain": 1.0, "use": 0.5},
    "help + 0.5 use": {"help": 1.0, "use": 0.5},
    "help + 0.5 names + 0.5 use": {"help": 1.0, "names": 0.5, "use": 0.5},
    "move_plain + help + names": {"move_plain": 1.0, "help": 1.0, "names": 1.0},
    "move_plain + help + names + use": {"move_plain": 1.0, "help": 1.0, "names": 1.0, "use": 1.0},
}


def scene_rows() -> list[dict]:
    """One row per pickable object of each dev implicit or ambiguous task whose gold is one object
    (or one of a few) given to the user, in the judgement set's shape (``kind`` "need")."""
    rows = []
    for category in ("implicit", "ambiguous"):
        for task in json.loads((DEV / "tasks" / f"{category}.json").read_text(encoding="utf-8")):
            gold = task["gold"]
            if gold["type"] == "any_of" and all(len(plan) == 1 for plan in gold["plans"]):
                found = [MOVE.match(plan[0]) for plan in gold["plans"]]
                accepted = {m.group(1) for m in found if m}
            elif gold["type"] == "assign" and len(gold["assign"]) == 1 and not gold.get("choose"):
                # the object the plan must give: an optional one may come too, but alone fails
                accepted = {o for o, places in gold["assign"].items() if "user" in places}
            else:
                continue
            if not accepted:
                continue
            scene = json.loads((DEV / "scenes" / f"{task['scene']}.json").read_text(encoding="utf-8"))
            for obj in scene["pickable_objects"]:
                rows.append(
                    {"object": obj, "criterion": "", "kind": "need", "answer": obj in accepted}
                    | {"request": task["request"], "source": task["id"]}
                )
    return rows


def groups_of(rows: Sequence[dict]) -> dict[str, list[dict]]:
    """The need rows by request, in file order."""
    found: dict[str, list[dict]] = defaultdict(list)
    for row in rows:
        if row["kind"] == "need":
            found[row["request"]].append(row)
    return dict(found)


def standardised(values: Sequence[float]) -> list[float]:
    """Each value as standard deviations from the group's mean (0 for a missing one)."""
    values = [math.nan if v is None else v for v in values]
    known = [v for v in values if math.isfinite(v)]
    if len(known) < 2:
        return [0.0] * len(values)
    mean = sum(known) / len(known)
    spread = math.sqrt(sum((v - mean) ** 2 for v in known) / len(known)) or 1.0
    return [(v - mean) / spread if math.isfinite(v) else 0.0 for v in values]


def auc(positive: Sequence[float], negative: Sequence[float]) -> float:
    """P(a positive scores above a negative), ties half."""
    pairs = [(p > n) + 0.5 * (p == n) for p in positive for n in negative]
    return sum(pairs) / len(pairs) if pairs else float("nan")


def report(groups: dict[str, list[dict]], weights: dict[str, float]) -> tuple[float, int]:
    """The AUC (pooled over groups) and top-1 hits of the weighted sum of standardised readings."""
    positive: list[float] = []
    negative: list[float] = []
    hits = 0
    for rows in groups.values():
        total = [0.0] * len(rows)
        for reading, weight in weights.items():
            for i, z in enumerate(standardised([r[reading] for r in rows])):
                total[i] += weight * z
        for row, score in zip(rows, total, strict=True):
            (positive if row["answer"] else negative).append(score)
        hits += rows[max(range(len(rows)), key=lambda i: total[i])]["answer"]
    return auc(positive, negative), hits


def read_group(
    request: str, objects: list[str], graph: Decider, plain: Decider
) -> dict[str, dict[str, float]]:
    """Every reading of one group's objects."""
    scene = Scene(objects=(), name="judgement-set")
    move = "give the {object} to the user"
    found: dict[str, dict[str, float]] = {o: {} for o in objects}
    for label, decider in (("move", graph), ("move_plain", plain)):
        judgements, _, _ = decider.moves(request, "user", move, objects, scene)
        for j in judgements:
            found[j.subject][label] = j.score
    names, _ = graph.name_scores(request, "give to the user", objects)
    for obj, score in names.items():
        found[obj]["names"] = score
    helps, _ = graph.helps(request, objects)
    for j in helps:
        found[j.subject]["help"] = j.score
    for obj, (similarity, _) in graph.facts.uses(objects, request).items():
        found[obj]["use"] = similarity
    return found


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--scenes", action="store_true", help="the dev tasks' scenes (see above)")
    args = parser.parse_args(argv)
    settings = load_settings()
    systems = [build_system(settings, name) for name in ("conceptbot", "nokg")]
    graph, plain = (s.goal_planner.decider for s in systems)  # type: ignore[attr-defined]
    model = settings.llm.split(":", 1)[-1]
    out: Path = args.out or Path(
        f"results/parts/need-questions{'-scenes' if args.scenes else ''}-{model}.jsonl"
    )
    rows = [json.loads(line) for line in SET.read_text(encoding="utf-8").splitlines() if line.strip()]
    if args.scenes:
        rows = scene_rows()
    done = {}
    if out.exists():
        done = {(r["request"], r["object"]): r for r in map(json.loads, out.read_text().splitlines())}
    groups = groups_of(rows)
    started = time.perf_counter()
    with out.open("a", encoding="utf-8") as sink:
        for number, (request, members) in enumerate(groups.items(), 1):
            if all((request, r["object"]) in done for r in members):
                continue
            objects = list(dict.fromkeys(r["object"] for r in members))
            found = read_group(request, objects, graph, plain)
            for row in members:
                record = {
                    **{k: row[k] for k in ("object", "criterion", "answer", "request", "source")},
                    **{k: round(v, 4) if math.isfinite(v) else None for k, v in found[row["object"]].items()},
                }
                done[(request, row["object"])] = record
                sink.write(json.dumps(record) + "\n")
            sink.flush()
            print(f"{number}/{len(groups)} groups, {time.perf_counter() - started:.0f} s", file=sys.stderr)
    read = groups_of(
        [{**done[(r["request"], r["object"])], "kind": "need"} for r in rows if r["kind"] == "need"]
    )
    print(f"{sum(len(g) for g in read.values())} need rows in {len(read)} groups ({model})")
    print(f"{'reading or ranking':42} {'AUC':>6} {'top-1':>7}")
    for reading in READINGS:
        score, hits = report(read, {reading: 1.0})
        print(f"{reading:42} {score:6.3f} {hits:3d}/{len(read)}")
    for name, weights in RANKINGS.items():
        score, hits = report(read, weights)
        print(f"{name:42} {score:6.3f} {hits:3d}/{len(read)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
