"""Pipeline cost benchmark: seconds and tokens per module for the embedded model on this machine,
cold (empty caches) and warm (cached), for any configuration.

Run: .venv/bin/python benchmarks/bench_pipeline.py [--scene example-spill] [--request "..."]
     [--config conceptbot|paper|...] [--runs 3] [--json out.json]

Each cold run uses a fresh cache database in a temporary home that links the installed models and
knowledge graph, so nothing is reused from earlier runs; the warm run repeats the same plan on the
same cache. Medians over --runs. Modules are whatever the planner reports: ``goal``, ``decide``,
``ope``, ``risk`` for the goal planner (the default), ``ope``, ``urp``, ``planner`` for the paper's
pipeline (``--config paper``). The paper (gpt-4o-mini over the API): OPE 2.40 s/object, URP 2.12 s,
Planner 1.05 s/step.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
from pathlib import Path

from conceptbot.core.config import load_settings
from conceptbot.scenes import resolve_scene
from conceptbot.systems import SystemOptions, build_system


def one_run(settings, scene, request: str, config: str) -> tuple[dict[str, float], dict[str, float], str]:
    """Cold then warm figures (module seconds and tokens, total seconds) and the plan."""
    system = build_system(settings, config, SystemOptions(fallback=False))  # SayCan ignores options
    figures = []
    plan = None
    for _ in range(2):  # cold, then warm
        plan = system.plan(request, scene)
        row: dict[str, float] = {}
        for module, usage in plan.usage.items():
            row[f"{module}_s"] = usage.latency_s
            row[f"{module}_tokens"] = usage.total_tokens
        figures.append(row)
    assert plan is not None
    return figures[0], figures[1], " ; ".join(plan.actions)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="example-spill")
    parser.add_argument("--request", default="Bring me a bag of chips and something to wipe a spill.")
    parser.add_argument("--config", default="conceptbot")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    base = load_settings()
    scene = resolve_scene(args.scene)
    colds, warms, plans = [], [], []
    for _ in range(args.runs):
        with tempfile.TemporaryDirectory() as tmp:
            home = Path(tmp)
            for part in ("models", "kg"):
                (home / part).symlink_to(base.home / part)
            cold, warm, plan = one_run(base.with_overrides(home=home), scene, args.request, args.config)
            colds.append(cold)
            warms.append(warm)
            plans.append(plan)
    print(
        f"pipeline cost, {args.config}, scene {scene.name} ({len(scene.names)} objects), "
        f"LLM {base.llm}, median of {args.runs} runs"
    )
    print(f"request: {args.request}")
    print(f"{'figure':<22}{'cold':>12}{'warm':>12}")
    result: dict[str, dict[str, float]] = {"cold": {}, "warm": {}}
    keys = sorted(
        {k for r in colds for k in r}, key=lambda k: (k.startswith("total"), k.endswith("tokens"), k)
    )
    for key in keys:
        cold = statistics.median(r.get(key, 0.0) for r in colds)
        warm = statistics.median(r.get(key, 0.0) for r in warms)
        result["cold"][key], result["warm"][key] = cold, warm
        print(f"{key:<22}{cold:>12.2f}{warm:>12.2f}")
    print("plans (cold runs):")
    for plan in plans:
        print(f"  {plan}")
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
