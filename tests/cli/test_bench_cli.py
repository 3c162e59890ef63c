"""`conceptbot bench` as a user runs it: a smoke run on the real small model, and the report."""

import json
from pathlib import Path

import pytest

from tests.cli.test_cli import run


def test_report_of_a_results_file_and_bad_path(isolated_home: Path, tmp_path: Path) -> None:
    results = tmp_path / "r.jsonl"
    record = {
        "task": "risk-5",
        "category": "risk",
        "config": "conceptbot",
        "trial": 0,
        "backend": "fake",
        "model": "m",
        "ok": True,
        "reason": "ok",
        "seconds": 1.0,
        "usage": {
            "total": {
                "latency_s": 1.0,
                "prompt_tokens": 5,
                "completion_tokens": 1,
                "cost_usd": 0.0,
                "calls": 1,
            }
        },
    }
    results.write_text(json.dumps(record) + "\n")
    out = run("bench", "report", str(results), home=isolated_home).stdout
    assert "| risk | 100% (n=1) [paper 76%] |" in out
    assert (tmp_path / "success.png").is_file() and (tmp_path / "report.md").is_file()
    missing = run("bench", "report", str(tmp_path / "none.jsonl"), home=isolated_home, check_exit=2)
    assert "no results file" in missing.stderr
    # The same configuration from two commits of the code: refused, unless asked for, and then said.
    later = {**record, "task": "risk-6", "commit": "b" * 40}
    results.write_text(json.dumps({**record, "commit": "a" * 40}) + "\n" + json.dumps(later) + "\n")
    mixed = run("bench", "report", str(results), home=isolated_home, check_exit=2)
    assert "several commits" in mixed.stderr and "--allow-mixed" in mixed.stderr
    assert "Traceback" not in mixed.stderr
    allowed = run("bench", "report", str(results), "--allow-mixed", home=isolated_home).stdout
    assert "Mixed: records of several commits of the code are reported together" in allowed


def test_run_on_the_dev_split_records_it(isolated_home: Path, tmp_path: Path) -> None:
    """--split dev plans dev tasks in dev scenes; the fake LLM has no replies, so each plan is an
    error record (the plumbing, not the planning, is under test here)."""
    replies = tmp_path / "replies.json"
    replies.write_text("[]")
    out = tmp_path / "dev.jsonl"
    args = ["--llm", f"fake:{replies}", "--embedder", "fake", "bench", "run", "-c", "nokg", "--split", "dev"]
    first = run(*args, "--category", "risk", "--limit", "2", "--out", str(out), home=isolated_home)
    assert "split: dev" in first.stdout and "2 plans (2 tasks x 1 configs x 1 trials)" in first.stdout
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert [(r["task"], r["split"]) for r in records] == [("dev-risk-1", "dev"), ("dev-risk-2", "dev")]
    assert all(r["reason"].startswith("error: ") for r in records), records
    report = run("bench", "report", str(out), home=isolated_home).stdout
    assert "Task split: dev;" in report and "[paper" not in report and "| risk | 0% (n=2) |" in report
    bad = run(*args[:-1], "train", home=isolated_home, check_exit=2)
    assert "unknown task split 'train': neither test nor dev nor a folder" in bad.stderr


def test_run_help_documents_the_split(isolated_home: Path) -> None:
    out = run("bench", "run", "--help", home=isolated_home).stdout
    said = " ".join(out.split())
    assert "--split TEXT" in out and "with --split dev" in said and "the path of a task folder" in said


def bench_smoke(
    llm: str, category: str, home: Path, omcs_file: Path, wordnet_dir: Path, out: Path, limit: int = 1
) -> tuple[list[str], str, list[dict]]:
    """Install the graph, then ``bench run -c saycan -c conceptbot`` on the first ``limit`` tasks
    of ``category`` with ``llm``; checks the header and both configurations, returns the arguments
    (to run again), the output and the records."""
    run("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=home)
    args = ["--llm", llm, "bench", "run", "-c", "saycan", "-c", "conceptbot"]
    args += ["--category", category, "--limit", str(limit), "--out", str(out)]
    first = run(*args, home=home)
    assert f"{2 * limit} plans ({limit} tasks x 2 configs x 1 trials); 0 already" in first.stdout
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert {r["config"] for r in records} == {"saycan", "conceptbot"}
    return args, first.stdout, records


@pytest.mark.slow
def test_smoke_run_on_the_small_model(
    isolated_home: Path, smollm2_path: Path, omcs_file: Path, wordnet_dir: Path, tmp_path: Path
) -> None:
    out = tmp_path / "smoke.jsonl"
    args, _, records = bench_smoke(
        f"llamacpp:{smollm2_path}", "risk", isolated_home, omcs_file, wordnet_dir, out
    )
    assert all(r["task"] == "risk-1" and r["reason"] and r["plan"][-1] == "done()" for r in records), records
    again = run(*args, home=isolated_home)
    assert "2 already in" in again.stdout and len(out.read_text().splitlines()) == 2
