"""Would a sharper "which one" ask less, honestly? Each split's tasks are planned once without
asking (through the answer cache); every which-one decision's ``p_one`` is raised to a power ``s``
and renormalised (a sharper softmax, the ranking unchanged), the plan-level conformal threshold is
refit on dev at coverage 0.9, and the script prints, per ``s``: the threshold, how many tasks of
each split would get a question about a calibrated decision, how many have every decision's set
holding the gold's answer, and the mean log-likelihood on dev of drawing an object the gold accepts
(the honest sharpness maximises it; a sharper one claims more than it knows).

The power applies on top of the shipped ``Thresholds.one_sharpness`` (1.5 since 2026-12-05, chosen
with this script when the shipped scale was 1: s = 1.5 then had the best likelihood). Reading
questions are not simulated (they do not depend on ``p_one``), so "asked" counts only the
calibrated decisions' questions.

    .venv/bin/python benchmarks/bench_one_sharpness.py
"""

from __future__ import annotations

import math

from conceptbot.bench.grading import gold_answer, load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.core.system import SystemOptions
from conceptbot.pipeline.goal_planner.conformal import conformal_threshold
from conceptbot.systems import build_system

SCALES = (1.0, 1.5, 2.0, 3.0, 4.0, 6.0)


def decisions(split: str) -> list[tuple[list[float], list[tuple[dict[str, float], list[str]]]]]:
    """Per task: the gold's probability of each yes/no decision, and each which-one decision's
    ``p_one`` by object with the objects the gold accepts."""
    system = build_system(load_settings(), "conceptbot", SystemOptions(coverage=0.9))
    found = []
    for task in load_tasks(split=split):
        plan = system.plan(task.request, task_scene(task))
        yes_no, ones = [], []
        for d in plan.trace.decisions or ():
            for j in d.objects:
                if j.answers is not None:
                    yes = gold_answer(task, j.object, d.target.to) == "yes"
                    yes_no.append(j.p_yes if yes else 1.0 - j.p_yes)
            chances = {j.object: j.p_one for j in d.objects if j.p_one is not None}
            if chances:
                accepted = [o for o in chances if gold_answer(task, o, d.target.to) == "yes"]
                ones.append((chances, accepted))
        found.append((yes_no, ones))
    return found


def sharpened(chances: dict[str, float], s: float) -> dict[str, float]:
    """``chances`` raised to ``s`` and renormalised."""
    weights = {o: p**s if p > 0 else 0.0 for o, p in chances.items()}
    total = sum(weights.values()) or 1.0
    return {o: w / total for o, w in weights.items()}


def main() -> None:
    splits = {split: decisions(split) for split in ("dev", "test")}
    for s in SCALES:
        scores = []
        for yes_no, ones in splits["dev"]:
            worst = [1.0 - p for p in yes_no]
            worst += [1.0 - max(sharpened(c, s)[a] for a in acc) for c, acc in ones if acc]
            if worst:
                scores.append(max(worst))
        qhat = conformal_threshold(scores, 0.9)
        keep = 1.0 - qhat
        line = [f"s={s:<4} qhat {qhat:.3f}"]
        for split, tasks in splits.items():
            asked = covered = calibrated = 0
            for yes_no, ones in tasks:
                ask = any(min(p, 1.0 - p) >= keep for p in yes_no)
                right = all(p >= keep for p in yes_no)
                for chances, accepted in ones:
                    kept = [o for o, p in sharpened(chances, s).items() if p >= keep]
                    ask = ask or len(kept) != 1
                    right = right and (not accepted or bool(set(kept) & set(accepted)))
                asked += ask
                calibrated += bool(yes_no or ones)
                covered += bool(yes_no or ones) and right
            line.append(f"{split}: asked {asked}/{len(tasks)}, covered {covered}/{calibrated}")
        likelihoods = [
            math.log(max(1e-12, sum(sharpened(c, s)[a] for a in acc)))
            for _, ones in splits["dev"]
            for c, acc in ones
            if acc
        ]
        line.append(f"dev log-lik {sum(likelihoods) / len(likelihoods):.4f} ({len(likelihoods)} decisions)")
        print("  ".join(line))


if __name__ == "__main__":
    main()
