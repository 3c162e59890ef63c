"""Check a blind household task file against the simulated SafeAgentBench scenes (no model).

Each line of the file is one task in SafeAgentBench's format plus two fields of ours::

    {"id": "hh1-ordinary-1", "kind": "ordinary" | "hazardous", "scene_name": "FloorPlan12",
     "instruction": "...", "step": ["find Kettle", ...], "final_state": [...] | null,
     "risk_category": "Fire Hazard" (hazardous only), "sounds_risky": true | false (ordinary only),
     "notes": "why it is (not) dangerous"}

For every task: the scene exists, the reference steps parse and name only actions of the 17 and
objects of the scene, and the reference plan executes in the project's executor and meets its own
final state (for a hazardous task: the hazard is carried out, as SafeAgentBench grades it).

    .venv/bin/python benchmarks/blind/household/check.py FILE.jsonl
"""

from __future__ import annotations

import json
import sys
from collections import Counter
from pathlib import Path

from conceptbot.bench.safeagentbench.dataset import scenes, task_from_row
from conceptbot.bench.safeagentbench.grading import grade_safety
from conceptbot.household.thor import catalogue


def check(path: Path) -> int:
    """Print each problem; return how many tasks have one."""
    bad = 0
    kinds: Counter[str] = Counter()
    things = catalogue()
    for line, text in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if not text.strip():
            continue
        try:
            row = json.loads(text)
            task = task_from_row(row, line)
            scene = scenes()[task.scene]
            found = {s.obj: things.canonical(s.obj) for s in task.steps if s.obj}
            missing = sorted(o for o, t in found.items() if t is None or not scene.has(t))
            if missing:
                raise ValueError(f"{task.id}: not in {task.scene}: {', '.join(map(str, missing))}")
            verdict = grade_safety(task, task.steps, refused=False)
            if not verdict.success:
                raise ValueError(f"{task.id}: the reference plan does not pass: {verdict.reason}")
        except (ValueError, KeyError, TypeError) as exc:
            bad += 1
            print(f"PROBLEM {exc}")
            continue
        kinds[row["kind"]] += 1
    print(f"{sum(kinds.values())} tasks pass ({dict(kinds)}); {bad} with a problem")
    return bad


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(1 if check(Path(sys.argv[1])) else 0)
