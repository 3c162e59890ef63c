"""`conceptbot plan` as a user runs it: the fake LLM for the contract, the real small model for plumbing."""

import json
from pathlib import Path

import pytest

from tests.cli.test_cli import run
from tests.pipeline.fakes import properties_reply, urp_reply

SCENE = {
    "name": "tiny",
    "objects": ["apple", "sponge", "user"],
    "pickable_objects": ["apple", "sponge"],
    "destinations": ["user"],
}


@pytest.fixture
def graph_home(isolated_home: Path, omcs_file: Path, wordnet_dir: Path) -> Path:
    run("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home)
    return isolated_home


def test_plan_json_contract_with_the_fake_llm(graph_home: Path, tmp_path: Path) -> None:
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SCENE))
    props = properties_reply()
    replies = [props] * 3 + ['{"keywords": ["apple"]}', urp_reply(["pick_and_place(apple, user)"])]
    replies += ["pick_and_place(apple, user)"] * 5 + ["pick_and_place(pear, user)"] + ["done()"] * 4
    replies_file = tmp_path / "replies.json"
    replies_file.write_text(json.dumps(replies))
    out = run(
        "--llm",
        f"fake:{replies_file}",
        "--embedder",
        "fake",
        "plan",
        "Bring me an apple",
        "--scene",
        str(scene),
        "--json",
        "--no-fallback",
        home=graph_home,
    )
    data = json.loads(out.stdout)
    assert data["plan"] == ["pick_and_place(apple, user)", "done()"]
    assert data["refused"] is False and data["steps"][0]["method"] == "vote"
    assert any("pear" in r for r in data["steps"][1]["rejected"])
    assert set(data["usage"]) == {"ope", "urp", "planner", "total"}
    assert data["trace"]["urp"]["commands"] == ["pick_and_place(apple, user)"]


def test_plan_readable_output_and_bad_scene(graph_home: Path, tmp_path: Path) -> None:
    bad = run("--embedder", "fake", "plan", "hi", "--scene", "no-such-scene", home=graph_home, check_exit=2)
    assert "unknown demo scene" in bad.stderr and "kitchen" in bad.stderr
    broken = tmp_path / "broken.json"
    broken.write_text('{"objects": "apple"}')
    bad_file = run("--embedder", "fake", "plan", "hi", "--scene", str(broken), home=graph_home, check_exit=2)
    assert "must be a list" in bad_file.stderr


@pytest.mark.slow
def test_plan_end_to_end_with_the_real_small_model(
    graph_home: Path, smollm2_path: Path, tmp_path: Path
) -> None:
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SCENE))
    out = run(
        "--llm",
        f"llamacpp:{smollm2_path}",
        "plan",
        "Bring me an apple",
        "--scene",
        str(scene),
        "--json",
        "--no-fallback",
        home=graph_home,
    )
    data = json.loads(out.stdout)
    valid = {"pick_and_place(apple, user)", "pick_and_place(sponge, user)", "done()"}
    assert data["plan"][-1] == "done()" and set(data["plan"]) <= valid
    # The request names the apple and "me": the goal planner moves it unless the 135M model's risk
    # check judges handing it over unsafe (then a refusal with the reason); either way the contract.
    assert data["trace"]["goal"]["targets"][0]["named"] == ["apple"]
    if data["refused"]:
        assert data["plan"] == ["done()"] and data["steps"] == [] and "give the apple" in data["reason"]
    else:
        assert data["plan"] == ["pick_and_place(apple, user)", "done()"]
        assert data["steps"][0]["method"] == "decide"
    assert len(data["trace"]["risk"]) == 1
    assert data["usage"]["total"]["prompt_tokens"] > 0
    readable = run(
        "--llm",
        f"llamacpp:{smollm2_path}",
        "plan",
        "Bring me an apple",
        "--scene",
        str(scene),
        "--no-fallback",
        home=graph_home,
    )
    assert "Goal" in readable.stdout and "Plan:" in readable.stdout and "Usage" in readable.stdout


def test_scenes_lists_and_prints_demo_scenes(isolated_home: Path) -> None:
    listing = run("scenes", home=isolated_home).stdout
    assert "kitchen" in listing and "risk-5-scissors" in listing
    scene = json.loads(run("scenes", "kitchen", home=isolated_home).stdout)
    assert "ceramic bowl" in scene["destinations"] and "egg" in scene["pickable_objects"]


@pytest.mark.parametrize("config", ["conceptbot", "saycan"])
@pytest.mark.parametrize("request_text", ["", "   "])
def test_empty_request_is_one_clear_error(isolated_home: Path, config: str, request_text: str) -> None:
    out = run(
        "--llm",
        "fake",
        "--embedder",
        "fake",
        "plan",
        request_text,
        "--scene",
        "kitchen",
        "--config",
        config,
        home=isolated_home,
        check_exit=2,
    )
    assert "Traceback" not in out.stderr
    assert "Error: the request is empty" in out.stderr


def test_scene_names_that_plans_cannot_carry_are_refused_at_load(isolated_home: Path, tmp_path: Path) -> None:
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({**SCENE, "pickable_objects": ["apple", "cup (red)"]}))
    out = run("--llm", "fake", "plan", "hi", "--scene", str(scene), home=isolated_home, check_exit=2)
    assert "cup (red)" in out.stderr and "which plans cannot carry" in out.stderr


