"""The model's readings of the judgement set (``benchmarks/data/judgement_set.jsonl``), for fitting
and measuring the combination of model and graph evidence (``benchmarks/fit_judgements.py``).

Each row is asked the way the goal planner asks it (``Decider.fits``: "does the X fit the
description ...?", or "is the X an ingredient of ...?" for a dish, calibrated against a
content-free object), two ways:

* ``model``: with the object's graph facts in the question (the default system's question);
* ``plain``: without any graph facts (the no-graph ablation's question).

Rows sharing a request and a criterion are asked together (one calibration question for them).
Results are appended as they come to the output file, which is read back on a rerun: a stopped run
goes on where it stopped (the model's answers are also in the response cache).

    .venv/bin/python benchmarks/judgement_readings.py [--out results/parts/judgements-MODEL.jsonl] [--limit N]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections import defaultdict
from pathlib import Path

from conceptbot.bench.provenance import stamp
from conceptbot.core.config import load_settings
from conceptbot.core.scene import Scene
from conceptbot.pipeline.goal_planner.decide import Decider
from conceptbot.pipeline.goal_planner.evidence import criterion_terms
from conceptbot.systems import build_system

SET = Path(os.environ.get("JUDGEMENT_SET", "benchmarks/data/judgement_set.jsonl"))


def made() -> dict[str, object]:
    """What made each record: version, commit of the code, model (conceptbot.bench.provenance)."""
    return stamp({"llm": load_settings().llm})


def key(row: dict) -> tuple[str, str, str]:
    """What identifies a row's reading."""
    return (row["object"], row["criterion"], row["request"])


def load_rows(path: Path = SET) -> list[dict]:
    """The judgement set's rows."""
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]


def deciders() -> tuple[Decider, Decider, str]:
    """The default system's decider (with graph facts), the no-graph one, and the model's name."""
    settings = load_settings()
    with_graph = build_system(settings, "conceptbot")
    without = build_system(settings, "nokg")
    model = settings.llm.split(":", 1)[-1]
    # The model's own readings: deciders with the systems' model and facts but no combination.
    found = [s.goal_planner.decider for s in (with_graph, without)]  # type: ignore[attr-defined]
    return Decider(found[0].llm, found[0].facts), Decider(found[1].llm, found[1].facts), model


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--limit", type=int, default=0, help="read at most this many new rows")
    args = parser.parse_args(argv)
    graph_decider, plain_decider, model = deciders()
    out: Path = args.out or Path(f"results/parts/judgements-{model}.jsonl")
    done = {key(r) for r in load_rows(out)} if out.exists() else set()
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for row in load_rows():
        if key(row) not in done:
            groups[(row["request"], row["criterion"])].append(row)
    todo = sum(len(g) for g in groups.values())
    print(f"{len(done)} rows read before, {todo} to read", file=sys.stderr)
    scene = Scene(objects=(), name="judgement-set")
    read = 0
    started = time.perf_counter()
    with out.open("a", encoding="utf-8") as sink:
        for (request, criterion), rows in groups.items():
            if args.limit and read >= args.limit:
                break
            objects = list(dict.fromkeys(r["object"] for r in rows))
            dish = criterion_terms(criterion).dish
            found = {}
            for label, decider in (("model", graph_decider), ("plain", plain_decider)):
                judgements, _, _ = decider.fits(request, criterion, objects, scene, dish=dish)
                found[label] = {j.subject: j for j in judgements}
            for row in rows:
                m, p = found["model"][row["object"]], found["plain"][row["object"]]
                record = {
                    **{k: row[k] for k in ("object", "criterion", "kind", "answer", "request", "source")},
                    "model": round(m.score, 4),
                    "p_model": round(m.p_yes, 4),
                    "plain": round(p.score, 4),
                    "p_plain": round(p.p_yes, 4),
                    "facts": list(m.facts),
                }
                sink.write(json.dumps({**record, **made()}) + "\n")
            sink.flush()
            read += len(rows)
            rate = (time.perf_counter() - started) / read
            print(f"{read}/{todo} rows, {rate:.1f} s/row", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
