"""How often the household planning call's plan of an ordinary task is done, per planning prompt.

ConceptBot's household planning call plans what was asked and leaves refusing to the fitted harm
judgement. This measures the plans alone on ordinary tuning tasks (the dev split's safe tasks and
the folded blind household sets' ordinary ones): each is planned with a system prompt and examples
given as template files (``$actions`` and ``$examples`` are filled: with the task steps, or with
``--actions`` the 17 actions), with the repair round and the skill layer, and graded against its
final state. Rows are appended as they come (resumable).

With ``--similar K`` the call also sees the K tuning tasks nearest in meaning with their reference
steps, as ConceptBot's planner does (the task's own set left out of them).

    .venv/bin/python benchmarks/bench_household_planning.py NAME SYSTEM.txt EXAMPLES.txt [--actions]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from string import Template

from conceptbot.bench.safeagentbench.dataset import load_task_file, scenes, select
from conceptbot.bench.safeagentbench.grading import grade_safety
from conceptbot.core.config import load_settings
from conceptbot.core.plan import format_actions
from conceptbot.core.trace import HouseholdTrace
from conceptbot.household.planner import PROMPTS, _PlanCall, similar_tasks
from conceptbot.household.similar import SimilarCases
from conceptbot.models.registry import open_embedder, open_llm
from conceptbot.pipeline import prompts

FOLDED = (
    Path("benchmarks/blind/household/set1/tasks.jsonl"),
    Path("benchmarks/blind/household/set2/tasks.jsonl"),
    Path("benchmarks/blind/household/set3/tasks.jsonl"),
    Path("benchmarks/blind/household/set4/tasks.jsonl"),
    Path("benchmarks/blind/household/set5/tasks.jsonl"),
    Path("benchmarks/blind/household/set6/tasks.jsonl"),
)


class _Variant(_PlanCall):
    """The planning call with another prompt."""

    def __init__(self, system: Path, examples: Path, task_steps: bool) -> None:
        super().__init__(open_llm(load_settings(), module="planner"), repair=True, refusal=False)
        self.task_steps = task_steps
        self.template = Template(system.read_text(encoding="utf-8"))
        self.examples = examples.read_text(encoding="utf-8").strip() + "\n"

    def system(self) -> str:
        actions = prompts.render("household_task_steps" if self.task_steps else "household_actions", PROMPTS)
        return self.template.substitute(actions=actions, examples=self.examples).strip() + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name")
    parser.add_argument("system", type=Path)
    parser.add_argument("examples", type=Path)
    parser.add_argument("--actions", action="store_true", help="the model writes actions, not task steps")
    parser.add_argument("--limit-dev", type=int, default=30, help="the first N safe dev tasks")
    parser.add_argument("--only", default="", help="only the tasks whose id starts with this (hh3-)")
    parser.add_argument(
        "--similar",
        type=int,
        default=0,
        help="show the planning call this many tasks like it with their reference steps (from the "
        "shipped examples, leaving out the task's own set)",
    )
    parser.add_argument("--out", type=Path, default=Path("/tmp/household-planning.jsonl"))
    args = parser.parse_args(argv)
    tasks = list(select(("safe",), split="dev"))[: args.limit_dev]
    tasks += [t for path in FOLDED for t in load_task_file(path) if not t.should_refuse]
    tasks = [t for t in tasks if t.id.startswith(args.only)]
    done = set()
    if args.out.exists():
        rows = [json.loads(x) for x in args.out.read_text().splitlines() if x.strip()]
        done = {(r["variant"], r["task"]) for r in rows}
    call = _Variant(args.system, args.examples, task_steps=not args.actions)
    cases = SimilarCases(open_embedder(load_settings())) if args.similar else None
    with args.out.open("a", encoding="utf-8") as sink:
        for number, task in enumerate(tasks, 1):
            if (args.name, task.id) in done:
                continue
            own = task.id.split("-")[0] + "-"  # safe-, hh3-: the task's own set is left out
            like = cases.nearest(task.instruction, args.similar, leave_out=own) if cases else []
            reply, _, _ = call(task.instruction, scenes()[task.scene], similar_tasks(like), HouseholdTrace())
            ok = None if task.should_refuse else grade_safety(task, reply.steps, refused=False).success
            row = {"variant": args.name, "task": task.id, "done": ok, "steps": format_actions(reply.steps)}
            sink.write(json.dumps(row) + "\n")
            sink.flush()
            print(f"{number}/{len(tasks)} {task.id} {ok}", file=sys.stderr)
    rows = [json.loads(x) for x in args.out.read_text().splitlines() if x.strip()]
    for name in sorted({r["variant"] for r in rows}):
        mine = [r for r in rows if r["variant"] == name]
        for prefix in ("safe-", "hh1-", "hh2-", "hh3-", "hh4-", "hh5-", "hh6-"):
            part = [r for r in mine if r["task"].startswith(prefix) and r["done"] is not None]
            print(f"{name} {prefix}: {sum(r['done'] for r in part)}/{len(part)} done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
