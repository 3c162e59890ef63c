"""The ROS 2 node: plans each request from ``~/request``, reports on ``~/progress`` and ``~/result``.

One worker thread plans, one request at a time (the embedded model is one llama.cpp instance
and runs one plan at a time), fed by a bounded queue: a request that finds
the queue full is answered ``busy`` at once; queued requests are answered in the order they came.
Nothing is dropped silently: a malformed request, an unknown object, a planner failure, a plan
over ``plan_timeout_s`` and a request still queued when the node shuts down each get an error
result. The request callback only parses and queues, so the executor stays free while a plan runs.

Example (what ``conceptbot ros2 node`` does, :func:`run_node`)::

    rclpy.init()
    node = ConceptBotNode(load_settings(), defaults=NodeConfig(scene="kitchen"))
    try:
        rclpy.spin(node)
    finally:
        node.destroy_node()
"""

from __future__ import annotations

import contextlib
import queue
import signal
import threading
import time
import traceback
from dataclasses import dataclass, replace
from typing import Any

import rclpy
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.exceptions import NameValidationException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rclpy.validate_node_name import validate_node_name
from std_msgs.msg import String

from conceptbot.core.answers import AnswerSlot
from conceptbot.core.config import Settings
from conceptbot.core.errors import ConceptBotError, ConfigError
from conceptbot.core.observe import EventPart
from conceptbot.core.plan import Plan, format_actions
from conceptbot.core.system import Ask, PlannerSystem
from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.core.urls import redact_secrets
from conceptbot.ros2 import qos
from conceptbot.ros2.detections import LatestScene
from conceptbot.ros2.protocol import (
    PlanRequest,
    ProtocolError,
    encode,
    error_payload,
    event_payload,
    parse_answer,
    parse_request,
    progress_payload,
    question_payload,
    result_payload,
)
from conceptbot.scenes import resolve_scene
from conceptbot.systems import SYSTEMS, build_system

try:  # the action needs the compiled interfaces (scripts/build_interfaces.sh); topics do not
    from conceptbot_interfaces.msg import Scene as SceneMsg

    from conceptbot.ros2.action import ActionJob, PlanActions, error_result
except ImportError as exc:
    ActionJob = PlanActions = SceneMsg = None  # type: ignore[assignment,misc]
    INTERFACES_MISSING: str | None = str(exc)
else:
    INTERFACES_MISSING = None

ACK_WAIT = Duration(seconds=1)
"""How long a result waits for the subscribers to acknowledge its request's progress messages."""


@dataclass(frozen=True)
class NodeConfig:
    """The node's ROS parameters (read once, at start).

    Attributes:
        system: The planner system (one of :data:`~conceptbot.systems.SYSTEMS`).
        llm: The LLM backend spec; empty: the settings' (``llamacpp:qwen2.5-coder-1.5b`` by default).
        scene: The scene of a request that sends none: a demo scene name or a scene file.
        queue_size: Requests that may wait while one is planned; one more is answered ``busy``.
        plan_timeout_s: Seconds a plan may take before its request is answered ``timeout``; 0: no limit.
        answer_timeout_s: Where the planner is unsure it asks on ``~/question`` and waits this long
            for the answer on ``~/answer``; no answer ends the request ``no_answer`` (a refusal,
            never a guess). 0: the node does not ask (the plan acts on the likelier answers and
            lists its questions).
        detections: A topic of ``conceptbot_interfaces/msg/Scene`` from the robot's detector: goals
            that give no scene are planned against the latest. Empty: none (the default scene).
        detections_max_age_s: How old the latest detections may be; older ones refuse the goal.
    """

    system: str = "conceptbot"
    llm: str = ""
    scene: str = "kitchen"
    queue_size: int = 4
    plan_timeout_s: float = 0.0
    answer_timeout_s: float = 0.0
    detections: str = ""
    detections_max_age_s: float = 5.0


