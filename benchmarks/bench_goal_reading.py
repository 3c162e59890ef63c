"""How often a request's goal is read exactly right: the goal reader (``pipeline/goal``) and today's
``TargetFinder`` (``pipeline/goal_planner/targets.py``) on the goal set
(``benchmarks/data/goal_set.json``: the dev requests and rounds of hand-written paraphrases).
No model is run.

Exact match is :func:`conceptbot.pipeline.goal.same_goal`: same stack, dish and need-presence, and the
same targets (destination, kind, named objects, count, criterion words). A second figure ignores the
criterion's words (the goal's structure only), since ``TargetFinder`` keeps no criterion for a
target taking a number ("something to write with"): the planner asks about the whole request.

How ``TargetFinder``'s targets become a goal:

* It gets a fake LLM (``conceptbot.models.fake.FakeLLM``) that scores every destination the same;
  a target it chose by scoring (``how="scored"``) is compared with ``to`` null, as the goal leaves
  such a choice to the planner; which place the scores would pick is not what is measured here.
* It gets an oracle for food (``FoodKnowledge``): the dish of the row's gold goal, as the graph
  would give it at best, so that its failures are about the request's structure.
* A target of the speaker's with nothing named is a need (its ``user`` is the planner's choice);
  ``ingredients`` is a dish's ingredients; named objects, when it takes just those, are ``named``;
  the criterion "belongs in the X" (a place in a sort) is ``""``; a target taking all with no
  criterion takes ``all``; a stacking request is a pile of everything.

    .venv/bin/python benchmarks/bench_goal_reading.py [--failures reader|finder|both|none]
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path

from conceptbot.bench.grading import load_dev_scene
from conceptbot.core.config import load_settings
from conceptbot.core.scene import Scene
from conceptbot.knowledge.registry import open_graph
from conceptbot.models.fake import FakeLLM
from conceptbot.models.registry import open_embedder
from conceptbot.pipeline.goal import ALL as GOAL_ALL
from conceptbot.pipeline.goal import Goal, GoalReader, GoalTarget, same_goal
from conceptbot.pipeline.goal.compare import structure
from conceptbot.pipeline.goal_planner.decide import FactFinder
from conceptbot.pipeline.goal_planner.targets import ALL, Target, TargetFinder, is_stacking
from conceptbot.pipeline.hazards import is_person
from conceptbot.pipeline.retrieval import RelationRetriever, default_theta

GOAL_SET = Path(__file__).parent / "data" / "goal_set.json"


class OracleFood:
    """``FoodKnowledge`` that knows the row's dish (and no cookware: every place is a candidate)."""

    def __init__(self, dish: str | None) -> None:
        self._dish = dish

    def dish(self, request: str, pickable: Sequence[str]) -> str | None:
        return self._dish

    def prep_places(self, destinations: Sequence[str]) -> list[str]:
        return []


def finder_goal(request: str, scene: Scene, dish: str | None) -> Goal:
    """Today's reading of ``request`` as a goal (see the module docstring)."""
    if is_stacking(request):
        return Goal(True, None, None, (GoalTarget(None, "all"),))
    llm = FakeLLM(scores=[[-1.0, -1.0]] * (2 * len(scene.destinations)))
    targets, _ = TargetFinder(llm, is_person, food=OracleFood(dish)).find(request, scene)
    goal_targets = [_as_goal_target(t) for t in targets]
    need = request if any(t.takes == "need" for t in goal_targets) else None
    found_dish = next((t.dish for t in targets if t.dish), None)
    return Goal(False, found_dish, need, tuple(goal_targets))


