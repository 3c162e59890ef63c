"""`conceptbot plan --json` against its shipped JSON Schema, for every configuration the fake LLM
can run (the step planner: the fake backend cannot score options), a refusal, and the goal planner
and SayCan in process; and the schema rejects what breaks the contract."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from jsonschema import Draft202012Validator, ValidationError

from conceptbot.baselines.saycan import SayCan
from conceptbot.cli.main import cli
from conceptbot.core.plan import plan_schema
from conceptbot.core.scene import scene_from_dict
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline.conceptbot import ConceptBot
from tests.pipeline.fakes import properties_reply, risk_reply, urp_reply

SCENE = {
    "name": "tiny",
    "objects": ["apple", "sponge", "user"],
    "pickable_objects": ["apple", "sponge"],
    "destinations": ["user"],
}
OPE = [properties_reply()] * 3  # one per scene object
KEYWORDS = ['{"keywords": ["apple"]}']
URP = [urp_reply(["pick_and_place(apple, user)"])]
PLANNER = ["pick_and_place(apple, user)"] * 5 + ["done()"] * 5  # two voting steps of 5 completions
# The scripted replies each configuration asks for, in order (no graph: no keywords).
REPLIES = {
    "conceptbot": OPE + KEYWORDS + URP + PLANNER,
    "paper": OPE + KEYWORDS + URP + PLANNER,
    "urp": KEYWORDS + URP + PLANNER,
    "ope": OPE + PLANNER,
    "nokg": OPE + URP + PLANNER,
    "paper-nokg": OPE + URP + PLANNER,
}


def _validator() -> Draft202012Validator:
    schema = plan_schema()
    Draft202012Validator.check_schema(schema)
    return Draft202012Validator(schema)


@pytest.fixture
def home(isolated_home: Path, omcs_file: Path, wordnet_dir: Path) -> Path:
    """A home with a small graph installed."""
    args = ["kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir)]
    result = CliRunner().invoke(cli, args)
    assert result.exit_code == 0, result.output
    return isolated_home


def _plan_json(tmp_path: Path, config: str, replies: list[str], progress: list[str] | None = None) -> dict:
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SCENE))
    replies_file = tmp_path / "replies.json"
    replies_file.write_text(json.dumps(replies))
    args = ["--llm", f"fake:{replies_file}", "--embedder", "fake", "plan", "Bring me an apple"]
    args += ["--scene", str(scene), "--config", config, "--json", "--no-fallback"]
    result = CliRunner().invoke(cli, args)
    assert result.exit_code == 0, f"{result.output}\n{result.exception!r}"
    # Progress messages go to stderr; stdout is the one JSON object.
    if progress is not None:
        progress += result.stderr.splitlines()
    return json.loads(result.stdout)


@pytest.mark.parametrize("config", sorted(REPLIES))
def test_plan_json_of_each_configuration_validates(home: Path, tmp_path: Path, config: str) -> None:
    data = _plan_json(tmp_path, config, REPLIES[config])
    _validator().validate(data)
    assert data["plan"] == ["pick_and_place(apple, user)", "done()"] and not data["refused"]
    trace = data["trace"]
    assert trace["config"] == (
        "conceptbot" if config == "paper" else "nokg" if config == "paper-nokg" else config
    )
    assert trace["planner_kind"] == "steps" and trace["planner"] == {"method": "vote", "steps": 2}
    assert ("ope" in trace) == (config != "urp") and ("urp" in trace) == (config != "ope")


def test_a_refusal_validates(home: Path, tmp_path: Path) -> None:
    refuse = urp_reply([], refuse=True, why="not safe")
    progress: list[str] = []
    data = _plan_json(tmp_path, "conceptbot", OPE + KEYWORDS + [refuse], progress)
    _validator().validate(data)
    assert progress == ["URP: keywords"]  # then URP refuses: no planner steps
    assert data["refused"] and data["plan"] == ["done()"] and data["reason"] == "not safe"
    assert data["steps"] == [] and "planner" not in data["trace"] and data["trace"]["urp"]["refused"]


def test_the_goal_planner_with_ope_and_saycan_validate() -> None:
    scene = scene_from_dict(
        {"name": "craft", "pickable_objects": ["scissors", "glue"], "destinations": ["child", "table"]}
    )
    prior, safe = [-1.0, -1.0], [-0.05, -3.0]
    # Named object, handed to a child: OPE's Risk Index rates it, then the risk question.
    llm = FakeLLM([risk_reply(4, [("child", 3)])], scores=[prior, safe])
    bot = ConceptBot(llm, None, "nokg", planner="goal", reading="words")  # OPE gets the scripted reply
    goal = bot.plan("Give the child the scissors", scene).to_dict()
    _validator().validate(goal)
    assert goal["refused"] and goal["trace"]["risk"][0]["why"] == "judged dangerous"
    assert list(goal["trace"]) == [
        "config",
        "planner_kind",
        "request",
        "scene",
        "goal",
        "decisions",
        "risk",
        "planner",
        "calibration",
        "ope",
    ]
    llm = FakeLLM(scores=[[0.0, -9.0, -9.0, -9.0, -9.0], [-9.0] * 4 + [0.0]])
    saycan = SayCan(llm).plan("Put the glue on the table", scene).to_dict()
    _validator().validate(saycan)
    assert saycan["trace"] == {"config": "saycan", "request": "Put the glue on the table", "scene": "craft"}


VALID = {
    "plan": ["pick_and_place(apple, user)", "done()"],
    "steps": [
        {
            "index": 1,
            "chosen": "pick_and_place(apple, user)",
            "method": "vote",
            "scoring": "vote",
            "rejected": [],
            "candidates": [
                {"action": "done()", "llm": 0.0, "affordance": 0.2, "combined": 0.0, "factors": {}},
            ],
        }
    ],
    "refused": False,
    "reason": None,
    "trace": {"config": "conceptbot", "planner_kind": "steps", "someday": {"a": 1}},
    "usage": {
        "total": {"prompt_tokens": 1, "completion_tokens": 2, "latency_s": 0.5, "cost_usd": 0.0, "calls": 1}
    },
}


def _broken(path: list, value: object = None, delete: bool = False) -> dict:
    data = copy.deepcopy(VALID)
    parent = data
    for key in path[:-1]:
        parent = parent[key]
    if delete:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return data


@pytest.mark.parametrize(
    ("data", "why"),
    [
        (_broken(["plan"], delete=True), "'plan' is a required property"),
        (_broken(["plan"], "done()"), "is not of type 'array'"),
        (_broken(["plan"], []), "should be non-empty"),
        (_broken(["plan", 0], "pick_and_place(apple)"), "does not match"),
        (_broken(["refused"], "no"), "is not of type 'boolean'"),
        (_broken(["extra"], 1), "Additional properties are not allowed"),
        (_broken(["steps", 0, "index"], "1"), "is not of type 'integer'"),
        (_broken(["steps", 0, "method"], "guess"), "is not one of"),
        (_broken(["usage", "total", "calls"], delete=True), "'calls' is a required property"),
        (_broken(["usage", "total"], delete=True), "'total' is a required property"),
        (_broken(["trace", "planner_kind"], "greedy"), "is not one of"),
        (_broken(["trace", "ope"], {"mode": "risk"}), "'why' is a required property"),
    ],
)
def test_the_schema_rejects_what_breaks_the_contract(data: dict, why: str) -> None:
    validator = _validator()
    validator.validate(VALID)  # the unbroken example passes: each case fails for its own reason
    with pytest.raises(ValidationError):
        validator.validate(data)
    assert any(why in error.message for error in validator.iter_errors(data))


def test_the_goal_s_readings_validate_and_a_reading_of_no_kind_does_not() -> None:
    from conceptbot.core.trace import GoalTrace, ReadingOption

    readings = (
        ReadingOption("give the user the tea", 0.65),
        ReadingOption("give the cake", float("nan"), "other"),
    )
    goal = GoalTrace((), False, "Give me tea.", "plain", None, "need", readings, -0.31234).to_dict()
    assert goal["readings"][1] == {"text": "give the cake", "p": None, "kind": "other"}
    assert goal["preference"] == -0.3123  # the model's view of the two, which moved their odds
    unasked = GoalTrace((), False, "Give me tea.", "plain", None, "need", readings, float("nan")).to_dict()
    assert "preference" not in unasked  # a model error is no view (JSON has no NaN)
    data = copy.deepcopy(VALID)
    data["trace"]["goal"] = goal
    validator = _validator()
    validator.validate(data)
    data["trace"]["goal"]["preference"] = "taken"
    assert any("is not of type 'number'" in error.message for error in validator.iter_errors(data))
    data["trace"]["goal"]["preference"] = -0.3123
    data["trace"]["goal"]["readings"][0]["kind"] = "guess"
    assert any("is not one of" in error.message for error in validator.iter_errors(data))
    with pytest.raises(ValueError, match="kind must be one of"):
        ReadingOption("x", 0.5, "guess")
