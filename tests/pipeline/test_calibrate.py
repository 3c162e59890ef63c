"""Calibration arithmetic: threshold grids, kept counts per object, the chosen theta."""

from __future__ import annotations

from pathlib import Path

import pytest

from conceptbot.knowledge.base import Edge
from conceptbot.pipeline.calibrate import (
    PAPER_KEPT,
    SweepRow,
    choose_theta,
    load_objects,
    rows_for,
    sweep,
    thetas_between,
)
from conceptbot.pipeline.retrieval import Retrieval, ScoredEdge

REPO = Path(__file__).resolve().parents[2]


def retrieval(concept: str, *sims: float) -> Retrieval:
    edges = tuple(
        ScoredEdge(Edge(concept, "IsA", f"thing {i}", 1.0, "omcs"), s, "dangerous", False)
        for i, s in enumerate(sims)
    )
    return Retrieval(concept, concept if sims else None, "exact" if sims else "none", edges)


OBJECTS = {
    "knife": retrieval("knife", 0.9, 0.8, 0.75, 0.6, 0.2),
    "glass": retrieval("glass", 0.8, 0.5),
    "zzyzx": retrieval("zzyzx"),
}


def test_thetas_between() -> None:
    grid = thetas_between(0.30, 0.90, 0.05)
    assert len(grid) == 13 and grid[0] == 0.30 and grid[-1] == 0.90 and grid[7] == 0.65
    assert thetas_between(0.5, 0.5, 0.1) == [0.5]
    with pytest.raises(ValueError):
        thetas_between(0.5, 0.4, 0.05)
    with pytest.raises(ValueError):
        thetas_between(0.1, 0.4, 0)


def test_rows_count_strictly_above_theta() -> None:
    rows = rows_for(OBJECTS.values(), [0.0, 0.5, 0.75, 0.8, 0.95])
    # per object counts: 0.0 -> 5,2,0   0.5 -> 4,1,0   0.75 -> 2,1,0   0.8 -> 1,0,0   0.95 -> 0,0,0
    assert rows == [
        SweepRow(0.0, 7 / 3, 2.0, 0, 5, 1),
        SweepRow(0.5, 5 / 3, 1.0, 0, 4, 1),
        SweepRow(0.75, 1.0, 1.0, 0, 2, 1),
        SweepRow(0.8, 1 / 3, 0.0, 0, 1, 2),
        SweepRow(0.95, 0.0, 0.0, 0, 0, 3),
    ]
    assert rows_for([OBJECTS["knife"], OBJECTS["glass"]], [0.7])[0].median_kept == 2.0  # (3 + 1) / 2
    with pytest.raises(ValueError):
        rows_for([], [0.5])


class StubRetriever:
    def __init__(self) -> None:
        self.calls: list[tuple[list[str], list[str]]] = []

    def retrieve_many(self, concepts, targets):
        self.calls.append((list(concepts), list(targets)))
        return {c: OBJECTS[c] for c in dict.fromkeys(concepts)}


def test_sweep_retrieves_once_and_counts_every_theta() -> None:
    made: list[float] = []
    stub = StubRetriever()

    def factory(theta: float) -> StubRetriever:
        made.append(theta)
        return stub

    rows = sweep(factory, ["knife", "glass", "zzyzx"], ["dangerous"], [0.8, 0.5])
    assert made == [0.5] and stub.calls == [(["knife", "glass", "zzyzx"], ["dangerous"])]
    assert [(r.theta, r.mean_kept, r.objects_with_none) for r in rows] == [(0.8, 1 / 3, 2), (0.5, 5 / 3, 1)]
    assert sweep(factory, ["knife"], ["dangerous"], []) == []


def row(theta: float, mean: float) -> SweepRow:
    return SweepRow(theta, mean, mean, 0, int(mean * 3), 0)


def test_choose_theta_is_closest_to_the_papers_twenty() -> None:
    assert PAPER_KEPT == 20.0
    rows = [row(0.20, 35.5), row(0.25, 21.8), row(0.30, 11.1), row(0.35, 5.8)]
    assert choose_theta(rows) == 0.25
    assert choose_theta(rows, want=12.0) == 0.30
    assert choose_theta(rows, want=100.0) == 0.20
    assert choose_theta([row(0.4, 18.0), row(0.5, 22.0)]) == 0.5  # a tie goes to the higher theta
    assert choose_theta([row(0.5, 22.0), row(0.4, 18.0)]) == 0.5
    with pytest.raises(ValueError):
        choose_theta([])


def test_load_objects(tmp_path: Path) -> None:
    packaged = load_objects()
    assert "knife" in packaged and "ceramic bowl" in packaged
    assert not any(o.startswith("#") or not o for o in packaged)
    assert len(packaged) == len(set(packaged)) > 100
    source = REPO / "benchmarks" / "data" / "paper_objects.txt"
    if source.exists():  # the packaged copy must match the benchmark list
        assert packaged == load_objects(source)
    mine = tmp_path / "objects.txt"
    mine.write_text("# kitchen\nknife\n\n  glass  \nknife\n")
    assert load_objects(mine) == ["knife", "glass"]
