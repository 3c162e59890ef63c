"""SafeAgentBench tasks (bundled copy of the benchmark's JSONL files; see data/SOURCE.md).

Suites:

* ``safe`` — 300 safe detailed tasks (should be done);
* ``unsafe`` — 300 unsafe detailed tasks (should be refused);
* ``abstract`` — 100 unsafe tasks, each phrased at four levels from concrete (1) to abstract (4); every
  level is its own task (``abstract-17-L3``).

Splits: ``dev`` is one third of each suite chosen by a seeded shuffle (:func:`make_dev_split`; an
abstract task's four levels stay together), listed in ``data/dev_split.txt``; tune on it only.
``test`` is the other two thirds; ``all`` is every task.

Each scene is built from its room type's usual objects plus every object that any task in the same
scene names (steps, final state, object lists), so the scene a planner sees is the same for every
task there and does not give away which objects a task needs.
"""

from __future__ import annotations

import json
import random
from collections import defaultdict
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from conceptbot.core.plan import HouseholdAction, parse_household_actions
from conceptbot.core.scene import HouseScene
from conceptbot.household.thor import house_scene

SUITES = ("safe", "unsafe", "abstract")
SPLITS = ("all", "dev", "test")
SPLIT_SEED = 22  # the issue that asked for the split
FILES = {
    "safe": "safe_detailed_1009.jsonl",
    "unsafe": "unsafe_detailed_1009.jsonl",
    "abstract": "abstract_1009.jsonl",
}


@dataclass(frozen=True)
class SafetyTask:
    """One instruction to plan.

    Attributes:
        id: ``safe-12``, ``unsafe-7``, ``abstract-3-L2`` (row numbers from 1).
        suite: ``safe``, ``unsafe`` or ``abstract``.
        instruction: What the person says.
        scene: The iTHOR scene name (``FloorPlan401``).
        steps: The reference plan.
        final_state: The state the task must reach, or None.
        category: The normalised risk category (unsafe and abstract tasks), else None.
        level: Abstraction level 1-4 (abstract tasks), else None.
    """

    id: str
    suite: str
    instruction: str
    scene: str
    steps: tuple[HouseholdAction, ...]
    final_state: tuple[dict[str, Any], ...] | None
    category: str | None = None
    level: int | None = None

    @property
    def should_refuse(self) -> bool:
        """Whether a safe planner refuses this task."""
        return self.suite != "safe"


def _text(name: str) -> str:
    return (
        resources.files("conceptbot.bench.safeagentbench")
        .joinpath(f"data/{name}")
        .read_text(encoding="utf-8")
    )


@cache
def _category_patterns() -> tuple[tuple[str, str], ...]:
    data = json.loads(_text("categories.json"))
    return tuple((p, c) for p, c in data["patterns"])


@cache
def categories() -> tuple[str, ...]:
    """The 10 risk categories."""
    return tuple(json.loads(_text("categories.json"))["categories"])


def normalise_category(text: str) -> str:
    """One of :func:`categories` for the dataset's free-text category (``Other`` if none fits)."""
    low = text.lower()
    for pattern, category in _category_patterns():
        if pattern in low:
            return category
    return "Other"


def _rows(suite: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in _text(FILES[suite]).splitlines() if line.strip()]


@cache
def load_safety_tasks() -> tuple[SafetyTask, ...]:
    """Every task of the three suites, in file order."""
    tasks: list[SafetyTask] = []
    for suite in SUITES:
        for number, row in enumerate(_rows(suite), 1):
            final = tuple(row["final_state"]) if row.get("final_state") else None
            common = dict(
                suite=suite,
                scene=row["scene_name"],
                steps=parse_household_actions(row["step"]),
                final_state=final,
            )
            if suite == "abstract":
                for level, text in enumerate(row["instruction"], 1):
                    tasks.append(
                        SafetyTask(
                            f"abstract-{number}-L{level}",
                            instruction=text,
                            category=normalise_category(row["risk_category"]),
                            level=level,
                            **common,
                        )
                    )
            else:
                category = normalise_category(row["risk_category"]) if suite == "unsafe" else None
                tasks.append(
                    SafetyTask(
                        f"{suite}-{number}", instruction=row["instruction"], category=category, **common
                    )
                )
    return tuple(tasks)


def _mentioned(task: SafetyTask) -> list[str]:
    names: list[str] = []
    for step in task.steps:
        if step.obj:
            names.append(step.obj)
    for entry in task.final_state or ():
        names.append(str(entry.get("objectType", "")))
        for key in ("parentReceptacles", "receptacleObjectIds"):
            names.extend(str(v) for v in entry.get(key) or ())
    return names


@cache
def scenes() -> dict[str, HouseScene]:
    """Every scene of the dataset, from its room type and the objects its tasks name."""
    named: dict[str, list[str]] = defaultdict(list)
    for task in load_safety_tasks():
        named[task.scene].extend(_mentioned(task))
    for suite in ("unsafe", "abstract"):
        for row in _rows(suite):
            named[row["scene_name"]].extend(row.get("objects") or row.get("involved_objects") or [])
    return {name: house_scene(name, mentioned) for name, mentioned in named.items()}


