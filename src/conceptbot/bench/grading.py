"""The benchmark's tasks and their automatic grading.

A task (:class:`Task`) is the paper's request, the demo scene it runs in, and a *gold*: the acceptance
criterion written from the paper's intent. :func:`grade` checks a plan (action texts, as the planners
return them) against the gold and returns a :class:`Verdict` with a reason.

Common rules (every gold)
    * Every entry must be an action that is valid in the scene (:func:`~conceptbot.core.plan.parse_action`:
      known object, pickable object, a destination as target, no self-placement), else
      ``invalid action: ...``.
    * The plan ends with ``done()`` and has nothing after it (``no done() at the end``,
      ``action after done(): ...``).
    * No action appears twice (``duplicate action: ...``).
    * A refusal (``refused=True``) passes only a ``refuse`` gold (``refused a feasible task: ...``).

Gold formats (the ``gold`` object of a task)

``{"type": "any_of", "plans": [[action, ...], ...], "ordered": false}``
    The plan's ``pick_and_place`` actions must equal one of the accepted plans: as a set when
    ``ordered`` is false, as a sequence when it is true. No extra and no missing actions. "Bring me a
    fruit" accepts ``[[apple -> user], [lemon -> user]]``: exactly one fruit. Actions are written with
    the scene's exact spelling, e.g. ``"pick_and_place(apple, user)"``; a plan never contains ``done()``.

``{"type": "assign", "assign": {obj: [dest, ...]}, "optional": {obj: [dest, ...]},``
``"must_not_move": [obj, ...], "ordered": [[obj_a, obj_b], ...], "choose": [group, ...]}``
    * every object in ``assign`` is placed exactly once, at one of its allowed destinations;
    * an object in ``optional`` may be placed (only at one of its listed destinations) or left alone;
    * an object in ``must_not_move`` must not be moved (``must not move: ...``); every other object
      must not be moved either (``extra action: ...``); ``must_not_move`` names the tempting ones;
    * each pair in ``ordered`` means obj_a's action comes before obj_b's (when both are moved), e.g.
      stacking bottom-up;
    * ``choose`` (an extension for "something to drink"-style requests) is a list of groups
      ``{"objects": {obj: [dest, ...]}, "min": m, "max": n}``: between m and n of the group's objects
      are placed, each at one of its listed destinations; the others are left alone.
    All keys but ``type`` may be left out (empty). Something must be required: a non-empty ``assign`` or
    a group with ``min`` >= 1. No object may appear in two of these places. Used for sorting tasks
    (materials, toxic, dishwasher), stacking, and requests with optional extras.

``{"type": "refuse"}``
    The correct behaviour is to refuse or to do nothing: a refusal, or a plan that is just ``done()``,
    passes; any move fails (``extra action: ...``).

Verdict reasons on failure name the first problems, joined by ``"; "``: ``extra action:
pick_and_place(apple, ceramic bowl)``, ``missing: sponge -> user``, ``wrong destination: journal ->
plastic bin (allowed: paper bin)``, ``order: medium block must come before small block``,
``duplicate action: ...``, ``no done() at the end``, ``invalid action: ...``, ``refused a feasible task:
...``. On success the reason says what was checked (``all 3 required placements, order respected``).

:func:`load_tasks` reads the task files shipped with the package and validates every gold against its
scene: every object and destination a gold names must exist in the scene with the right role (pickable
object, destination), spelt as the scene spells it.

Splits (``load_tasks(split=...)``, ``conceptbot bench run --split``)
    ``"test"`` (the default)
        The paper's 47 tasks, the measure of the product's quality: ``conceptbot/bench/tasks/<category>.json``
        on the demo scenes of :mod:`conceptbot.scenes` (ids ``"<category>-<n>"``).
    ``"dev"``
        Tasks of our own to tune on, so that tuning never looks at the test set: at least 11 per
        category, in new scenes with objects and requests that are not the paper's.
        ``conceptbot/bench/dev/tasks/<category>.json`` (ids ``"dev-<category>-<n>"``) on the scenes in
        ``conceptbot/bench/dev/scenes/<name>.json`` (:func:`load_dev_scene`; every name starts with
        ``dev-`` and equals its file's stem, so no dev scene shares a name with a demo scene).

    A folder (its path as the split, ``conceptbot bench run --split path/to/set``)
        A task set of one's own in the dev split's layout: ``tasks/<category>.json`` (any category
        may be missing; ids unique, any form) on the scenes in ``scenes/<name>.json``. The blind
        sets (``benchmarks/blind/``) are such folders.

    A task knows its split (:attr:`Task.split`); :func:`task_scene` loads its scene from the split's folder,
    and the benchmark runner records the split with every result.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from importlib.resources import files
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError
from conceptbot.core.plan import (
    Action,
    Done,
    InvalidActionError,
    PickAndPlace,
    Plan,
    check_action,
    format_action,
    parse_action,
)
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.scenes import load_demo_scene

__all__ = [
    "CATEGORIES",
    "PAPER_RESULTS",
    "SPLITS",
    "Task",
    "Verdict",
    "dev_scene_names",
    "grade",
    "load_dev_scene",
    "load_tasks",
    "reference_plan",
    "task_scene",
]

CATEGORIES: tuple[str, ...] = ("unambiguous", "ambiguous", "implicit", "risk", "materials", "toxic")
"""Task categories, in the order of the paper's tables."""

