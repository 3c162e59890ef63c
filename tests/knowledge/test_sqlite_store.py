import sqlite3
from pathlib import Path

import pytest

from conceptbot.core.errors import ImportDataError, KnowledgeUnavailableError
from conceptbot.knowledge.base import Edge, KnowledgeGraph
from conceptbot.knowledge.install import install_conceptnet5, install_offline
from conceptbot.knowledge.sqlite_store import GraphBuilder, SQLiteGraph


def _build(path: Path) -> None:
    with GraphBuilder(path, "test") as builder:
        builder.add("knife", "IsA", "weapon", 7.0, "omcs")
        builder.add("knife", "UsedFor", "cut", 8.0, "omcs")
        builder.add("stab", "HasPrerequisite", "knife", 7.5, "omcs")
        builder.add("knife", "IsA", "edge tool", 2.0, "wordnet")
        builder.add("knife", "IsA", "weapon", 7.0, "omcs")  # duplicate
        builder.add("bowl", "UsedFor", "hold liquid", 3.0, "omcs")


def test_head_and_tail_edges_strongest_first(tmp_path: Path) -> None:
    path = tmp_path / "kg.db"
    _build(path)
    graph = SQLiteGraph(path)
    assert isinstance(graph, KnowledgeGraph)
    result = graph.edges("Knives")
    assert (result.matched, result.match) == ("knife", "lemma")
    assert [e.sentence for e in result.edges] == [
        "knife UsedFor cut",
        "stab HasPrerequisite knife",
        "knife IsA weapon",
        "knife IsA edge tool",
    ]
    assert result.edges[3] == Edge("knife", "IsA", "edge tool", 2.0, "wordnet")
    assert [e.relation for e in graph.edges("knife", relations=["IsA"]).edges] == ["IsA", "IsA"]
    assert len(graph.edges("knife", limit=2).edges) == 2
    assert graph.edges("knife", relations=["NoSuchRelation"]).edges == ()


def test_stats_count_per_source(tmp_path: Path) -> None:
    path = tmp_path / "kg.db"
    _build(path)
    stats = SQLiteGraph(path).stats()
    assert {s["name"]: s["edges"] for s in stats["sources"]} == {"omcs": 4, "wordnet": 1}
    assert stats["edges"] == 5 and stats["relations"]["IsA"] == 2 and stats["meta"]["install"] == "test"


def test_version_names_the_install_and_build_time(tmp_path: Path) -> None:
    path = tmp_path / "kg.db"
    _build(path)
    graph = SQLiteGraph(path)
    # The form OPE cache keys have always had: changing it would orphan every cached result.
    assert graph.version == f"test:{graph.meta['built_at']}" and graph.meta["built_at"].endswith("Z")


def test_unknown_concept_is_empty_not_an_error(tmp_path: Path) -> None:
    path = tmp_path / "kg.db"
    _build(path)
    result = SQLiteGraph(path).edges("flux capacitor")
    assert result.match == "none" and result.edges == ()


def test_failed_build_keeps_the_current_database(tmp_path: Path) -> None:
    path = tmp_path / "kg.db"
    _build(path)
    with pytest.raises(RuntimeError), GraphBuilder(path, "broken") as builder:
        builder.add("a", "IsA", "b", 1.0, "x")
        raise RuntimeError("interrupted")
    assert SQLiteGraph(path).meta["install"] == "test"
    assert [p.name for p in tmp_path.iterdir()] == ["kg.db"]


