"""`conceptbot kg` as a user runs it, on small source files in the real formats."""

import gzip
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from tests.cli.test_cli import run
from tests.kg_sources import cn5_line


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


def _big_dump(path: Path, lines: int = 3_000_000) -> Path:
    """A ConceptNet 5 dump that takes several seconds to import (one edge, repeated: small on disk)."""
    line = (cn5_line("UsedFor", "/c/en/knife", "/c/en/cut_bread", 3.46) + "\n").encode()
    with gzip.open(path, "wb", compresslevel=1) as handle:
        for _ in range(lines // 10_000):
            handle.write(line * 10_000)
    return path


def _interrupted_install(home: Path, dump: Path, sig: signal.Signals) -> tuple[int, str, Path]:
    """Start `kg install conceptnet5 --file DUMP`, send ``sig`` once its build file exists; return
    the exit code, stderr and the build file's path."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CONCEPTBOT_", "OPENAI_"))}
    env["CONCEPTBOT_HOME"] = str(home)
    process = subprocess.Popen(
        [sys.executable, "-m", "conceptbot", "kg", "install", "conceptnet5", "--file", str(dump)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    building = home / "kg" / f".conceptnet.db.{process.pid}.building"
    try:
        deadline = time.monotonic() + 60
        while not building.exists():
            assert process.poll() is None, "the install ended before it was interrupted"
            assert time.monotonic() < deadline, "no build file appeared"
            time.sleep(0.05)
        process.send_signal(sig)
        _, err = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    return process.returncode, err, building


def test_sigterm_during_a_build_leaves_no_temporary_file(
    isolated_home: Path, cn5_file: Path, tmp_path: Path
) -> None:
    run("kg", "install", "conceptnet5", "--file", str(cn5_file), home=isolated_home)
    db = isolated_home / "kg" / "conceptnet.db"
    before = db.read_bytes()
    code, err, building = _interrupted_install(
        isolated_home, _big_dump(tmp_path / "big.csv.gz"), signal.SIGTERM
    )
    assert code == 128 + signal.SIGTERM and "Terminated." in err and "Traceback" not in err
    assert not building.exists() and sorted(p.name for p in db.parent.iterdir()) == ["conceptnet.db"]
    assert db.read_bytes() == before  # the installed graph is untouched


def test_the_next_install_removes_what_a_killed_one_left(
    isolated_home: Path, cn5_file: Path, tmp_path: Path
) -> None:
    code, _, building = _interrupted_install(
        isolated_home, _big_dump(tmp_path / "big.csv.gz"), signal.SIGKILL
    )
    assert code == -signal.SIGKILL and building.exists()  # nothing can clean up after SIGKILL...
    out = run("kg", "install", "conceptnet5", "--file", str(cn5_file), home=isolated_home)
    assert not building.exists()  # ... but the next install does, and says so
    assert f"removed {building}" in out.stderr and "interrupted install" in out.stderr