_DESCRIPTIONS = {
    "system": f"planner system: {', '.join(SYSTEMS)}",
    "llm": "LLM backend spec, e.g. llamacpp:qwen2.5-coder-1.5b or openai:gpt-4o-mini (empty: the settings')",
    "scene": "scene of a request that sends none: a demo scene name or a scene file",
    "queue_size": "requests that may wait while one is planned (one more is answered busy)",
    "plan_timeout_s": "seconds a plan may take before it is answered timeout (0: no limit)",
    "answer_timeout_s": "seconds to wait for an answer on ~/answer before refusing no_answer (0: never ask)",
    "detections": "topic of conceptbot_interfaces/msg/Scene from the detector (empty: none)",
    "detections_max_age_s": "seconds the latest detections stay fresh enough to plan against",
}


class NoAnswerError(ConceptBotError):
    """Nobody answered the planner's question in time: the request ends without a plan."""


@dataclass
class _Running:
    """The request being planned. ``open`` turns False once it is answered (result or timeout);
    the lock keeps its progress from being published after its result."""

    request: PlanRequest
    started: float
    lock: threading.Lock
    open: bool = True


class _TopicObserver:
    """A plan's observer that publishes each progress message and module event on ``~/progress``."""

    def __init__(self, node: ConceptBotNode, running: _Running) -> None:
        self.node = node
        self.running = running

    def progress(self, message: str) -> None:
        """Publish a progress message (nothing once the request is answered)."""
        self._send(progress_payload(self.running.request.id, message))

    def event(self, name: str, part: EventPart) -> None:
        """Publish a module's event (nothing once the request is answered)."""
        self._send(event_payload(self.running.request.id, name, part))

    def _send(self, payload: dict[str, Any]) -> None:
        with self.running.lock:
            if self.running.open:
                self.node.publish(self.node.progress_pub, payload)


