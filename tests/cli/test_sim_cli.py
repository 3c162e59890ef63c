"""`conceptbot sim run` as a user runs it: executing a plan file, pictures, bad input, and a plan
made by `conceptbot plan --json` on the real small model."""

import json
from pathlib import Path

import pytest
from PIL import Image

from tests.cli.test_cli import run

SCENE = {
    "objects": ["apple", "energy bar", "ceramic bowl", "user"],
    "pickable_objects": ["apple", "energy bar"],
    "destinations": ["ceramic bowl", "user"],
}


@pytest.fixture
def scene_file(tmp_path: Path) -> Path:
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(SCENE))
    return path


def test_run_a_plan_file_writes_pictures_and_a_verdict(
    isolated_home: Path, scene_file: Path, tmp_path: Path
) -> None:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps({"plan": ["pick_and_place(apple, ceramic bowl)", "done()"]}))
    out = tmp_path / "out"
    result = run(
        "sim", "run", "--scene", str(scene_file), "--plan", str(plan), "--out", str(out), home=isolated_home
    )
    assert "Verdict: success" in result.stdout and "apple -> ceramic bowl" in result.stdout
    data = json.loads((out / "result.json").read_text())
    assert data["ok"] and data["placements"] == {"apple": "ceramic bowl"}
    assert Image.open(out / "before.png").size == (640, 480)
    assert Image.open(out / "after.png").size == (640, 480)
    assert Image.open(out / "execution.gif").n_frames > 3


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((), "give a REQUEST"),
        (("--plan", "missing.json"), "no plan file"),
        (("--plan", "BAD"), "not in the scene"),
    ],
)
def test_bad_input_is_a_clear_error(
    isolated_home: Path, scene_file: Path, tmp_path: Path, args: tuple, message: str
) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"plan": ["pick_and_place(unicorn, user)", "done()"]}))
    args = tuple(str(bad) if a == "BAD" else str(tmp_path / a) if a.endswith(".json") else a for a in args)
    result = run("sim", "run", "--scene", str(scene_file), *args, home=isolated_home, check_exit=2)
    assert message in result.stderr and "Traceback" not in result.stderr


@pytest.mark.slow
def test_a_plan_from_conceptbot_plan_json_executes(
    isolated_home: Path, smollm2_path: Path, scene_file: Path, tmp_path: Path
) -> None:
    made = run(
        "--llm",
        f"llamacpp:{smollm2_path}",
        "plan",
        "--scene",
        str(scene_file),
        "--config",
        "saycan",
        "--json",
        "Put the apple in the bowl",
        home=isolated_home,
    )
    plan = tmp_path / "plan.json"
    plan.write_text(made.stdout)
    actions = json.loads(made.stdout)["plan"]
    out = tmp_path / "out"
    run(
        "sim",
        "run",
        "--scene",
        str(scene_file),
        "--plan",
        str(plan),
        "--out",
        str(out),
        "--no-gif",
        home=isolated_home,
    )
    data = json.loads((out / "result.json").read_text())
    moves = [a for a in actions if a != "done()"]
    # Every step ran until the first failure (if any); the verdict is a checked final state.
    assert [s["action"] for s in data["steps"]] == moves[: len(data["steps"])]
    assert data["verdict"].startswith(("success", "failure"))
    assert (out / "after.png").exists() and not (out / "execution.gif").exists()
