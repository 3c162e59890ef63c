"""`conceptbot plan` asks where the planner is unsure: on a terminal (``--ask``), the question on
stderr and the answer read from the person; with ``--json`` the questions come back in the JSON."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from conceptbot.cli import main as cli_main
from conceptbot.cli import plan_cmd
from conceptbot.core.plan import Done, PickAndPlace, Plan
from conceptbot.core.trace import ClarifyingQuestion, PlanTrace

QUESTION = ClarifyingQuestion("Should I put the lemon in or on the bowl (sour)?", "bowl", ("lemon",), (0.5,))
CHOOSE = ClarifyingQuestion(
    "Which of these should I put in or on the bowl (sour): the lemon, the lime or the cup?"
    " Name them, or say all or none.",
    "bowl",
    ("lemon", "lime", "cup"),
    (0.5, 0.6, 0.4),
    kind="choose",
)


class Unsure:
    """A system with one unsure decision: asks if it can, else acts on the likelier answer."""

    def __init__(self, question: ClarifyingQuestion = QUESTION) -> None:
        self.asked: list[Any] = []
        self.question = question
        self.answers: list[str | None] = []

    def plan(self, request, scene, risk=False, feedback=None, observer=None, ask=None) -> Plan:
        self.asked.append(ask)
        answer = ask(self.question) if ask is not None else None
        self.answers.append(answer)
        actions = [Done()] if answer == "no" else [PickAndPlace("apple", "user"), Done()]
        question = replace(self.question, answer=answer)
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
    assert "Question: Should I put the lemon in or on the bowl (sour)? [yes/no]:" in out.output
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


def test_a_choose_question_lists_the_objects_and_takes_numbers_or_names(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    system = Unsure(CHOOSE)
    monkeypatch.setattr(plan_cmd, "build_system", lambda settings, config, options: system)
    out = _plan(tmp_path, "--ask", answer="3, lime\n")
    assert out.exit_code == 0, out.output
    assert "  1. lemon\n  2. lime\n  3. cup\n" in out.output
    assert system.answers == ["lime, cup"] and "answered lime, cup" in out.output


@pytest.mark.parametrize("first", ["4", "spoon", "lemon, lemon", "yes"])
def test_a_reply_to_a_choose_question_that_is_not_an_answer_is_asked_again(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, first: str
) -> None:
    system = Unsure(CHOOSE)
    monkeypatch.setattr(plan_cmd, "build_system", lambda settings, config, options: system)
    out = _plan(tmp_path, "--ask", answer=f"{first}\nnone\n")
    assert out.exit_code == 0, out.output
    assert system.answers == ["none"] and "Give numbers or names" in out.output


def test_a_which_one_question_takes_another_candidate_by_name(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    one = ClarifyingQuestion(
        "Which one should I give to the user: the lemon or the lime? One of them, another, or none.",
        "user",
        ("lemon", "lime"),
        (0.5, 0.4),
        kind="one",
        others=("orange", "cup"),
    )
    system = Unsure(one)
    monkeypatch.setattr(plan_cmd, "build_system", lambda settings, config, options: system)
    out = _plan(tmp_path, "--ask", answer="3\nOrange\n")  # no third in the list: asked again
    assert out.exit_code == 0, out.output
    assert "  1. lemon\n  2. lime\n  or another: orange, cup\n" in out.output
    assert system.answers == ["orange"] and "Give a number or a name" in out.output


def test_a_reading_question_lists_the_two_readings_and_takes_a_number(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    readings = ('give the user one "fruit"', 'give the user one "fruit" and give the user one "soda"')
    question = ClarifyingQuestion(
        f"Did you mean: {readings[0]}, or {readings[1]}? One of them, or none.",
        "",
        readings,
        (0.65, 0.15),
        kind="reading",
    )
    system = Unsure(question)
    monkeypatch.setattr(plan_cmd, "build_system", lambda settings, config, options: system)
    out = _plan(tmp_path, "--ask", answer="fruit\n2\n")  # part of a reading is not an answer
    assert out.exit_code == 0, out.output
    assert f"  1. {readings[0]}\n  2. {readings[1]}\n" in out.output
    assert system.answers == [readings[1]] and "P(meant) 0.65, 0.15" in out.output
