"""Does the model tell a move that needs a mat under it? Measured on ``benchmarks/data/underlay_set.jsonl``
(our own 34 rows, none from the test split: a request, the object moved, its state, the place, a mat or
stand in the scene, and whether a careful person puts the mat down first), asked the way the goal
planner asks (``Decider.underneath``), in two wordings:

* ``hot``: "is the casserole dish too hot to put straight on the dining table?"
  (``prompts/underlay_user.txt``, the planner's);
* ``pad``: "should the robot put the cork mat on the dining table first and the casserole dish on the
  cork mat, to protect the dining table?" (``prompts/underlay_pad_user.txt``).

* ``damage``: "would the heat of the casserole dish damage the dining table if ...?"
  (``prompts/underlay_damage_user.txt``).

Each score is the log-odds of Yes against a content-free object's. The script prints, per wording,
the AUC, and how many rows are right by the score above each margin, by P(Yes) above each floor,
and by P(Yes) above each floor where the graph makes the place a surface heat can mark
(``FactFinder.is_surface``; the planner's rule: that, and P(Yes) above ``Thresholds.underlay``).

    .venv/bin/python benchmarks/bench_underlay.py
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from conceptbot.core.config import load_settings
from conceptbot.systems import build_system

SET = Path("benchmarks/data/underlay_set.jsonl")
#: 12 more rows written after the rule was chosen on SET, and measured once with it (not tuned on).
HELD_OUT = Path("benchmarks/data/underlay_heldout.jsonl")
WORDINGS = {"hot": "underlay_user", "damage": "underlay_damage_user", "pad": "underlay_pad_user"}


def auc(scores: list[float], labels: list[bool]) -> float:
    """The chance that a positive row scores above a negative one (ties count half)."""
    pos = [s for s, y in zip(scores, labels, strict=True) if y]
    neg = [s for s, y in zip(scores, labels, strict=True) if not y]
    wins = sum((p > n) + 0.5 * (p == n) for p in pos for n in neg)
    return wins / (len(pos) * len(neg))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--set", type=Path, default=SET, help=f"the labelled moves (default {SET}; held out: {HELD_OUT})"
    )
    args = parser.parse_args()
    rows = [json.loads(line) for line in args.set.read_text(encoding="utf-8").splitlines() if line.strip()]
    decider = build_system(load_settings(), "conceptbot").goal_planner.decider  # type: ignore[attr-defined]
    facts = decider.facts
    labels = [bool(r["label"]) for r in rows]
    for name, template in WORDINGS.items():
        scores, probs = [], []
        for r in rows:
            j, _ = decider.underneath(r["request"], r["object"], r["state"], r["place"], r["pad"], template)
            scores.append(j.score)
            probs.append(j.p_yes)
        line = [f"{name:4s} AUC {auc(scores, labels):.3f}"]
        for margin in (0.0, 0.5, 1.0):
            right = sum((s > margin) == y for s, y in zip(scores, labels, strict=True))
            line.append(f"score>{margin}: {right}/{len(rows)}")
        for floor in (0.4, 0.5):
            right = sum((p > floor) == y for p, y in zip(probs, labels, strict=True))
            line.append(f"P>{floor}: {right}/{len(rows)}")
        gated = [facts.is_surface(r["place"]) for r in rows]
        for floor in (0.4, 0.5):
            right = sum((g and p > floor) == y for g, p, y in zip(gated, probs, labels, strict=True))
            line.append(f"surface & P>{floor}: {right}/{len(rows)}")
        print("  ".join(line))
        for r, s, p in zip(rows, scores, probs, strict=True):
            sign = "+" if r["label"] else "-"
            print(f"    {sign} {s:6.2f} {p:.2f} {r['object']} ({r['state']}) on {r['place']}, {r['pad']}")


if __name__ == "__main__":
    main()
