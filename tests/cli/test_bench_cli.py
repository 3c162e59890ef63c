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


@pytest.mark.slow
def test_smoke_run_on_the_small_model(
    isolated_home: Path, smollm2_path: Path, omcs_file: Path, wordnet_dir: Path, tmp_path: Path
) -> None:
    run("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home)
    out = tmp_path / "smoke.jsonl"
    args = [
        "--llm",
        f"llamacpp:{smollm2_path}",
        "bench",
        "run",
        "-c",
        "saycan",
        "-c",
        "conceptbot",
        "--category",
        "risk",
        "--limit",
        "1",
        "--out",
        str(out),
    ]
    first = run(*args, home=isolated_home)
    assert "2 plans (1 tasks x 2 configs x 1 trials); 0 already" in first.stdout
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert {r["config"] for r in records} == {"saycan", "conceptbot"}
    assert all(r["task"] == "risk-1" and r["reason"] and r["plan"][-1] == "done()" for r in records), records
    again = run(*args, home=isolated_home)
    assert "2 already in" in again.stdout and len(out.read_text().splitlines()) == 2
