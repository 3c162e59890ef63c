"""The fitted combination of the model's answer and the graph's evidence (issue 33, item 2)."""

from __future__ import annotations

import math

import pytest

from conceptbot.pipeline.goal_planner.combine import Combination, combination, sigmoid
from conceptbot.pipeline.goal_planner.evidence import FEATURES, GRAPH_FREE, Evidence


def test_the_log_odds_add_the_weighted_readings_and_features() -> None:
    combo = Combination(("model", "own_yes", "own_no"), (0.5, 3.0, -3.0), -0.2)
    evidence = Evidence("death cap", "poisonous", {"own_yes": 1.0})
    assert combo.log_odds({"model": -1.0}, evidence) == pytest.approx(-0.2 - 0.5 + 3.0)
    assert combo.log_odds({"model": -1.0}, None) == pytest.approx(-0.7)


def test_a_non_finite_reading_is_an_error_not_a_decision() -> None:
    with pytest.raises(ValueError, match="non-finite"):
        Combination(("model",), (1.0,), 0.0).log_odds({"model": math.nan}, None)


def test_malformed_weights_are_refused() -> None:
    with pytest.raises(ValueError):
        Combination.from_dict({"features": ["model", "own_yes"], "weights": [1.0], "bias": 0})
    with pytest.raises(ValueError):
        Combination.from_dict({"features": ["model"], "weights": [math.inf], "bias": 0})


def test_the_shipped_weights_use_the_graph_only_where_there_is_one() -> None:
    graph, nograph = combination(True), combination(False)
    assert any(f in graph.features for f in FEATURES if f not in GRAPH_FREE)
    # The model's answers, no graph in them: with graph facts left out, or its own description.
    readings = ("model", "model_z", "model_gap", "plain", "described", "described_z", "described_gap")
    assert all(part in (*readings, *GRAPH_FREE) for f in nograph.features for part in f.split("*"))
    # The model's answer counts in both, and in the same direction.
    assert graph.weights[graph.features.index("model")] > 0
    assert nograph.weights[nograph.features.index("model")] > 0


def test_sigmoid_is_stable_at_the_extremes() -> None:
    assert sigmoid(0.0) == 0.5
    assert sigmoid(-1000.0) == 0.0 and sigmoid(1000.0) == 1.0