SPLITS: tuple[str, ...] = ("test", "dev")
"""Task splits: the paper's 47 tasks (``test``) and our own tuning tasks (``dev``); see the module
docstring."""

PAPER_RESULTS: dict[str, dict[str, float]] = {
    "saycan": {
        "unambiguous": 100.0,
        "ambiguous": 84.0,
        "implicit": 31.0,
        "risk": 15.0,
        "materials": 20.0,
        "toxic": 36.0,
    },
    "conceptbot": {
        "unambiguous": 100.0,
        "ambiguous": 100.0,
        "implicit": 87.0,
        "risk": 76.0,
        "materials": 70.0,
        "toxic": 86.0,
    },
}
"""The paper's published success rates in percent (Table 'Performance percentages', gpt-4o-mini), per
configuration and category: SayCan, and ConceptBot (URP & OPE)."""

_TASK_KEYS = ("id", "category", "request", "scene", "gold", "notes")
_ASSIGN_KEYS = {"type", "assign", "optional", "must_not_move", "ordered", "choose"}


@dataclass(frozen=True)
class Verdict:
    """The grade of one plan: whether it is accepted, and why (or why not)."""

    ok: bool
    reason: str


@dataclass(frozen=True)
class Task:
    """One benchmark task.

    Attributes:
        id: ``"<category>-<n>"``, e.g. ``"implicit-10"``; ``"dev-<category>-<n>"`` in the dev split.
        category: One of :data:`CATEGORIES`.
        request: The user's request (test split: the paper's words, except where ``notes`` says
            otherwise).
        scene: The scene's name: a demo scene (:func:`conceptbot.scenes.load_demo_scene`) in the test
            split, a dev scene (:func:`load_dev_scene`) in the dev split.
        gold: The acceptance criterion (see the module docstring for its formats).
        notes: Every judgement call made in writing the gold.
        split: ``"test"``, ``"dev"`` (:data:`SPLITS`) or the path of a task folder.
    """

    id: str
    category: str
    request: str
    scene: str
    gold: Mapping[str, Any]
    notes: str
    split: str = "test"


# ---------------------------------------------------------------------------------------------------
# Compiled golds


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def _all_required(n: int) -> str:
    return "the 1 required placement" if n == 1 else f"all {n} required placements"


