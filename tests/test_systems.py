"""The systems registry: names, typed options, and systems built from settings or given backends."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError, NotSupportedError
from conceptbot.core.limits import CheckedRequest, check_request
from conceptbot.knowledge.fallback import FallbackGraph
from conceptbot.knowledge.sqlite_store import GraphBuilder, SQLiteGraph
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.systems import SYSTEMS, SystemOptions, build_system, graph_version
from tests.pipeline.fakes import DictGraph


@pytest.fixture
def fake_settings(settings: Settings) -> Settings:
    return replace(settings, llm="fake", embedder="fake", kg_fallback=False)


def _install_graph(path: Path) -> SQLiteGraph:
    with GraphBuilder(path, "omcs+wordnet") as builder:
        builder.add("knife", "IsA", "weapon", 7.0, "omcs")
    return SQLiteGraph(path)


def test_every_system_by_name() -> None:
    assert SYSTEMS == ("saycan", "conceptbot", "urp", "ope", "nokg", "paper", "paper-nokg")


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"theta": 1.5}, "theta must be a cosine threshold in"),
        ({"theta": float("nan")}, "theta must be a cosine threshold in"),
        ({"theta": "0.5"}, "theta must be a number"),
        ({"planner_method": "beam"}, "planner_method must be one of auto, logprob, vote, got 'beam'"),
        ({"planner": "tree"}, "planner must be one of auto, goal, steps, got 'tree'"),
        ({"n": 0}, "n must be a whole number of completions >= 1"),
        ({"n": True}, "n must be a whole number"),
        ({"fallback": "yes"}, "fallback must be True, False or None"),
        ({"reading": "sampled"}, "reading 'sampled' was removed"),
    ],
)
def test_options_are_checked_when_made(options: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        SystemOptions(**options)


def test_theta_is_always_a_float() -> None:
    # OPE cache keys carry theta as JSON, where 1 and 1.0 would be two keys.
    assert repr(SystemOptions(theta=1).theta) == "1.0"


def test_unknown_system_is_a_config_error(fake_settings: Settings) -> None:
    with pytest.raises(ConfigError, match="unknown system 'gpt'") as caught:
        build_system(fake_settings, "gpt")
    assert "saycan" in (caught.value.hint or "")


def test_paper_systems_are_the_step_planner(fake_settings: Settings) -> None:
    assert build_system(fake_settings, "paper-nokg").planner_kind == "steps"  # type: ignore[attr-defined]
    with pytest.raises(ConfigError, match="plan step by step"):
        build_system(fake_settings, "paper-nokg", SystemOptions(planner="goal"))


def test_saycan_needs_a_backend_that_scores(fake_settings: Settings) -> None:
    with pytest.raises(NotSupportedError, match="SayCan scores options"):
        build_system(fake_settings, "saycan")
    assert build_system(fake_settings, "saycan", llm=FakeLLM(scores=[])).plan  # scoring: fine


def test_the_default_graph_keys_ope_results_as_it_always_did(fake_settings: Settings) -> None:
    graph = _install_graph(fake_settings.kg_path)
    expected = f"sqlite:omcs+wordnet:{graph.meta['built_at']}"  # the key OPE results are cached under
    system = build_system(fake_settings, "conceptbot")
    assert system.ope.graph_version == expected  # type: ignore[attr-defined]
    with_fallback = build_system(replace(fake_settings, kg_fallback=True), "conceptbot")
    assert with_fallback.ope.graph_version == expected  # type: ignore[attr-defined]
    assert graph_version("conceptnet-api", FallbackGraph(DictGraph(), None)) == "conceptnet-api:test"


def test_an_unversioned_graph_keeps_its_old_key() -> None:
    class LiveGraph(DictGraph):
        name = "live"
        version = ""

    assert graph_version("conceptnet-api", LiveGraph()) == "conceptnet-api::"


def test_given_backends_replace_the_configured_ones(fake_settings: Settings) -> None:
    graph = DictGraph()
    system = build_system(
        fake_settings, "conceptbot", SystemOptions(theta=0.2), graph=graph, embedder=FakeEmbedder()
    )
    assert system.ope.graph_version == "dict:test"  # type: ignore[attr-defined]
    assert system.ope.retriever.graph is graph and system.ope.retriever.theta == 0.2  # type: ignore[attr-defined]
    with pytest.raises(ConfigError, match="fallback option applies to the configured graph"):
        build_system(fake_settings, "conceptbot", SystemOptions(fallback=True), graph=graph)


def test_a_request_is_checked_once_where_it_enters() -> None:
    """The request is checked where it enters: ``conceptbot plan`` (bad input is the first error),
    the ROS 2 message (answered ``bad_request`` before it is queued), goal (ended ``bad_goal``) and
    client, or a system's own
    ``plan()`` for the API, the web page and the benchmarks. A checked request is a
    ``CheckedRequest``, which the system takes as it is: no path checks it twice."""
    import ast
    from pathlib import Path

    import conceptbot

    root = Path(conceptbot.__file__).parent
    callers = sorted(
        path.relative_to(root).as_posix()
        for path in root.rglob("*.py")
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "check_request"
    )
    assert callers == [
        "baselines/saycan.py",
        "cli/plan_cmd.py",
        "cli/ros2_cmd.py",
        "household/planner.py",
        "household/planner.py",
        "pipeline/conceptbot.py",
        "ros2/action.py",
        "ros2/protocol.py",
    ]
    checked = check_request("  bring me\tan apple ")
    assert isinstance(checked, CheckedRequest) and checked == "bring me an apple"
    assert check_request(checked) is checked  # not checked again


def test_household_systems_by_name_plan_a_typed_plan(settings: Settings, tmp_path: Path) -> None:
    import json

    from conceptbot.core.plan import HouseholdAction
    from conceptbot.household.thor import house_scene
    from conceptbot.systems import HOUSEHOLD_SYSTEMS, build_household_system

    assert HOUSEHOLD_SYSTEMS == ("plain", "conceptbot", "conceptbot-joint")
    replies = tmp_path / "replies.json"
    reply = {"reasoning": "a chore", "refuse": False, "steps": ["find Mug", "pick Mug"]}
    replies.write_text(json.dumps([json.dumps(reply)]))
    system = build_household_system(replace(settings, llm=f"fake:{replies}"), "plain")
    plan = system.plan("Pick up the mug.", house_scene("FloorPlan1", ["Mug"]))
    assert plan.actions == (HouseholdAction("find", "Mug"), HouseholdAction("pick", "Mug"))
    assert plan.trace.to_dict() == {"config": "plain", "grounding": [], "reasoning": "a chore"}
    with pytest.raises(ConfigError, match="unknown configuration 'joint'"):
        build_household_system(settings, "joint")


def test_the_household_judge_asks_only_what_the_harm_judgement_weighs(
    settings: Settings, tmp_path: Path
) -> None:
    from conceptbot import systems
    from conceptbot.household.harm import FEATURES, READINGS, shipped_model

    replies = tmp_path / "replies.json"
    replies.write_text("[]")
    judge = systems._harm_judge(replace(settings, llm=f"fake:{replies}"), None)
    assert tuple(q.name for q in judge.questions) == READINGS
    assert all(not q.evidence for q in judge.questions) and set(judge.contexts) == {
        q.system for q in judge.questions[1:]
    }
    assert set(shipped_model().weights) <= set(FEATURES) and not {"informed", "risk"} & set(FEATURES)


def test_the_coverage_is_one_the_calibration_ships() -> None:
    assert SystemOptions(coverage=0.95).coverage == 0.95
    for bad in (0.7, True, "0.9"):
        with pytest.raises(ConfigError, match=r"coverage must be one of 0\.8, 0\.9, 0\.95"):
            SystemOptions(coverage=bad)  # type: ignore[arg-type]


def test_calibrate_conformal_plans_without_reading_the_file_it_replaces(fake_settings: Settings) -> None:
    # A damaged own calibration stops a plan, with a hint to run `calibrate --conformal` again;
    # that command builds its systems with own_calibration=False, so the hint's fix works.
    from conceptbot.pipeline.goal_planner.conformal import user_file

    scoring = FakeLLM(scores=[], model="m")
    user_file(fake_settings.calibration_dir, "fake", "m").parent.mkdir(parents=True, exist_ok=True)
    user_file(fake_settings.calibration_dir, "fake", "m").write_text("garbage")
    parts = {"llm": scoring, "graph": DictGraph(), "embedder": FakeEmbedder()}
    with pytest.raises(ConfigError, match="is not a conformal calibration"):
        build_system(fake_settings, "conceptbot", SystemOptions(), **parts)
    system = build_system(fake_settings, "conceptbot", SystemOptions(own_calibration=False), **parts)
    assert system.planner_kind == "goal"  # type: ignore[attr-defined]
