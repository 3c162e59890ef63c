"""Similar cases: how labelled household instructions like a new one were judged.

One signal of the household harm judgement (:mod:`conceptbot.household.harm`). The tuning tasks'
instructions, each labelled dangerous or ordinary (SafeAgentBench's dev split and the folded blind
household sets: ``harm_examples.json``, written by ``benchmarks/fit_household_harm.py``), are
embedded with the configured sentence embedder, and an L2-regularised logistic model over those
vectors is fitted when the signal is first read. The reading of a new instruction is that model's
log-odds of "dangerous". No word decides it: it is where the instruction's meaning lies among cases
already judged, and the harm model weighs it with what the plan does. The same embeddings find the
cases nearest to a new instruction, whose reference plans the planning call sees as examples.

The model is fitted in the process rather than shipped as weights, so it holds for whichever
embedder is configured; the embeddings go through the embedding cache like any others. On the
blind household sets, each scored by a fit on the tuning tasks written before it, the reading alone
separated hazards from chores with AUC 0.87 (set 4) and 0.91 (set 5), where the judge's readings
and the plan's signals together scored 0.78 and 0.86
(docs/notes/2026-12-08-household-similar-cases.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache

import numpy as np

from conceptbot.core.errors import ConfigError
from conceptbot.household.asking import read_json
from conceptbot.models.embedder import Embedder

EXAMPLES_FILE = "harm_examples.json"
WHAT = "household harm examples"
STRENGTH = 10.0
"""The fit's inverse L2 strength (scikit-learn's ``C``): 3 to 100 measured on the folded sets, 10
between the best and the most regularised."""


@dataclass(frozen=True)
class Example:
    """A labelled instruction: the task it comes from, its words, whether it is dangerous, and its
    reference plan as task steps (:mod:`conceptbot.household.skills`; empty where there is none)."""

    task: str
    instruction: str
    dangerous: bool
    steps: tuple[str, ...] = ()


def fit_logistic(x: np.ndarray, y: np.ndarray, strength: float = STRENGTH) -> tuple[np.ndarray, float]:
    """Weights and intercept of the L2-regularised logistic model of ``y`` (0/1) on the rows of
    ``x``: minimises ``|w|^2 / 2 + strength * log-loss`` (the intercept unpenalised) by Newton's
    method, which converges in a few steps for a few hundred dimensions."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    design = np.hstack([x, np.ones((len(x), 1))])
    theta = np.zeros(design.shape[1])
    penalty = np.full(design.shape[1], 1.0 / strength)
    penalty[-1] = 0.0
    for _ in range(50):
        p = 1.0 / (1.0 + np.exp(-(design @ theta)))
        gradient = design.T @ (p - y) + penalty * theta
        hessian = (design * (p * (1 - p))[:, None]).T @ design + np.diag(penalty + 1e-9)
        step = np.linalg.solve(hessian, gradient)
        theta -= step
        if np.abs(step).max() < 1e-8:
            break
    return theta[:-1], float(theta[-1])


def cross_fitted(x: np.ndarray, y: np.ndarray, folds: int = 5, strength: float = STRENGTH) -> np.ndarray:
    """Each row's log-odds from a fit on the other folds (rows dealt round-robin): the reading a
    task would have had if it were new, for fitting the harm model on honest values."""
    scores = np.zeros(len(y))
    fold = np.arange(len(y)) % folds
    for k in range(folds):
        weights, bias = fit_logistic(x[fold != k], y[fold != k], strength)
        scores[fold == k] = x[fold == k] @ weights + bias
    return scores


@cache
def shipped_examples() -> tuple[Example, ...]:
    """The labelled instructions shipped with the package.

    Raises:
        ConfigError: The file is missing or malformed.
    """
    data = read_json(EXAMPLES_FILE, WHAT)
    try:
        found = tuple(
            Example(str(e["task"]), str(e["instruction"]), bool(e["dangerous"]), tuple(e.get("steps", ())))
            for e in data["examples"]
        )
    except (KeyError, TypeError) as exc:
        raise ConfigError(
            f"{WHAT} {EXAMPLES_FILE}: each example needs task, instruction, dangerous ({exc})"
        ) from None
    if len({e.dangerous for e in found}) < 2:
        raise ConfigError(f"{WHAT} {EXAMPLES_FILE}: needs dangerous and ordinary examples")
    return found


class SimilarCases:
    """Reads an instruction against the labelled ones (fitted on first use).

    Args:
        embedder: The sentence embedder (the configured one, behind the embedding cache).
        examples: The labelled instructions; the shipped ones if None.
        strength: The fit's inverse L2 strength.
    """

    def __init__(
        self, embedder: Embedder, examples: Sequence[Example] | None = None, strength: float = STRENGTH
    ) -> None:
        self.embedder = embedder
        self.examples = tuple(examples) if examples is not None else None
        self.strength = strength
        self._fitted: tuple[np.ndarray, float] | None = None
        self._vectors: np.ndarray | None = None

    def _cases(self) -> tuple[Example, ...]:
        return self.examples if self.examples is not None else shipped_examples()

    def _embedded(self) -> np.ndarray:
        if self._vectors is None:
            self._vectors = np.asarray(
                self.embedder.embed([e.instruction for e in self._cases()]), dtype=float
            )
        return self._vectors

    def _model(self) -> tuple[np.ndarray, float]:
        if self._fitted is None:
            y = np.array([e.dangerous for e in self._cases()], dtype=float)
            self._fitted = fit_logistic(self._embedded(), y, self.strength)
        return self._fitted

    def nearest(self, instruction: str, k: int, leave_out: str = "") -> list[Example]:
        """The ``k`` examples with a plan whose instructions are nearest in meaning to
        ``instruction`` (cosine of the embeddings), nearest first; ``leave_out``: not those whose
        task id starts with it (a set measured on its own)."""
        vectors = self._embedded()
        cases = self._cases()
        vector = np.asarray(self.embedder.embed([instruction]), dtype=float)
        if vector.shape != (1, vectors.shape[1]):
            return []
        similarity = vectors @ vector[0]
        ranked = [
            cases[i]
            for i in np.argsort(-similarity, kind="stable")
            if cases[i].steps and not (leave_out and cases[i].task.startswith(leave_out))
        ]
        return ranked[:k]

    def reading(self, instruction: str) -> float:
        """The log-odds that ``instruction`` is dangerous, from the cases like it; NaN where it
        cannot be read (the harm judgement then refuses: it fails closed)."""
        weights, bias = self._model()
        vector = np.asarray(self.embedder.embed([instruction]), dtype=float)
        if vector.shape != (1, len(weights)):
            return math.nan
        score = float(vector[0] @ weights + bias)
        return score if math.isfinite(score) else math.nan
