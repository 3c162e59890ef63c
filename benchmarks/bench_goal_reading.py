"""How often a request's goal is read exactly right by the goal reader (``pipeline/goal``) on the goal
set (``benchmarks/data/goal_set.json``: the dev requests and rounds of hand-written paraphrases).
No model is run.

Exact match is :func:`conceptbot.pipeline.goal.same_goal`: same stack, dish and need-presence, and the
same targets (destination, kind, named objects, count, criterion words). A second figure ignores the
criterion's words (the goal's structure only). The word-rule reader it was once compared with
(``TargetFinder.find``) was removed on 2026-12-06; its figures are in ``docs/planning.md``.

    .venv/bin/python benchmarks/bench_goal_reading.py [--failures | --no-failures] [--no-graph]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from conceptbot.bench.grading import load_dev_scene
from conceptbot.core.config import load_settings
from conceptbot.knowledge.registry import open_graph
from conceptbot.models.registry import open_embedder
from conceptbot.pipeline.goal import Goal, GoalReader, same_goal
from conceptbot.pipeline.goal.compare import structure
from conceptbot.pipeline.goal_planner.decide import FactFinder
from conceptbot.pipeline.retrieval import RelationRetriever, default_theta

GOAL_SET = Path(__file__).parent / "data" / "goal_set.json"


def graph_reader() -> GoalReader:
    """The goal reader as ``conceptbot plan`` builds it: the installed graph tells dishes."""
    settings = load_settings()
    graph = open_graph(settings, fallback=False)
    embedder = open_embedder(settings, None)
    facts = FactFinder(RelationRetriever(graph, embedder, default_theta(embedder.model)))
    return GoalReader(is_dish=facts.may_be_dish)


def main() -> None:
    """Print the figures and the failures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--failures", action=argparse.BooleanOptionalAction, default=True)
    parser.add_argument(
        "--no-graph",
        action="store_true",
        help="read without the graph's dish checks (the no-graph ablation's reader, and the tests')",
    )
    args = parser.parse_args()
    rows = json.loads(GOAL_SET.read_text(encoding="utf-8"))["requests"]
    reader = GoalReader() if args.no_graph else graph_reader()
    print(f"goal reader {'without' if args.no_graph else 'with'} the graph's dish checks\n")
    tally: dict[str, list[int]] = {}
    failures: list[str] = []
    for row in rows:
        scene = load_dev_scene(row["scene"])
        gold = Goal.from_dict(row["goal"])
        group = row["split"] if row["split"] == "original" else f"paraphrase round {row['round']}"
        read = reader.read(row["request"], scene)
        match = same_goal(read, gold)
        counts = tally.setdefault(group, [0, 0, 0])
        counts[0] += match.ok
        counts[1] += same_goal(structure(read), structure(gold)).ok
        counts[2] += 1
        if not match.ok:
            failures.append(
                f"{row['task']} [{group}] {row['request']}\n    {match.reason}\n"
                f"    read: {json.dumps(read.to_dict())}\n    gold: {json.dumps(gold.to_dict())}"
            )
    _report(tally)
    if args.failures:
        print(f"\nFailures of the goal reader ({len(failures)}):")
        print("\n".join(failures) or "  none")


def _report(tally: dict[str, list[int]]) -> None:
    # "original" first, then the rounds by number ("round 10" after "round 9")
    groups = sorted(tally, key=lambda g: (g != "original", int(g.split()[-1]) if g[-1].isdigit() else 0))
    print(f"{'':20} | {'exact':^15} {'structure':>11}")

    def line(name: str, picks: list[str]) -> None:
        ok = sum(tally[g][0] for g in picks)
        shape = sum(tally[g][1] for g in picks)
        n = sum(tally[g][2] for g in picks)
        print(f"{name:20} | {ok:>3}/{n:<3} {100 * ok / n:5.1f}% {100 * shape / n:10.1f}%")

    for group in groups:
        line(group, [group])
    line("paraphrases, all", [g for g in groups if g != "original"])


if __name__ == "__main__":
    main()
