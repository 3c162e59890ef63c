import pytest

from conceptbot.pipeline import modes


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
