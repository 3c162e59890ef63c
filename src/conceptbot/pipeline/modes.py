"""Which OPE variant a request needs: plain properties, the Risk Index, or materials.

The Risk Index runs when the user asks for it (``--risk``) or when the request or the scene
mentions safety, people who need protecting, heat, sharpness, toxicity, breakage or stacking; the
materials variant runs when the request is about what things are made of. The word lists are in
``mode_triggers.json`` (data, not code); a request that matches both uses the Risk Index.
"""

from __future__ import annotations

import json
import re
from functools import cache
from importlib import resources

PROPERTIES, RISK, MATERIALS = "properties", "risk", "materials"


@cache
def _triggers() -> dict[str, list[str]]:
    text = resources.files("conceptbot.pipeline").joinpath("mode_triggers.json").read_text(encoding="utf-8")
    return json.loads(text)


def _hits(text: str, words: list[str]) -> list[str]:
    lowered = text.lower()
    return [w for w in words if re.search(rf"\b{re.escape(w)}", lowered)]


def choose_mode(request: str, object_names: list[str], force_risk: bool = False) -> tuple[str, str]:
    """``(mode, why)`` for a request and the scene's object names."""
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
