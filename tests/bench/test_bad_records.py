"""Results files of the wrong shape: one error naming the file and the line, before any work is done.

``{"a": 1}`` lines, another benchmark's records, wrong types and binary files used to be a KeyError or
a UnicodeDecodeError, for ``bench report`` and ``safebench report`` and, after planning everything,
for a resumed ``bench run --out``. A torn line (a run stopped mid-write) is still skipped.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from conceptbot.bench.grading import load_tasks
from conceptbot.bench.report import RECORD, write_report
from conceptbot.bench.results import done_keys, load_records, read_records
from conceptbot.bench.runner import RESULT_KEY, Job, run
from conceptbot.bench.safeagentbench.report import write_safety_report
from conceptbot.core.errors import ConfigError
from conceptbot.core.plan import Plan
from conceptbot.core.usage import Usage
from tests.cli.test_cli import run as cli

BENCH = {
    "task": "risk-5",
    "category": "risk",
    "config": "conceptbot",
    "trial": 0,
    "backend": "fake",
    "model": "m",
    "ok": True,
    "reason": "ok",
    "seconds": 1.0,
    "usage": {"total": {"latency_s": 1.0, "prompt_tokens": 5, "completion_tokens": 1, "cost_usd": 0.0}},
}
SAFETY = {
    "task": "unsafe-1",
    "suite": "unsafe",
    "category": "Fire Hazard",
    "level": None,
    "config": "plain",
    "backend": "fake",
    "model": "m",
    "refused": True,
    "success": False,
}


def _write(path: Path, *lines: Any) -> Path:
    path.write_text("".join((x if isinstance(x, str) else json.dumps(x)) + "\n" for x in lines))
    return path


def _binary(path: Path) -> Path:
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe\n" + bytes(range(256)) * 4)
    return path


# -- reports ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("lines", "where", "words"),
    [
        ([{"a": 1}], "line 1", "lacks 'task', 'category'"),
        ([BENCH, SAFETY], "line 2", "lacks 'ok'"),  # another benchmark's record
        ([BENCH, [1, 2]], "line 2", "a list where a record"),
        ([BENCH | {"category": ["risk"]}], "line 1", "'category' is a list, not text"),
        ([BENCH | {"ok": "yes"}], "line 1", "'ok' is text, not true/false"),
        ([BENCH | {"usage": {"total": {"latency_s": "slow"}}}], "line 1", "'latency_s' is text"),
        ([BENCH | {"usage": [1]}], "line 1", "'usage' is not an object"),
        ([BENCH | {"usage": {"total": {"prompt_tokens": None}}}], "line 1", "'prompt_tokens' is null"),
    ],
)
def test_bench_report_names_the_bad_line(tmp_path: Path, lines: list[Any], where: str, words: str) -> None:
    results = _write(tmp_path / "r.jsonl", *lines)
    with pytest.raises(ConfigError) as info:
        write_report(results, tmp_path / "out")
    assert f"{results} {where} is not a `conceptbot bench run` record" in info.value.message
    assert words in info.value.message and "bench run" in (info.value.hint or "")


@pytest.mark.parametrize(
    ("lines", "words"),
    [
        ([{"a": 1}], "line 1 is not a `conceptbot safebench run` record: it lacks 'task', 'suite'"),
        ([SAFETY, BENCH], "line 2 is not a `conceptbot safebench run` record: it lacks 'suite'"),
        ([SAFETY | {"level": "two"}], "line 1 is not a `conceptbot safebench run` record: 'level' is text"),
    ],
)
def test_safebench_report_names_the_bad_line(tmp_path: Path, lines: list[Any], words: str) -> None:
    results = _write(tmp_path / "s.jsonl", *lines)
    with pytest.raises(ConfigError) as info:
        write_safety_report(results, tmp_path / "out")
    assert f"{results} {words}" in info.value.message


def test_records_older_versions_wrote_still_report(tmp_path: Path) -> None:
    old = {k: v for k, v in BENCH.items() if k not in ("reason", "seconds", "split")} | {"ok": False}
    old["usage"] = {"total": {"latency_s": 1.0, "cost_usd": None}}  # an unknown price
    summary = json.loads(write_report(_write(tmp_path / "r.jsonl", old), tmp_path)["json"].read_text())
    assert summary["failures"] == {"conceptbot": ["risk-5: no reason recorded"]}


def test_a_binary_file_is_named_with_its_first_bad_line(tmp_path: Path) -> None:
    results = _binary(tmp_path / "image.jsonl")
    for report in (write_report, write_safety_report):
        with pytest.raises(ConfigError) as info:
            report(results, tmp_path / "out")
        assert f"{results} line 1 is not UTF-8 text (byte 1" in info.value.message


def test_torn_lines_are_still_skipped_even_cut_inside_a_character(tmp_path: Path) -> None:
    results = tmp_path / "r.jsonl"
    torn = json.dumps(BENCH | {"reason": "déjà vu"}, ensure_ascii=False).encode()
    cut = torn[: torn.index("é".encode()) + 1]  # the run stopped inside the two bytes of "é"
    results.write_bytes(json.dumps(BENCH).encode() + b"\n{torn line\n" + cut)
    assert len(load_records(results, shape=RECORD)) == 1
    assert write_report(results, tmp_path / "out")["markdown"].is_file()


# -- resumed runs ----------------------------------------------------------------------------------
class _Reference:
    """Plans every task as "done" (what is planned does not matter here, only what is written)."""

    def plan(self, request, scene, risk=False, feedback=None, observer=None) -> Plan:
        usage = Usage(1, 1, 0.0, 0.0, 1)
        return Plan(["done()"], usage={"planner": usage, "total": usage})


def test_a_run_after_a_torn_last_line_keeps_its_first_record(tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    out.write_text(json.dumps(BENCH) + "\n" + '{"task": "unambiguous-1", "con')  # stopped mid-write
    tasks = load_tasks(["unambiguous"])[:2]
    written = run([Job(t, "conceptbot", 0) for t in tasks], lambda _: _Reference(), out, "fake", "m")
    assert len(written) == 2
    assert len(read_records(out, RECORD)) == 3  # the first new record did not join the torn line
    assert len(done_keys(out, RESULT_KEY)) == 3


def test_bench_run_refuses_a_bad_out_file_before_planning(isolated_home: Path, tmp_path: Path) -> None:
    replies = tmp_path / "replies.json"
    replies.write_text("[]")  # any plan would be an error record appended to the file
    out = _write(tmp_path / "w.jsonl", {"a": 1})
    args = ["--llm", f"fake:{replies}", "--embedder", "fake", "bench", "run", "-c", "nokg", "--limit", "1"]
    result = cli(*args, "--out", str(out), home=isolated_home, check_exit=2)
    assert f"Error: {out} line 1 is not a `conceptbot bench run` record" in result.stderr
    assert "Traceback" not in result.stderr and "plans (" not in result.stdout  # nothing planned
    assert out.read_text() == '{"a": 1}\n'
    binary = _binary(tmp_path / "b.jsonl")
    result = cli(*args, "--out", str(binary), home=isolated_home, check_exit=2)
    assert f"{binary} line 1 is not UTF-8 text" in result.stderr and "Traceback" not in result.stderr


def test_safebench_run_refuses_a_bad_out_file_before_planning(isolated_home: Path, tmp_path: Path) -> None:
    replies = tmp_path / "replies.json"
    replies.write_text("[]")
    out = _write(tmp_path / "w.jsonl", BENCH)  # the other benchmark's results
    args = ["--llm", f"fake:{replies}", "safebench", "run", "-c", "plain", "--task", "safe-3"]
    result = cli(*args, "--out", str(out), home=isolated_home, check_exit=2)
    assert f"{out} line 1 is not a `conceptbot safebench run` record: it lacks 'suite'" in result.stderr
    assert "Traceback" not in result.stderr and out.read_text() == json.dumps(BENCH) + "\n"


@pytest.mark.parametrize("command", ["bench", "safebench"])
def test_report_commands_print_one_error(isolated_home: Path, tmp_path: Path, command: str) -> None:
    for path in (_write(tmp_path / "w.jsonl", {"a": 1}), _binary(tmp_path / "b.jsonl")):
        result = cli(command, "report", str(path), home=isolated_home, check_exit=2)
        lines = result.stderr.strip().splitlines()
        assert lines[0].startswith(f"Error: {path} line ") and lines[1].startswith("Hint: "), lines
        assert len(lines) == 2 and "Traceback" not in result.stderr
