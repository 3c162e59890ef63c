"""Pipeline cost benchmark: the paper's cost table (OPE s/object, URP s, Planner s/step, tokens per
module) for the embedded model on this machine, cold (empty caches) and warm (cached).

Run: .venv/bin/python benchmarks/bench_pipeline.py [--scene example-spill] [--request "..."] [--runs 3]

Each cold run uses a fresh cache database in a temporary home that links the installed models and
knowledge graph, so nothing is reused from earlier runs; the warm run repeats the same plan on the
same cache. Medians over --runs. The paper (gpt-4o-mini over the API): OPE 2.40 s/object, URP
2.12 s, Planner 1.05 s/step.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
from pathlib import Path

from conceptbot.core.config import load_settings
from conceptbot.pipeline.factory import build_conceptbot
from conceptbot.scenes import resolve_scene

PAPER = {"ope_s_per_object": 2.40, "urp_s": 2.12, "planner_s_per_step": 1.05}


def one_run(settings, scene, request: str, config: str) -> tuple[dict[str, float], dict[str, float]]:
    bot = build_conceptbot(settings, config, fallback=False)
    figures = []
    for _ in range(2):  # cold, then warm
        plan = bot.plan(request, scene)
        usage = plan.usage
        steps = max(len(plan.steps), 1)
        figures.append(
            {
                "ope_s_per_object": usage["ope"].latency_s / len(scene.names) if "ope" in usage else 0.0,
                "urp_s": usage["urp"].latency_s if "urp" in usage else 0.0,
                "planner_s_per_step": usage["planner"].latency_s / steps if "planner" in usage else 0.0,
                "total_s": usage["total"].latency_s,
                "ope_tokens": usage["ope"].total_tokens if "ope" in usage else 0,
                "urp_tokens": usage["urp"].total_tokens if "urp" in usage else 0,
                "planner_tokens": usage["planner"].total_tokens if "planner" in usage else 0,
                "steps": len(plan.steps),
                "plan": " ; ".join(plan.actions),
            }
        )
    return figures[0], figures[1]


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
    colds, warms = [], []
    for _ in range(args.runs):
        with tempfile.TemporaryDirectory() as tmp:
            home = Path(tmp)
            for part in ("models", "kg"):
                (home / part).symlink_to(base.home / part)
            cold, warm = one_run(base.with_overrides(home=home), scene, args.request, args.config)
            colds.append(cold)
            warms.append(warm)
    print(
        f"pipeline cost, {args.config}, scene {scene.name} ({len(scene.names)} objects), "
        f"LLM {base.llm}, median of {args.runs} runs"
    )
    print(f"request: {args.request}")
    print(f"{'figure':<22}{'cold':>12}{'warm':>12}{'paper (gpt-4o-mini)':>22}")
    result: dict[str, dict[str, float]] = {"cold": {}, "warm": {}}
    for key in (
        "ope_s_per_object",
        "urp_s",
        "planner_s_per_step",
        "total_s",
        "ope_tokens",
        "urp_tokens",
        "planner_tokens",
        "steps",
    ):
        cold = statistics.median(r[key] for r in colds)
        warm = statistics.median(r[key] for r in warms)
        result["cold"][key], result["warm"][key] = cold, warm
        paper = f"{PAPER[key]:.2f}" if key in PAPER else ""
        print(f"{key:<22}{cold:>12.2f}{warm:>12.2f}{paper:>22}")
    print("plans (cold runs):")
    for r in colds:
        print(f"  {r['plan']}")
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