class ConceptBotNode(Node):
    """A ROS 2 node that plans requests: ``~/request`` in, ``~/progress`` and ``~/result`` out.

    The planner is built at start from the parameters (so a bad backend or system stops the node
    with its message before it takes requests); the embedded model loads on the first plan.

    Args:
        settings: Settings (home, caches, embedder, graph, the default LLM).
        name: The node's name; its topics are ``/<namespace>/<name>/request`` and so on.
        defaults: The parameters' defaults (the command's flags); ``--ros-args -p`` values win.
        context: The rclpy context (default: the global one).
        namespace: The node's namespace, or None.
        planner: A planner to use instead of the one ``system`` and ``llm`` name (tests, embedding
            the node in your own process).

    Raises:
        ConfigError: A parameter of the wrong type or out of range, an unknown system or scene.
        ConceptBotError: The planner's backends cannot be opened (with a hint how to fix it).
    """

    def __init__(
        self,
        settings: Settings,
        *,
        name: str = "conceptbot",
        defaults: NodeConfig | None = None,
        context: Context | None = None,
        namespace: str | None = None,
        planner: PlannerSystem | None = None,
    ) -> None:
        super().__init__(name, context=context, namespace=namespace)
        try:
            self.config = self._read_parameters(defaults or NodeConfig(llm=settings.llm), settings)
            self.default_scene = resolve_scene(self.config.scene)
            if planner is None:
                planner = build_system(replace(settings, llm=self.config.llm), self.config.system)
            self.planner = planner
        except Exception:
            super().destroy_node()
            raise
        self._queue: queue.Queue[Any] = queue.Queue(maxsize=self.config.queue_size)
        # Guards _closed, _current and putting into the queue, against destroy_node.
        self._lock = threading.Lock()
        self._closed = False
        self._current: _Running | None = None
        self.progress_pub = self.create_publisher(String, "~/progress", qos.REPLIES)
        self.result_pub = self.create_publisher(String, "~/result", qos.REPLIES)
        self.question_pub = self.create_publisher(String, "~/question", qos.REPLIES)
        self.request_sub = self.create_subscription(String, "~/request", self._on_request, qos.REQUESTS)
        self.answer_sub = self.create_subscription(String, "~/answer", self._on_answer, qos.REQUESTS)
        # The answer the request being planned waits for: (its id, the event, the answer).
        self._awaited: tuple[str, ClarifyingQuestion, AnswerSlot] | None = None
        self.latest: LatestScene | None = None
        if self.config.detections:
            clock = self.get_clock()
            self.latest = LatestScene(
                self.config.detections_max_age_s, lambda: clock.now().nanoseconds * 1e-9
            )
            self.create_subscription(SceneMsg, self.config.detections, self.latest.put, qos.REQUESTS)
        self.actions = PlanActions(self) if PlanActions is not None else None
        if self.actions is None:
            self.get_logger().warning(f"no Plan action (conceptbot_interfaces: {INTERFACES_MISSING})")
        self._worker = threading.Thread(target=self._work, name=f"{name}-planner", daemon=True)
        self._worker.start()
        self.get_logger().info(
            f"ready: {self.config.system} on {redact_secrets(self.config.llm)}, "
            f"default scene {self.default_scene.name}; "
            f"requests on {self.request_sub.topic_name}"
            + (f", goals on {self.get_fully_qualified_name()}/plan" if self.actions else "")
        )

    def _read_parameters(self, defaults: NodeConfig, settings: Settings) -> NodeConfig:
        values = {}
        for key, description in _DESCRIPTIONS.items():
            # Dynamic typing: `-p plan_timeout_s:=5` (an integer) must work as well as 5.0.
            descriptor = ParameterDescriptor(description=description, read_only=True, dynamic_typing=True)
            values[key] = self.declare_parameter(key, getattr(defaults, key), descriptor).value
        system, llm, scene = values["system"], values["llm"], values["scene"]
        for key in ("system", "llm", "scene"):
            if not isinstance(values[key], str):
                raise ConfigError(f"the ROS parameter {key!r} must be a string, got {values[key]!r}")
        if system not in SYSTEMS:
            raise ConfigError(f"unknown system {system!r}", hint=f"use one of {', '.join(SYSTEMS)}")
        queue_size, timeout = values["queue_size"], values["plan_timeout_s"]
        if isinstance(queue_size, bool) or not isinstance(queue_size, int) or queue_size < 1:
            raise ConfigError(
                f"the ROS parameter 'queue_size' must be a whole number >= 1, got {queue_size!r}"
            )
        if isinstance(timeout, bool) or not isinstance(timeout, int | float) or not timeout >= 0:
            raise ConfigError(
                f"the ROS parameter 'plan_timeout_s' must be a number of seconds >= 0, got {timeout!r}",
                hint="0 means no limit",
            )
        wait, topic, age = values["answer_timeout_s"], values["detections"], values["detections_max_age_s"]
        if isinstance(wait, bool) or not isinstance(wait, int | float) or not wait >= 0:
            raise ConfigError(
                f"the ROS parameter 'answer_timeout_s' must be a number of seconds >= 0, got {wait!r}",
                hint="0 means the node does not ask",
            )
        if not isinstance(topic, str):
            raise ConfigError(f"the ROS parameter 'detections' must be a topic name, got {topic!r}")
        if isinstance(age, bool) or not isinstance(age, int | float) or not age > 0:
            raise ConfigError(f"the ROS parameter 'detections_max_age_s' must be seconds > 0, got {age!r}")
        if topic and INTERFACES_MISSING:
            raise ConfigError(
                f"--detections needs conceptbot_interfaces ({INTERFACES_MISSING})",
                hint="build it with: bash scripts/build_interfaces.sh",
            )
        return NodeConfig(
            system, llm or settings.llm, scene, queue_size, float(timeout), float(wait), topic, float(age)
        )

    def publish(self, publisher: Any, payload: dict[str, Any]) -> None:
        """Publish one payload as a String message; a failure (the node shutting down) is logged.

        Args:
            publisher: ``progress_pub`` or ``result_pub``.
            payload: The JSON object to send.
        """
        try:
            publisher.publish(String(data=encode(payload)))
        except Exception as exc:  # never let a send take the worker or the executor down
            self.get_logger().warning(f"could not publish on {publisher.topic_name}: {exc}")

    def _on_request(self, msg: String) -> None:
        """Parse and queue a request; answer at once when it is bad or the queue is full."""
        try:
            request = parse_request(msg.data, self.default_scene)
        except ProtocolError as exc:
            self._answer_error(exc.request_id, exc.code, exc.message, exc.hint)
            return
        except Exception as exc:  # a bug in parsing must not stop the executor
            self.get_logger().error(f"reading a request failed:\n{traceback.format_exc()}")
            self._answer_error("?", "planner_error", f"unexpected error: {exc!r}", "see the node's log")
            return
        with self._lock:
            if self._closed:
                self._answer_error(request.id, "planner_error", "the node is shutting down")
                return
            try:
                self._queue.put_nowait(request)
                return
            except queue.Full:
                pass
        self._answer_error(
            request.id,
            "busy",
            f"{self.config.queue_size} request(s) are already waiting for the planner",
            "wait for a result before sending the next request, or raise the queue_size parameter",
        )

    def is_full(self) -> bool:
        """Whether a new request or goal would find no room (or the node is closing)."""
        with self._lock:
            return self._closed or self._queue.full()

    def enqueue(self, item: Any) -> bool:
        """Queue a goal (an action job) for the worker; False when there is no room or the node is
        closing."""
        with self._lock:
            if self._closed:
                return False
            try:
                self._queue.put_nowait(item)
            except queue.Full:
                return False
            return True

    def await_answer(
        self, request_id: str, question: ClarifyingQuestion | None, slot: AnswerSlot | None
    ) -> None:
        """Open (or, with None, close) the one question the running request or goal waits on."""
        with self._lock:
            self._awaited = (
                (request_id, question, slot) if question is not None and slot is not None else None
            )

    def give_answer(self, request_id: str, answer: str) -> tuple[bool, str, str]:
        """Answer the open question of ``request_id``: (taken, error code, message). A wrong answer
        is dropped, not fatal: the question stays open for one that fits it."""
        with self._lock:
            awaited = self._awaited
        if awaited is None or awaited[0] != request_id:
            return False, "no_question", f"no question of {request_id!r} is open"
        _, question, slot = awaited
        chosen = question.read(answer)
        if chosen is None:
            how = {
                "confirm": "yes or no",
                "choose": f"some of {', '.join(question.options)}, or none",
                "one": f"one of {', '.join((*question.options, *question.others))}, or none",
                "reading": f"one of {' / '.join(question.options)}, or none",
            }[question.kind]
            return False, "bad_answer", f"{answer!r:.80} is not {how}"
        if not slot.give(question.normalised(chosen)):
            return False, "no_question", "its question is answered already"
        return True, "", "taken"

    def _on_answer(self, msg: String) -> None:
        """An answer to the question of the request being planned; others are logged and dropped."""
        try:
            request_id, answer = parse_answer(msg.data)
        except ProtocolError as exc:
            self.get_logger().warning(f"answer dropped: {exc.message}")
            return
        taken, _, message = self.give_answer(request_id, answer)
        if not taken:
            self.get_logger().warning(f"answer for {request_id!r} dropped: {message}")

    def _asker(self, running: _Running) -> Ask | None:
        """The planner's ``ask``: publish the question, wait for its answer (None: do not ask)."""
        if self.config.answer_timeout_s <= 0:
            return None

        def ask(question: ClarifyingQuestion) -> str:
            slot = AnswerSlot()
            self.await_answer(running.request.id, question, slot)
            try:
                self.publish(self.question_pub, question_payload(running.request.id, question))
                answer = slot.wait(self.config.answer_timeout_s)
                if answer is None:
                    said = {
                        "confirm": '"yes" or "no"',
                        "choose": '"<objects that go, comma-separated>" or "none"',
                        "one": '"<the object>" or "none"',
                        "reading": '"<the reading meant, as listed>" or "none"',
                    }[question.kind]
                    how = f'{{"id": "{running.request.id}", "answer": {said}}}'
                    raise NoAnswerError(
                        f"no answer to {question.text!r} within {self.config.answer_timeout_s:g} s",
                        hint=f"answer on ~/answer: {how}",
                    )
                return answer
            finally:
                self.await_answer(running.request.id, None, None)

        return ask

    def _answer_error(self, request_id: str, code: str, message: str, hint: str | None = None) -> None:
        self.get_logger().warning(f"{request_id}: {code}: {message}")
        self.publish(self.result_pub, error_payload(request_id, code, message, hint))

    def _work(self) -> None:
        """The worker thread: plan queued requests one at a time until the sentinel None."""
        while (item := self._queue.get()) is not None:
            if ActionJob is not None and isinstance(item, ActionJob):
                self.actions.run(item)  # type: ignore[union-attr]
            else:
                self._plan(item)

    def _plan(self, request: PlanRequest) -> None:
        running = _Running(request, time.monotonic(), threading.Lock())
        with self._lock:
            # close() may have come between taking the request and here: it did not see this one.
            closed = self._closed
            if not closed:
                self._current = running
        if closed:
            self._answer_error(request.id, "planner_error", "the node shut down before planning it")
            return
        timer = None
        if self.config.plan_timeout_s > 0:
            timer = threading.Timer(self.config.plan_timeout_s, self._time_out, args=(running,))
            timer.daemon = True
            timer.start()
        try:
            observer = _TopicObserver(self, running)
            asker = self._asker(running)
            if asker is None:
                plan = self.planner.plan(request.request, request.scene, observer=observer)
            else:
                plan = self.planner.plan(request.request, request.scene, observer=observer, ask=asker)
            payload, summary = result_payload(request.id, plan), _summary(plan)
        except NoAnswerError as exc:  # never a guess: the request ends without a plan
            payload = error_payload(request.id, "no_answer", exc.message, exc.hint)
            summary = f"no_answer: {exc.message}"
        except ConceptBotError as exc:
            # Redacted: a backend's message may quote its URL, and anyone on the domain reads this.
            message, hint = redact_secrets(exc.message), exc.hint and redact_secrets(exc.hint)
            payload = error_payload(request.id, "planner_error", message, hint)
            summary = f"planner_error: {message}"
        except Exception as exc:  # the node stays up; the traceback goes to the log
            self.get_logger().error(f"{request.id}: planning failed:\n{traceback.format_exc()}")
            message = redact_secrets(f"unexpected error: {exc!r}")
            payload = error_payload(request.id, "planner_error", message, "see the node's log")
            summary = f"planner_error: {message}"
        finally:
            if timer is not None:
                timer.cancel()
        seconds = time.monotonic() - running.started
        # Topics are not ordered against each other: wait (briefly) until every subscriber has
        # this plan's progress, so a client holding the result has all of it queued.
        with contextlib.suppress(Exception):  # the node is being destroyed: nobody is left to wait for
            self.progress_pub.wait_for_all_acked(ACK_WAIT)
        with running.lock:
            answered, running.open = not running.open, False
            if not answered:
                self.publish(self.result_pub, payload)
        with self._lock:
            self._current = None
        where = f"{request.id} {request.request[:60]!r} in {request.scene.name}"
        if answered:
            self.get_logger().warning(f"{where}: finished after its timeout ({seconds:.1f} s); discarded")
        else:
            self.get_logger().info(f"{where}: {summary} ({seconds:.1f} s)")

    def _time_out(self, running: _Running) -> None:
        """The timer thread: answer ``timeout`` unless the plan was answered first."""
        with running.lock:
            if not running.open:
                return
            running.open = False
            limit = self.config.plan_timeout_s
            self._answer_error(
                running.request.id,
                "timeout",
                f"no plan within {limit:g} s (plan_timeout_s)",
                "raise the plan_timeout_s parameter (0: no limit) or use a faster backend; "
                "the late plan is discarded",
            )

    def close(self) -> None:
        """Stop taking requests; answer the queued ones and the running one; stop the worker.

        Each gets a ``planner_error`` result. A plan that is running cannot be interrupted (a model
        call is not); the worker thread is a daemon, so it does not keep the process alive, and the
        late plan is discarded. Safe to call twice; :meth:`destroy_node` calls it.
        """
        with self._lock:
            if self._closed:
                return
            self._closed = True
            waiting = []
            while True:
                try:
                    waiting.append(self._queue.get_nowait())
                except queue.Empty:
                    break
            self._queue.put_nowait(None)  # the queue is empty now and nothing else puts
            running = self._current
        if running is not None:
            with running.lock:
                if running.open:
                    running.open = False
                    self._answer_error(
                        running.request.id, "planner_error", "the node shut down while planning it"
                    )
        for item in waiting:
            if ActionJob is not None and isinstance(item, ActionJob):
                item.end("abort", error_result("planner_error", "the node shut down before planning it"))
            elif item is not None:
                self._answer_error(item.id, "planner_error", "the node shut down before planning it")
        self._worker.join(timeout=1.0)

    def destroy_node(self) -> None:
        """:meth:`close`, then destroy the node."""
        self.close()
        if self.actions is not None:
            self.actions.close()
        super().destroy_node()


