"""The results-file helpers both benchmarks share."""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from conceptbot.bench.results import built_once, done_keys, load_records, write_report_files
from conceptbot.core.errors import ConfigError


def test_each_configuration_is_built_once_even_from_several_workers() -> None:
    built: list[str] = []
    get = built_once(lambda config: built.append(config) or f"system {config}")
    with ThreadPoolExecutor(max_workers=4) as pool:
        systems = list(pool.map(get, ["a", "b", "a", "a", "b", "a"]))
    assert sorted(built) == ["a", "b"] and systems[2] == "system a"


def test_keys_skip_torn_lines_and_records_without_the_fields(tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    out.write_text('{"task": "t1", "config": "c"}\n{"task": "t2"}\n[1, 2]\n{"task": "t3", "con')
    assert done_keys(out, ("task", "config")) == {("t1", "c")}
    assert done_keys(tmp_path / "absent.jsonl", ("task",)) == set()
    with pytest.raises(ConfigError) as info:
        load_records(tmp_path / "absent.jsonl", hint="run `conceptbot safebench run` first")
    assert "safebench run" in str(info.value.hint)


def test_report_files_are_written_by_kind(tmp_path: Path) -> None:
    summary = {"configs": ["a"], "models": {"fake:m"}}

    def chart(summary: dict, path: Path) -> None:
        path.write_bytes(b"PNG")

    paths = write_report_files(summary, tmp_path / "out", ("r.md", "r.json", "r.png"), str, chart)
    assert [p.name for p in paths.values()] == ["r.md", "r.json", "r.png"]
    assert json.loads(paths["json"].read_text())["models"] == ["fake:m"]  # a set is written as a list
    assert paths["chart"].read_bytes() == b"PNG" and paths["markdown"].read_text().startswith("{")
