"""A broken home or cache.db is one error with its fix, never a traceback; --no-cache gets by without it.

Tests run as root, which permission bits do not stop, and without mounts. So a read-only home is
made the way a read-only mount fails: the database file is opened read-only (SQLite's ``mode=ro``,
the same SQLITE_READONLY a read-only file system gives) or a folder cannot be made because a file
stands in its path. A full disk is SQLite's own SQLITE_FULL, from ``PRAGMA max_page_count`` capped
at the file's size. The damaged files, the home that is a file and ``--no-cache`` also run through
the CLI, as a user meets them; a real read-only mount and a full tmpfs were checked by hand (they
need ``mount``), with the same messages.
"""

from __future__ import annotations

import json
import logging
import os
import sqlite3
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from conceptbot.core import sqlite as core_sqlite
from conceptbot.core.config import Settings
from conceptbot.core.errors import FakeExhaustedError
from conceptbot.core.sqlite import failure_kind
from conceptbot.models import cache_db
from conceptbot.models.cache_db import CacheError, CacheStore, CallRecord
from conceptbot.models.caching import CachedEmbedder, CachedLLM
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.models.llm import ChatRequest
from conceptbot.models.registry import open_llm, open_run_store
from tests.pipeline.fakes import properties_reply, urp_reply

RECORD = CallRecord("chat", "cli", "fake", "m", 1, 1, 0.0, 0.0, False)


