"""`conceptbot calibrate --conformal`: the configured model's own plan-level thresholds, fitted on
the dev tasks and kept where the planner finds them for that model."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from conceptbot.bench.grading import load_tasks
from conceptbot.cli import calibrate_cmd
from conceptbot.core.config import load_settings
from conceptbot.core.plan import Done, Plan
from conceptbot.core.trace import DecisionTrace, JudgementTrace, PlanTrace, TargetTrace
from conceptbot.pipeline.goal_planner.conformal import calibration_for
from tests.cli.inprocess import invoke


class Calibrating:
    """A goal-planner system whose every plan has one calibrated decision, P(yes) 0.7 for the
    request's first scene object going to its first destination."""

    planner_kind = "goal"
    calibration_key = ("openai-compatible", "my-model")

    def __init__(self) -> None:
        self.planned = 0

    def plan(self, request: str, scene: Any, **_: Any) -> Plan:
        self.planned += 1
        obj, target = scene.pickable[0], scene.destinations[0]
        decision = DecisionTrace(
            TargetTrace(target, "all", "named"), True, (JudgementTrace(obj, 0.7, 0.85, answers=("yes",)),)
        )
        return Plan([Done()], trace=PlanTrace(config="conceptbot", decisions=(decision,)))


def test_calibrate_conformal_writes_the_models_thresholds_for_the_planner(
    isolated_home: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    systems: list[Calibrating] = []

    def build(settings: Any, config: str, options: Any) -> Calibrating:
        systems.append(Calibrating())
        return systems[-1]

    monkeypatch.setattr(calibrate_cmd, "build_system", build)
    out = invoke("calibrate", "--conformal", "--json")
    assert out.code == 0, out.stderr
    assert out.stdout.lstrip().startswith("{"), (out.stdout[:300], out.stderr[-500:])
    data = json.loads(out.stdout)
    dev = len(load_tasks(split="dev"))
    assert [s.planned for s in systems] == [dev, dev]  # every dev task, with and without the graph
    assert data["model"] == "my-model" and set(data["plan_qhat"]) == {"graph", "nograph"}
    found = calibration_for(load_settings().calibration_dir, "openai-compatible", "my-model")
    assert Path(data["path"]).is_file() and found.qhat == {
        float(k): v for k, v in data["plan_qhat"]["graph"].items()
    }
    # The planner reads them as this model's own: the coverage they promise holds for its plans.
    assert found.fits("openai-compatible", "my-model") and found.source == data["path"]
    # Every task's worst decision is 1 - 0.7 (yes) or 0.7 (no): the threshold is one of them.
    assert all(round(q, 4) in (0.3, 0.7) for q in found.qhat.values())
    # Both which-one rules are fitted from the same plans; the default is the shipped one's.
    assert data["plan_which_one"] == found.rule == "softmax"
    assert set(data["plan_qhat_fits"]) == {"graph", "nograph"}
    # Each kind's own thresholds are written and read back (the plans here have no which-one
    # decision, so its threshold is the yes/no one).
    assert set(data["plan_qhat_one"]) == set(data["plan_qhat_yes_no"]) == {"graph", "nograph"}
    assert (
        found.qhat_one
        == found.qhat_yes_no
        == {float(k): v for k, v in data["plan_qhat_yes_no"]["graph"].items()}
    )
    fits = calibration_for(load_settings().calibration_dir, "openai-compatible", "my-model", rule="fits")
    assert fits.rule == "fits" and set(fits.qhat) == set(found.qhat)


def test_calibrate_conformal_needs_the_goal_planner(
    isolated_home: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    class Steps(Calibrating):
        planner_kind = "steps"

    monkeypatch.setattr(calibrate_cmd, "build_system", lambda settings, config, options: Steps())
    out = invoke("calibrate", "--conformal")
    assert out.code == 1
    [error] = out.errors()
    assert "needs the goal planner" in error and "Traceback" not in out.stderr
