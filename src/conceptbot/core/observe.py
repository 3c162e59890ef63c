"""One observer for a plan: the messages as work starts and the results as modules finish.

A planner's stages report two things while a plan is made (LLM calls take seconds, a plan tens of
them): a short progress message as each piece of work starts ("URP: keywords", "Planner: step 2
...") and an event with JSON-able data as each module finishes (``goal``, ``decisions``, ``risk``,
``ope``, ``urp``, ``step``). The caller attaches one :class:`Observer` to
:meth:`~conceptbot.core.system.PlannerSystem.plan`; every stage reports to that object, and none of
them knows who listens (the CLI prints the messages, the web page streams both to the browser).
An event carries a typed part of the trace (an :class:`EventPart`); whoever listens turns it into
JSON at their own edge (``part.to_dict()``: the web page, the ROS 2 node, :class:`Callbacks` for
code that wants plain data)::

    planner.plan(request, scene, observer=Callbacks(on_progress=print))
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

EventSink = Callable[[str, dict[str, Any]], None]
"""``(event name, JSON-able data) -> None``."""


class EventPart(Protocol):
    """What an event carries: a typed part of the trace that knows its JSON form."""

    def to_dict(self) -> dict[str, Any]:
        """The part as ``conceptbot plan --json`` shows it."""
        ...


class Observer(Protocol):
    """What a plan reports to while it is made. Any object with these two methods will do."""

    def progress(self, message: str) -> None:
        """A piece of work starts.

        Args:
            message: One short line for a person ("Decide: which objects go to the user (4 objects)").
        """
        ...

    def event(self, name: str, part: EventPart) -> None:
        """A module finished; ``part`` is its part of the trace.

        Args:
            name: ``goal``, ``decisions``, ``risk`` (the goal planner), ``ope``, ``urp`` (the paper's
                pipeline) or ``step`` (one per plan step, both planners and SayCan).
            part: The typed part (``GoalTrace``, ``DecisionsEvent``, ``RiskEvent``, ``OPETrace``,
                ``URPTrace``, ``Step``); ``part.to_dict()`` is the same part as it appears in
                ``conceptbot plan --json``.
        """
        ...


class Silent:
    """An observer that ignores everything (the default when nobody listens)."""

    def progress(self, message: str) -> None:
        """Ignore the message."""

    def event(self, name: str, part: EventPart) -> None:
        """Ignore the event."""


SILENT: Observer = Silent()
"""The observer stages use when none is given."""


@dataclass(frozen=True)
class Callbacks:
    """An observer from two plain functions; either may be None (that half is ignored).

    Attributes:
        on_progress: Called with each progress message.
        on_event: Called with each event's name and its part as JSON-able data (``part.to_dict()``).
    """

    on_progress: Callable[[str], None] | None = None
    on_event: EventSink | None = None

    def progress(self, message: str) -> None:
        """Pass the message to ``on_progress``."""
        if self.on_progress is not None:
            self.on_progress(message)

    def event(self, name: str, part: EventPart) -> None:
        """Pass the event to ``on_event``, its part as data."""
        if self.on_event is not None:
            self.on_event(name, part.to_dict())


class FanOut:
    """An observer that passes everything to several observers, in the order given.

    Args:
        observers: Who gets each message and event.
    """

    def __init__(self, *observers: Observer) -> None:
        self.observers = observers

    def progress(self, message: str) -> None:
        """Pass the message to each observer."""
        for observer in self.observers:
            observer.progress(message)

    def event(self, name: str, part: EventPart) -> None:
        """Pass the event to each observer."""
        for observer in self.observers:
            observer.event(name, part)
