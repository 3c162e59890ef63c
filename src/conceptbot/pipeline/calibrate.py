"""Measure the similarity threshold ``theta`` for an embedding model (``conceptbot calibrate``).

The paper's ``theta = 0.75`` belongs to ``text-embedding-ada-002``. It reports the coverage that
choice gives: over its objects, about 35 relations are kept per object at ``theta > 0.70``, about
20 at ``> 0.75`` and about 3 at ``> 0.80`` (section III-A). Another embedding model spreads its
cosines differently, so the same number would keep far more or far fewer relations. Calibration
transfers the paper's choice instead of its number: sweep ``theta`` over the paper's objects and
targets, and take the value whose mean kept count per object is closest to the paper's ~20
(:func:`choose_theta`).
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from conceptbot.pipeline.retrieval import RelationRetriever, Retrieval

#: Relations kept per object in the paper (ada-002), by threshold.
PAPER_REFERENCE: dict[float, float] = {0.70: 35.0, 0.75: 20.0, 0.80: 3.0}
#: The paper's threshold, and the mean kept count per object it gives.
PAPER_THETA = 0.75
PAPER_KEPT = PAPER_REFERENCE[PAPER_THETA]

RetrieverFactory = Callable[[float], RelationRetriever]


@dataclass(frozen=True)
class SweepRow:
    """Kept relations per object at one threshold.

    Attributes:
        theta: The threshold (an edge is kept when its similarity is strictly above it).
        mean_kept: Mean kept edges per object (objects the graph does not know count as 0).
        median_kept: Median of the same counts.
        min_kept: Fewest kept edges of any object.
        max_kept: Most kept edges of any object.
        objects_with_none: Objects left with no kept edge.
    """

    theta: float
    mean_kept: float
    median_kept: float
    min_kept: int
    max_kept: int
    objects_with_none: int


def thetas_between(start: float, stop: float, step: float) -> list[float]:
    """``start, start + step, ...`` up to and including ``stop`` (rounded to 4 decimals, so 0.05
    steps do not drift).

    Raises:
        ValueError: ``step`` is not positive or ``stop < start``.
    """
    if step <= 0:
        raise ValueError(f"step must be positive, got {step}")
    if stop < start:
        raise ValueError(f"the sweep goes up: {start} > {stop}")
    count = int((stop - start) / step + 1e-9) + 1
    return [round(start + i * step, 4) for i in range(count)]


def load_objects(path: Path | None = None) -> list[str]:
    """Object names, one a line; blank lines and ``#`` comments skipped, duplicates dropped.

    Args:
        path: A text file; None reads the paper's objects shipped with the package.
    """
    if path is None:
        text = resources.files("conceptbot.pipeline").joinpath("data/paper_objects.txt").read_text("utf-8")
    else:
        text = Path(path).read_text(encoding="utf-8")
    lines = (line.strip() for line in text.splitlines())
    return list(dict.fromkeys(line for line in lines if line and not line.startswith("#")))


def measure(
    retriever: RelationRetriever, objects: Sequence[str], targets: Sequence[str]
) -> dict[str, Retrieval]:
    """Every object's scored edges, embedded in one batch (:meth:`RelationRetriever.retrieve_many`)."""
    return retriever.retrieve_many(objects, targets)


def rows_for(retrievals: Iterable[Retrieval], thetas: Sequence[float]) -> list[SweepRow]:
    """One :class:`SweepRow` per threshold, counting edges with ``similarity > theta``.

    The counts come from the stored similarities, so one retrieval serves every threshold.

    Raises:
        ValueError: No retrievals (nothing to average).
    """
    sims = [[e.similarity for e in r.edges] for r in retrievals]
    if not sims:
        raise ValueError("no objects to measure")
    out = []
    for theta in thetas:
        counts = [sum(1 for s in per_object if s > theta) for per_object in sims]
        out.append(
            SweepRow(
                theta=float(theta),
                mean_kept=statistics.fmean(counts),
                median_kept=float(statistics.median(counts)),
                min_kept=min(counts),
                max_kept=max(counts),
                objects_with_none=sum(1 for c in counts if c == 0),
            )
        )
    return out


def sweep(
    retriever_factory: RetrieverFactory,
    objects: Sequence[str],
    targets: Sequence[str],
    thetas: Sequence[float],
) -> list[SweepRow]:
    """Kept relations per object at each threshold.

    Args:
        retriever_factory: ``factory(theta) -> RelationRetriever``; called once, with the lowest
            threshold: similarities do not depend on theta, so one retrieval is counted at all.
        objects: Concepts to measure (duplicates are counted once).
        targets: Target texts, e.g. :data:`~conceptbot.knowledge.base.TARGET_PROPERTIES`.
        thetas: The thresholds, reported in the order given.
    """
    if not thetas:
        return []
    retriever = retriever_factory(min(thetas))
    return rows_for(measure(retriever, objects, targets).values(), thetas)


def choose_theta(rows: Sequence[SweepRow], want: float = PAPER_KEPT) -> float:
    """The threshold whose mean kept count per object is closest to ``want``.

    ``want`` defaults to the paper's ~20 relations per object at its theta = 0.75 with ada-002, so
    the chosen value keeps as much per object with another embedding model as the paper's choice
    did with its own. On a tie the higher threshold wins (fewer, more relevant relations).

    Raises:
        ValueError: No rows.
    """
    if not rows:
        raise ValueError("no sweep rows to choose from")
    return min(rows, key=lambda r: (abs(r.mean_kept - want), -r.theta)).theta
