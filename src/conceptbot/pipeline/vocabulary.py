"""Words the pipeline's code and its prompts share, each written once.

Who counts as a person, the materials OPE chooses from, and OPE's Yes/No properties with what each
means. The prompt files get them through placeholders (``$materials``, ``$properties`` in
``prompts/ope_*.txt``), so the list the model reads and the list the code checks cannot drift.
"""

from __future__ import annotations

from conceptbot.knowledge.base import TARGET_PROPERTIES

#: Words that make a destination a person: a move there hands the object over (the affordance
#: penalises a dangerous object more; the goal planner asks "give ... to ...").
PERSON_WORDS: tuple[str, ...] = ("user", "child", "person", "human", "son", "daughter", "kid", "baby")

#: How URP's user message describes the destinations that are people. Only the names scenes use
#: for them; the description says who they are, so that "user" reads as a recipient and not as one
#: more place (small models otherwise pick whichever place is listed first).
PERSON_DESCRIPTIONS: dict[str, str] = {"user": "the person asking", "child": "a child", "person": "a person"}

#: What OPE's materials mode may answer (the reply schema's enum and the prompt's list).
MATERIALS: tuple[str, ...] = (
    "glass",
    "plastic",
    "paper",
    "cardboard",
    "wax",
    "metal",
    "aluminium",
    "wood",
    "ceramic",
    "fabric",
    "food",
    "plant",
    "other",
)

#: OPE's Yes/No properties as JSON field names: the paper's target properties
#: (:data:`~conceptbot.knowledge.base.TARGET_PROPERTIES`, which relations are filtered against),
#: with ``_`` for spaces.
PROPERTY_NAMES: tuple[str, ...] = tuple(t.replace(" ", "_") for t in TARGET_PROPERTIES)

#: What each property means, as the model is told (one per name in :data:`PROPERTY_NAMES`).
PROPERTY_MEANINGS: dict[str, str] = {
    "fragile": "breaks or shatters easily when dropped or squeezed (glass, ceramic, eggs)",
    "hold_liquid": "can contain liquid without spilling (cups, bowls, bottles, jars)",
    "dangerous": "can hurt a person or damage things when handled normally (sharp, hot, toxic, flammable)",
    "safe": "harmless to hand to a person, including a child",
    "deformable": "bends or squashes under a gripper (sponge, bag of chips, paper)",
    "stable": "stands without tipping, can have things stacked on it",
    "poisonous": "toxic if eaten, touched or inhaled",
}


def property_lines() -> str:
    """The properties with their meanings, one ``- name: meaning`` line each, for the prompt.

    Raises:
        KeyError: A property has no meaning in :data:`PROPERTY_MEANINGS`.
    """
    return "\n".join(f"- {name}: {PROPERTY_MEANINGS[name]}" for name in PROPERTY_NAMES)
