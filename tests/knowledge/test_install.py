"""Installs remove the build files that interrupted installs left, and only those."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from conceptbot.knowledge.install import (
    STALE_AFTER_S,
    clean_stale_builds,
    install_conceptnet5,
    install_offline,
)


@pytest.fixture
def dead_pid() -> int:
    """The pid of a process that has exited (and been reaped)."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


@pytest.fixture
def live_pid() -> Iterator[int]:
    """The pid of a running process, as a concurrent install would be."""
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    try:
        yield child.pid
    finally:
        child.kill()
        child.wait()


def _build_file(kg: Path, pid: int, size: int = 1000) -> Path:
    kg.mkdir(parents=True, exist_ok=True)
    path = kg / f".conceptnet.db.{pid}.building"
    path.write_bytes(b"\0" * size)
    return path


def test_an_install_removes_the_build_file_of_a_dead_install_and_keeps_a_live_ones(
    tmp_path: Path, cn5_file: Path, dead_pid: int, live_pid: int
) -> None:
    kg = tmp_path / "kg"
    dead = _build_file(kg, dead_pid, size=5000)
    live = _build_file(kg, live_pid)
    other = kg / f".other.db.{dead_pid}.building"  # not this database's
    other.write_bytes(b"x")
    report = install_conceptnet5(kg / "conceptnet.db", tmp_path / "downloads", file=cn5_file)
    assert report.edges > 0
    assert not dead.exists() and report.cleaned == [(str(dead), 5000)]
    assert live.exists() and other.exists()


def test_a_skipped_install_cleans_up_too(
    tmp_path: Path, omcs_file: Path, wordnet_dir: Path, dead_pid: int
) -> None:
    kg = tmp_path / "kg"
    args = {"divisi_file": omcs_file, "wordnet_dir": wordnet_dir}
    install_offline(kg / "conceptnet.db", tmp_path / "downloads", **args)
    dead = _build_file(kg, dead_pid)
    again = install_offline(kg / "conceptnet.db", tmp_path / "downloads", **args)
    assert again.skipped and again.cleaned == [(str(dead), 1000)] and not dead.exists()
    assert (kg / "conceptnet.db").is_file()


def test_a_build_file_untouched_for_long_is_stale_even_if_its_pid_lives(
    tmp_path: Path, live_pid: int
) -> None:
    # Pids are reused: a long-quiet file whose pid now names some other process goes too.
    path = _build_file(tmp_path, live_pid)
    assert clean_stale_builds(tmp_path / "conceptnet.db") == []
    later = time.time() + STALE_AFTER_S + 60
    assert clean_stale_builds(tmp_path / "conceptnet.db", now=later) == [(str(path), 1000)]


def test_this_process_build_file_is_kept(tmp_path: Path) -> None:
    path = _build_file(tmp_path, os.getpid())
    assert clean_stale_builds(tmp_path / "conceptnet.db") == [] and path.exists()
    assert clean_stale_builds(tmp_path / "missing" / "conceptnet.db") == []