def _as_goal_target(target: Target) -> GoalTarget:
    to = None if target.how == "scored" else target.name
    count = GOAL_ALL if target.count == ALL else target.count
    named = tuple(target.named)
    if target.ingredients:
        return GoalTarget(None, "ingredients", named, "", GOAL_ALL)
    if target.how == "speaker" and not named:
        return GoalTarget(None, "need")
    if named and count == len(named):
        return GoalTarget(to, "named", named, "", count)
    if target.criterion.startswith("belongs in the "):
        return GoalTarget(to, "criterion", named, "", count)  # a place in a sort, by its name
    if count == GOAL_ALL and not target.criterion and not named:
        return GoalTarget(to, "all")
    criterion = target.criterion
    return GoalTarget(to, "criterion", named, criterion, count)


def graph_reader() -> GoalReader:
    """The goal reader as ``conceptbot plan`` builds it: the installed graph tells dishes."""
    settings = load_settings()
    graph = open_graph(settings, fallback=False)
    embedder = open_embedder(settings, None)
    facts = FactFinder(RelationRetriever(graph, embedder, default_theta(embedder.model)))
    return GoalReader(is_dish=facts.may_be_dish, find_dish=facts.dish_concept, same_kind=facts.same_kind)


def main() -> None:
    """Print the figures and the failures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--failures", choices=["reader", "finder", "both", "none"], default="both")
    parser.add_argument(
        "--no-graph",
        action="store_true",
        help="read without the graph's dish checks (the no-graph ablation's reader, and the tests')",
    )
    args = parser.parse_args()
    rows = json.loads(GOAL_SET.read_text(encoding="utf-8"))["requests"]
    reader = GoalReader() if args.no_graph else graph_reader()
    print(f"goal reader {'without' if args.no_graph else 'with'} the graph's dish checks\n")
    tally: dict[tuple[str, str], list[int]] = {}
    failures: dict[str, list[str]] = {"reader": [], "finder": []}
    for row in rows:
        scene = load_dev_scene(row["scene"])
        gold = Goal.from_dict(row["goal"])
        group = row["split"] if row["split"] == "original" else f"paraphrase round {row['round']}"
        reads = {
            "reader": reader.read(row["request"], scene),
            "finder": finder_goal(row["request"], scene, gold.dish),
        }
        for who, read in reads.items():
            match = same_goal(read, gold)
            shape = same_goal(structure(read), structure(gold))
            counts = tally.setdefault((who, group), [0, 0, 0])
            counts[0] += match.ok
            counts[1] += shape.ok
            counts[2] += 1
            if not match.ok:
                failures[who].append(
                    f"{row['task']} [{group}] {row['request']}\n    {match.reason}\n"
                    f"    read: {json.dumps(read.to_dict())}\n    gold: {json.dumps(gold.to_dict())}"
                )
    _report(tally)
    for who in ("reader", "finder"):
        if args.failures in (who, "both"):
            name = "goal reader" if who == "reader" else "TargetFinder"
            print(f"\nFailures of the {name} ({len(failures[who])}):")
            print("\n".join(failures[who]) or "  none")


def _report(tally: dict[tuple[str, str], list[int]]) -> None:
    # "original" first, then the rounds by number ("round 10" after "round 9")
    groups = sorted(
        {g for _, g in tally}, key=lambda g: (g != "original", int(g.split()[-1]) if g[-1].isdigit() else 0)
    )
    print(f"{'':20} | {'goal reader':^27} | {'TargetFinder':^27}")
    print(f"{'':20} | {'exact':^15} {'structure':>11} | {'exact':^15} {'structure':>11}")

    def line(name: str, picks: list[str]) -> None:
        cells = []
        for who in ("reader", "finder"):
            ok = sum(tally[(who, g)][0] for g in picks)
            shape = sum(tally[(who, g)][1] for g in picks)
            n = sum(tally[(who, g)][2] for g in picks)
            cells.append(f"{ok:>3}/{n:<3} {100 * ok / n:5.1f}% {100 * shape / n:10.1f}%")
        print(f"{name:20} | {cells[0]} | {cells[1]}")

    for group in groups:
        line(group, [group])
    line("paraphrases, all", [g for g in groups if g != "original"])


if __name__ == "__main__":
    main()