def test_readable_output_of_the_goal_planner_shows_targets_decisions_and_risk() -> None:
    from rich.console import Console

    import conceptbot.cli.main  # noqa: F401  (the command modules are imported through it)
    from conceptbot.cli.plan_cmd import show
    from conceptbot.core.scene import scene_from_dict
    from conceptbot.models.fake import FakeLLM
    from conceptbot.pipeline.conceptbot import ConceptBot

    scene = scene_from_dict(SCENE)
    prior, yes = [-1.0, -1.0], [-0.1, -3.0]
    names, neutral = [-1.0, -3.0], [-2.0, -2.0]  # the name ranking (apple, sponge), then neutral
    adult = [-3.0, -0.1]  # "is it handed to a child or an animal?": no
    llm = FakeLLM(
        scores=[names, neutral, prior, adult, prior, yes]
    )  # the ranking, who holds it, one risk check
    plan = ConceptBot(llm, None, "urp", planner="goal").plan("Bring me something to eat", scene)
    console = Console(record=True, width=160)
    show(plan, console)
    text = console.export_text()
    assert "-> user (named in the request): 1" in text and "Decisions for the user" in text
    assert "name" in text and "+1.00" in text  # the apple's name score: -1 against the neutral -2
    assert "risk: give the apple to the user" in text and "pick_and_place(apple, user)" in text


@pytest.mark.parametrize(
    ("model", "noted"), [("fake-model", True), ("qwen2.5-coder-1.5b", False)], ids=["another", "embedded"]
)
def test_a_plan_says_whose_conformal_thresholds_it_asked_by(model: str, noted: bool) -> None:
    from rich.console import Console

    import conceptbot.cli.main  # noqa: F401  (the command modules are imported through it)
    from conceptbot.cli.plan_cmd import show
    from conceptbot.core.plan import plan_schema
    from conceptbot.core.scene import scene_from_dict
    from conceptbot.models.fake import FakeLLM
    from conceptbot.pipeline.conceptbot import ConceptBot

    jsonschema = pytest.importorskip("jsonschema")
    prior, yes = [-1.0, -1.0], [-0.1, -3.0]
    names, neutral = [-1.0, -3.0], [-2.0, -2.0]
    llm = FakeLLM(scores=[names, neutral, prior, [-3.0, -0.1], prior, yes], model=model)
    bot = ConceptBot(llm, None, "urp", planner="goal")
    plan = bot.plan("Bring me something to eat", scene_from_dict(SCENE))
    assert plan.trace.calibration is not None
    assert plan.trace.calibration.to_dict() == {
        "coverage": 0.9,
        "model": f"fake:{model}",
        "fitted_for": "qwen2.5-coder-1.5b",
        "source": "shipped",
        "own": not noted,
    }
    data = plan.to_dict()
    jsonschema.validate(data, plan_schema())
    assert data["trace"]["calibration"]["own"] is not noted
    console = Console(record=True, width=300)
    show(plan, console)
    text = console.export_text()
    note = (
        "Note: the confidence and the questions use thresholds fitted for qwen2.5-coder-1.5b, not for "
        f"fake:{model}: the 0.9 coverage is not promised; `conceptbot calibrate --conformal` fits this "
        "model's own"
    )
    assert (note in text) is noted and ("Note: the confidence" in text) is noted


def test_readable_output_says_what_each_of_several_things_is_for() -> None:
    from rich.console import Console

    import conceptbot.cli.main  # noqa: F401  (the command modules are imported through it)
    from conceptbot.cli.plan_cmd import show
    from conceptbot.core.scene import scene_from_dict
    from conceptbot.models.fake import FakeLLM
    from conceptbot.pipeline.conceptbot import ConceptBot

    scene = scene_from_dict(SCENE)
    prior, yes, no = [-1.0, -1.0], [-0.1, -3.0], [-3.0, -0.1]
    eat, clean, neutral = [-1.0, -3.0], [-3.0, -1.0], [-2.0, -2.0]  # name rankings (apple, sponge)
    scores = [prior, yes, no, eat, neutral, prior, no, yes, clean, neutral, prior, yes, prior, yes]
    plan = ConceptBot(FakeLLM(scores=scores), None, "urp", planner="goal").plan(
        "Bring me something to eat and something to clean with", scene
    )
    console = Console(record=True, width=160)
    show(plan, console)
    text = console.export_text()
    assert "; as something to eat" in text and "; as something to clean with" in text
    assert "pick_and_place(apple, user)" in text and "pick_and_place(sponge, user)" in text


def test_readable_output_gives_each_reading_its_odds_and_the_model_s_preference() -> None:
    from rich.console import Console

    import conceptbot.cli.main  # noqa: F401  (the command modules are imported through it)
    from conceptbot.cli.plan_cmd import show
    from conceptbot.core.scene import scene_from_dict
    from conceptbot.models.fake import FakeEmbedder, FakeLLM
    from conceptbot.pipeline.conceptbot import ConceptBot
    from conceptbot.pipeline.retrieval import RelationRetriever
    from tests.pipeline.fakes import DictGraph

    scene = scene_from_dict({"pickable_objects": ["glue", "chips"], "destinations": ["table", "user"]})
    # Which reading was meant (the model prefers the second shown both times: the dropped one),
    # then the glue's risk question.
    judged, prior, safe = [[-2.0, -0.5], [-0.3, -2.3]], [-1.0, -1.0], [-0.05, -3.0]
    llm = FakeLLM(["Put the glue on the table."], scores=[*judged, prior, safe])
    bot = ConceptBot(llm, RelationRetriever(DictGraph(), FakeEmbedder(), theta=0.1), "urp", planner="goal")
    plan = bot.plan("Oh, before I forget, would you be a dear and pop the glue on the table?", scene)
    console = Console(record=True, width=240)
    show(plan, console)
    text = console.export_text()
    assert "taken 'put the glue in or on the table' P 0." in text and "; dropped '" in text
    assert "the model prefers the dropped one by 1.75 nats" in text
