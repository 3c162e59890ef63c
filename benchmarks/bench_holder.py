"""Who holds what a request hands over: the adult speaking, or a child or an animal?

Measured on ``benchmarks/data/holder_set.jsonl``: every dev and blind-set-1 request whose gold hands
something to a person or an animal (or refuses a hand-over), labelled ``vulnerable`` where the
hand-over goes to a child or an animal ("My four-year-old wants to help: hand him the craft
knife", in a scene whose only person is the user). Each request is asked
:meth:`~conceptbot.pipeline.goal_planner.decide.Decider.holder` (one yes/no, calibrated against a
hand-over to the speaker); the script prints the AUC, and the accuracy at the shipped threshold
(``Thresholds.holder``) and at the threshold chosen leave-one-out.

    .venv/bin/python benchmarks/bench_holder.py [--out results/parts/holder-MODEL.jsonl]
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path

from conceptbot.core.config import load_settings
from conceptbot.pipeline.goal_planner.planner import Thresholds
from conceptbot.systems import build_system

DATA = Path("benchmarks/data/holder_set.jsonl")


def auc(rows: list[dict]) -> float:
    """The chance that a vulnerable hand-over scores above an adult one (ties count a half)."""
    pos = [r["score"] for r in rows if r["vulnerable"]]
    neg = [r["score"] for r in rows if not r["vulnerable"]]
    pairs = [(p > n) + 0.5 * (p == n) for p in pos for n in neg]
    return sum(pairs) / len(pairs)


def right(rows: list[dict], limit: float) -> int:
    """Rows decided right when a score above ``limit`` means a child or an animal."""
    return sum((r["score"] > limit) == r["vulnerable"] for r in rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    settings = load_settings()
    out: Path = args.out or Path(f"results/parts/holder-{settings.llm.split(':', 1)[-1]}.jsonl")
    decider = build_system(settings, "conceptbot").goal_planner.decider  # type: ignore[attr-defined]
    rows = []
    for line in DATA.read_text(encoding="utf-8").splitlines():
        row = json.loads(line)
        judgement, _ = decider.holder(row["request"])
        rows.append({**row, "score": round(judgement.score, 4)})
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("".join(json.dumps(r) + "\n" for r in rows), encoding="utf-8")
    limits = sorted({r["score"] for r in rows})
    cuts = [(a + b) / 2 for a, b in itertools.pairwise(limits)] or [0.0]
    held = 0
    for n, row in enumerate(rows):
        others = rows[:n] + rows[n + 1 :]
        best = max(cuts, key=lambda c: (right(others, c), -abs(c)))
        held += right([row], best)
    shipped = Thresholds().holder
    vulnerable = sum(r["vulnerable"] for r in rows)
    print(f"{len(rows)} requests, {vulnerable} handing to a child or an animal; AUC {auc(rows):.3f}")
    print(f"right at the shipped threshold {shipped}: {right(rows, shipped)}/{len(rows)}")
    print(f"right at a leave-one-out threshold: {held}/{len(rows)}")
    best = max(cuts, key=lambda c: (right(rows, c), -abs(c)))
    print(f"best threshold on all: {best:.2f} ({right(rows, best)}/{len(rows)})")
    for r in sorted(rows, key=lambda r: -r["score"]):
        print(f"{r['score']:+.2f} {'V' if r['vulnerable'] else ' '} {r['request'][:80]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
