"""Plan-level conformal calibration on the dev tasks (issue 35; KnowNo's multi-step form): a plan is
right only if every calibrated decision in it is, so the nonconformity of a task is its worst
decision's ``1 - p(right answer)`` (yes/no decisions of targets taking all that fit, and which-one
decisions of targets taking one object), and ``qhat`` is their split-conformal quantile. With it, every
decision of a new task lands in its prediction set with the chosen probability (the decision-level
thresholds from the judgement set promise that per decision only: a plan of twenty decisions at 0.9
each is all right far less often).

Each system (the default ``conceptbot``: the ``graph`` combination; ``nokg``: ``nograph``) plans
every dev task once without asking (through the cache; the probabilities do not depend on
``qhat``), and :mod:`conceptbot.bench.conformal_fit` fits (``conceptbot calibrate --conformal`` does
the same for a user's own model). Printed per coverage: ``qhat``, the leave-one-task-
out coverage of whole tasks (how often a task's every decision would be covered by a ``qhat``
fitted without it). ``--write`` stores the
thresholds in ``src/conceptbot/pipeline/conformal.json`` (``plan_qhat``), which the planner reads.

    .venv/bin/python benchmarks/fit_conformal_plans.py [--write]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from conceptbot.bench.conformal_fit import SYSTEMS, PlanFit, collect, fit
from conceptbot.bench.grading import load_tasks
from conceptbot.core.config import load_settings
from conceptbot.core.system import SystemOptions
from conceptbot.pipeline.goal_planner.conformal import CALIBRATION_DOC
from conceptbot.systems import build_system

CONFORMAL = Path("src/conceptbot/pipeline/conformal.json")


def fit_system(system_name: str) -> PlanFit:
    """Plan the dev tasks with one system and fit; print the figures per coverage."""
    system = build_system(load_settings(), system_name, SystemOptions())
    found = fit(collect(system, load_tasks(split="dev")))
    print(f"\n{system_name}: {found.tasks} dev tasks with calibrated decisions ({found.decisions} decisions)")
    print(f"{'coverage':>8} {'qhat':>6} {'leave-one-out':>13}")
    for coverage, q in found.qhat.items():
        print(f"{coverage:>8.2f} {q:>6.3f} {found.held_out[coverage]:>13.1%}")
    return found


def main(argv: list[str] | None = None) -> int:
    """Fit and print; with ``--write``, store the thresholds."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"store the thresholds in {CONFORMAL}")
    args = parser.parse_args(argv)
    fits = {name: fit_system(system) for name, system in SYSTEMS}
    qhat = {name: found.qhat for name, found in fits.items()}
    counts = {name: found.tasks for name, found in fits.items()}
    if args.write:
        data = json.loads(CONFORMAL.read_text(encoding="utf-8"))
        data["_doc"] = CALIBRATION_DOC
        data["plan_qhat"] = {n: {str(c): round(q, 4) for c, q in f.items()} for n, f in qhat.items()}
        data["plan_fitted_on"] = (
            f"dev tasks with calibrated decisions (graph {counts['graph']}, nograph {counts['nograph']}), "
            "benchmarks/fit_conformal_plans.py"
        )
        CONFORMAL.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {CONFORMAL}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
