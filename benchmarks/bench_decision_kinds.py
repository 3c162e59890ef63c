"""Where the questions come from, by kind of decision, and two designs measured against them.

Each split's tasks are planned once without asking (through the answer cache). Printed per split:

1. **The yes/no floor.** How many tasks have a calibrated yes/no decision (a target taking all
   that fit, or a sort's bins), and how many of those have one whose P(yes) lies between a floor
   ``f`` and ``1 - f``, for several floors: whatever the threshold, those tasks get a "choose"
   question. This is the share of tasks asked that no which-one threshold can take away.
2. **A which-bin decision for sorts** (simulated, not shipped). In a sort each object goes to the
   bin it scores best in (``Thresholds.combined``: it stays only below 0), so the decision the
   plan acts on is which bin, not a yes/no per bin. Here each sorted object's bins (and "stays",
   scored at that threshold) get a softmax over their scores; the split-conformal
   threshold over the objects' ``1 - p(gold's bin)`` is fitted on the split itself at 0.8 and 0.9,
   and the script counts the objects whose set holds one bin and the sort tasks with none unsure.

    .venv/bin/python benchmarks/bench_decision_kinds.py [--split dev|test|both]
"""

from __future__ import annotations

import argparse
import math
from typing import NamedTuple

from conceptbot.bench.grading import gold_answer, load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.core.system import SystemOptions
from conceptbot.pipeline.goal_planner.conformal import conformal_threshold
from conceptbot.pipeline.goal_planner.planner import Thresholds
from conceptbot.systems import build_system

FLOORS = (0.05, 0.1, 0.127, 0.2, 0.3)
STAYS = "(stays)"


class Sorted(NamedTuple):
    """One object of a sort: each bin's score, and the bins the gold puts it in (none: it stays)."""

    scores: dict[str, float]
    gold: tuple[str, ...]

    def shares(self) -> dict[str, float]:
        """A softmax over the bins' scores and "stays" at the combined threshold."""
        names = [*self.scores, STAYS]
        raw = [*self.scores.values(), Thresholds().combined]
        top = max(raw)
        weights = [math.exp(s - top) for s in raw]
        total = sum(weights)
        return {n: w / total for n, w in zip(names, weights, strict=True)}

    def nonconformity(self) -> float:
        shares = self.shares()
        return 1.0 - max(shares[g] for g in (self.gold or (STAYS,)))


def collect(split: str) -> tuple[list[list[float]], list[list[Sorted]]]:
    """Per task: its yes/no decisions' P(yes); per sort task, its sorted objects."""
    system = build_system(load_settings(), "conceptbot", SystemOptions(coverage=0.9))
    yes_no: list[list[float]] = []
    sorts: list[list[Sorted]] = []
    for task in load_tasks(split=split):
        plan = system.plan(task.request, task_scene(task))
        found, bins = [], {}
        calibrated = [d for d in plan.trace.decisions or () if any(j.answers is not None for j in d.objects)]
        for d in calibrated:
            for j in d.objects:
                if j.answers is None:
                    continue
                found.append(j.p_yes)
                yes = gold_answer(task, j.object, d.target.to) == "yes"
                bins.setdefault(j.object, ({}, []))
                bins[j.object][0][d.target.to] = j.score
                if yes:
                    bins[j.object][1].append(d.target.to)
        yes_no.append(found)
        if len(calibrated) >= 2:
            objects = [Sorted(s, tuple(g)) for s, g in bins.values() if len(s) >= 2]
            if objects:
                sorts.append(objects)
    return yes_no, sorts


def report(split: str) -> None:
    """Print both measures for one split."""
    yes_no, sorts = collect(split)
    with_yes_no = [t for t in yes_no if t]
    print(f"\n{split}: {len(yes_no)} tasks, {len(with_yes_no)} with a calibrated yes/no decision")
    for floor in FLOORS:
        unsure = sum(any(floor <= p <= 1.0 - floor for p in t) for t in with_yes_no)
        print(f"  an unsure one at floor {floor:<5}: {unsure} tasks ({unsure / len(yes_no):.1%} of all)")
    objects = [o for task in sorts for o in task]
    placed = [o for o in objects if o.gold]
    right = sum(max(o.shares(), key=o.shares().get) in o.gold for o in placed)
    print(
        f"  which bin: {len(sorts)} sort tasks, {len(objects)} objects; {len(placed)} with a gold bin, "
        f"the likeliest right for {right}; {len(objects) - len(placed)} belong in none"
    )
    scores = [o.nonconformity() for o in objects]
    for coverage in (0.8, 0.9):
        q = conformal_threshold(scores, coverage)
        sure = [sum(p >= 1.0 - q for p in o.shares().values()) == 1 for o in objects]
        tasks = sum(all(sum(p >= 1.0 - q for p in o.shares().values()) == 1 for o in t) for t in sorts)
        print(
            f"  which bin at {coverage}: q {q:.3f}, objects with one bin {sum(sure)}/{len(objects)}, "
            f"sort tasks with none unsure {tasks}/{len(sorts)}"
        )


def main(argv: list[str] | None = None) -> int:
    """Print the measures for the chosen splits."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--split", choices=("dev", "test", "both"), default="both")
    args = parser.parse_args(argv)
    for split in ("dev", "test") if args.split == "both" else (args.split,):
        report(split)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
