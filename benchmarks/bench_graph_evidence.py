"""How often the offline graph states whether an object is poisonous, and how often it is right, on
the dev split's toxicity tasks, beside the default planner's own placements (no model is run).

Issue 33 asks whether the graph's statements, used as evidence rather than prompt text, can decide
what the 1.5B model gets wrong. Each object of a dev toxicity task is labelled by its gold
destination (the poisonous-things destination, or the food one; an object left where it is in a
task that moves only the poisonous things is not poisonous). The graph's verdict is the strongest
statement about the object itself (an exact or lemma match; a WordNet gloss only for a one-sense
word) that names poison ("poisonous", "toxic", ...) or food ("edible"); the planner's verdict is
where its committed dev run (``results/dev/records.jsonl``) put the object.

    .venv/bin/python benchmarks/bench_graph_evidence.py
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from conceptbot.bench.grading import load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.knowledge.base import KnowledgeGraph
from conceptbot.knowledge.registry import open_graph

POISON_DESTINATIONS = {
    "toxic tray", "discard bin", "locked cabinet", "high shelf",
    "balcony shelf", "disposal bin", "high cabinet",
}  # fmt: skip
FOOD_DESTINATIONS = {
    "edible tray",
    "cooking basket",
    "pantry basket",
    "kitchen basket",
    "windowsill",
    "cake plate",
}
POISON = ("poisonous", "poison", "toxic", "venomous", "deadly", "lethal")
FOOD = ("edible",)
NEGATIONS = ("not", "non", "no", "never", "inedible")
RELATIONS = ["HasProperty", "IsA", "DefinedAs"]
RUN = Path("results/dev/records.jsonl")


def labels() -> dict[tuple[str, str], bool]:
    """``(task, object) -> poisonous`` from the dev gold."""
    found: dict[tuple[str, str], bool] = {}
    for task in load_tasks(["toxic"], split="dev"):
        assign = task.gold.get("assign", {})
        places = {d for ds in assign.values() for d in ds}
        for obj, dests in assign.items():
            if set(dests) <= POISON_DESTINATIONS:
                found[(task.id, obj)] = True
            elif set(dests) <= FOOD_DESTINATIONS:
                found[(task.id, obj)] = False
        if places <= POISON_DESTINATIONS:  # only the poisonous things move: the rest are not
            optional = set(task.gold.get("optional", {}))
            for obj in task_scene(task).pickable:
                if obj not in assign and obj not in optional:
                    found[(task.id, obj)] = False
    return found


def graph_verdict(graph: KnowledgeGraph, obj: str, loose: bool = False) -> tuple[bool | None, str]:
    """True (poison), False (food) or None (the graph states neither), and the statement.

    ``loose`` also reads what a multi-word name's words match ("rhubarb leaves" -> ``leaf + rhubarb``:
    the edges of "rhubarb" and of "leaf"), as the retrieval does for prompts."""
    result = graph.edges(obj, RELATIONS, 100)
    if result.match not in ("exact", "lemma") and not loose:
        return None, f"({result.match} match)"
    if loose:
        parts = {p.strip().lower() for p in (result.matched or "").split("+")} | {obj.lower()}
        own = [e for e in result.edges if e.head.lower() in parts and e.weight > 0]
    else:
        heads = {obj.lower(), (result.matched or obj).lower()}
        own = [e for e in result.edges if e.head.lower() in heads and e.weight > 0]
    senses = sum(1 for e in own if e.source == "wordnet" and e.relation == "DefinedAs")
    for edge in own:  # strongest first
        if edge.source == "wordnet" and senses > 1:
            continue
        words = re.findall(r"[a-z]+", edge.tail.lower())
        if any(n in words for n in NEGATIONS):
            continue
        if any(w in words for w in POISON):
            return True, edge.sentence
        if any(w in words for w in FOOD):
            return False, edge.sentence
    return None, ""


def planner_verdicts() -> dict[tuple[str, str], bool]:
    """``(task, object) -> placed with the poisonous things`` from the default planner's dev run."""
    out: dict[tuple[str, str], bool] = {}
    if not RUN.exists():
        return out
    for line in RUN.read_text(encoding="utf-8").splitlines():
        record = json.loads(line)
        if record["config"] != "conceptbot" or record["category"] != "toxic":
            continue
        for action in record["plan"]:
            if action.startswith("pick_and_place("):
                obj, dest = action[len("pick_and_place(") : -1].split(", ")
                out[(record["task"], obj)] = dest in POISON_DESTINATIONS
    return out


def main() -> None:
    graph = open_graph(load_settings(), fallback=False)
    gold = labels()
    placed = planner_verdicts()
    stated = right = planner_right = planner_right_where_stated = 0
    loose_stated = loose_right = 0
    for (task, obj), poisonous in sorted(gold.items()):
        verdict, why = graph_verdict(graph, obj)
        mine = placed.get((task, obj), False)  # not moved: not with the poisonous things
        planner_right += mine == poisonous
        if verdict is not None:
            stated += 1
            right += verdict == poisonous
            planner_right_where_stated += mine == poisonous
        loose, _ = graph_verdict(graph, obj, loose=True)
        if loose is not None:
            loose_stated += 1
            loose_right += loose == poisonous
        mark = "-" if verdict is None else ("ok" if verdict == poisonous else "WRONG")
        theirs = "ok" if mine == poisonous else "WRONG"
        print(f"{task:12} {obj:22} poisonous={poisonous!s:5} graph={mark:5} planner={theirs:5} {why}")
    total = len(gold)
    print(f"\nlabelled objects: {total}; the planner (its committed dev run) right on {planner_right}")
    print(f"the graph states poison or food for {stated} ({stated / total:.0%}); right on {right} of them")
    print(f"on those {stated}, the planner was right on {planner_right_where_stated}")
    print(f"reading a multi-word name's words too: states {loose_stated}, right on {loose_right}")


if __name__ == "__main__":
    main()
