"""The node's Plan action (``conceptbot_interfaces/action/Plan``) and its Answer service.

A behaviour tree or any action client sends a goal (the request and a scene) to ``~/plan``; the
node accepts it at once or rejects it (the queue is full, the node is shutting down). Accepted goals
share the topic requests' queue and worker, so one plan runs at a time. Feedback carries each
module's progress and, where the planner is unsure and the goal asked for questions, the question;
``~/answer_question`` (``conceptbot_interfaces/srv/Answer``) answers it by goal id. A cancelled
goal stops between pieces of work: the model call in flight finishes, nothing after it runs, and
the result says ``cancelled``. A goal the node cannot plan (a malformed scene, stale detections, a
planner error) ends aborted with one error code and message, and the next goal is served.

How a goal runs: the worker thread takes it from the queue, marks it executing and plans; the
action's execute callback (a coroutine on the node's executor) waits for the worker's outcome and
ends the goal with it, so the executor is never blocked by a plan.
"""

from __future__ import annotations

import json
import time
import traceback
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from conceptbot_interfaces.action import Plan
from conceptbot_interfaces.msg import Move, Question
from conceptbot_interfaces.srv import Answer
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.task import Future

from conceptbot.core.answers import AnswerSlot
from conceptbot.core.errors import ConceptBotError, ConfigError
from conceptbot.core.limits import check_request
from conceptbot.core.observe import EventPart
from conceptbot.core.plan import PickAndPlace
from conceptbot.core.plan import Plan as PlanOutput
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.core.urls import redact_secrets
from conceptbot.ros2.detections import scene_from_msg
from conceptbot.ros2.protocol import MAX_PAYLOAD_BYTES
from conceptbot.scenes import load_demo_scene

if TYPE_CHECKING:
    from conceptbot.ros2.node import ConceptBotNode

#: How long a goal that asks for questions waits for an answer when the node's
#: ``answer_timeout_s`` is 0 (the topic requests then never ask).
DEFAULT_ANSWER_WAIT_S = 120.0
POLL_S = 0.1  # how often a wait for an answer looks for a cancel
FEEDBACK_GRACE_S = 0.25  # see PlanActions.run


class PlanCancelled(BaseException):
    """The goal was cancelled: raised from its observer between pieces of work. A BaseException,
    as :class:`asyncio.CancelledError` is, so no ``except Exception`` in a planner swallows it."""


@dataclass
class ActionJob:
    """An accepted goal waiting for, or in, the worker.

    Attributes:
        handle: The goal's server handle.
        goal_id: The goal's UUID as 32 hex digits (what the Answer service takes).
        goal: The goal message.
        outcome: Done with ``(terminal state, result)`` when the goal has ended.
    """

    handle: Any
    goal_id: str
    goal: Any
    outcome: Future = field(default_factory=Future)

    def end(self, state: str, result: Any) -> None:
        """End the goal: ``state`` is ``succeed``, ``abort`` or ``canceled`` (once; later calls do
        nothing)."""
        if not self.outcome.done():
            self.outcome.set_result((state, result))


def error_result(code: str, message: str, hint: str | None = None) -> Any:
    """A result that says what went wrong (``ok`` false)."""
    text = f"{message} ({hint})" if hint else message
    return Plan.Result(ok=False, error_code=code, error_message=text)


def plan_result(plan: PlanOutput) -> Any:
    """The typed result of a plan (a refusal is a result too: ``ok`` and ``refused``)."""
    moves = [
        Move(object=a.obj, destination=a.destination) for a in plan.actions if isinstance(a, PickAndPlace)
    ]
    confidence = plan.confidence if plan.confidence is not None else float("nan")
    return Plan.Result(
        ok=True,
        refused=plan.refused,
        reason=plan.reason or "",
        confidence=confidence,
        actions=moves,
        plan_json=json.dumps(plan.to_dict(), ensure_ascii=False),
    )


class _FeedbackObserver:
    """A goal's observer: each piece of work as feedback; a cancel stops the plan there."""

    def __init__(self, job: ActionJob) -> None:
        self.job = job

    def _check(self) -> None:
        if self.job.handle.is_cancel_requested:
            raise PlanCancelled

    def progress(self, message: str) -> None:
        """A piece of work starts: stop here if cancelled, else say so."""
        self._check()
        self.job.handle.publish_feedback(Plan.Feedback(stage="progress", message=message))

    def event(self, name: str, part: EventPart) -> None:
        """A module finished: stop here if cancelled, else say so."""
        self._check()
        self.job.handle.publish_feedback(Plan.Feedback(stage=name, message=f"{name}: done"))


