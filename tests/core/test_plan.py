import ast
import re
from pathlib import Path

import pytest

import conceptbot
from conceptbot.core.plan import (
    HOUSEHOLD_ACTIONS,
    Done,
    InvalidActionError,
    PickAndPlace,
    Plan,
    check_action,
    format_action,
    format_actions,
    parse_action,
    read_action,
    read_actions,
    valid_actions,
)
from tests.pipeline.fakes import spill_scene


def test_parse_maps_to_the_scene_spelling() -> None:
    scene = spill_scene()
    assert parse_action("1. pick_and_place( Sponge , USER )", scene) == PickAndPlace("sponge", "user")
    assert parse_action("done()", scene).is_done
    assert (
        str(parse_action("I choose pick_and_place(chips, table).", scene)) == "pick_and_place(chips, table)"
    )


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("pick_and_place(banana, user)", "object not in the scene"),
        ("pick_and_place(chips, fridge)", "destination not in the scene"),
        ("pick_and_place(table, user)", "cannot be picked"),
        ("pick_and_place(chips, knife)", "is not a destination"),
        ("", "not an action"),
        ("bring the chips", "not an action"),
    ],
)
def test_invalid_actions_are_rejected_with_a_reason(text: str, reason: str) -> None:
    with pytest.raises(InvalidActionError, match=reason):
        parse_action(text, spill_scene())


def test_self_placement_is_invalid() -> None:
    from conceptbot.core.scene import scene_from_dict

    scene = scene_from_dict(
        {"objects": ["block", "box"], "pickable_objects": ["block", "box"], "destinations": ["block", "box"]}
    )
    with pytest.raises(InvalidActionError, match="on itself"):
        parse_action("pick_and_place(block, block)", scene)
    assert [str(a) for a in valid_actions(scene)] == [
        "pick_and_place(block, box)",
        "pick_and_place(box, block)",
        "done()",
    ]


def test_valid_actions_cover_every_pair_plus_done() -> None:
    actions = valid_actions(spill_scene())
    assert len(actions) == 3 * 2 + 1 and actions[-1].is_done


def test_a_plan_built_by_hand_has_an_empty_trace_and_the_schema_ships_with_the_package() -> None:
    from conceptbot.core.plan import plan_schema

    data = Plan([Done()]).to_dict()
    assert data == {
        "plan": ["done()"],
        "steps": [],
        "refused": False,
        "reason": None,
        "trace": {},
        "usage": {},
        "confidence": None,
        "questions": [],
    }
    schema = plan_schema()
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["required"] == ["plan", "steps", "refused", "reason", "trace", "usage"]
    schema["required"].clear()  # each call is a fresh copy: a caller's edit does not leak
    assert plan_schema()["required"]


def test_actions_round_trip_through_their_one_text_form() -> None:
    scene = spill_scene()
    for action in valid_actions(scene):
        text = format_action(action)
        assert read_action(text) == action and parse_action(text, scene) == action and str(action) == text
    plan = (PickAndPlace("chips", "user"), PickAndPlace("sponge", "user"), Done())
    assert read_actions(format_actions(plan)) == plan
    assert format_actions(plan) == ["pick_and_place(chips, user)", "pick_and_place(sponge, user)", "done()"]
    # unchecked reading keeps the names as written; checking maps them to the scene's spelling
    assert read_action("pick_and_place( Sponge , USER )") == PickAndPlace("Sponge", "USER")
    assert check_action(PickAndPlace("Sponge", "USER"), scene) == PickAndPlace("sponge", "user")
    with pytest.raises(InvalidActionError, match="not an action"):
        read_action("bring the chips")
    with pytest.raises(InvalidActionError, match="object not in the scene"):
        check_action(PickAndPlace("banana", "user"), scene)


def test_a_plan_holds_typed_actions_only() -> None:
    plan = Plan([PickAndPlace("chips", "user"), Done()])
    assert plan.actions == (PickAndPlace("chips", "user"), Done()) and plan.to_dict()["plan"] == [
        "pick_and_place(chips, user)",
        "done()",
    ]
    with pytest.raises(TypeError, match="PickAndPlace, Done or HouseholdAction"):
        Plan(["pick_and_place(chips, user)", "done()"])  # type: ignore[list-item]


def _package_sources() -> list[tuple[str, ast.Module]]:
    root = Path(conceptbot.__file__).parent
    return [
        (path.relative_to(root).as_posix(), ast.parse(path.read_text(encoding="utf-8")))
        for path in sorted(root.rglob("*.py"))
    ]


_HOUSEHOLD_STEP = re.compile(rf"^({'|'.join(HOUSEHOLD_ACTIONS)})( \{{\}}){{1,2}}$")


def _builds_action_text(node: ast.AST) -> bool:
    """An f-string that is a tabletop action ("pick_and_place({o}, {d})") or a whole household step
    ("find {obj}", "fillLiquid {obj} {liquid}"), or a bare "done()"."""
    if isinstance(node, ast.Constant):
        return node.value == "done()"
    if not isinstance(node, ast.JoinedStr):
        return False
    template = "".join(str(v.value) if isinstance(v, ast.Constant) else "{}" for v in node.values)
    return "pick_and_place(" in template or bool(_HOUSEHOLD_STEP.match(template))


def test_only_core_plan_writes_action_text() -> None:
    """No module but ``core/plan.py`` builds an action's text, of either world: every other one
    passes actions and formats them with ``format_action(s)``."""
    found = [
        f"{name}:{node.lineno}"
        for name, tree in _package_sources()
        if name != "core/plan.py"
        for node in ast.walk(tree)
        if _builds_action_text(node)
    ]
    assert found == []
    assert _builds_action_text(ast.parse('f"find {obj}"').body[0].value)  # the check sees one
    assert not _builds_action_text(ast.parse('f"put on {obj} instead"').body[0].value)


# Where action text arrives from outside, and so is parsed: nowhere else.
TEXT_EDGES = {
    "pipeline/urp.py": "URP's LLM reply (the robot script)",
    "pipeline/steps/planner.py": "the step planner's LLM completions (votes)",
    "household/planner.py": "the household planning call's JSON reply",
    "cli/sim_cmd.py": "a user's plan file",
    "bench/grading.py": "a task file's reference plans",
    "bench/safeagentbench/dataset.py": "SafeAgentBench's reference plans",
}
PARSERS = {"parse_action", "read_action", "read_actions", "parse_household_action", "parse_household_actions"}


def _called(node: ast.Call) -> str | None:
    return getattr(node.func, "id", getattr(node.func, "attr", None))


def test_action_text_is_parsed_only_where_it_arrives_from_outside() -> None:
    callers = {
        name
        for name, tree in _package_sources()
        if name != "core/plan.py"
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and getattr(node.func, "id", getattr(node.func, "attr", None)) in PARSERS
    }
    assert callers == set(TEXT_EDGES)