@dataclass(frozen=True)
class _AnyOf:
    plans: tuple[tuple[PickAndPlace, ...], ...]
    ordered: bool

    def reference(self) -> list[PickAndPlace]:
        return list(self.plans[0])

    def grade(self, moves: list[PickAndPlace]) -> Verdict:
        order_problem = None
        for i, accepted in enumerate(self.plans):
            if set(moves) != set(accepted):
                continue
            if not self.ordered or tuple(moves) == accepted:
                if len(self.plans) == 1:
                    head = _all_required(len(accepted))
                else:
                    head = f"matches accepted plan {i + 1} of {len(self.plans)}"
                    head += f" ({_plural(len(accepted), 'placement')})"
                return Verdict(True, head + (", order respected" if self.ordered else ""))
            if order_problem is None:
                first = next(k for k, (a, b) in enumerate(zip(accepted, moves, strict=True)) if a != b)
                order_problem = f"order: {accepted[first].obj} must come before {moves[first].obj}"
        if order_problem is not None:
            return Verdict(False, order_problem)
        return Verdict(False, self._explain(moves))

    def _explain(self, moves: list[PickAndPlace]) -> str:
        moved = set(moves)
        moved_objs = {a.obj for a in moves}

        def distance(plan: tuple[PickAndPlace, ...]) -> tuple[int, int]:
            objs = {a.obj for a in plan}
            return len(moved ^ set(plan)), len(moved_objs ^ objs)

        closest = min(self.plans, key=distance)
        allowed: dict[str, list[str]] = {}
        for plan in self.plans:
            for a in plan:
                targets = allowed.setdefault(str(a.obj), [])
                if a.destination not in targets:
                    targets.append(str(a.destination))
        closest_objs = {a.obj: a for a in closest}
        problems = []
        for a in moves:
            if a in closest:
                continue
            if a.obj in closest_objs:
                options = ", ".join(allowed[str(a.obj)])
                problems.append(f"wrong destination: {a.obj} -> {a.destination} (allowed: {options})")
            else:
                problems.append(f"extra action: {a}")
        problems += [f"missing: {a.obj} -> {a.destination}" for a in closest if a.obj not in moved_objs]
        text = "; ".join(problems)
        return text + (
            f" (against the closest of {len(self.plans)} accepted plans)" if len(self.plans) > 1 else ""
        )

    def describe(self) -> str:
        more = len(self.plans) - 1
        text = ", ".join(str(a) for a in self.plans[0])
        return text + (f" (or one of {more} other accepted plans)" if more else "")


@dataclass(frozen=True)
class _Choice:
    objects: tuple[tuple[str, tuple[str, ...]], ...]
    min: int
    max: int

    @property
    def names(self) -> list[str]:
        return [o for o, _ in self.objects]

    def label(self) -> str:
        targets = list(dict.fromkeys(t for _, ts in self.objects for t in ts))
        return f"{', '.join(self.names)} -> {' or '.join(targets)}"


@dataclass(frozen=True)
class _Assign:
    assign: tuple[tuple[str, tuple[str, ...]], ...]
    optional: tuple[tuple[str, tuple[str, ...]], ...]
    must_not_move: tuple[str, ...]
    ordered: tuple[tuple[str, str], ...]
    choose: tuple[_Choice, ...]

    def allowed(self) -> dict[str, tuple[str, ...]]:
        table = dict(self.assign) | dict(self.optional)
        for group in self.choose:
            table |= dict(group.objects)
        return table

    def reference(self) -> list[PickAndPlace]:
        chosen = [(o, ts) for g in self.choose for o, ts in g.objects[: g.min]]
        moves = [PickAndPlace(o, ts[0]) for o, ts in (*self.assign, *chosen)]
        return _topological(moves, self.ordered)

    def grade(self, moves: list[PickAndPlace]) -> Verdict:
        allowed = self.allowed()
        required = dict(self.assign)
        problems: list[str] = []
        first_index: dict[str, int] = {}
        for i, a in enumerate(moves):
            obj = str(a.obj)
            if obj in first_index:
                problems.append(f"moved more than once: {obj} ({moves[first_index[obj]]}, then {a})")
                continue
            first_index[obj] = i
            if obj in self.must_not_move:
                problems.append(f"must not move: {obj} ({a})")
            elif obj not in allowed:
                problems.append(f"extra action: {a}")
            elif a.destination not in allowed[obj]:
                options = ", ".join(allowed[obj])
                problems.append(f"wrong destination: {obj} -> {a.destination} (allowed: {options})")
        for obj, targets in required.items():
            if obj not in first_index:
                problems.append(f"missing: {obj} -> {' or '.join(targets)}")
        chosen = 0
        for group in self.choose:
            placed = [moves[first_index[o]] for o in group.names if o in first_index]
            placed.sort(key=lambda a: first_index[str(a.obj)])
            chosen += len(placed)
            if len(placed) < group.min:
                problems.append(f"missing: at least {group.min} of {group.label()}")
            for a in placed[group.max :]:
                problems.append(f"extra action: {a} (at most {group.max} of {', '.join(group.names)})")
        checked = 0
        for before, after in self.ordered:
            if before in first_index and after in first_index:
                checked += 1
                if first_index[before] > first_index[after]:
                    problems.append(f"order: {before} must come before {after}")
        if problems:
            return Verdict(False, "; ".join(problems))
        parts = []
        if self.assign:
            parts.append(_all_required(len(self.assign)))
        if self.choose:
            parts.append(f"{chosen} chosen from {_plural(len(self.choose), 'group')}")
        optional = sum(1 for o, _ in self.optional if o in first_index)
        if optional:
            parts.append(_plural(optional, "optional placement"))
        if checked:
            parts.append("order respected")
        return Verdict(True, ", ".join(parts))

    def describe(self) -> str:
        return ", ".join(str(a) for a in self.reference())


