import hashlib

import pytest

from conceptbot.pipeline import modes
from conceptbot.pipeline.vocabulary import MATERIALS, PROPERTY_MEANINGS, PROPERTY_NAMES


@pytest.mark.parametrize(
    ("request_text", "objects", "mode"),
    [
        ("Give my son scissors to cut paper.", ["scissors"], modes.RISK),
        ("Heat my food in the microwave.", ["soup bowl", "microwave oven"], modes.RISK),
        (
            "Put items made exclusively of paper into the bin designated for them.",
            ["journal"],
            modes.MATERIALS,
        ),
        ("I would like a hollandaise sauce.", ["egg", "butter"], modes.PROPERTIES),
        ("Bring me an apple.", ["apple", "knife"], modes.RISK),  # a knife in the scene
    ],
)
def test_mode_triggers(request_text: str, objects: list[str], mode: str) -> None:
    assert modes.choose_mode(request_text, objects)[0] == mode


def test_forced_risk() -> None:
    assert modes.choose_mode("Bring me an apple", ["apple"], force_risk=True) == (
        modes.RISK,
        "requested with --risk",
    )


# The system prompts are part of OPE's cache keys and of the LLM response cache: a change to one
# (its file, or a constant it is filled from) makes every cached answer stale and moves the
# benchmarks. Update a hash only for a deliberate prompt change (issue 33 replaced the risk and
# materials examples that mirrored test items).
PROMPT_SHA256 = {
    modes.PROPERTIES: "75c8f8c622d9bb1c3258a61d09205d4e6e74a2688bccdc10634da386524710ab",
    modes.RISK: "8cad876b6cf1e2e87152523602054dc43c0be9f915feb4d7eb686a1954b6a2e2",
    modes.MATERIALS: "e427967f163b9d9f135d61d24fce48a8c9b076c3e817ae3ca55a6132dbf4a4dd",
}


def test_each_mode_is_registered_once_by_its_name() -> None:
    assert list(modes.MODES) == [modes.PROPERTIES, modes.RISK, modes.MATERIALS]
    assert all(modes.get(name).name == name for name in modes.MODES)
    risk = modes.MODES[modes.RISK]
    assert modes.get(risk) is risk
    with pytest.raises(ValueError, match="use one of properties, risk, materials"):
        modes.get("standard")


@pytest.mark.parametrize("name", list(PROMPT_SHA256))
def test_system_prompts_are_unchanged(name: str) -> None:
    text = modes.get(name).system_prompt()
    assert "$" not in text and text.endswith("\n")
    assert hashlib.sha256(text.encode()).hexdigest() == PROMPT_SHA256[name]


def test_prompts_are_filled_from_the_constants() -> None:
    properties = modes.get(modes.PROPERTIES).system_prompt()
    for name in PROPERTY_NAMES:
        assert f"\n- {name}: {PROPERTY_MEANINGS[name]}\n" in properties
    assert "- hold_liquid: can contain liquid without spilling (cups, bowls, bottles, jars)" in properties
    materials = modes.get(modes.MATERIALS).system_prompt()
    assert f"Materials to choose from: {', '.join(MATERIALS)}.\n" in materials
    assert "glass, plastic, paper, cardboard, wax, metal, aluminium, wood, ceramic" in materials
    enum = modes.get(modes.MATERIALS).reply_schema("cup", ["cup"])["properties"]["materials"]["items"]["enum"]
    assert enum == list(MATERIALS)
    schema = modes.get(modes.PROPERTIES).reply_schema("cup", ["cup"])
    assert schema["required"] == ["object", *PROPERTY_NAMES]
    assert "1 - Not dangerous" in modes.get(modes.RISK).system_prompt()


def test_user_messages_per_mode() -> None:
    plain = modes.get(modes.PROPERTIES).user_message("knife", ["knife is sharp"], ["knife", "user"], "x")
    assert plain == "Object: knife\nRelations:\n- knife is sharp\n"
    assert (
        modes.get(modes.MATERIALS).user_message("cup", [], ["cup"], "x")
        == "Object: cup\nRelations:\n- (none)\n"
    )
    risk = modes.get(modes.RISK).user_message("knife", [], ["knife", "user", "child"], " give me it ")
    assert risk == (
        "Object: knife\nRelations:\n- (none)\n"
        "Other objects in the scene: user, child\nUser request:  give me it \n"
    )
    # Only the Risk Index depends on the scene and the request (cache key) and limits partners.
    assert modes.get(modes.PROPERTIES).context(["a", "b"], "r") == ""
    assert modes.get(modes.RISK).context(["b", "a"], "r") == '[["a", "b"], "r"]'
    partners = modes.get(modes.RISK).reply_schema("knife", ["knife", "user"])["properties"]["dangerous_with"]
    assert partners["maxItems"] == 1 and partners["items"]["properties"]["object"]["enum"] == ["user"]


def test_the_risk_reply_has_room_for_a_rating_of_every_partner() -> None:
    # With a fixed 200 tokens a 20-object room's reply was cut off mid-list: no JSON, no plan.
    partners = [f"object {i}" for i in range(20)]
    assert modes.get(modes.RISK).reply_tokens(partners) >= 200 + 12 * len(partners)
    assert modes.get(modes.PROPERTIES).reply_tokens(partners) == 200
