import pytest

from conceptbot.core.plan import Action, InvalidActionError, parse_action, valid_actions
from tests.pipeline.fakes import spill_scene


def test_parse_maps_to_the_scene_spelling() -> None:
    scene = spill_scene()
    assert parse_action("1. pick_and_place( Sponge , USER )", scene) == Action("sponge", "user")
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
    from conceptbot.core.plan import DONE, Plan, plan_schema

    data = Plan([DONE]).to_dict()
    assert data == {
        "plan": ["done()"],
        "steps": [],
        "refused": False,
        "reason": None,
        "trace": {},
        "usage": {},
    }
    schema = plan_schema()
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["required"] == ["plan", "steps", "refused", "reason", "trace", "usage"]
    schema["required"].clear()  # each call is a fresh copy: a caller's edit does not leak
    assert plan_schema()["required"]
