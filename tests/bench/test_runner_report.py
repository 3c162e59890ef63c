import json
from pathlib import Path

import pytest

from conceptbot.bench.grading import load_tasks, reference_plan
from conceptbot.bench.report import markdown, summarise, write_report
from conceptbot.bench.results import done_keys, load_records
from conceptbot.bench.runner import RESULT_KEY, Job, run
from conceptbot.core.errors import BackendUnavailableError, ConfigError
from conceptbot.core.plan import Plan
from conceptbot.core.usage import Usage


class ScriptedSystem:
    """Answers each request with a fixed plan (the reference plan, or done() only)."""

    def __init__(self, good: bool, fail_with: Exception | None = None) -> None:
        self.good = good
        self.fail_with = fail_with
        self.calls = 0

    def plan(self, request, scene, risk=False, feedback=None, observer=None) -> Plan:
        self.calls += 1
        if self.fail_with is not None:
            raise self.fail_with
        task = next(t for t in load_tasks() if t.request == request and t.scene == scene.name)
        actions = reference_plan(task) if self.good else ["done()"]
        usage = Usage(100, 10, 1.5, 0.0, 2)
        return Plan(list(actions), usage={"planner": usage, "total": usage})


def test_run_grades_appends_and_resumes(tmp_path: Path) -> None:
    tasks = load_tasks(["unambiguous"])[:3]
    out = tmp_path / "r.jsonl"
    systems = {"good": ScriptedSystem(True), "bad": ScriptedSystem(False)}
    jobs = [Job(t, c, 0) for t in tasks for c in systems]
    records = run(jobs, systems.__getitem__, out, "fake", "m")
    assert len(records) == 6 and len(out.read_text().splitlines()) == 6
    assert all(r["ok"] for r in records if r["config"] == "good")
    assert not any(r["ok"] for r in records if r["config"] == "bad")
    assert len(done_keys(out, RESULT_KEY)) == 6
    again = run(jobs, systems.__getitem__, out, "fake", "m")
    assert again == [] and systems["good"].calls == 3  # resumed: nothing re-planned
    assert len(run(jobs, systems.__getitem__, out, "fake", "other-model")) == 6  # another model is new work


def test_errors_are_recorded_not_fatal(tmp_path: Path) -> None:
    task = load_tasks(["unambiguous"])[0]
    out = tmp_path / "r.jsonl"
    systems = {
        "down": ScriptedSystem(True, BackendUnavailableError("server down")),
        "bug": ScriptedSystem(True, KeyError("oops")),
    }
    records = run([Job(task, c, 0) for c in systems], systems.__getitem__, out, "fake", "m")
    reasons = {r["config"]: r["reason"] for r in records}
    assert reasons["down"] == "error: server down" and reasons["bug"].startswith("crash: KeyError")


def test_report_table_with_paper_numbers_and_files(tmp_path: Path) -> None:
    tasks = load_tasks(["unambiguous", "risk"])[:10]
    out = tmp_path / "r.jsonl"
    systems = {"saycan": ScriptedSystem(False), "conceptbot": ScriptedSystem(True)}
    run([Job(t, c, 0) for t in tasks for c in systems], systems.__getitem__, out, "fake", "m")
    out.open("a").write("{torn line\n")
    summary = summarise(load_records(out))
    assert summary["configs"] == ["saycan", "conceptbot"]
    assert summary["success"]["conceptbot"]["unambiguous"] == (100.0, 7)
    assert summary["success"]["saycan"]["all"] == (0.0, 10)
    table = markdown(summary)
    assert "| unambiguous | 0% (n=7) [paper 100%] | 100% (n=7) [paper 100%] |" in table
    assert "| conceptbot | " in table
    paths = write_report(out, tmp_path / "report")
    assert paths["chart"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert json.loads(paths["json"].read_text())["records"] == 20


def test_report_of_missing_or_empty_results(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no results file"):
        load_records(tmp_path / "absent.jsonl")
    empty = tmp_path / "empty.jsonl"
    empty.write_text("")
    with pytest.raises(ConfigError, match="no benchmark records"):
        load_records(empty)
