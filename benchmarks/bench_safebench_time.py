"""Seconds per SafeAgentBench plan, cold: the plain planner and ConceptBot with the answer cache off.

A ``safebench run`` reuses every answer it has seen, so its "plans not served from the cache" mix
cold and warm module calls once a design changes. This benchmark plans the first N detailed dev
tasks (safe and unsafe alternating) with caching off for every model call, and prints the median
seconds per plan and per module for each configuration, and the ratio.

Run: .venv/bin/python benchmarks/bench_safebench_time.py [--tasks 10] [--json out.json]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import time
from pathlib import Path

from conceptbot.bench.safeagentbench.dataset import interleaved, scenes, select
from conceptbot.core.config import load_settings
from conceptbot.systems import build_household_system


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--tasks", type=int, default=10, help="detailed dev tasks to plan")
    parser.add_argument("--json", type=Path, default=None, help="write the figures here")
    args = parser.parse_args()
    settings = dataclasses.replace(load_settings(), use_cache=False)
    tasks = [t for t in interleaved(select(split="dev")) if t.suite != "abstract"][: args.tasks]
    figures: dict[str, dict[str, float]] = {}
    for config in ("plain", "conceptbot"):
        planner = build_household_system(settings, config)
        planner.plan("Open the fridge.", scenes()[tasks[0].scene])  # load the weights: not timed
        totals: list[float] = []
        modules: dict[str, list[float]] = {}
        refused = 0
        for task in tasks:
            started = time.perf_counter()
            plan = planner.plan(task.instruction, scenes()[task.scene])
            totals.append(time.perf_counter() - started)
            refused += plan.refused
            for module, usage in plan.usage.items():
                if module != "total":
                    modules.setdefault(module, []).append(usage.latency_s)
        figures[config] = {"median_s": statistics.median(totals), "refused": refused}
        figures[config] |= {f"{m}_median_s": statistics.median(v) for m, v in modules.items()}
        parts = ", ".join(f"{m} {statistics.median(v):.1f} s" for m, v in modules.items())
        print(
            f"{config:10} median {statistics.median(totals):5.1f} s per plan over {len(tasks)} tasks "
            f"({refused} refused); per module when called: {parts}"
        )
    ratio = figures["conceptbot"]["median_s"] / figures["plain"]["median_s"]
    print(f"ConceptBot / plain: {ratio:.1f}x")
    if args.json:
        args.json.write_text(json.dumps({"tasks": len(tasks), "figures": figures, "ratio": ratio}, indent=2))


if __name__ == "__main__":
    main()
