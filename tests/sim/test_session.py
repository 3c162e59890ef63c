"""One simulator run for the CLI and the web page: detector first, pictures, animation options."""

from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

from conceptbot.core.plan import Done, PickAndPlace
from conceptbot.sim.options import SimOptions
from conceptbot.sim.session import SimSession, run_in_simulator
from tests.sim.conftest import small_scene

PLAN = [PickAndPlace("apple", "ceramic bowl"), Done()]


def test_a_run_looks_first_then_executes_and_writes_the_pictures(tmp_path: Path) -> None:
    scene = small_scene()
    seen_by_act = []

    def act(session: SimSession):
        seen_by_act.append(session.scene)
        return session.execute(PLAN)

    outcome = run_in_simulator(scene, tmp_path, act, SimOptions(gif_size=(160, 120)), title="apple")
    assert outcome.execution is not None and outcome.execution.ok
    assert outcome.files == ("before.png", "after.png", "execution.gif")
    # The plan was made on what the detector saw: boxes and sizes it measured, not the scene file's.
    apple = seen_by_act[0].get("apple")
    assert apple is not None and apple.bbox_px is not None and apple.size_m is not None
    assert 0.7 < apple.confidence <= 1.0
    assert scene.get("apple").bbox_px is None and outcome.scene is seen_by_act[0]
    assert Image.open(tmp_path / "before.png").size == (640, 480)
    gif = Image.open(tmp_path / "execution.gif")
    assert gif.size == (160, 120) and gif.n_frames > 3


def test_gif_every_keeps_one_segment_in_n(tmp_path: Path) -> None:
    counts = []
    for every in (1, 2):
        out = tmp_path / str(every)
        options = SimOptions(gif_size=(64, 48), gif_every=every)
        run_in_simulator(small_scene(), out, lambda s: s.execute(PLAN), options)
        counts.append(Image.open(out / "execution.gif").n_frames)
    assert counts[1] == (counts[0] + 1) // 2


def test_nothing_executed_leaves_only_the_before_picture(tmp_path: Path) -> None:
    scene = small_scene()
    outcome = run_in_simulator(scene, tmp_path, lambda s: None, SimOptions(detect=False, gif=False))
    assert outcome.execution is None and outcome.files == ("before.png",)
    assert outcome.scene is scene  # detector off: the scene as given
    assert sorted(p.name for p in tmp_path.iterdir()) == ["before.png"]


def test_bad_options_are_refused() -> None:
    with pytest.raises(ValueError, match="grasp"):
        SimOptions(grasp="magnetic")
    with pytest.raises(ValueError, match="gif_every"):
        SimOptions(gif_every=0)