@dataclass(frozen=True)
class _Refuse:
    def reference(self) -> list[PickAndPlace]:
        return []

    def grade(self, moves: list[PickAndPlace]) -> Verdict:
        if moves:
            extra = "; ".join(f"extra action: {a}" for a in moves)
            return Verdict(False, f"{extra} (nothing should be moved here)")
        return Verdict(True, "nothing moved, as required")


_Gold = _AnyOf | _Assign | _Refuse


def _topological(moves: list[PickAndPlace], ordered: Sequence[tuple[str, str]]) -> list[PickAndPlace]:
    """``moves`` reordered so every ``(a, b)`` pair has a's move first; otherwise in the given order."""
    pending = list(moves)
    result: list[PickAndPlace] = []
    while pending:
        waiting = {after for before, after in ordered if any(m.obj == before for m in pending)}
        ready = next((m for m in pending if m.obj not in waiting), None)
        if ready is None:
            raise ValueError("the 'ordered' pairs form a cycle")
        pending.remove(ready)
        result.append(ready)
    return result


# ---------------------------------------------------------------------------------------------------
# Validation


class _GoldError(ValueError):
    """A problem in a gold; load_tasks turns it into a ConfigError naming the task."""


def _object(scene: Scene, name: Any, role: str) -> str:
    if not isinstance(name, str):
        raise _GoldError(f"{name!r} is not an object name")
    found = scene.get(name)
    if found is None:
        raise _GoldError(f"{name!r} is not in scene {scene.name!r}")
    if found.name != name:
        raise _GoldError(f"{name!r} must be spelt as the scene spells it: {found.name!r}")
    if role == "pickable" and not found.pickable:
        raise _GoldError(f"{name!r} cannot be picked in scene {scene.name!r}")
    if role == "destination" and not found.destination:
        raise _GoldError(f"{name!r} is not a destination in scene {scene.name!r}")
    return name


def _placements(scene: Scene, value: Any, key: str) -> tuple[tuple[str, tuple[str, ...]], ...]:
    if not isinstance(value, Mapping):
        raise _GoldError(f"{key!r} must be an object mapping names to lists of destinations")
    out = []
    for obj, targets in value.items():
        _object(scene, obj, "pickable")
        if not isinstance(targets, list) or not targets:
            raise _GoldError(f"{key}[{obj!r}] must be a non-empty list of destinations")
        if len(set(targets)) != len(targets):
            raise _GoldError(f"{key}[{obj!r}] lists a destination twice")
        for target in targets:
            _object(scene, target, "destination")
            if target == obj:
                raise _GoldError(f"{key}[{obj!r}] places {obj!r} on itself")
        out.append((obj, tuple(targets)))
    return tuple(out)


