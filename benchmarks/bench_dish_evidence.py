"""What the offline graph says about "is the X an ingredient of the dish?", read without the model
(:meth:`conceptbot.pipeline.goal_planner.evidence.GraphEvidence.read`, the ``dish_yes`` and
``dish_no`` features the combination weighs beside the model's answer).

Two labelled sets: the judgement set's ingredient rows (``benchmarks/data/judgement_set.jsonl``, the
dev set the rules were written on) and ``benchmarks/data/ingredient_heldout.jsonl`` (76 rows, 13
dishes none of the judgement set's, each object labelled before the graph was read: containers named
by their contents, "milk carton", "vinegar bottle", tableware, "coffee mug", "wine glass", and
sauces that are not the dish's). Per set, how often the graph states Yes (the dish's gloss or
``MadeOf`` edges name the object; "half": they name one of its kinds), No (they exist and do not name
it) or nothing, against the label, and how often a statement is right.

    .venv/bin/python benchmarks/bench_dish_evidence.py [--show-wrong]
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path

from conceptbot.core.config import load_settings
from conceptbot.knowledge.registry import open_graph
from conceptbot.pipeline.goal_planner.evidence import Evidence, GraphEvidence

SETS = (Path("benchmarks/data/judgement_set.jsonl"), Path("benchmarks/data/ingredient_heldout.jsonl"))
STATES = ("yes", "half", "no", "silent")


def state(evidence: Evidence) -> str:
    """What the graph states: ``yes``, ``half`` (a kind of the object is named), ``no`` or ``silent``."""
    found = evidence.features
    if found["dish_yes"] >= 1.0:
        return "yes"
    if found["dish_yes"] > 0.0:
        return "half"
    return "no" if found["dish_no"] else "silent"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--show-wrong", action="store_true", help="list the rows where a statement is wrong")
    args = parser.parse_args()
    evidence = GraphEvidence(open_graph(load_settings(), fallback=False))
    print(f"{'set':<28}{'rows':>6}" + "".join(f"{s + ' T/F':>12}" for s in STATES) + f"{'stated right':>16}")
    for path in SETS:
        rows = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]
        rows = [r for r in rows if r["kind"] == "ingredient"]
        counts: Counter[tuple[str, bool]] = Counter()
        wrong = []
        for row in rows:
            found = state(evidence.read(row["object"], row["criterion"]))
            counts[(found, row["answer"])] += 1
            if found != "silent" and (found == "no") == row["answer"]:
                wrong.append(f"  {found:>4}  {row['object']} | {row['criterion']} | label {row['answer']}")
        stated = sum(n for (s, _), n in counts.items() if s != "silent")
        right = stated - len(wrong)
        cells = "".join(f"{counts[(s, True)]:>7}/{counts[(s, False)]:<4}" for s in STATES)
        share = f"{right}/{stated} ({100 * right / stated:.0f}%)" if stated else "-"
        print(f"{path.name:<28}{len(rows):>6}{cells}{share:>16}")
        if args.show_wrong:
            print("\n".join(wrong))


if __name__ == "__main__":
    main()
