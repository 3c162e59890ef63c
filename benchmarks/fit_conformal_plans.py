"""Plan-level conformal calibration on the dev tasks (issue 35; KnowNo's multi-step form): a plan is
right only if every calibrated decision in it is, so the nonconformity of a task is its worst
decision's ``1 - p(right answer)`` (yes/no decisions of targets taking all that fit, and which-one
decisions of targets taking one object), and ``qhat`` is their split-conformal quantile. With it, every
decision of a new task lands in its prediction set with the chosen probability (the decision-level
thresholds from the judgement set promise that per decision only: a plan of twenty decisions at 0.9
each is all right far less often).

Each system (the default ``conceptbot``: the ``graph`` combination; ``nokg``: ``nograph``) plans
every dev task once without asking (through the cache; the probabilities do not depend on
``qhat``), and :mod:`conceptbot.bench.conformal_fit` fits both which-one rules from those plans
(``fits``: whether the likeliest candidate fits; ``softmax``: its share of the ranking;
``conceptbot calibrate --conformal`` does the same for a user's own model). Printed per rule and
coverage: ``qhat`` and the leave-one-task-out coverage of whole tasks (how often a task's every
decision would be covered by a ``qhat`` fitted without it). ``--write`` stores the thresholds in
``src/conceptbot/pipeline/conformal.json``, which the planner reads: ``plan_qhat`` for the rule
``--which-one`` names (the default), ``plan_qhat_RULE`` for the other: one threshold for every decision
(the reading questions take it), and beside each the pair per kind of decision the calibrated
decisions take (``plan_qhat_yes_no``, ``plan_qhat_one``, and ``_RULE`` for the other rule).

    .venv/bin/python benchmarks/fit_conformal_plans.py [--write] [--which-one fits|softmax]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from conceptbot.bench.conformal_fit import SYSTEMS, PlanFit, collect, fit, thresholds_document
from conceptbot.bench.grading import load_tasks
from conceptbot.core.config import load_settings
from conceptbot.core.system import WHICH_ONE, SystemOptions
from conceptbot.pipeline.goal_planner.conformal import CALIBRATION_DOC, shipped
from conceptbot.systems import build_system

CONFORMAL = Path("src/conceptbot/pipeline/conformal.json")


def fit_system(system_name: str) -> dict[str, PlanFit]:
    """Plan the dev tasks with one system and fit each which-one rule; print the figures."""
    system = build_system(load_settings(), system_name, SystemOptions())
    fits = {rule: fit(scores) for rule, scores in collect(system, load_tasks(split="dev")).items()}
    for rule, found in fits.items():
        print(
            f"\n{system_name}, which-one rule {rule}: {found.tasks} dev tasks with calibrated decisions "
            f"({found.decisions} decisions)"
        )
        print(f"{'coverage':>8} {'yes/no':>6} {'one':>6} {'single':>6} {'asked':>5} {'leave-one-out':>13}")
        ones, single, asked = found.qhat_one or found.qhat, found.single or found.qhat, found.asked or {}
        for coverage, q in found.qhat.items():
            print(
                f"{coverage:>8.2f} {q:>6.3f} {ones[coverage]:>6.3f} {single[coverage]:>6.3f} "
                f"{asked.get(coverage, 0):>5} {found.held_out[coverage]:>13.1%}"
            )
    return fits


def merged(data: dict[str, Any], fits: dict[str, dict[str, PlanFit]], rule: str) -> dict[str, Any]:
    """The calibration file ``data`` with the plan-level thresholds of the combinations in ``fits``
    replaced (the other combinations' kept, so that a long fit can be split by system), ``rule``
    the default which-one rule."""
    data = {**data, "_doc": CALIBRATION_DOC}
    # The default rule's thresholds are plan_qhat and its kinds' keys, not plan_qhat_RULE.
    for stale in (f"plan_qhat_{rule}", f"plan_qhat_one_{rule}", f"plan_qhat_yes_no_{rule}"):
        data.pop(stale, None)
    for key, value in thresholds_document(fits, rule).items():
        kept = data.get(key) if isinstance(data.get(key), dict) else {}
        data[key] = {**kept, **value} if isinstance(value, dict) else value
    counts = {**data.get("plan_fitted_tasks", {})}
    counts.update({name: found[rule].tasks for name, found in fits.items()})
    data["plan_fitted_tasks"] = counts
    tasks = ", ".join(f"{name} {n}" for name, n in counts.items())
    data["plan_fitted_on"] = f"dev tasks with calibrated decisions ({tasks}), {Path(__file__).name}"
    return data


def main(argv: list[str] | None = None) -> int:
    """Fit and print; with ``--write``, store the thresholds."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"store the thresholds in {CONFORMAL}")
    parser.add_argument(
        "--which-one",
        choices=WHICH_ONE,
        default=shipped().rule,
        help="the rule the planner uses by default (default: the one the shipped file names now)",
    )
    parser.add_argument(
        "--systems",
        default=",".join(system for _, system in SYSTEMS),
        help="comma-separated systems to fit (a long fit can be split; the others' thresholds are kept)",
    )
    args = parser.parse_args(argv)
    wanted = {s for s in args.systems.split(",") if s}
    unknown = wanted - {system for _, system in SYSTEMS}
    if unknown:
        known = ", ".join(system for _, system in SYSTEMS)
        parser.error(f"unknown systems: {', '.join(sorted(unknown))} (known: {known})")
    data = json.loads(CONFORMAL.read_text(encoding="utf-8"))
    switching = data.get("plan_which_one", args.which_one) != args.which_one
    if args.write and switching and len(wanted) < len(SYSTEMS):
        # The default rule's thresholds are plan_qhat: switching it moves every combination's.
        parser.error("switching --which-one needs every system fitted at once")
    fits = {name: fit_system(system) for name, system in SYSTEMS if system in wanted}
    if args.write:
        text = json.dumps(merged(data, fits, args.which_one), indent=2) + "\n"
        CONFORMAL.write_text(text, encoding="utf-8")
        print(f"wrote {CONFORMAL}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
