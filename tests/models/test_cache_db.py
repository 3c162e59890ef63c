import multiprocessing
import sqlite3
from pathlib import Path

import numpy as np

from conceptbot.models.cache_db import CacheStore, CallRecord, request_key
from conceptbot.models.migrations import MIGRATIONS


def test_migrations_apply_once_and_are_recorded(tmp_path: Path) -> None:
    db = CacheStore(tmp_path / "c.db")
    db.close()
    again = CacheStore(tmp_path / "c.db")
    assert again.applied_migrations() == [(n, name) for n, name, _ in MIGRATIONS]
    mode = again._conn.execute("PRAGMA journal_mode").fetchone()[0]
    assert mode == "wal"


def test_request_key_is_canonical() -> None:
    a = request_key("chat", "llamacpp", "m", {"x": 1, "y": [1, 2]})
    b = request_key("chat", "llamacpp", "m", {"y": [1, 2], "x": 1})
    assert a == b
    assert a != request_key("chat", "llamacpp", "other", {"x": 1, "y": [1, 2]})


def test_responses_and_embeddings_round_trip(tmp_path: Path) -> None:
    db = CacheStore(tmp_path / "c.db")
    db.put_response("k", kind="chat", backend="b", model="m", request={"q": 1}, response={"choices": ["hi"]})
    assert db.get_response("k") == {"choices": ["hi"]}
    assert db.get_response("missing") is None
    vectors = np.eye(3, dtype=np.float32)
    db.put_embeddings("mini", ["a", "b", "c"], vectors)
    found = db.get_embeddings("mini", ["a", "c", "zzz"])
    assert set(found) == {"a", "c"}
    assert np.array_equal(found["c"], vectors[2])
    assert db.get_embeddings("other-model", ["a"]) == {}


def _writer(path: str, worker: int) -> None:
    db = CacheStore(Path(path))
    for i in range(50):
        db.log_call(CallRecord("chat", f"w{worker}", "fake", "m", i, 1, 0.0, 0.0, False))
        db.put_response(f"{worker}-{i}", kind="chat", backend="b", model="m", request={}, response={"i": i})
    db.close()


def test_several_processes_share_the_database(tmp_path: Path) -> None:
    path = tmp_path / "shared.db"
    ctx = multiprocessing.get_context("spawn")
    workers = [ctx.Process(target=_writer, args=(str(path), w)) for w in range(4)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(60)
    assert all(w.exitcode == 0 for w in workers)
    db = CacheStore(path)
    assert len(db.calls(limit=1000)) == 200
    assert db.get_response("3-49") == {"i": 49}


def test_a_row_damaged_on_disk_is_a_miss_then_overwritten(tmp_path: Path) -> None:
    db = CacheStore(tmp_path / "c.db")
    with sqlite3.connect(tmp_path / "c.db") as other:
        other.execute("INSERT INTO llm_cache VALUES ('k', 'chat', 'b', 'm', '{}', '{\"choi', 0)")
        other.execute("INSERT INTO value_cache VALUES ('ope', 'k', 'not json', 0)")
    assert db.get_response("k") is None and db.get_value("ope", "k") is None
    db.put_value("ope", "k", {"dangerous": "No"})
    assert db.get_value("ope", "k") == {"dangerous": "No"}