class PlanActions:
    """The Plan action server and the Answer service of ``node`` (see the module).

    Args:
        node: The node; its queue, worker, planner, scenes and answer slot are used.
    """

    def __init__(self, node: ConceptBotNode) -> None:
        self.node = node
        self._jobs: dict[str, ActionJob] = {}
        self.server = ActionServer(
            node,
            Plan,
            "~/plan",
            execute_callback=self._execute,
            goal_callback=self._goal,
            handle_accepted_callback=self._accepted,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT,
        )
        self.answer_service = node.create_service(Answer, "~/answer_question", self._answer)

    def _goal(self, _goal: Any) -> GoalResponse:
        """Accept at once unless the node cannot take it now."""
        return GoalResponse.REJECT if self.node.is_full() else GoalResponse.ACCEPT

    def _accepted(self, handle: Any) -> None:
        goal_id = bytes(handle.goal_id.uuid).hex()
        job = ActionJob(handle, goal_id, handle.request, Future(executor=self.node.executor))
        # The outcome is set by the worker thread: a done callback is scheduled on the executor,
        # which wakes it so that the execute coroutine awaiting the outcome resumes.
        job.outcome.add_done_callback(lambda _done: None)
        self._jobs[goal_id] = job
        if not self.node.enqueue(job):  # filled up since it was accepted, or closing
            handle.execute()
            job.end("abort", error_result("busy", "the planner's queue is full or the node is closing"))

    async def _execute(self, handle: Any) -> Any:
        job = self._jobs.pop(bytes(handle.goal_id.uuid).hex())
        state, result = await job.outcome
        getattr(handle, state)()
        return result

    def close(self) -> None:
        """Destroy the action server and the service (the node's close ends the queued goals)."""
        self.server.destroy()
        self.node.destroy_service(self.answer_service)

    def run(self, job: ActionJob) -> None:
        """Plan one goal (the worker thread); always ends it, and logs how."""
        started = time.monotonic()
        state, result = self._outcome(job)
        # Feedback and result travel apart, and a client drops feedback that comes after the
        # result: give the last feedback time to arrive first.
        time.sleep(FEEDBACK_GRACE_S)
        job.end(state, result)
        how = result.error_code or f"{len(result.actions)} move(s)" + (" (refused)" if result.refused else "")
        seconds = time.monotonic() - started
        self.node.get_logger().info(
            f"goal {job.goal_id[:8]} {job.goal.request[:60]!r}: {state} {how} ({seconds:.1f} s)"
        )

    def _outcome(self, job: ActionJob) -> tuple[str, Any]:
        """Plan the goal: its terminal state and result."""
        try:
            job.handle.execute()
            if job.handle.is_cancel_requested:
                raise PlanCancelled
            request, scene = self._read(job.goal)
            job.handle.publish_feedback(Plan.Feedback(stage="planning", message=f"planning in {scene.name}"))
            observer = _FeedbackObserver(job)
            ask = self._asker(job) if job.goal.ask else None
            if ask is None:
                plan = self.node.planner.plan(request, scene, observer=observer)
            else:
                plan = self.node.planner.plan(request, scene, observer=observer, ask=ask)
            return "succeed", plan_result(plan)
        except PlanCancelled:
            said = "cancelled by the client: nothing after the piece of work in flight ran"
            return "canceled", Plan.Result(
                ok=False, cancelled=True, error_code="cancelled", error_message=said
            )
        except _NoAnswerError as exc:
            return "abort", error_result("no_answer", str(exc))
        except ConfigError as exc:
            return "abort", error_result("bad_goal", exc.message, exc.hint)
        except ConceptBotError as exc:
            message, hint = redact_secrets(exc.message), exc.hint and redact_secrets(exc.hint)
            return "abort", error_result("planner_error", message, hint)
        except Exception as exc:  # the node stays up; the traceback goes to the log
            self.node.get_logger().error(f"goal {job.goal_id}: planning failed:\n{traceback.format_exc()}")
            return "abort", error_result("planner_error", redact_secrets(f"unexpected error: {exc!r}"))

    def _read(self, goal: Any) -> tuple[str, Scene]:
        """The goal's request and scene (see ``Plan.action``).

        Raises:
            ConfigError: An empty request, a bad scene, stale or missing detections, another system.
        """
        request = check_request(goal.request)
        if goal.config and goal.config != self.node.config.system:
            raise ConfigError(
                f"this node plans with {self.node.config.system!r}, not {goal.config!r}",
                hint=f"leave config empty, or start a node with -p system:={goal.config}",
            )
        if goal.scene.detections:
            return request, scene_from_msg(goal.scene)
        if goal.scene_json:
            if len(goal.scene_json.encode("utf-8")) > MAX_PAYLOAD_BYTES:
                raise ConfigError(f"scene_json is larger than {MAX_PAYLOAD_BYTES:,} bytes")
            try:
                data = json.loads(goal.scene_json)
            except (ValueError, RecursionError) as exc:
                raise ConfigError(f"scene_json is not valid JSON: {exc}") from None
            if not isinstance(data, dict):
                raise ConfigError("scene_json must be a JSON object (a scene file's fields)")
            return request, scene_from_dict(data, where="scene_json")
        if goal.scene_name:
            return request, load_demo_scene(goal.scene_name)
        if self.node.latest is not None:
            return request, self.node.latest.current()
        return request, self.node.default_scene

    def _asker(self, job: ActionJob) -> Any:
        """The planner's ``ask`` for a goal: the question as feedback, the answer from the service."""
        wait = self.node.config.answer_timeout_s or DEFAULT_ANSWER_WAIT_S

        def ask(question: ClarifyingQuestion) -> str:
            slot = AnswerSlot()
            self.node.await_answer(job.goal_id, question, slot)
            try:
                asked = Question(kind=question.kind, text=question.text, options=list(question.options))
                asked.options.extend(question.others)
                job.handle.publish_feedback(
                    Plan.Feedback(stage="question", message=question.text, question=asked)
                )
                deadline = time.monotonic() + wait
                while (answer := slot.wait(POLL_S)) is None:
                    if job.handle.is_cancel_requested:
                        raise PlanCancelled
                    if time.monotonic() >= deadline:
                        raise _NoAnswerError(f"no answer to {question.text!r} within {wait:g} s")
                return answer
            finally:
                self.node.await_answer(job.goal_id, None, None)

        return ask

    def _answer(self, request: Any, response: Any) -> Any:
        """The Answer service: give a running goal's open question its answer."""
        accepted, code, message = self.node.give_answer(request.goal_id.strip().lower(), request.answer)
        response.accepted, response.error_code, response.message = accepted, code, message
        return response


class _NoAnswerError(Exception):
    """Nobody answered a goal's question in time: the goal ends without a plan, never a guess."""
