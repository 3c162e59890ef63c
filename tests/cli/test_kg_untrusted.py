"""`kg query` prints graph text (a dump, the ConceptNet API, Wikipedia) as literal text: markup and
control characters in an edge cannot crash it or reach the terminal raw (issue 32, item 4/5)."""

from __future__ import annotations

import gzip
from pathlib import Path

from tests.cli.test_cli import run

HOSTILE = "knife\tsharp [/x] \x1b]0;pwned\x07 [bold]\t{'freq': 5, 'score': 9, 'rel': u'HasProperty'}"


def test_kg_query_prints_hostile_edges_literally(
    isolated_home: Path, tmp_path: Path, wordnet_dir: Path
) -> None:
    dump = tmp_path / "conceptnet_en.graph.gz"
    with gzip.open(dump, "wt") as handle:
        handle.write(HOSTILE + "\n")
    run("kg", "install", "--file", str(dump), "--wordnet-dir", str(wordnet_dir), home=isolated_home)
    human = run("kg", "query", "knife", "--no-fallback", home=isolated_home)
    as_json = run("kg", "query", "knife", "--no-fallback", "--json", home=isolated_home)
    for out in (human, as_json):
        shown = out.stdout + out.stderr
        assert "\x1b" not in shown and "\x07" not in shown and "Traceback" not in shown
    assert "[/x]" in human.stdout and "\\x1b" in human.stdout  # printed as typed, the escape visible


def test_ros2_send_refuses_a_nan_time_out(isolated_home: Path) -> None:
    out = run("ros2", "send", "hi", "--timeout", "nan", home=isolated_home, check_exit=2)
    assert "Traceback" not in out.stderr and "nan" in out.stderr.lower()


def test_a_concept_with_bytes_that_are_not_utf8_is_an_input_error_not_damage(
    isolated_home: Path, omcs_file: Path, wordnet_dir: Path
) -> None:
    run("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home)
    out = run("kg", "query", "kn\udcffife", "--no-fallback", home=isolated_home, check_exit=2)
    assert "undecodable bytes" in out.stderr and "damaged" not in out.stderr and "--force" not in out.stderr
    # The library, asked the same, finds no such concept: the graph is not damaged.
    from conceptbot.knowledge.sqlite_store import SQLiteGraph

    assert not SQLiteGraph(isolated_home / "kg" / "conceptnet.db").edges("kn\udcffife")
