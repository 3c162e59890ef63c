"""Are two things used together, or is either enough? Measured on a labelled set of pairs, and the
shipped combination fitted.

The set (``benchmarks/data/together_set.jsonl``, 46 pairs written for it, none of the paper's
objects) holds a need, the object a planner would give first, another object that also helps, and
whether the person needs both ("I want to brush my teeth": toothbrush and toothpaste, yes; "I'm
thirsty": juice box and bottle of water, no). Half the pairs are the ``tune`` round, half ``held``.

For each pair: the model's raw log-odds of Yes to "would they also need the X, used together with
the Y?" (:meth:`Decider.together`) and whether the graph links the two by use rather than by kind
(:func:`companions.graph_link`). A logistic fit on the tune round, with and without the graph's
link, is measured on the held round (accuracy at one half, log-loss, AUC); ``--write`` ships the
tune round's fits (``src/conceptbot/pipeline/companion_weights.json``: ``graph`` for the default
system, ``nograph`` for the ablation).

    .venv/bin/python benchmarks/bench_together.py [--write]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from conceptbot.core.config import load_settings
from conceptbot.pipeline.goal_planner.companions import graph_link
from conceptbot.systems import build_system
from fit_judgements import fit  # the same Newton fit as the judgement set's combination

SET = Path("benchmarks/data/together_set.jsonl")
WEIGHTS = Path("src/conceptbot/pipeline/companion_weights.json")
L2 = 0.1  # a little shrinkage: 24 pairs per round


def fit_rows(rows: list[tuple[list[float], bool]]) -> list[float]:
    """The logistic fit of ``fit_judgements`` (Newton, L2 on the weights only), intercept first."""
    weights, bias = fit(np.array([x for x, _ in rows]), np.array([float(y) for _, y in rows]), l2=L2)
    return [bias, *weights.tolist()]


def measure(w: list[float], rows: list[tuple[list[float], bool]]) -> tuple[float, float, float]:
    """Accuracy at one half, mean log-loss and AUC of the fit ``w`` on ``rows``."""
    scored = []
    for x, y in rows:
        z = w[0] + sum(a * b for a, b in zip(w[1:], x, strict=True))
        scored.append((1.0 / (1.0 + math.exp(-z)), y))
    accuracy = sum((p > 0.5) == y for p, y in scored) / len(scored)
    loss = -sum(math.log(p if y else 1 - p) for p, y in scored) / len(scored)
    pos = [p for p, y in scored if y]
    neg = [p for p, y in scored if not y]
    auc = sum((a > b) + 0.5 * (a == b) for a in pos for b in neg) / (len(pos) * len(neg))
    return accuracy, loss, auc


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", action="store_true", help="ship the tune round's fits")
    args = parser.parse_args(argv)
    pairs = [json.loads(line) for line in SET.read_text(encoding="utf-8").splitlines() if line.strip()]
    system = build_system(load_settings(), "conceptbot")
    decider = system.goal_planner.decider  # type: ignore[attr-defined]
    graph = decider.facts.retriever.graph
    started = time.perf_counter()
    read = []
    for n, pair in enumerate(pairs, start=1):
        print(f"\r{n}/{len(pairs)} pairs", end="", file=sys.stderr, flush=True)
        (answer,), _ = decider.together(pair["need"], pair["first"], [pair["other"]])
        linked, statement = graph_link(graph, pair["first"], pair["other"])
        read.append((pair, answer.score, linked, statement))
    print(f"\n{len(pairs)} pairs read in {time.perf_counter() - started:.0f} s", file=sys.stderr)
    print("| pair | round | together | model log-odds | graph link |")
    print("|---|---|---|---|---|")
    for pair, score, linked, statement in read:
        said = f"yes: {statement}" if linked else "no"
        print(
            f"| {pair['first']} + {pair['other']} | {pair['round']} | {pair['together']} | "
            f"{score:+.2f} | {said} |"
        )
    forms = {"nograph": lambda s, g: [s], "graph": lambda s, g: [s, 1.0 if g else 0.0]}
    fits: dict[str, list[float]] = {}
    print("\n| fit | features | trained on | measured on | accuracy | log-loss | AUC |")
    print("|---|---|---|---|---|---|---|")
    for name, features in forms.items():
        for train, test in (("tune", "held"), ("held", "tune")):
            rows = {
                r: [(features(s, g), p["together"]) for p, s, g, _ in read if p["round"] == r]
                for r in ("tune", "held")
            }
            w = fit_rows(rows[train])
            if train == "tune":
                fits[name] = w
            accuracy, loss, auc = measure(w, rows[test])
            what = "model" if name == "nograph" else "model + graph link"
            print(f"| {name} | {what} | {train} | {test} | {accuracy:.1%} | {loss:.3f} | {auc:.3f} |")
    for name, w in fits.items():
        print(
            f"{name} (tune): intercept {w[0]:+.3f}, model {w[1]:+.3f}"
            + (f", graph {w[2]:+.3f}" if len(w) > 2 else "")
        )
    if args.write:
        out = {
            name: {
                "intercept": round(w[0], 4),
                "model": round(w[1], 4),
                "graph": round(w[2], 4) if len(w) > 2 else 0.0,
                "considered": 2,
                "fitted_on": f"{SET.name} tune round ({sum(p['round'] == 'tune' for p in pairs)} pairs)",
            }
            for name, w in fits.items()
        }
        WEIGHTS.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {WEIGHTS}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
