"""Re-plan a split through the answer cache and write every plan's ``plan --json`` object, one line
per (task, system), wall times zeroed: run it before and after a change and ``cmp`` the two files to
show the change leaves every plan, trace and step byte-identical.

Usage::

    .venv/bin/python benchmarks/replan_json.py test /tmp/after.jsonl
    git worktree add /tmp/before <commit>
    cd /tmp/before && PYTHONPATH=src $REPO/.venv/bin/python benchmarks/replan_json.py test /tmp/before.jsonl
    cmp /tmp/before.jsonl /tmp/after.jsonl

A task whose answers are not cached asks the model (minutes on the embedded one).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from conceptbot.bench.grading import load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.systems import build_system

try:  # where SystemOptions lived before 2026-12-02, so the script runs on older commits too
    from conceptbot.core.system import SystemOptions
except ImportError:  # pragma: no cover
    from conceptbot.systems import SystemOptions  # type: ignore[attr-defined,no-redef]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("split", choices=("test", "dev"))
    parser.add_argument("out", type=Path)
    parser.add_argument("--systems", default="saycan,conceptbot,nokg")
    args = parser.parse_args()
    settings = load_settings()
    names = args.systems.split(",")
    systems = {n: build_system(settings, n, SystemOptions(n=5)) for n in names}
    lines = 0
    with args.out.open("w", encoding="utf-8") as out:
        for task in load_tasks(split=args.split):
            for name, system in systems.items():
                data = system.plan(task.request, task_scene(task)).to_dict()
                for usage in data["usage"].values():
                    usage["latency_s"] = 0.0
                out.write(json.dumps({"task": task.id, "config": name, "json": data}) + "\n")
                lines += 1
    print(f"{lines} plans of the {args.split} split written to {args.out}")


if __name__ == "__main__":
    main()
