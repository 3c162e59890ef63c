"""The answer slot the web page and the ROS 2 node ask through."""

from __future__ import annotations

import threading

from conceptbot.core.answers import AnswerSlot


def test_the_first_answer_counts_and_a_missing_one_is_none() -> None:
    slot = AnswerSlot()
    assert slot.wait(0.01) is None  # nobody answered: no guess
    threading.Timer(0.05, slot.give, args=("no",)).start()
    assert slot.wait(5.0) == "no"
    assert slot.give("yes") is False and slot.wait(0.0) == "no"
