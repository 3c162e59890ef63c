"""`conceptbot kg` as a user runs it, on small source files in the real formats."""

import json
from pathlib import Path

from tests.cli.test_cli import run


def test_install_stats_and_query_offline(isolated_home: Path, omcs_file: Path, wordnet_dir: Path) -> None:
    out = run(
        "kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home
    )
    assert "offline:" in out.stdout and "edges" in out.stdout and "skipped line 9" in out.stdout
    again = run(
        "kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home
    )
    assert "already installed" in again.stdout
    stats = run("kg", "stats", home=isolated_home).stdout
    assert "omcs" in stats and "wordnet" in stats
    data = json.loads(run("kg", "stats", "--json", home=isolated_home).stdout)
    assert {s["name"] for s in data["sources"]} == {"omcs", "wordnet"}
    query = json.loads(run("kg", "query", "Knives", "--json", "--no-fallback", home=isolated_home).stdout)
    assert query["matched"] == "knife" and query["match"] == "lemma"
    assert query["edges"][0] == {
        "head": "knife",
        "relation": "AtLocation",
        "tail": "kitchen",
        "weight": 17.0,
        "source": "omcs",
        "sentence": "knife AtLocation kitchen",
    }
    only_isa = json.loads(
        run("kg", "query", "knife", "-r", "IsA", "--json", "--no-fallback", home=isolated_home).stdout
    )
    assert {e["relation"] for e in only_isa["edges"]} == {"IsA"}


def test_query_offline_reports_the_fallback_unavailable(
    isolated_home: Path, omcs_file: Path, wordnet_dir: Path
) -> None:
    run("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home)
    env_url = "http://127.0.0.1:1/w/api.php"  # nothing listens there
    out = run("kg", "query", "zzyzx", home=isolated_home, extra_env={"CONCEPTBOT_WIKIPEDIA_URL": env_url})
    assert "no edges" in out.stdout and "fallback unavailable" in out.stdout


def test_conceptnet5_from_a_local_dump(isolated_home: Path, cn5_file: Path) -> None:
    out = run("kg", "install", "conceptnet5", "--file", str(cn5_file), home=isolated_home)
    assert "conceptnet5: 4 edges" in out.stdout and "'other_language': 2" in out.stdout
    assert "conceptnet5/wordnet" in run("kg", "stats", home=isolated_home).stdout


def test_bad_input_is_a_clear_error(isolated_home: Path, tmp_path: Path) -> None:
    missing = run("kg", "stats", home=isolated_home, check_exit=1)
    assert "no knowledge graph" in missing.stderr and "conceptbot kg install" in missing.stderr
    broken = tmp_path / "broken.csv.gz"
    broken.write_bytes(b"\x1f\x8b\x08\x00garbage")
    bad = run("kg", "install", "conceptnet5", "--file", str(broken), home=isolated_home, check_exit=1)
    assert "truncated or corrupt" in bad.stderr and "Traceback" not in bad.stderr
    assert not (isolated_home / "kg" / "conceptnet.db").exists()
    (isolated_home / "kg").mkdir(parents=True, exist_ok=True)
    (isolated_home / "kg" / "conceptnet.db").write_bytes(b"not a database at all" * 50)
    corrupt = run("kg", "query", "knife", home=isolated_home, check_exit=1)
    assert "not a readable knowledge graph" in corrupt.stderr
    unknown = run("--kg", "neo4j", "kg", "query", "knife", home=isolated_home, check_exit=2)
    assert "unknown knowledge graph" in unknown.stderr


def test_damaged_graph_file_is_one_clear_error(
    isolated_home: Path, omcs_file: Path, wordnet_dir: Path
) -> None:
    from tests.knowledge.test_sqlite_store import _damage

    run("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home)
    _damage(isolated_home / "kg" / "conceptnet.db", seed=1, pages=10_000)
    for args in (("kg", "stats"), ("kg", "query", "knife", "--no-fallback")):
        out = run(*args, home=isolated_home, check_exit=1)
        assert "Traceback" not in out.stderr
        assert "Error:" in out.stderr and "conceptnet.db" in out.stderr
        assert "kg install" in out.stderr
