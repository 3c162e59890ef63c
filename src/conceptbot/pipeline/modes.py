"""OPE's variants, one object each, and which one a request needs.

A mode (:class:`OPEMode`) holds everything that differs between the variants: the system prompt
(filled from :mod:`conceptbot.pipeline.vocabulary`), the per-object user message, the reply's JSON
schema, the target texts relations are filtered against, and the typed answer
(:mod:`conceptbot.pipeline.ope_answers`: summary, penalty S_prop, danger rating). They are
registered by name in :data:`MODES`; the name is what the trace shows and what OPE's cache keys hold.

* ``properties`` — Yes/No properties (fragile, hold liquid, dangerous, safe, deformable, stable,
  poisonous);
* ``risk`` — the Risk Index: danger 1-5 and DangerousWith scores 1-5 (the appendix's criteria),
  judged with the scene's other objects and the request;
* ``materials`` — what the object is made of.

To add a mode: a prompt file, an answer class, an :class:`OPEMode` (or a subclass where the mode
needs more than the object: see :class:`RiskMode`) in :data:`MODES`, and a trigger in
:func:`choose_mode`.

The Risk Index runs when the user asks for it (``--risk``) or when the request or the scene
mentions safety, people who need protecting, heat, sharpness, toxicity, breakage or stacking; the
materials variant runs when the request is about what things are made of. The word lists are in
``mode_triggers.json`` (data, not code); a request that matches both uses the Risk Index.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any

from conceptbot.knowledge.base import TARGET_PROPERTIES
from conceptbot.pipeline import prompts
from conceptbot.pipeline.ope_answers import AnswerType, Materials, OPEAnswer, RiskIndex, YesNoProperties
from conceptbot.pipeline.vocabulary import MATERIALS as MATERIAL_NAMES
from conceptbot.pipeline.vocabulary import PROPERTY_NAMES, property_lines

PROPERTIES, RISK, MATERIALS = "properties", "risk", "materials"

_YES_NO = {"type": "string", "enum": ["Yes", "No"]}
_ONE_TO_FIVE = {"type": "integer", "enum": [1, 2, 3, 4, 5]}


@dataclass(frozen=True, eq=False)
class OPEMode:
    """One OPE variant.

    Attributes:
        name: The mode's name (trace, cache keys, :func:`choose_mode`).
        prompt: The system prompt template (``prompts/<prompt>.txt``).
        user_prompt: The per-object user message template.
        schema: The reply's JSON schema.
        targets: The texts the object's relations are filtered against.
        answer: The typed answer's class; its ``from_json`` reads the reply.
        prompt_values: Values for the system prompt's placeholders.
    """

    name: str
    prompt: str
    user_prompt: str
    schema: Mapping[str, Any]
    targets: tuple[str, ...]
    answer: AnswerType
    prompt_values: Mapping[str, str] = field(default_factory=dict)

    def system_prompt(self) -> str:
        """The system message (part of OPE's cache keys: editing it never serves a stale answer)."""
        return prompts.render(self.prompt, **self.prompt_values)

    def parse(self, values: Mapping[str, Any]) -> OPEAnswer:
        """The typed answer of a JSON reply (fresh or cached)."""
        return self.answer.from_json(values)

    def context(self, scene_objects: list[str], request: str) -> str:
        """What an answer depends on besides the object, for the cache key (nothing here)."""
        return ""

    def reply_schema(self, name: str, scene_objects: list[str]) -> dict[str, Any]:
        """The reply schema for the object ``name`` (a copy: callers may change it)."""
        return json.loads(json.dumps(self.schema))

    def reply_tokens(self, scene_objects: list[str]) -> int:
        """The reply's token budget: enough for every field of the answer."""
        return 200

    def user_message(self, name: str, relations: list[str], scene_objects: list[str], request: str) -> str:
        """The user message for one object and its kept relations."""
        return prompts.fill(self.user_prompt, name=name, relations=_bullets(relations))

    def clean(self, value: dict[str, Any], name: str, scene_objects: list[str]) -> dict[str, Any]:
        """The reply as kept: the scene's name for the object (the model sometimes rewrites it)."""
        value["object"] = name
        return value


@dataclass(frozen=True, eq=False)
class RiskMode(OPEMode):
    """The Risk Index judges interactions, so it depends on the scene's other objects and the
    request: they are in the user message, in the cache key, and the reply's partners are limited
    to them."""

    def context(self, scene_objects: list[str], request: str) -> str:
        """The scene's objects and the request."""
        return json.dumps([sorted(scene_objects), request])

    def reply_schema(self, name: str, scene_objects: list[str]) -> dict[str, Any]:
        """Interaction partners limited to the scene's other objects (an enum, at most one entry
        each), so constrained decoding cannot invent objects or repeat one until the token budget
        runs out (small models do both)."""
        schema = super().reply_schema(name, scene_objects)
        others = [o for o in scene_objects if o != name]
        items = schema["properties"]["dangerous_with"]
        items["maxItems"] = len(others)
        if others:
            items["items"]["properties"]["object"] = {"type": "string", "enum": others}
        return schema

    def reply_tokens(self, scene_objects: list[str]) -> int:
        """Room for a rating of every other object (about 14 tokens each): with 200 in all, a
        20-object room's reply was cut off mid-list and the plan failed."""
        return 200 + 14 * len(scene_objects)

    def user_message(self, name: str, relations: list[str], scene_objects: list[str], request: str) -> str:
        """The object, its relations, the other objects and the request."""
        others = ", ".join(o for o in scene_objects if o != name)
        return prompts.fill(
            self.user_prompt, name=name, relations=_bullets(relations), others=others, request=request
        )

    def clean(self, value: dict[str, Any], name: str, scene_objects: list[str]) -> dict[str, Any]:
        """Also interaction scores for objects of the scene only, with the scene's spelling."""
        value = super().clean(value, name, scene_objects)
        value["dangerous_with"] = known_partners(value["dangerous_with"], scene_objects, name)
        return value


def _bullets(relations: list[str]) -> str:
    return "\n".join(f"- {r}" for r in relations) or "- (none)"


def known_partners(items: list[dict[str, Any]], objects: list[str], name: str) -> list[dict[str, Any]]:
    """Interaction scores for objects of the scene only (not ``name`` itself), with the scene's
    spelling: unconstrained backends may answer ``USER`` or an object that is not there."""
    by_lower = {o.lower(): o for o in objects}
    kept = []
    for item in items:
        other = by_lower.get(str(item["object"]).strip().lower())
        if other is not None and other != name:
            kept.append({"object": other, "score": int(item["score"])})
    return kept


MODES: dict[str, OPEMode] = {
    mode.name: mode
    for mode in (
        OPEMode(
            name=PROPERTIES,
            prompt="ope_properties",
            user_prompt="ope_user",
            schema={
                "type": "object",
                "properties": {"object": {"type": "string"}, **{p: _YES_NO for p in PROPERTY_NAMES}},
                "required": ["object", *PROPERTY_NAMES],
            },
            targets=TARGET_PROPERTIES,
            answer=YesNoProperties,
            prompt_values={"properties": property_lines()},
        ),
        RiskMode(
            name=RISK,
            prompt="ope_risk",
            user_prompt="ope_risk_user",
            schema={
                "type": "object",
                "properties": {
                    "object": {"type": "string"},
                    "dangerous": _ONE_TO_FIVE,
                    "dangerous_with": {
                        "type": "array",
                        "items": {
                            "type": "object",
                            "properties": {"object": {"type": "string"}, "score": _ONE_TO_FIVE},
                            "required": ["object", "score"],
                        },
                    },
                    "reason": {"type": "string", "maxLength": 160},
                },
                "required": ["object", "dangerous", "dangerous_with", "reason"],
            },
            targets=("dangerous", "fragile", "poisonous", "sharp", "hot", "toxic", "flammable", "safe"),
            answer=RiskIndex,
        ),
        OPEMode(
            name=MATERIALS,
            prompt="ope_materials",
            user_prompt="ope_user",
            schema={
                "type": "object",
                "properties": {
                    "object": {"type": "string"},
                    "materials": {"type": "array", "items": {"type": "string", "enum": list(MATERIAL_NAMES)}},
                    "single_material": {"type": "boolean"},
                    "reason": {"type": "string", "maxLength": 160},
                },
                "required": ["object", "materials", "single_material", "reason"],
            },
            targets=("glass", "plastic", "paper", "cardboard", "wax", "metal", "wood", "made of"),
            answer=Materials,
            prompt_values={"materials": ", ".join(MATERIAL_NAMES)},
        ),
    )
}


def get(mode: str | OPEMode) -> OPEMode:
    """The mode of a name (a mode is returned as it is).

    Raises:
        ValueError: No mode has that name.
    """
    if isinstance(mode, OPEMode):
        return mode
    try:
        return MODES[mode]
    except KeyError:
        raise ValueError(f"unknown OPE mode {mode!r}: use one of {', '.join(MODES)}") from None


@cache
def _triggers() -> dict[str, list[str]]:
    text = resources.files("conceptbot.pipeline").joinpath("mode_triggers.json").read_text(encoding="utf-8")
    return json.loads(text)


def _hits(text: str, words: list[str]) -> list[str]:
    lowered = text.lower()
    return [w for w in words if re.search(rf"\b{re.escape(w)}", lowered)]


def choose_mode(request: str, object_names: list[str], force_risk: bool = False) -> tuple[str, str]:
    """``(mode name, why)`` for a request and the scene's object names (:func:`get` gives the mode)."""
    if force_risk:
        return RISK, "requested with --risk"
    triggers = _triggers()
    risk = _hits(request, triggers["risk_request"]) + _hits(" ".join(object_names), triggers["risk_objects"])
    if risk:
        return RISK, f"safety trigger: {', '.join(sorted(set(risk))[:4])}"
    materials = _hits(request, triggers["materials_request"])
    if materials:
        return MATERIALS, f"materials trigger: {', '.join(sorted(set(materials))[:4])}"
    return PROPERTIES, "default"