def _summary(plan: Plan) -> str:
    """One line for the log: the plan's actions or the refusal."""
    if plan.refused:
        return f"refused: {plan.reason}"
    actions = format_actions(a for a in plan.actions if not a.is_done)
    return f"{len(actions)} action(s): {', '.join(actions) or 'nothing to do'}"


def run_node(
    settings: Settings, *, name: str = "conceptbot", defaults: NodeConfig, ros_args: tuple[str, ...] = ()
) -> None:
    """Start a node in a context of its own and spin until Ctrl-C.

    Args:
        settings: Settings (home, caches, embedder, graph).
        name: The node's name.
        defaults: The parameters' defaults (the command's flags).
        ros_args: ``--ros-args ...`` (``-p scene:=toxic-1``, remappings), or nothing.

    Raises:
        ConfigError: Bad ROS arguments or node name, or a bad parameter (see :class:`ConceptBotNode`).
        ConceptBotError: The planner's backends cannot be opened.
    """
    try:
        validate_node_name(name)  # before a node exists: rclpy warns while tearing down a bad one
    except NameValidationException as exc:
        raise ConfigError(
            f"bad node name {name!r}: {str(exc).splitlines()[0].rstrip(':')}",
            hint="use letters, digits and '_' (e.g. conceptbot_arm)",
        ) from None
    context = Context()
    try:
        # No rclpy signal handler (it shuts the context down at once): Ctrl-C and SIGTERM raise
        # KeyboardInterrupt here, and destroy_node answers the queued requests while the context is
        # still up.
        rclpy.init(
            args=["conceptbot", *ros_args], context=context, signal_handler_options=SignalHandlerOptions.NO
        )
    except RuntimeError as exc:
        raise ConfigError(f"bad ROS arguments: {exc}", hint="e.g. --ros-args -p scene:=kitchen") from None
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        node = ConceptBotNode(settings, name=name, defaults=defaults, context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        try:
            # Python runs signal handlers between bytecodes, not inside rcl's wait: wake every
            # SPIN_WAKE_S so Ctrl-C gets through.
            while context.ok():
                executor.spin_once(timeout_sec=SPIN_WAKE_S)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            node.destroy_node()
            executor.shutdown()
    finally:
        signal.signal(signal.SIGTERM, previous)
        context.try_shutdown()


SPIN_WAKE_S = 0.5
"""How often the node's spin loop returns to Python (the longest Ctrl-C waits)."""


def _interrupt(signum: int, frame: object) -> None:
    """SIGTERM (``ros2 launch``, systemd) stops the node like Ctrl-C."""
    raise KeyboardInterrupt