def _cli(*args: str, home: Path | str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CONCEPTBOT_", "OPENAI_"))}
    env["CONCEPTBOT_HOME"] = str(home)
    return subprocess.run(
        [sys.executable, "-m", "conceptbot", *args], capture_output=True, text=True, env=env, timeout=120
    )


def _llm_hi(tmp_path: Path, home: Path | str, *flags: str) -> subprocess.CompletedProcess[str]:
    replies = tmp_path / "replies.json"
    replies.write_text(json.dumps(["hello there"]))
    return _cli(*flags, "--llm", f"fake:{replies}", "llm", "hi", home=home)


def _assert_one_error(result: subprocess.CompletedProcess[str], *words: str) -> None:
    assert result.returncode == 1, result.stdout + result.stderr
    assert "Traceback" not in result.stderr, result.stderr
    lines = result.stderr.strip().splitlines()
    assert lines[0].startswith("Error: ") and lines[1].startswith("Hint: ") and len(lines) == 2, lines
    for word in words:
        assert word in result.stderr, result.stderr


def _fresh_db(path: Path) -> None:
    CacheStore(path).close()


def _not_a_db(path: Path) -> None:
    path.write_text("not a db\n")


def _truncated(path: Path) -> None:
    store = CacheStore(path)
    for i in range(200):  # enough rows that the tables span pages past the cut
        store.put_value("ope", f"k{i}", "x" * 200)
    store.close()  # the last connection checkpoints the WAL into the file
    path.write_bytes(path.read_bytes()[:8192])


def _folder(path: Path) -> None:
    path.mkdir()


def _calls_dropped(path: Path) -> None:
    _fresh_db(path)
    with sqlite3.connect(path) as conn:
        conn.execute("DROP TABLE calls")


def _foreign_table(path: Path) -> None:
    with sqlite3.connect(path) as conn:  # another program's file with a same-named table
        conn.execute("CREATE TABLE llm_cache (id INTEGER, blob BLOB)")


def _foreign_columns(path: Path) -> None:
    _fresh_db(path)
    with sqlite3.connect(path) as conn:  # migrations recorded, but the table is not ours
        conn.execute("DROP TABLE llm_cache")
        conn.execute("CREATE TABLE llm_cache (id INTEGER, blob BLOB)")


DAMAGE: dict[str, tuple[Callable[[Path], None], str]] = {
    "not a database": (_not_a_db, "file is not a database"),
    "truncated": (_truncated, "malformed"),
    "a folder": (_folder, "is a folder"),
    "table dropped": (_calls_dropped, "table calls is missing"),
    "foreign table": (_foreign_table, "table llm_cache already exists"),
    "foreign columns": (_foreign_columns, "table llm_cache has other columns"),
}


# -- the store ------------------------------------------------------------------------------------
@pytest.mark.parametrize("case", DAMAGE)
def test_a_damaged_cache_db_is_one_error_with_the_move_away_fix(tmp_path: Path, case: str) -> None:
    damage, detail = DAMAGE[case]
    path = tmp_path / "cache.db"
    damage(path)
    with pytest.raises(CacheError) as info:
        CacheStore(path)
    assert str(path) in info.value.message and detail in info.value.message
    assert info.value.hint and "move it away" in info.value.hint and f"mv {path}*" in info.value.hint


def test_the_move_away_fix_works_and_the_cache_is_rebuilt(tmp_path: Path) -> None:
    path = tmp_path / "cache.db"
    _calls_dropped(path)
    with pytest.raises(CacheError) as info:
        CacheStore(path)
    command = (info.value.hint or "").removeprefix("move it away: ").split(" ;")[0]
    subprocess.run(["sh", "-c", command], check=True)
    store = CacheStore(path)  # empty, and whole again
    store.log_call(RECORD)
    assert len(store.calls()) == 1 and (tmp_path / "broken-cache" / "cache.db").is_file()


@pytest.mark.parametrize("home", ["a-file", "a-file/below"])
def test_a_home_that_cannot_be_made_is_one_error(tmp_path: Path, home: str) -> None:
    (tmp_path / "a-file").write_text("I am a file")
    with pytest.raises(CacheError) as info:
        CacheStore(tmp_path / home / "cache.db")
    assert f"cannot create the folder {tmp_path / home}" in info.value.message
    assert "is a file" in info.value.message and "CONCEPTBOT_HOME" in (info.value.hint or "")


def _read_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """Open the store's file read-only, as a read-only mount forces (root ignores chmod)."""

    def connect(path: Path, timeout: float = 30.0) -> sqlite3.Connection:
        return sqlite3.connect(f"file:{path}?mode=ro", uri=True, isolation_level=None)

    monkeypatch.setattr(cache_db, "connect_shared", connect)


def test_a_read_only_cache_db_is_one_error_that_offers_no_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _fresh_db(tmp_path / "new.db")  # migrated: opening it writes nothing
    _read_only(monkeypatch)
    with pytest.raises(CacheError) as info:
        CacheStore(tmp_path / "absent.db")  # read-only and missing: it cannot be made
    assert "cannot open" in info.value.message or "read-only" in info.value.message
    assert "writable folder" in (info.value.hint or "") and "--no-cache" in (info.value.hint or "")
    store = CacheStore(tmp_path / "new.db")
    with pytest.raises(CacheError) as info:
        store.log_call(RECORD)
    assert "read-only" in info.value.message and "--no-cache" in (info.value.hint or "")


def test_cannot_open_is_told_apart_by_what_the_file_system_says(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    cannot_open = sqlite3.OperationalError("unable to open database file")
    (tmp_path / "a-folder").mkdir()
    assert failure_kind(cannot_open, tmp_path / "a-folder") == "folder"
    assert failure_kind(cannot_open, tmp_path / "cache.db") == "unopenable"
    # A read-only mount is where os.access says "not writable" even to root.
    monkeypatch.setattr(core_sqlite.os, "access", lambda path, mode: False)
    assert failure_kind(cannot_open, tmp_path / "cache.db") == "read-only"
    assert failure_kind(sqlite3.OperationalError("database or disk is full"), tmp_path) == "full"
    assert failure_kind(sqlite3.OperationalError("database is locked"), tmp_path) == "locked"


def _disk_full(store: CacheStore) -> None:
    """Cap the file at its present size: SQLite then answers SQLITE_FULL to anything that grows it."""
    pages = store._conn.execute("PRAGMA page_count").fetchone()[0]
    store._conn.execute(f"PRAGMA max_page_count = {pages}")


def test_a_full_disk_on_write_is_a_cache_error_naming_the_fix(tmp_path: Path) -> None:
    store = CacheStore(tmp_path / "cache.db")
    _disk_full(store)
    with pytest.raises(CacheError) as info:
        store.put_value("ope", "k", "x" * 100_000)
    assert "disk is full" in info.value.message and "free some disk space" in (info.value.hint or "")
    with pytest.raises(CacheError):
        long_text = "a" * 100_000  # the text is the row's key: it must be stored
        store.put_embeddings("m", [long_text], FakeEmbedder().embed([long_text]))


# -- calls keep their results when the cache fails mid-run ------------------------------------------
def test_a_full_disk_mid_run_keeps_every_answer_and_warns_once(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    store = CacheStore(tmp_path / "cache.db")
    _disk_full(store)
    big = "y" * 100_000  # a reply too big for the capped file
    llm = CachedLLM(FakeLLM([big, big]), store, module="cli")
    with caplog.at_level(logging.WARNING):
        first = llm.chat(ChatRequest.of("q1"))
        second = llm.chat(ChatRequest.of("q2"))
    assert first.text == big and second.text == big and not second.cached
    warnings = [r.getMessage() for r in caplog.records if "could not write the cache" in r.getMessage()]
    assert len(warnings) == 1 and "free some disk space" in warnings[0]
    embedder = CachedEmbedder(FakeEmbedder(), store)
    assert embedder.embed(["z" * 100_000]).shape[0] == 1


def test_a_cache_damaged_mid_run_is_a_miss_and_the_backend_error_still_reaches_the_caller(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    store = CacheStore(tmp_path / "cache.db")
    with sqlite3.connect(tmp_path / "cache.db") as other:  # someone breaks the file while we run
        other.execute("DROP TABLE llm_cache")
        other.execute("DROP TABLE calls")
    llm = CachedLLM(FakeLLM(["fresh"]), store)
    with caplog.at_level(logging.WARNING):
        assert llm.chat(ChatRequest.of("q")).text == "fresh"
        with pytest.raises(FakeExhaustedError):
            llm.chat(ChatRequest.of("another"))  # the backend's own error, not "no such table"
    text = caplog.text
    assert "could not read the cache" in text and "could not write the call log" in text
    assert "move it away" in text


# -- --no-cache with an unusable home ---------------------------------------------------------------
def test_no_cache_runs_without_the_call_log_when_the_home_is_unusable(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    (tmp_path / "a-file").write_text("")
    settings = Settings(home=tmp_path / "a-file" / "home", llm="fake", use_cache=False)
    with caplog.at_level(logging.WARNING):
        assert open_run_store(settings) is None
    assert "the call log is off" in caplog.text and "--no-cache (" not in caplog.text
    llm = open_llm(settings.with_overrides(llm=f"fake:{_replies(tmp_path)}"), module="cli")
    assert llm.store is None and llm.chat(ChatRequest.of("q")).text == "hello there"
    with pytest.raises(CacheError, match="cannot create the folder"):
        open_run_store(settings.with_overrides(use_cache=True))


def _replies(tmp_path: Path) -> Path:
    path = tmp_path / "replies.json"
    path.write_text(json.dumps(["hello there"]))
    return path


# -- as a user meets it ---------------------------------------------------------------------------
@pytest.mark.parametrize("case", DAMAGE)
def test_llm_on_a_damaged_cache_db_prints_one_error(tmp_path: Path, case: str) -> None:
    home = tmp_path / "home"
    home.mkdir()
    DAMAGE[case][0](home / "cache.db")
    _assert_one_error(_llm_hi(tmp_path, home), str(home / "cache.db"), "move it away")


def test_llm_with_a_home_that_is_a_file_prints_one_error(tmp_path: Path) -> None:
    home = tmp_path / "passwd"
    home.write_text("root:x:0:0\n")
    _assert_one_error(_llm_hi(tmp_path, home), "cannot create the folder", "CONCEPTBOT_HOME")
    _assert_one_error(_llm_hi(tmp_path, home / "x"), "cannot create the folder")


def test_llm_no_cache_with_a_broken_home_still_answers(tmp_path: Path) -> None:
    home = tmp_path / "home"
    home.mkdir()
    _not_a_db(home / "cache.db")
    result = _llm_hi(tmp_path, home, "--no-cache")
    assert result.returncode == 0, result.stderr
    assert "hello there" in result.stdout and "Traceback" not in result.stderr
    assert "warning: --no-cache: the call log is off" in result.stderr
    assert (home / "cache.db").read_text() == "not a db\n"  # left as it was


def test_plan_on_a_damaged_cache_db_is_one_error_and_runs_with_no_cache(tmp_path: Path) -> None:
    home = tmp_path / "home"
    home.mkdir()
    _not_a_db(home / "cache.db")
    replies = [properties_reply()] * 3 + [urp_reply(["pick_and_place(apple, user)"])]
    replies += ["pick_and_place(apple, user)"] * 5 + ["done()"] * 5
    (tmp_path / "replies.json").write_text(json.dumps(replies))
    scene = {"objects": ["apple", "sponge", "user"], "pickable_objects": ["apple"], "destinations": ["user"]}
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    args = ["--llm", f"fake:{tmp_path / 'replies.json'}", "--embedder", "fake", "plan", "Bring me an apple"]
    args += ["--scene", str(tmp_path / "scene.json"), "-c", "paper-nokg", "--json"]
    _assert_one_error(_cli(*args, home=home), "file is not a database", "move it away")
    result = _cli("--no-cache", *args, home=home)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["plan"] == ["pick_and_place(apple, user)", "done()"]
    assert "the call log is off" in result.stderr and "Traceback" not in result.stderr
