"""The observer a plan reports to, and its adapters."""

from typing import Any

from conceptbot.core.observe import SILENT, Callbacks, FanOut, Observer, Silent
from conceptbot.core.trace import GoalTrace, PlannerSummary
from tests.pipeline.fakes import Recorder

PART = PlannerSummary("decide", 1)


def test_silent_ignores_everything() -> None:
    assert isinstance(SILENT, Silent)
    assert SILENT.progress("URP: keywords") is None
    assert SILENT.event("planner", PART) is None


def test_callbacks_pass_each_half_to_its_function_and_ignore_a_missing_one() -> None:
    messages: list[str] = []
    events: list[tuple[str, dict[str, Any]]] = []
    both = Callbacks(messages.append, lambda name, data: events.append((name, data)))
    both.progress("Planner: step 1")
    both.event("planner", PART)  # the callback is an edge: it gets the part's JSON form
    assert messages == ["Planner: step 1"] and events == [("planner", {"method": "decide", "steps": 1})]
    only_progress = Callbacks(on_progress=messages.append)
    only_progress.event("planner", PART)  # no event function: ignored
    only_progress.progress("Planner: step 2")
    assert messages == ["Planner: step 1", "Planner: step 2"] and len(events) == 1
    Callbacks().progress("nobody listens")  # neither: ignored


def test_fan_out_tells_every_observer_in_order() -> None:
    first, second = Recorder(), Recorder()
    order: list[str] = []
    tracer = Callbacks(lambda message: order.append("third"))
    fan: Observer = FanOut(first, second, tracer, SILENT)
    fan.progress("Goal: where the request sends things")
    fan.event("goal", GoalTrace((), False))
    goal = ("event", "goal", {"targets": [], "stack": False})
    expected = [("progress", "Goal: where the request sends things"), goal]
    assert first.seen == expected and second.seen == expected
    assert order == ["third"]
    FanOut().progress("no observers: nothing happens")
