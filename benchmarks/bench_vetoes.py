"""How the graph's hazard vetoes (pipeline/hazards.py) agree with the dev split's gold, with no model.

For every dev task, each move the gold accepts that hands an object to a child or an animal is a
move the veto must let through (a veto there is a false veto), and each object a ``refuse`` task's
request names for a child or an animal should be vetoed (a true veto; OPE's ratings and the risk
question cover what the graph does not state). Run on the dev split only: the test split is for
reporting, not for choosing words.

    .venv/bin/python benchmarks/bench_vetoes.py            # needs the offline graph (kg install)
"""

from __future__ import annotations

from conceptbot.bench.grading import load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.knowledge.registry import open_graph
from conceptbot.pipeline.hazards import HazardCheck, is_vulnerable


def _gold_moves(gold: dict) -> set[tuple[str, str]]:
    moves: set[tuple[str, str]] = set()
    for plan in gold.get("plans", []):
        for action in plan:
            obj, target = action[len("pick_and_place(") : -1].split(", ")
            moves.add((obj, target))
    for obj, targets in {**gold.get("assign", {}), **gold.get("optional", {})}.items():
        moves |= {(obj, t) for t in targets}
    for choice in gold.get("choose", []):
        moves |= {(o, t) for o, ts in choice.get("objects", {}).items() for t in ts}
    return moves


def main() -> None:
    check = HazardCheck(open_graph(load_settings(), fallback=False))
    allowed = vetoed_allowed = refused_named = vetoed_refused = 0
    for task in load_tasks(split="dev"):
        scene = task_scene(task)
        gold = task.gold
        if gold["type"] == "refuse":
            request = task.request.lower()
            people = [d for d in scene.destinations if is_vulnerable(d)]
            for obj in (o for o in scene.pickable if o.lower() in request):
                for person in people:
                    refused_named += 1
                    veto = check.veto(obj, person, {})
                    vetoed_refused += veto is not None
                    print(f"{task.id}: refuse {obj} -> {person}: {veto.statement if veto else 'no veto'}")
            continue
        for obj, target in sorted(_gold_moves(gold)):
            if not is_vulnerable(target):
                continue
            allowed += 1
            veto = check.veto(obj, target, {})
            if veto is not None:
                vetoed_allowed += 1
                print(f"{task.id}: FALSE VETO {obj} -> {target}: {veto.statement}")
    print(f"gold hand-overs to a child or an animal: {allowed}, vetoed by the graph: {vetoed_allowed}")
    named = f"objects refuse tasks name for a child or an animal: {refused_named}"
    print(f"{named}, vetoed by the graph: {vetoed_refused}")


if __name__ == "__main__":
    main()
