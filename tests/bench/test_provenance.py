"""What made a record: version, commit of the code, settings; reports refuse mixed commits."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from conceptbot.bench import provenance
from conceptbot.bench.grading import load_tasks
from conceptbot.bench.provenance import UNKNOWN, code_commit, commits_by_config, stamp
from conceptbot.bench.report import markdown, summarise, write_report
from conceptbot.bench.results import done_keys
from conceptbot.bench.runner import RESULT_KEY, Job, run
from conceptbot.core.errors import ConfigError
from conceptbot.core.version import __version__
from tests.bench.test_runner_report import ScriptedSystem


def _git(cwd: Path, *args: str) -> str:
    return subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, check=True).stdout.strip()


def test_the_commit_is_the_last_one_that_changed_the_source_and_dirty_source_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    repo, package = tmp_path / "repo", tmp_path / "repo" / "src" / "pkg"
    package.mkdir(parents=True)
    (package / "a.py").write_text("x = 1\n")
    _git(repo, "init", "-q")
    _git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "add", ".")
    _git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "code")
    code = _git(repo, "rev-parse", "HEAD")
    (repo / "results.jsonl").write_text("{}\n")  # a later commit of results and a front end only
    (package / "web").mkdir()
    (package / "web" / "page.py").write_text("y = 1\n")
    _git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "add", ".")
    _git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "results")
    monkeypatch.setattr(provenance, "PACKAGE", package)
    code_commit.cache_clear()
    try:
        assert code_commit() == code  # committing results or a front end does not change it
        (package / "web" / "page.py").write_text("y = 2\n")
        code_commit.cache_clear()
        assert code_commit() == code  # nor does editing a front end
        (package / "a.py").write_text("x = 2\n")
        code_commit.cache_clear()
        assert code_commit() == f"{code}+dirty"
        monkeypatch.setattr(provenance, "PACKAGE", tmp_path)  # not a checkout
        code_commit.cache_clear()
        assert code_commit() == UNKNOWN
    finally:
        code_commit.cache_clear()


def test_every_record_names_its_code_and_settings_and_other_code_is_planned_again(tmp_path: Path) -> None:
    tasks = load_tasks(["unambiguous"])[:2]
    out = tmp_path / "r.jsonl"
    system = ScriptedSystem(True)
    jobs = [Job(t, "conceptbot", 0) for t in tasks]
    made = {**stamp({"reading": "model", "coverage": 0.9}), "commit": "a" * 40}
    records = run(jobs, lambda _: system, out, "fake", "m", stamp=made)
    first = json.loads(out.read_text().splitlines()[0])
    assert first["commit"] == "a" * 40 and first["version"] == __version__
    assert first["settings"] == {"reading": "model", "coverage": 0.9} and len(first["started"]) == 10
    assert run(jobs, lambda _: system, out, "fake", "m", stamp=made) == [] and system.calls == 2
    later = {**made, "commit": "b" * 40}
    assert len(run(jobs, lambda _: system, out, "fake", "m", stamp=later)) == 2  # new code: planned again
    assert len(done_keys(out, RESULT_KEY, "b" * 40)) == 2 and len(records) == 2


def test_a_report_refuses_a_configuration_of_two_commits_unless_told_and_then_says_so(tmp_path: Path) -> None:
    tasks = load_tasks(["unambiguous"])[:2]
    out = tmp_path / "r.jsonl"
    system = ScriptedSystem(True)
    for commit in ("a" * 40, "b" * 40):
        run([Job(tasks[0], "conceptbot", 0)], lambda _: system, out, "fake", "m", stamp={"commit": commit})
    run([Job(tasks[1], "saycan", 0)], lambda _: system, out, "fake", "m", stamp={"commit": "c" * 40})
    with pytest.raises(ConfigError, match=r"conceptbot: (a{12}, b{12}|b{12}, a{12})"):
        write_report(out, tmp_path)
    summary = summarise([json.loads(line) for line in out.read_text().splitlines()], allow_mixed=True)
    assert "Mixed: records of several commits" in markdown(summary) and "for conceptbot (" in markdown(
        summary
    )
    assert summary["commits"]["saycan"] == ["c" * 40]


def test_one_commit_per_configuration_is_named_in_the_report() -> None:
    records = [{"config": "saycan", "commit": "c" * 40}, {"config": "conceptbot"}]
    assert commits_by_config(records) == {"saycan": ["c" * 40], "conceptbot": [UNKNOWN]}
