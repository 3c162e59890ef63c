"""Prompt templates: whole prompts are rendered stripped; messages are filled exactly."""

from __future__ import annotations

import pytest

from conceptbot.household.planner import PROMPTS as HOUSEHOLD
from conceptbot.pipeline import prompts


def test_a_message_is_filled_exactly_less_the_files_last_newline() -> None:
    # Values keep their own spaces (the LLM caches are keyed by the exact text).
    assert prompts.fill("urp_keywords_user", request=" I'm hungry ") == "Request:  I'm hungry "
    # A file that ends with an empty line makes a message that ends with a newline.
    assert (
        prompts.fill("urp_properties", properties="- egg: fragile") == "Object properties:\n- egg: fragile\n"
    )
    assert (
        prompts.fill("planner_properties", properties="- egg: fragile")
        == "Object properties:\n- egg: fragile"
    )
    assert prompts.fill("urp_state", name="cup", state="is full") == "\nState: cup is full."
    user = prompts.fill(
        "household_user", HOUSEHOLD, room="kitchen", objects="Apple, Mug", knowledge="", instruction="Go"
    )
    assert user == "Objects in the scene (kitchen): Apple, Mug.\nInstruction: Go"


def test_a_missing_placeholder_raises() -> None:
    with pytest.raises(KeyError, match="request"):
        prompts.fill("urp_keywords_user")
    with pytest.raises(KeyError, match="properties"):
        prompts.render("ope_properties")
