"""Calibrate the household harm judge for asking (issue 35): Platt scaling of its score and split
conformal thresholds on SafeAgentBench's dev split, from the judge scores a ``conceptbot safebench
run`` results file already holds (no model call; :mod:`conceptbot.bench.safeagentbench.conformal`).

Printed: the scaling, ``qhat`` per coverage, the share of dev tasks asked with it, and the
leave-one-task-out coverage. ``--write`` stores ``src/conceptbot/household/judge_conformal.json``,
which ``conceptbot.household.asking`` reads. For another model, run ``conceptbot safebench run
--split dev -c conceptbot --out FILE`` with it first and pass ``--results FILE``.

    .venv/bin/python benchmarks/fit_judge_conformal.py [--results FILE] [--write]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from conceptbot.bench.safeagentbench.conformal import calibration_document, fit_judge, judged_tasks
from conceptbot.bench.safeagentbench.dataset import dev_ids
from conceptbot.core.errors import ConfigError
from conceptbot.household.asking import judge_set

RESULTS = Path("results/parts/safeagentbench-v4-qwen2.5-coder-1.5b.jsonl")
OUT = Path("src/conceptbot/household/judge_conformal.json")


def main(argv: list[str] | None = None) -> int:
    """Fit and print; with ``--write``, store the calibration."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--results", type=Path, default=RESULTS, help="a safebench results file (JSONL)")
    parser.add_argument("--write", action="store_true", help=f"write {OUT}")
    args = parser.parse_args(argv)
    try:
        tasks = judged_tasks(args.results, dev_ids())
        found = fit_judge(tasks, f"SafeAgentBench dev split, judge scores in {args.results.name}")
    except (ConfigError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    c = found.calibration
    print(
        f"{found.tasks} dev tasks with a judge score ({found.dangerous} dangerous); "
        f"P(dangerous) = sigmoid({c.slope:.4f} * score {c.intercept:+.4f})"
    )
    print(f"{'coverage':>8} {'qhat':>6} {'asked':>6} {'leave-one-out':>13}")
    for coverage, q in c.qhat.items():
        asked = sum(len(judge_set(c.p_dangerous(t.log_odds), q)) == 2 for t in tasks)
        print(f"{coverage:>8.2f} {q:>6.3f} {asked:>6} {found.held_out.get(coverage, float('nan')):>13.1%}")
    if args.write:
        OUT.write_text(json.dumps(calibration_document(found), indent=2) + "\n", encoding="utf-8")
        print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
