"""The shared words have one home each and agree with each other."""

from conceptbot.knowledge.base import TARGET_PROPERTIES
from conceptbot.pipeline.vocabulary import (
    PERSON_DESCRIPTIONS,
    PERSON_WORDS,
    PROPERTY_MEANINGS,
    PROPERTY_NAMES,
    property_lines,
)


def test_every_property_has_a_meaning_and_is_a_target_property() -> None:
    assert list(PROPERTY_MEANINGS) == list(PROPERTY_NAMES)
    assert [n.replace("_", " ") for n in PROPERTY_NAMES] == list(TARGET_PROPERTIES)
    assert property_lines().splitlines()[1] == (
        "- hold_liquid: can contain liquid without spilling (cups, bowls, bottles, jars)"
    )


def test_described_people_are_people() -> None:
    # The two lists differ on purpose: every word that makes a destination a person, and the
    # descriptions URP gives the destinations scenes name that way.
    assert set(PERSON_DESCRIPTIONS) <= set(PERSON_WORDS)