@pytest.mark.parametrize("content", [b"", b"this is not sqlite" * 100])
def test_empty_or_corrupt_database(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "kg.db"
    path.write_bytes(content)
    with pytest.raises(KnowledgeUnavailableError, match="kg install"):
        SQLiteGraph(path)


def test_database_of_another_kind(tmp_path: Path) -> None:
    path = tmp_path / "kg.db"
    sqlite3.connect(path).execute("CREATE TABLE t (x)").connection.commit()
    with pytest.raises(KnowledgeUnavailableError, match="not a readable knowledge graph"):
        SQLiteGraph(path)


def test_missing_database_names_the_install_command(tmp_path: Path) -> None:
    with pytest.raises(KnowledgeUnavailableError) as info:
        SQLiteGraph(tmp_path / "absent.db")
    assert "conceptbot kg install" in str(info.value)


def test_install_offline_from_local_files_is_idempotent(
    tmp_path: Path, omcs_file: Path, wordnet_dir: Path
) -> None:
    db = tmp_path / "kg" / "conceptnet.db"
    report = install_offline(db, tmp_path / "dl", divisi_file=omcs_file, wordnet_dir=wordnet_dir)
    assert report.edges > 10 and not report.skipped
    graph = SQLiteGraph(db)
    sources = {s["name"] for s in graph.stats()["sources"]}
    assert sources == {"omcs", "wordnet"}
    assert "hollandaise IsA sauce" in [e.sentence for e in graph.edges("hollandaise").edges]
    again = install_offline(db, tmp_path / "dl", divisi_file=omcs_file, wordnet_dir=wordnet_dir)
    assert again.skipped
    forced = install_offline(db, tmp_path / "dl", divisi_file=omcs_file, wordnet_dir=wordnet_dir, force=True)
    assert forced.edges == report.edges


def test_install_conceptnet5_replaces_and_bad_dump_keeps_it(tmp_path: Path, cn5_file: Path) -> None:
    db = tmp_path / "conceptnet.db"
    report = install_conceptnet5(db, tmp_path, file=cn5_file)
    assert report.edges == 4 and report.details["conceptnet5"]["other_language"] == 2
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(ImportDataError, match="no English ConceptNet 5 edges"):
        install_conceptnet5(db, tmp_path, file=empty)
    assert SQLiteGraph(db).meta["install"] == "conceptnet5"
    assert SQLiteGraph(db).stats()["edges"] == 4


def _damage(path: Path, seed: int, pages: int = 6) -> None:
    """Overwrite ``pages`` random pages after the schema with random bytes (same file size)."""
    import random

    rng = random.Random(seed)
    data = bytearray(path.read_bytes())
    page = int.from_bytes(data[16:18], "big")
    count = len(data) // page
    for index in rng.sample(range(2, count), min(pages, count - 2)):
        data[index * page : (index + 1) * page] = rng.randbytes(page)
    path.write_bytes(bytes(data))


def test_damaged_pages_are_a_clear_error_never_a_crash(tmp_path: Path) -> None:
    clean = tmp_path / "clean.db"
    with GraphBuilder(clean, "test") as builder:
        for i in range(3000):
            builder.add(f"thing {i}", "IsA", f"kind {i % 50}", float(i % 7), "omcs")
    found = 0
    for seed in range(12):
        path = tmp_path / f"kg{seed}.db"
        path.write_bytes(clean.read_bytes())
        _damage(path, seed)
        assert path.stat().st_size == clean.stat().st_size
        try:
            graph = SQLiteGraph(path)
            graph.stats()
            for i in range(0, 3000, 97):
                graph.edges(f"thing {i}")
            graph.random_concepts(20)
        except KnowledgeUnavailableError as exc:  # any other exception fails the test
            assert str(path) in exc.message and exc.hint
            found += 1
    assert found >= 6  # most random damage is detected; the rest reads as (wrong) rows, not a crash


def test_damage_found_by_a_query_names_the_rebuild_command(tmp_path: Path) -> None:
    path = tmp_path / "kg.db"
    with GraphBuilder(path, "test") as builder:
        for i in range(3000):
            builder.add(f"thing {i}", "IsA", f"kind {i % 50}", 1.0, "omcs")
    graph = SQLiteGraph(path)  # opened while intact: damage appears under a running reader
    _damage(path, seed=0, pages=10_000)
    with pytest.raises(KnowledgeUnavailableError, match="is damaged") as info:
        graph.stats()
    assert "kg install --force" in (info.value.hint or "")