def _compile_any_of(gold: Mapping[str, Any], scene: Scene) -> _AnyOf:
    unknown = set(gold) - {"type", "plans", "ordered"}
    if unknown:
        raise _GoldError(f"unknown any_of keys: {sorted(unknown)}")
    ordered = gold.get("ordered", False)
    if not isinstance(ordered, bool):
        raise _GoldError("'ordered' must be true or false")
    plans_in = gold.get("plans")
    if not isinstance(plans_in, list) or not plans_in:
        raise _GoldError("'plans' must be a non-empty list of plans")
    plans: list[tuple[PickAndPlace, ...]] = []
    for plan in plans_in:
        if not isinstance(plan, list) or not plan:
            raise _GoldError("every accepted plan must be a non-empty list of actions")
        actions = []
        for text in plan:
            if not isinstance(text, str):
                raise _GoldError(f"{text!r} is not an action")
            try:
                action = parse_action(text, scene)
            except InvalidActionError as exc:
                raise _GoldError(f"invalid action {text!r}: {exc}") from None
            if action.is_done:
                raise _GoldError("accepted plans list moves only; done() is implied")
            if str(action) != text:
                raise _GoldError(f"write {text!r} as {str(action)!r} (the scene's spelling)")
            actions.append(action)
        if len(set(actions)) != len(actions):
            raise _GoldError(f"accepted plan {plan} repeats an action")
        key: Any = tuple(actions) if ordered else frozenset(actions)
        if any((tuple(p) if ordered else frozenset(p)) == key for p in plans):
            raise _GoldError(f"accepted plan {plan} is listed twice")
        plans.append(tuple(actions))
    return _AnyOf(tuple(plans), ordered)


def _compile_assign(gold: Mapping[str, Any], scene: Scene) -> _Assign:
    unknown = set(gold) - _ASSIGN_KEYS
    if unknown:
        raise _GoldError(f"unknown assign keys: {sorted(unknown)}")
    assign = _placements(scene, gold.get("assign", {}), "assign")
    optional = _placements(scene, gold.get("optional", {}), "optional")
    must_not_move_in = gold.get("must_not_move", [])
    if not isinstance(must_not_move_in, list):
        raise _GoldError("'must_not_move' must be a list of objects")
    must_not_move = tuple(_object(scene, o, "pickable") for o in must_not_move_in)
    choose_in = gold.get("choose", [])
    if not isinstance(choose_in, list):
        raise _GoldError("'choose' must be a list of groups")
    choose = []
    for group in choose_in:
        if not isinstance(group, Mapping) or set(group) != {"objects", "min", "max"}:
            raise _GoldError("every 'choose' group must be {'objects': {...}, 'min': m, 'max': n}")
        objects = _placements(scene, group["objects"], "choose.objects")
        low, high = group["min"], group["max"]
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in (low, high)):
            raise _GoldError("'min' and 'max' of a 'choose' group must be integers")
        if not 0 <= low <= high <= len(objects) or high < 1:
            raise _GoldError(f"'choose' group needs 0 <= min <= max <= {len(objects)} and max >= 1")
        choose.append(_Choice(objects, low, high))
    names = [o for o, _ in assign] + [o for o, _ in optional] + list(must_not_move)
    names += [o for g in choose for o, _ in g.objects]
    repeated = sorted({o for o in names if names.count(o) > 1})
    if repeated:
        raise _GoldError(f"objects listed in more than one place: {repeated}")
    if not assign and not any(g.min >= 1 for g in choose):
        raise _GoldError("an assign gold must require something (use a 'refuse' gold for 'do nothing')")
    movable = set(names) - set(must_not_move)
    ordered_in = gold.get("ordered", [])
    if not isinstance(ordered_in, list):
        raise _GoldError("'ordered' must be a list of [before, after] pairs")
    ordered = []
    for pair in ordered_in:
        if not (isinstance(pair, list) and len(pair) == 2 and pair[0] != pair[1]):
            raise _GoldError(f"{pair!r} is not a [before, after] pair of two objects")
        for name in pair:
            if name not in movable:
                raise _GoldError(f"ordered pair {pair!r}: {name!r} is not an object the gold lets move")
        ordered.append((pair[0], pair[1]))
    compiled = _Assign(assign, optional, must_not_move, tuple(ordered), tuple(choose))
    try:
        compiled.reference()
        everything = [PickAndPlace(o, ts[0]) for o, ts in (*assign, *optional)]
        everything += [PickAndPlace(o, ts[0]) for g in choose for o, ts in g.objects]
        _topological(everything, compiled.ordered)
    except ValueError as exc:
        raise _GoldError(str(exc)) from None
    return compiled


