"""How sure the choice between two readings of a request is, and the readings in words for a question.

How often each step of :func:`.aided.choose` keeps the right reading ships as ``reading_odds.json``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import cache
from importlib.resources import files
from typing import Any

from conceptbot.core.errors import ConfigError
from conceptbot.pipeline.goal.types import ALL, Goal, GoalTarget
from conceptbot.pipeline.hazards import is_person

ODDS_FILE = "reading_odds.json"
#: A step with no count (a new step, a fixed policy): either reading as likely, so the person is asked.
UNKNOWN = (0.5, 0.5)
NUMBERS = ("one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten")


@dataclass(frozen=True)
class Odds:
    """How often a step of the choice kept the right reading, and how often it dropped the right one.

    Attributes:
        taken: P(the reading kept is the one meant).
        other: P(the reading dropped is the one meant); the rest is neither.
        rows: How many goal-set rows the counts come from.
    """

    taken: float
    other: float
    rows: int = 0


@cache
def _odds_data() -> dict[str, Any]:
    where = f"reading odds file {ODDS_FILE}"
    try:
        data = json.loads(files("conceptbot.pipeline.goal").joinpath(ODDS_FILE).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"{where} is missing from the package") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{where} is not valid JSON: {exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("steps"), dict):
        raise ConfigError(f"{where}: needs a 'steps' object")
    return data


def odds(step: str) -> Odds:
    """The shipped odds of ``step``; :data:`UNKNOWN` for a step without valid counts (the person is asked)."""
    found = _odds_data()["steps"].get(step)
    if not isinstance(found, dict):
        return Odds(*UNKNOWN)
    taken, other = found.get("taken"), found.get("other")
    if not all(isinstance(p, (int, float)) and 0.0 <= p <= 1.0 for p in (taken, other)):  # NaN fails
        return Odds(*UNKNOWN)
    return Odds(float(taken), float(other), int(found.get("rows", 0)))


@dataclass(frozen=True)
class JudgeWeights:
    """How the model's preference between two readings moves a step's odds (fitted by ``--fit-judge``).

    Attributes:
        weight: Log-odds of the reading dropped per nat the model prefers it.
        bias: Added to the step's log-odds of the reading dropped.
    """

    weight: float
    bias: float


def judge_weights() -> JudgeWeights | None:
    """The shipped weights, or None where the odds file has none (the steps' odds stand alone).

    Raises:
        ConfigError: The file's weights are not two finite numbers.
    """
    found = _odds_data().get("judge")
    if found is None:
        return None
    weight, bias = (found.get("weight"), found.get("bias")) if isinstance(found, dict) else (None, None)
    if not (_finite(weight) and _finite(bias)):
        raise ConfigError(f"reading odds file {ODDS_FILE}: 'judge' needs finite 'weight' and 'bias'")
    return JudgeWeights(float(weight), float(bias))


def _finite(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def judged(found: Odds, preference: float, weights: JudgeWeights) -> Odds:
    """A step's odds moved by the model's ``preference`` (log-odds) for the reading taken: the dropped one
    gets ``sigmoid(log(other / taken) + bias - weight * preference)`` of their mass; NaN gives UNKNOWN."""
    if not math.isfinite(preference):
        return Odds(*UNKNOWN, found.rows)
    if found.taken <= 0.0 or found.other <= 0.0:
        return found  # odds of 0 (never smoothed so) have no log-odds to move
    shared = found.taken + found.other
    z = math.log(found.other / found.taken) + weights.bias - weights.weight * preference
    other = shared / (1.0 + math.exp(-z)) if z > -700 else 0.0
    return Odds(shared - other, other, found.rows)


def _things(target: GoalTarget, dish: str | None) -> str:
    """Which objects a target takes, in words."""
    if target.takes == "named":
        names = [f"the {n}" for n in target.named]
        return names[0] if len(names) == 1 else " and ".join((", ".join(names[:-1]), names[-1]))
    if target.takes == "ingredients":
        return f'the ingredients of "{dish}"' if dish else "the ingredients"
    if target.takes == "need":
        return f'something for "{target.criterion}"' if target.criterion else "what the need calls for"
    if target.takes == "remainder":
        return "the rest"
    if target.takes == "all" or not target.criterion:
        return "everything"
    if target.count == ALL:
        return f'everything that is "{target.criterion}"'
    count = int(target.count)
    number = NUMBERS[count - 1] if count <= len(NUMBERS) else str(count)
    return f'{number} "{target.criterion}"'


def _move(target: GoalTarget, dish: str | None, need: str | None) -> str:
    """One target as a move in words."""
    things = _things(target, dish)
    if target.takes == "need" and not target.criterion and need:
        things = f'something for "{need}"'
    if target.to is None:
        return f"give {things}" if target.takes == "need" else f"put {things} where it fits"
    if is_person(target.to):
        return f"give the {target.to} {things}"
    return f"put {things} in or on the {target.to}"


def describe(goal: Goal) -> str:
    """What a reading would do, in words ("do nothing" for no targets); no commas between moves, so an
    answer naming it reads whole."""
    if goal.stack:
        return "stack the objects on each other"
    moves = [_move(t, goal.dish, goal.need) for t in goal.targets]
    if not moves:
        return "do nothing"
    return " and ".join(moves) if len(moves) <= 2 else "; ".join(moves[:-1]) + " and " + moves[-1]
