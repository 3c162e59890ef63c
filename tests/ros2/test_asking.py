"""The node asks where the planner is unsure (real rclpy): the question on ``~/question``, the
answer from ``~/answer`` matched by the request's id, and no answer in time ends the request
``no_answer``, never a guess."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from std_msgs.msg import String

from conceptbot.core.plan import Done, PickAndPlace, Plan
from conceptbot.core.scene import Scene
from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.ros2 import qos
from conceptbot.ros2.node import NodeConfig
from conceptbot.ros2.protocol import parse_answer
from tests.ros2.harness import TINY_SCENE, Running, wait_for

QUESTION = ClarifyingQuestion(
    "Should I give the sponge to the user (to wipe a spill)?", "user", ("sponge",), (0.5,)
)
CHOOSE = ClarifyingQuestion(
    "Which of these should I give to the user (to wipe a spill): the sponge or the towel?"
    " Name them, or say all or none.",
    "user",
    ("sponge", "towel"),
    (0.5, 0.4),
    kind="choose",
)


class AskingPlanner:
    """Asks one question; moves the objects the answer sends (the sponge on a yes)."""

    def __init__(self, question: ClarifyingQuestion = QUESTION) -> None:
        self.question = question

    def plan(self, request: str, scene: Scene, risk=False, feedback=None, observer=None, ask=None) -> Plan:
        answer = ask(self.question) if ask is not None else None
        chosen = self.question.read(answer) if answer is not None else ()
        moves = [PickAndPlace("apple", "user")] + [PickAndPlace(o, "user") for o in chosen or ()]
        return Plan([*moves, Done()], questions=(replace(self.question, answer=answer),))


def _asking(
    start_node: Callable[..., Running], wait: float, question: ClarifyingQuestion = QUESTION
) -> tuple[Running, list[dict[str, Any]], Any]:
    running = start_node(NodeConfig(answer_timeout_s=wait), planner=AskingPlanner(question))
    questions: list[dict[str, Any]] = []
    running.client.create_subscription(
        String, "/conceptbot/question", lambda m: questions.append(json.loads(m.data)), qos.REPLIES
    )
    answers = running.client.create_publisher(String, "/conceptbot/answer", qos.REQUESTS)
    assert wait_for(lambda: answers.get_subscription_count() > 0, 10.0)
    return running, questions, answers


def test_the_question_goes_out_and_the_answer_finishes_the_plan(start_node) -> None:
    running, questions, answers = _asking(start_node, 20.0)
    running.send(
        {"id": "r1", "request": "Bring me the apple and something to wipe a spill", "scene": TINY_SCENE}
    )
    assert wait_for(lambda: questions, 10.0), "no question came"
    assert questions[0] == {"id": "r1", "kind": "question", "question": QUESTION.to_dict()}
    answers.publish(String(data=json.dumps({"id": "someone-else", "answer": "no"})))  # not this request's
    answers.publish(String(data=json.dumps({"id": "r1", "answer": "Yes"})))
    [result] = running.wait_results(1)
    assert result["ok"] is True
    assert result["plan"]["plan"] == ["pick_and_place(apple, user)", "pick_and_place(sponge, user)", "done()"]
    assert result["plan"]["questions"][0]["answer"] == "yes"


def test_no_answer_in_time_is_no_plan(start_node) -> None:
    running, questions, _ = _asking(start_node, 0.5)
    running.send({"id": "r2", "request": "Bring me something to wipe a spill", "scene": TINY_SCENE})
    [result] = running.wait_results(1)
    assert result["ok"] is False and result["error"]["code"] == "no_answer"
    assert "within 0.5 s" in result["error"]["message"] and '"id": "r2"' in result["error"]["hint"]
    assert len(questions) == 1


def test_without_a_wait_the_node_does_not_ask(start_node) -> None:
    running = start_node(NodeConfig(), planner=AskingPlanner())
    running.send({"id": "r3", "request": "Bring me something", "scene": TINY_SCENE})
    [result] = running.wait_results(1)
    assert result["plan"]["plan"] == ["pick_and_place(apple, user)", "done()"]
    assert result["plan"]["questions"][0]["answer"] is None


def test_an_answer_is_text_with_an_id() -> None:
    assert parse_answer('{"id": "r1", "answer": " NO "}') == ("r1", "NO")
    too_long = json.dumps({"id": "r1", "answer": "x" * 5000})
    for bad in ("{", "[]", '{"answer": "yes"}', '{"id": "r1", "answer": " "}', '{"id": "r1"}', too_long):
        try:
            parse_answer(bad)
        except Exception as exc:
            assert getattr(exc, "code", None) == "bad_request"
        else:
            raise AssertionError(f"{bad!r} was accepted")


def test_a_choose_question_takes_the_objects_and_drops_what_does_not_answer_it(start_node) -> None:
    running, questions, answers = _asking(start_node, 20.0, CHOOSE)
    running.send(
        {"id": "r4", "request": "Bring me the apple and something to wipe a spill", "scene": TINY_SCENE}
    )
    assert wait_for(lambda: questions, 10.0), "no question came"
    assert questions[0]["question"]["kind"] == "choose" and questions[0]["question"]["options"] == [
        "sponge",
        "towel",
    ]
    answers.publish(String(data=json.dumps({"id": "r4", "answer": "yes"})))  # not an answer to "which"
    answers.publish(String(data=json.dumps({"id": "r4", "answer": "Towel, sponge"})))
    [result] = running.wait_results(1)
    assert result["plan"]["plan"] == [
        "pick_and_place(apple, user)",
        "pick_and_place(sponge, user)",
        "pick_and_place(towel, user)",
        "done()",
    ]
    assert result["plan"]["questions"][0]["answer"] == "sponge, towel"
    assert result["plan"]["questions"][0]["chosen"] == ["sponge", "towel"]