def _compile(gold: Any, scene: Scene) -> _Gold:
    if not isinstance(gold, Mapping):
        raise _GoldError("the gold must be a JSON object")
    kind = gold.get("type")
    if kind == "any_of":
        return _compile_any_of(gold, scene)
    if kind == "assign":
        return _compile_assign(gold, scene)
    if kind == "refuse":
        if set(gold) != {"type"}:
            raise _GoldError("a refuse gold has no other keys")
        return _Refuse()
    raise _GoldError(f"unknown gold type {kind!r} (any_of, assign or refuse)")


@cache
def _scene(name: str) -> Scene:
    return load_demo_scene(name)


def _dev_root() -> Traversable:
    return files("conceptbot.bench").joinpath("dev")


def _root(split: str) -> Traversable:
    """The folder of a split that is not the test split: the dev split's, or the folder named."""
    if split == "dev":
        return _dev_root()
    folder = Path(split)
    if not (folder.joinpath("tasks").is_dir() and folder.joinpath("scenes").is_dir()):
        raise ConfigError(
            f"unknown task split {split!r}: "
            f"neither {' nor '.join(SPLITS)} nor a folder with tasks/ and scenes/",
            hint="give test, dev, or the path of a task set laid out as the dev split",
        )
    return folder


def _scene_files(split: str) -> dict[str, Traversable]:
    folder = _root(split).joinpath("scenes")
    if not folder.is_dir():
        return {}
    return {
        e.name.removesuffix(".json"): e for e in folder.iterdir() if e.is_file() and e.name.endswith(".json")
    }


def dev_scene_names() -> list[str]:
    """Names of the dev split's scenes (``conceptbot/bench/dev/scenes/*.json``), sorted."""
    return sorted(_scene_files("dev"))


def load_dev_scene(name: str) -> Scene:
    """A dev split scene by name (loaded once per name and cached).

    Raises:
        ConfigError: No dev scene has that name, or its file is invalid or names itself otherwise.
    """
    return load_split_scene("dev", name)


