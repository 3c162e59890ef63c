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


# Words of the test split's object list that any household prompt uses in their everyday sense.
EVERYDAY = {"user", "table", "can", "child", "counter", "glass", "egg"}


def test_no_prompt_example_mirrors_a_test_item() -> None:
    # Issue 33: prompt examples come from dev or general knowledge, never from the paper's 47 tasks
    # (their objects, listed in pipeline/data/paper_objects.txt, and their requests).
    import json
    import re
    from importlib import resources

    data = resources.files("conceptbot.pipeline")
    listed = data.joinpath("data", "paper_objects.txt").read_text(encoding="utf-8").splitlines()
    objects = {line.strip().lower() for line in listed if line.strip() and not line.startswith("#")}
    requests = [
        task["request"].lower()
        for path in resources.files("conceptbot.bench").joinpath("tasks").iterdir()
        if path.name.endswith(".json")
        for task in json.loads(path.read_text(encoding="utf-8"))
    ]
    for path in data.joinpath("prompts").iterdir():
        if not path.name.endswith(".txt"):
            continue
        text = " ".join(re.findall(r"[a-z0-9]+", path.read_text(encoding="utf-8").lower()))
        for name in objects - EVERYDAY:
            assert not re.search(rf"\b{re.escape(name)}\b", text), (
                f"{path.name} names the test object {name!r}"
            )
        for request in requests:
            assert " ".join(re.findall(r"[a-z0-9]+", request)) not in text, f"{path.name} quotes {request!r}"
