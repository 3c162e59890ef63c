"""Plan-level conformal calibration on the dev tasks (issue 35; KnowNo's multi-step form): a plan is
right only if every calibrated decision in it is, so the nonconformity of a task is its worst
decision's ``1 - p(right answer)`` (yes/no decisions of targets taking all that fit, and which-one
decisions of targets taking one object), and ``qhat`` is their split-conformal quantile. With it, every
decision of a new task lands in its prediction set with the chosen probability (the decision-level
thresholds from the judgement set promise that per decision only: a plan of twenty decisions at 0.9
each is all right far less often).

Each system (the default ``conceptbot``: the ``graph`` combination; ``nokg``: ``nograph``) plans
every dev task once without asking (through the cache; the probabilities do not depend on
``qhat``), the gold says which answer is right (:func:`conceptbot.bench.grading.gold_answer`), and
only tasks with a calibrated decision take part. Printed per coverage: ``qhat``, the leave-one-task-
out coverage of whole tasks (how often a task's every decision would be covered by a ``qhat``
fitted without it). ``--write`` stores the
thresholds in ``src/conceptbot/pipeline/conformal.json`` (``plan_qhat``), which the planner reads.

    .venv/bin/python benchmarks/fit_conformal_plans.py [--write]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from conceptbot.bench.grading import gold_answer, load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.core.system import COVERAGES, SystemOptions
from conceptbot.pipeline.goal_planner.conformal import CALIBRATION_DOC, conformal_threshold
from conceptbot.systems import build_system

CONFORMAL = Path("src/conceptbot/pipeline/conformal.json")
SYSTEMS = (("graph", "conceptbot"), ("nograph", "nokg"))


def decisions_of(system_name: str, split: str = "dev") -> list[list[float]]:
    """Per task with calibrated decisions: each decision's nonconformity, ``1 - p(right answer)``.
    A yes/no decision's right answer is the gold's; a which-one decision's is the likeliest object
    the gold accepts there (one the gold accepts none of is left out: the target itself is wrong,
    which no set of its objects can cover)."""
    system = build_system(load_settings(), system_name, SystemOptions())
    tasks = []
    for task in load_tasks(split=split):
        plan = system.plan(task.request, task_scene(task))
        found: list[float] = []
        for d in plan.trace.decisions or ():
            for j in d.objects:
                if j.answers is not None:
                    yes = gold_answer(task, j.object, d.target.to) == "yes"
                    found.append(nonconformity(j.p_yes if yes else 1.0 - j.p_yes))
            accepted = [
                j.p_one
                for j in d.objects
                if j.p_one is not None and gold_answer(task, j.object, d.target.to) == "yes"
            ]
            if d.candidates is not None and accepted:
                found.append(nonconformity(max(accepted)))
        if found:
            tasks.append(found)
    return tasks


def nonconformity(p_right: float) -> float:
    """``1 - p_right``; 1 (keep everything) for a probability that cannot be read."""
    return 1.0 - p_right if 0.0 <= p_right <= 1.0 else 1.0


def fit(tasks: list[list[float]], name: str) -> dict[float, float]:
    """Print the figures per coverage; return ``qhat`` fitted on every task."""
    scores = [max(t) for t in tasks]  # a plan is right only if its worst decision is
    print(f"\n{name}: {len(tasks)} dev tasks with calibrated decisions ({sum(map(len, tasks))} decisions)")
    print(f"{'coverage':>8} {'qhat':>6} {'leave-one-out':>13}")
    fitted = {}
    for coverage in COVERAGES:
        fitted[coverage] = conformal_threshold(scores, coverage)
        held = sum(
            s <= conformal_threshold(scores[:i] + scores[i + 1 :], coverage) for i, s in enumerate(scores)
        )
        print(f"{coverage:>8.2f} {fitted[coverage]:>6.3f} {held / len(scores):>13.1%}")
    return fitted


def main(argv: list[str] | None = None) -> int:
    """Fit and print; with ``--write``, store the thresholds."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"store the thresholds in {CONFORMAL}")
    args = parser.parse_args(argv)
    qhat, counts = {}, {}
    for name, system in SYSTEMS:
        tasks = decisions_of(system)
        qhat[name] = fit(tasks, name)
        counts[name] = len(tasks)
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