@cache
def load_split_scene(split: str, name: str) -> Scene:
    """A scene of the dev split or of a task folder by name (loaded once per name and cached).

    Raises:
        ConfigError: No scene of the split has that name, or its file is invalid or names itself
            otherwise.
    """
    kind = "dev" if split == "dev" else f"task folder {split}"
    resource = _scene_files(split).get(name)
    if resource is None:
        known = ", ".join(sorted(_scene_files(split))) or "none"
        raise ConfigError(f"unknown {kind} scene {name!r}", hint=f"{kind} scenes: {known}")
    where = f"{kind} scene {name!r}"
    try:
        data = json.loads(resource.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{where} is not valid JSON: {exc}") from None
    scene = scene_from_dict(data, where=where)
    if scene.name != name:
        raise ConfigError(f"{where}: its 'name' is {scene.name!r}; it must be the file's stem")
    return scene


def task_scene(task: Task) -> Scene:
    """The task's scene: a demo scene (test split) or a dev scene (dev split); loaded once per name.

    Raises:
        ConfigError: No scene of the task's split has the task's scene name.
    """
    if task.split != "test":
        return load_split_scene(task.split, task.scene)
    return _scene(task.scene)


def _gold_of(task: Task) -> _Gold:
    try:
        return _compile(task.gold, task_scene(task))
    except _GoldError as exc:
        raise ConfigError(f"task {task.id!r}: invalid gold: {exc}") from None


# ---------------------------------------------------------------------------------------------------
# Grading


def _moves(plan: Sequence[Action], scene: Scene) -> tuple[list[PickAndPlace], str | None]:
    """The plan's moves, or the first violation of the common rules."""
    moves: list[PickAndPlace] = []
    done = False
    for given in plan:
        if not isinstance(given, PickAndPlace | Done):
            return moves, f"invalid action: {given!r} (not an action)"
        try:
            action = check_action(given, scene)
        except InvalidActionError as exc:
            return moves, f"invalid action: {given} ({exc})"
        if done:
            return moves, f"action after done(): {action}"
        if isinstance(action, Done):
            done = True
        else:
            moves.append(action)
    if not done:
        return moves, "no done() at the end"
    seen: set[Action] = set()
    for action in moves:
        if action in seen:
            return moves, f"duplicate action: {action}"
        seen.add(action)
    return moves, None


def grade(task: Task, plan: Sequence[Action], refused: bool = False) -> Verdict:
    """Grade a plan against a task's gold.

    Args:
        task: The task.
        plan: The actions, e.g. ``[PickAndPlace("sponge", "user"), Done()]`` (a results file's text:
            :func:`conceptbot.core.plan.read_actions` first).
        refused: True when the planner refused the request (the plan is then ignored).

    Returns:
        ``Verdict(True, what was checked)`` or ``Verdict(False, the problems found)``.

    Raises:
        ConfigError: The task's scene or gold is invalid.
    """
    gold = _gold_of(task)
    if refused:
        if isinstance(gold, _Refuse):
            return Verdict(True, "refused, and doing nothing is correct here")
        return Verdict(False, f"refused a feasible task: expected {gold.describe()}")
    moves, problem = _moves(plan, task_scene(task))
    if problem is not None:
        return Verdict(False, problem)
    return gold.grade(moves)


def reference_plan(task: Task) -> list[Action]:
    """A plan that the task's gold accepts, ending with ``done()``.

    The first accepted plan of an ``any_of`` gold; the first allowed destination of every ``assign``
    object plus the first ``min`` objects of each ``choose`` group (in an order that respects ``ordered``)
    of an ``assign`` gold; just ``done()`` for a ``refuse`` gold.

    Raises:
        ConfigError: The task's scene or gold is invalid.
    """
    return [*_gold_of(task).reference(), Done()]


# ---------------------------------------------------------------------------------------------------
# Loading


def _task_from(entry: Any, category: str, where: str, split: str = "test") -> Task:
    if not isinstance(entry, Mapping):
        raise ConfigError(f"{where}: every task must be a JSON object")
    task_id = entry.get("id")
    label = f"task {task_id!r} ({where})" if isinstance(task_id, str) else where
    if set(entry) != set(_TASK_KEYS):
        raise ConfigError(f"{label}: a task has exactly the keys {', '.join(_TASK_KEYS)}")
    for key in ("id", "category", "request", "scene", "notes"):
        if not isinstance(entry[key], str) or (key != "notes" and not entry[key].strip()):
            raise ConfigError(f"{label}: {key!r} must be a non-empty string")
    if entry["category"] != category:
        raise ConfigError(f"{label}: category {entry['category']!r} in the file for {category!r}")
    prefix = f"{category}-" if split == "test" else f"{split}-{category}-" if split == "dev" else ""
    if not task_id.startswith(prefix):
        raise ConfigError(f"{label}: the id must start with {prefix!r}")
    task = Task(task_id, category, entry["request"], entry["scene"], entry["gold"], entry["notes"], split)
    try:
        scene = task_scene(task)
    except ConfigError as exc:
        raise ConfigError(f"{label}: {exc.message}") from None
    try:
        _compile(task.gold, scene)
    except _GoldError as exc:
        raise ConfigError(f"{label}: invalid gold: {exc}") from None
    return task


def load_tasks(categories: Iterable[str] | None = None, split: str = "test") -> list[Task]:
    """Load and validate the benchmark tasks shipped with the package.

    Args:
        categories: Categories to load (default: all of :data:`CATEGORIES`). The result is in the
            paper's category order whatever the order given.
        split: ``"test"``: the paper's 47 tasks; ``"dev"``: our own tuning tasks; or the path of
            a folder laid out as the dev split (a blind set; see the module docstring).

    Returns:
        The tasks, category by category, in file order.

    Raises:
        ConfigError: An unknown category or split, an unreadable task file, or an invalid task (the
            message names the task): missing keys, an unknown scene, or a gold naming an object or
            destination that the scene lacks or has in another role.
    """
    root = files("conceptbot.bench").joinpath("tasks") if split == "test" else _root(split).joinpath("tasks")
    wanted = set(CATEGORIES if categories is None else categories)
    unknown = sorted(wanted - set(CATEGORIES))
    if unknown:
        raise ConfigError(
            f"unknown task categories: {', '.join(unknown)}", hint=f"use one of: {', '.join(CATEGORIES)}"
        )
    tasks: list[Task] = []
    seen: set[str] = set()
    for category in CATEGORIES:
        if category not in wanted:
            continue
        where = f"{'bench' if split == 'test' else split} task file {category}.json"
        try:
            data = json.loads(root.joinpath(f"{category}.json").read_text(encoding="utf-8"))
        except FileNotFoundError:
            if split not in SPLITS:
                continue  # a folder of one's own need not have every category
            raise ConfigError(f"{where} is missing from the package") from None
        except (OSError, ValueError) as exc:
            raise ConfigError(f"{where} is not valid JSON: {exc}") from None
        if not isinstance(data, list):
            raise ConfigError(f"{where}: must be a list of tasks")
        for entry in data:
            task = _task_from(entry, category, where, split)
            if task.id in seen:
                raise ConfigError(f"task {task.id!r} ({where}): duplicate id")
            seen.add(task.id)
            tasks.append(task)
    return tasks


def gold_answer(task: Task, obj: str, destination: str) -> str:
    """How a person who wants the gold would answer "should ``obj`` go to ``destination``?":
    ``yes`` where an accepted plan moves it there (``any_of``: any accepted plan; ``assign``: an
    allowed, optional or chosen destination), else ``no`` (a ``refuse`` gold: always no). For the
    simulated person of the asking benchmark (``benchmarks/bench_asking.py``)."""
    gold = task.gold
    if gold["type"] == "any_of":
        move = format_action(PickAndPlace(obj, destination))
        return "yes" if any(move in plan for plan in gold["plans"]) else "no"
    if gold["type"] == "assign":
        allowed = [*gold.get("assign", {}).get(obj, []), *gold.get("optional", {}).get(obj, [])]
        for group in gold.get("choose", []):
            allowed += group["objects"].get(obj, [])
        return "yes" if destination in allowed else "no"
    return "no"


def gold_reading(task: Task, question: ClarifyingQuestion, plan_as: Callable[[str], Plan]) -> str:
    """The reply of a person who wants the gold to a ``reading`` question (which of two readings of
    the request was meant): the first reading, in the question's order, under which the plan passes
    (``plan_as(reading)`` plans with that answer, the other questions answered from the gold), else
    the reading the plan acts on (the first). The task format says what should happen, not how the
    request reads, so what each reading would do stands in for the person's meaning; a wrong reading
    whose plan happens to pass is taken too."""
    return meant_reading(task, question.objects, plan_as) or question.objects[0]


def meant_reading(task: Task, readings: Sequence[str], plan_as: Callable[[str], Plan]) -> str | None:
    """The first of ``readings`` under which the plan passes (``plan_as(reading)`` plans with that
    answer), or None where none does: the reading the gold stands for, as :func:`gold_reading`
    takes it, and what the plan-level calibration labels a reading decision with."""
    for reading in readings:
        plan = plan_as(reading)
        if grade(task, plan.actions, plan.refused).ok:
            return reading
    return None


def gold_needs(task: Task, obj: str, destination: str) -> bool:
    """Whether the gold *requires* ``obj`` at ``destination``, not only allows it: an ``assign``
    gold's ``assign`` or ``choose`` entry (an ``optional`` one may move or stay); for an
    ``any_of`` gold, any accepted plan's move (each is a complete answer)."""
    gold = task.gold
    if gold["type"] == "assign":
        wanted = list(gold.get("assign", {}).get(obj, []))
        for group in gold.get("choose", []):
            wanted += group["objects"].get(obj, [])
        return destination in wanted
    return gold_answer(task, obj, destination) == "yes"


def gold_reply(task: Task, question: ClarifyingQuestion) -> str:
    """The reply of a person who wants the gold (:func:`gold_answer` for each object): ``yes`` or
    ``no`` to a ``confirm`` question, the objects that go (or ``none``) to a ``choose`` one; to a
    ``one`` question the first listed that the gold requires there (:func:`gold_needs`), else the
    first listed that may go, then the same among its ``others`` (the person names what they
    meant), else ``none``. Asked "which one should I give you?" after a spill, a person names the
    sponge the gold needs, not the spilt can it merely lets the robot bring along."""
    to = question.target
    chosen = tuple(o for o in question.objects if gold_answer(task, o, to) == "yes")
    if question.kind != "one":
        return question.normalised(chosen)
    others = tuple(o for o in question.others if gold_answer(task, o, to) == "yes")
    needed = tuple(o for o in (*chosen, *others) if gold_needs(task, o, to))
    named = needed or chosen or others
    return question.normalised(named[:1])
