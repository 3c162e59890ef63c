"""`conceptbot plan` asks where the planner is unsure: on a terminal (``--ask``), the question on
stderr and the answer read from the person; with ``--json`` the questions come back in the JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from conceptbot.cli import main as cli_main
from conceptbot.cli import plan_cmd
from conceptbot.core.plan import Done, PickAndPlace, Plan
from conceptbot.core.trace import ClarifyingQuestion, PlanTrace

QUESTION = ClarifyingQuestion("Should I put the lemon in or on the bowl (sour)?", "lemon", "bowl", 0.5)


class Unsure:
    """A system with one unsure decision: asks if it can, else acts on the likelier answer."""

    def __init__(self) -> None:
        self.asked: list[Any] = []

    def plan(self, request, scene, risk=False, feedback=None, observer=None, ask=None) -> Plan:
        self.asked.append(ask)
        answer = ask(QUESTION) if ask is not None else None
        actions = [Done()] if answer == "no" else [PickAndPlace("apple", "user"), Done()]
        question = ClarifyingQuestion(QUESTION.text, "lemon", "bowl", 0.5, answer)
        return Plan(
            actions,
            trace=PlanTrace(config="conceptbot"),
            confidence=1.0 if answer else 0.5,
            questions=(question,),
        )


@pytest.fixture
def unsure(monkeypatch: pytest.MonkeyPatch) -> Unsure:
    system = Unsure()
    monkeypatch.setattr(plan_cmd, "build_system", lambda settings, config, options: system)
    return system


SCENE = {"objects": ["apple", "user"], "pickable_objects": ["apple"], "destinations": ["user"]}


def _plan(tmp_path: Path, *args: str, answer: str = "") -> Any:
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SCENE))
    argv = ["plan", "Bring me something sour", "--scene", str(scene), *args]
    return CliRunner().invoke(cli_main.cli, argv, input=answer)


def test_with_ask_the_question_is_put_and_the_answer_finishes_the_plan(
    unsure: Unsure, tmp_path: Path
) -> None:
    out = _plan(tmp_path, "--ask", answer="no\n")
    assert out.exit_code == 0, out.output
    assert "Question: Should I put the lemon in or on the bowl (sour)? (yes, no):" in out.output
    assert "1. done()" in out.output and "answered no" in out.output
    assert callable(unsure.asked[0])


def test_with_json_nobody_is_asked_and_the_questions_come_back(unsure: Unsure, tmp_path: Path) -> None:
    out = _plan(tmp_path, "--json")
    data = json.loads(out.stdout)
    assert unsure.asked == [None]
    assert data["questions"] == [QUESTION.to_dict()] and data["confidence"] == 0.5
    assert data["plan"] == ["pick_and_place(apple, user)", "done()"]


def test_an_answer_that_is_neither_yes_nor_no_is_asked_again(unsure: Unsure, tmp_path: Path) -> None:
    out = _plan(tmp_path, "--ask", answer="maybe\nyes\n")
    assert out.exit_code == 0, out.output
    assert "answered yes" in out.output and out.output.count("Question: Should I") >= 2
