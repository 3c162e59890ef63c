"""`conceptbot calibrate` as a user runs it: a small installed graph and the hashing embedder."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from conceptbot.knowledge.base import TARGET_PROPERTIES
from conceptbot.knowledge.sqlite_store import SQLiteGraph
from conceptbot.models.fake import FakeEmbedder
from conceptbot.pipeline.calibrate import rows_for, thetas_between
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.cli.test_cli import run


@pytest.fixture
def objects(tmp_path: Path) -> Path:
    path = tmp_path / "objects.txt"
    path.write_text("# a few objects\nknife\nglass\nbowl\napple\nzzyzx\n")
    return path


@pytest.fixture
def installed(isolated_home: Path, omcs_file: Path, wordnet_dir: Path) -> Path:
    run("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home)
    return isolated_home


def test_calibrate_json_matches_a_direct_measurement(installed: Path, objects: Path) -> None:
    out = run("--embedder", "fake", "calibrate", "--objects", str(objects), "--json", home=installed)
    data = json.loads(out.stdout)
    thetas = thetas_between(0.10, 0.90, 0.05)
    assert [r["theta"] for r in data["rows"]] == thetas
    assert data["model"] == "fake-embedder" and data["objects"] == 5
    assert data["objects_without_edges"] == ["zzyzx"]
    assert data["targets"] == list(TARGET_PROPERTIES)
    assert data["paper_reference"] == {"0.70": 35.0, "0.75": 20.0, "0.80": 3.0}
    graph = SQLiteGraph(installed / "kg" / "conceptnet.db")
    retriever = RelationRetriever(graph, FakeEmbedder(), theta=0.1)
    names = ["knife", "glass", "bowl", "apple", "zzyzx"]
    retrievals = retriever.retrieve_many(names, TARGET_PROPERTIES)
    expected = rows_for(retrievals.values(), thetas)
    assert data["edges"] == sum(len(r.edges) for r in retrievals.values()) > 0
    for got, want in zip(data["rows"], expected, strict=True):
        assert got["mean_kept"] == pytest.approx(want.mean_kept)
        assert (got["min_kept"], got["max_kept"], got["objects_with_none"]) == (
            want.min_kept,
            want.max_kept,
            want.objects_with_none,
        )
    assert data["rows"][0]["mean_kept"] > data["rows"][-1]["mean_kept"]
    assert data["rows"][-1]["objects_with_none"] == 5  # nothing is that close to a property word
    assert data["recommended_theta"] in thetas and data["default_theta"] == 0.20
    assert data["at_edge"] is True  # 8 edges in all: never ~20 per object


def test_calibrate_prints_the_table_and_the_recommendation(installed: Path, objects: Path) -> None:
    out = run(
        "--embedder",
        "fake",
        "calibrate",
        "--objects",
        str(objects),
        "--from",
        "0.5",
        "--to",
        "0.6",
        home=installed,
    ).stdout
    assert "theta" in out and "objects with none" in out
    assert "0.50" in out and "0.55" in out and "0.60" in out and "0.65" not in out
    assert "paper (text-embedding-ada-002): ~35 kept at >0.70, ~20 kept at >0.75, ~3 kept at >0.80" in out
    assert "objects without edges: zzyzx" in out
    # The small graph keeps far fewer than 20 per object, so the best lies below the swept range.
    assert "every threshold keeps fewer than ~20 per object" in out and "widen it with --from" in out
    # Means 0.4, 0.4, 0.2: the tie between 0.50 and 0.55 goes to the higher threshold.
    assert "recommended theta for fake-embedder: 0.55 " in out
    assert "current default 0.20" in out


def test_calibrate_without_a_graph_is_a_clear_error(isolated_home: Path, objects: Path) -> None:
    result = run(
        "--embedder", "fake", "calibrate", "--objects", str(objects), home=isolated_home, check_exit=1
    )
    assert "no knowledge graph" in result.stderr and "conceptbot kg install" in result.stderr
    assert "Traceback" not in result.stderr


def test_calibrate_rejects_a_backwards_range(installed: Path, objects: Path) -> None:
    result = run(
        "--embedder", "fake", "calibrate", "--from", "0.8", "--to", "0.2", home=installed, check_exit=2
    )
    assert "--to" in result.stderr
