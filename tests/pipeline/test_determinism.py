"""Same input, same plan, every run (issue 33, item 6): nothing the goal planner decides may depend
on Python's hash seed (set order), and a decider shared between threads keeps no per-question state.

The plan runs in subprocesses under different ``PYTHONHASHSEED`` values with a graph whose dish
lies behind one of many IsA parents (the planner follows 12 per level: which 12 must not depend on
the seed) and a backend whose log-probabilities are a stable hash of the prompt and the option.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from conceptbot.core.scene import scene_from_dict
from conceptbot.models.fake import FakeEmbedder
from conceptbot.pipeline.goal_planner.decide import Decider, FactFinder
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.determinism_plan import HashLLM, graph_edges
from tests.pipeline.fakes import DictGraph

ROOT = Path(__file__).resolve().parents[2]


def _plan_under(seed: str) -> dict:
    env = {**os.environ, "PYTHONHASHSEED": seed}
    out = subprocess.run(
        [sys.executable, "-m", "tests.pipeline.determinism_plan"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    return json.loads(out.stdout)


def test_one_plan_is_the_same_under_every_hash_seed() -> None:
    seen = [_plan_under(seed) for seed in ("0", "1", "2", "3", "4", "5")]
    assert all(found == seen[0] for found in seen[1:]), [s["dish_reached"] for s in seen]


def test_a_decider_keeps_no_state_a_question_changes() -> None:
    graph = DictGraph(graph_edges())
    decider = Decider(HashLLM(), FactFinder(RelationRetriever(graph, FakeEmbedder(), theta=0.1)))
    before = dict(vars(decider))
    scene = scene_from_dict({"pickable_objects": ["carrot", "onion"], "destinations": ["pot"]})
    judgements, _, _ = decider.fits("Make me a stew", "an ingredient", ["carrot", "onion"], scene)
    assert vars(decider) == before  # nothing written on the shared object
    assert {j.scoring for j in judgements} == {"logprob"}  # how each was scored travels with it
