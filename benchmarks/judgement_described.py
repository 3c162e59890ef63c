"""A third reading of the judgement set: the model first says what it knows about the object, then
answers the same yes/no question with that sentence in it ("generated knowledge", Liu et al. 2022).

Why: where the offline graph states nothing about an object (411 of the 1028 rows), the decision
is the model's own answer, at 65-70%. A small model often says more about a thing when asked to
describe it than its Yes/No log-odds show. This measures whether that description, put back into
the question, answers better than the question alone.

Each object is described once (``Decider.describe``: greedy, one sentence: what it is, what it is
made of, whether it is safe to eat or touch); each row is then asked as ``judgement_readings.py``
asks it, without graph facts, with the description as the object's facts
(``decide.described_question``), calibrated against the content-free object (no description).
Written per row to ``--out`` with the description; a rerun goes on where it stopped. Read by
``fit_judgements.py --described FILE``.

    .venv/bin/python benchmarks/judgement_described.py [--kinds toxic,edible] [--limit N]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import defaultdict
from pathlib import Path

from conceptbot.pipeline.goal_planner.decide import described_question
from conceptbot.pipeline.goal_planner.evidence import criterion_terms

# The rows and the deciders are the plain readings' (a sibling script, not a package).
sys.path.insert(0, str(Path(__file__).resolve().parent))
from judgement_readings import deciders, key, load_rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--kinds", default="", help="comma-separated kinds (default: every kind)")
    parser.add_argument("--limit", type=int, default=0, help="read at most this many new rows")
    args = parser.parse_args(argv)
    _, plain_decider, model = deciders()
    out: Path = args.out or Path(f"results/parts/judgements-described-{model}.jsonl")
    done = {key(r) for r in load_rows(out)} if out.exists() else set()
    kinds = {k for k in args.kinds.split(",") if k}
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for row in load_rows():
        if key(row) not in done and (not kinds or row["kind"] in kinds):
            groups[(row["request"], row["criterion"])].append(row)
    todo = sum(len(g) for g in groups.values())
    print(f"{len(done)} rows read before, {todo} to read", file=sys.stderr)
    descriptions: dict[str, str] = {}
    read = 0
    started = time.perf_counter()
    with out.open("a", encoding="utf-8") as sink:
        for (request, criterion), rows in groups.items():
            if args.limit and read >= args.limit:
                break
            dish = criterion_terms(criterion).dish
            _, prior, _, _ = plain_decider._ask(described_question(request, criterion, dish, None, ""))
            for row in rows:
                obj = row["object"]
                if obj not in descriptions:
                    descriptions.update(plain_decider.describe([obj])[0])
                told = described_question(request, criterion, dish, obj, descriptions[obj])
                p_yes, log_odds, _, _ = plain_decider._ask(told)
                record = {
                    **{k: row[k] for k in ("object", "criterion", "kind", "answer", "request", "source")},
                    "described": round(log_odds - prior, 4),
                    "p_described": round(p_yes, 4),
                    "description": descriptions[obj],
                }
                sink.write(json.dumps(record) + "\n")
                sink.flush()
                read += 1
            rate = (time.perf_counter() - started) / max(1, read)
            print(f"{read}/{todo} rows, {rate:.1f} s/row", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
