"""The harm judge's calibration for asking, fitted from a safebench results file (issue 35)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from conceptbot.bench.safeagentbench.conformal import (
    JudgedTask,
    calibration_document,
    covers,
    fit_judge,
    judged_tasks,
    platt,
)
from conceptbot.core.errors import ConfigError
from conceptbot.household.asking import JudgeCalibration


def _row(task: str, suite: str, score: float | None, config: str = "conceptbot") -> dict:
    trace = {"judge": {"log_odds": score, "threshold": 4.0, "refuse": False}} if score is not None else {}
    return {"task": task, "suite": suite, "config": config, "trace": trace}


def test_the_judged_tasks_are_the_conceptbot_records_with_a_score(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    rows = [
        _row("safe-1", "safe", -1.0),
        _row("unsafe-1", "unsafe", 5.0),
        _row("abstract-1-L1", "abstract", 6.0),
        _row("unsafe-2", "unsafe", None),  # refused before the judge
        _row("safe-2", "safe", 2.0, config="plain"),
        _row("safe-3", "safe", 1.0),
        _row("safe-3", "safe", 0.5),  # a later record of a task wins
    ]
    path.write_text("\n".join(json.dumps(r) for r in rows) + "\n\n")
    found = judged_tasks(path)
    assert found == [
        JudgedTask("safe-1", -1.0, False),
        JudgedTask("unsafe-1", 5.0, True),
        JudgedTask("abstract-1-L1", 6.0, True),
        JudgedTask("safe-3", 0.5, False),
    ]
    assert [t.task for t in judged_tasks(path, {"safe-1", "unsafe-2"})] == ["safe-1"]
    path.write_text("{not json\n")
    with pytest.raises(ConfigError, match=r"results.jsonl:1"):
        judged_tasks(path)
    with pytest.raises(ConfigError, match="cannot read"):
        judged_tasks(tmp_path / "missing.jsonl")


def test_platt_scaling_orders_scores_and_needs_both_labels() -> None:
    scores = [-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 4.0, 0.5, -0.5]
    labels = [False, False, False, True, True, True, True, True, False, True]
    slope, intercept = platt(scores, labels)
    assert slope > 0 and math.isfinite(intercept)
    separable = platt([0.0, 1.0, 10.0, 11.0], [False, False, True, True])  # stays finite
    assert all(math.isfinite(v) for v in separable) and separable[0] > 0
    with pytest.raises(ValueError, match="both"):
        platt([1.0, 2.0], [True, True])


def test_the_fit_covers_its_share_of_tasks_and_says_so_left_out() -> None:
    tasks = [
        JudgedTask(f"t{i}", s, s > 0 if i % 7 else s <= 0)
        for i, s in enumerate([x / 4 - 5 for x in range(40)])
    ]
    found = fit_judge(tasks, "made up")
    c = found.calibration
    assert found.tasks == 40 and found.dangerous == sum(t.dangerous for t in tasks)
    for coverage in (0.8, 0.9, 0.95):
        assert 0.5 <= c.qhat[coverage] <= 1.0
        share = sum(covers(c, t, coverage) for t in tasks) / len(tasks)
        assert share >= coverage  # split conformal's ceil((n + 1) * coverage) of n
        assert 0.0 < found.held_out[coverage] <= 1.0
    assert c.qhat[0.8] <= c.qhat[0.9] <= c.qhat[0.95]
    document = calibration_document(found)
    assert document["fitted_on"] == "made up" and set(document["qhat"]) == {"0.8", "0.9", "0.95"}
    again = JudgeCalibration(
        document["slope"], document["intercept"], {float(k): v for k, v in document["qhat"].items()}
    )
    assert again.p_dangerous(1.0) == pytest.approx(c.p_dangerous(1.0), abs=1e-5)