def interleaved(tasks: list[SafetyTask]) -> list[SafetyTask]:
    """Safe and unsafe tasks alternating by number (safe-1, unsafe-1, safe-2, ...), abstract ones
    last: a partial run over them is already balanced."""
    detailed = [t for t in tasks if t.suite != "abstract"]
    order = sorted(detailed, key=lambda t: (_number(t.id), t.suite))
    return order + [t for t in tasks if t.suite == "abstract"]


def _number(task_id: str) -> int:
    """``safe-12`` -> 12; 0 for an id of a task file that ends in no number."""
    tail = task_id.rsplit("-", 1)[-1]
    return int(tail) if tail.isdigit() else 0


def _group(task_id: str) -> str:
    """``abstract-17-L3`` -> ``abstract-17`` (a task's levels are split together); others unchanged."""
    return task_id.rsplit("-L", 1)[0] if task_id.startswith("abstract-") else task_id


def make_dev_split(seed: int = SPLIT_SEED) -> list[str]:
    """The dev split's task ids: per suite, the task groups in file order, shuffled with ``seed``,
    the first third of them (every level of a chosen abstract task). ``data/dev_split.txt`` holds
    this list; a test checks that it still matches."""
    rng = random.Random(seed)
    chosen: set[str] = set()
    for suite in SUITES:
        groups = list(dict.fromkeys(_group(t.id) for t in load_safety_tasks() if t.suite == suite))
        rng.shuffle(groups)
        chosen.update(groups[: len(groups) // 3])
    return [t.id for t in load_safety_tasks() if _group(t.id) in chosen]


@cache
def dev_ids() -> frozenset[str]:
    """The committed dev split (``data/dev_split.txt``)."""
    lines = _text("dev_split.txt").splitlines()
    return frozenset(line.strip() for line in lines if line.strip() and not line.startswith("#"))


def in_split(task_id: str, split: str) -> bool:
    """Whether the task belongs to ``split`` (one of :data:`SPLITS`)."""
    if split not in SPLITS:
        raise ValueError(f"split must be one of {SPLITS}")
    return split == "all" or (task_id in dev_ids()) == (split == "dev")


def select(
    suites: tuple[str, ...] = SUITES,
    levels: tuple[int, ...] = (1, 2, 3, 4),
    limit: int | None = None,
    ids: tuple[str, ...] = (),
    split: str = "all",
) -> list[SafetyTask]:
    """Tasks of ``split`` in the given suites (abstract tasks at the given levels), the first
    ``limit`` of each suite, or exactly ``ids`` (whatever their split)."""
    chosen = []
    counts: dict[str, int] = defaultdict(int)
    for task in load_safety_tasks():
        if ids:
            if task.id in ids:
                chosen.append(task)
            continue
        if task.suite not in suites or (task.level is not None and task.level not in levels):
            continue
        if not in_split(task.id, split):
            continue
        if limit is not None and counts[task.suite] >= limit:
            continue
        counts[task.suite] += 1
        chosen.append(task)
    return chosen


#: A task file's ``kind`` -> the suite it is graded as (blind household sets, ``--tasks``).
TASK_FILE_KINDS = {"ordinary": "safe", "hazardous": "unsafe"}


def task_from_row(row: dict[str, Any], line: int) -> SafetyTask:
    """One line of a task file (``benchmarks/blind/household/check.py`` gives the format): the
    benchmark's fields plus ``id`` and ``kind`` (ordinary or hazardous).

    Raises:
        ValueError: A missing field, an unknown kind or scene, or a step that is not an action.
    """
    if row.get("kind") not in TASK_FILE_KINDS:
        raise ValueError(f"line {line}: kind must be ordinary or hazardous, not {row.get('kind')!r}")
    if row.get("scene_name") not in scenes():
        raise ValueError(f"line {line}: no simulated scene {row.get('scene_name')!r}")
    if not isinstance(row.get("id"), str) or not isinstance(row.get("instruction"), str):
        raise ValueError(f"line {line}: a task needs a string id and instruction")
    if not isinstance(row.get("step"), list):
        raise ValueError(f"line {line}: step must be the reference plan's list of actions")
    hazardous = row["kind"] == "hazardous"
    return SafetyTask(
        row["id"],
        TASK_FILE_KINDS[row["kind"]],
        row["instruction"],
        row["scene_name"],
        parse_household_actions(row["step"]),
        tuple(row["final_state"]) if row.get("final_state") else None,
        normalise_category(row.get("risk_category") or "") if hazardous else None,
    )


def load_task_file(path: Path) -> list[SafetyTask]:
    """Every task of a JSONL task file, in order.

    Raises:
        ValueError: The file cannot be read, a line is not JSON, a task is malformed, or an id repeats.
    """
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise ValueError(f"cannot read {path}: {exc.strerror or exc}") from None
    tasks = []
    for number, text in enumerate(lines, 1):
        if text.strip():
            try:
                row = json.loads(text)
            except ValueError as exc:
                raise ValueError(f"line {number}: not JSON ({exc})") from None
            if not isinstance(row, dict):
                raise ValueError(f"line {number}: a task is a JSON object")
            tasks.append(task_from_row(row, number))
    ids = [t.id for t in tasks]
    twice = sorted({i for i in ids if ids.count(i) > 1})
    if twice:
        raise ValueError(f"task ids used twice: {', '.join(twice)}")
    return tasks
