"""Scripted replies for the ``fake:REPLIES.json`` backend, in the order the paper pipeline asks.

The paper's pipeline (``--config paper``, and what ``conceptbot`` runs on a backend that cannot
score) asks: one OPE answer per object, URP's keywords, URP's interpretation, then ``n`` votes per
planning step. :func:`paper_replies` writes such a file; :data:`TINY_SCENE` is the five-name scene
the hardening reproductions use.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

TINY_SCENE: dict[str, Any] = {
    "objects": ["apple", "knife", "bowl", "user", "child"],
    "pickable_objects": ["apple", "knife"],
    "destinations": ["bowl", "user", "child"],
}
PROPERTIES_NONE = {
    "object": "x",
    "fragile": "No",
    "hold_liquid": "No",
    "dangerous": "No",
    "safe": "Yes",
    "deformable": "No",
    "stable": "Yes",
    "poisonous": "No",
}


def risk_answer(danger: int = 1, dangerous_with: Sequence[tuple[str, int]] = (), reason: str = "r") -> str:
    """One OPE answer in the Risk Index mode."""
    partners = [{"object": o, "score": s} for o, s in dangerous_with]
    return json.dumps({"object": "x", "dangerous": danger, "dangerous_with": partners, "reason": reason})


def paper_replies(
    ope: Sequence[str],
    commands: Sequence[str],
    votes: Sequence[str],
    *,
    keywords: Sequence[str] = ("apple",),
    reasoning: str = "because",
    n: int = 5,
) -> list[str]:
    """Replies for one run of the paper pipeline.

    Args:
        ope: One OPE answer (JSON text) per scene object, in the scene's order.
        commands: URP's commands.
        votes: One completion per planning step, repeated ``n`` times (the paper's five votes).
        keywords: URP's keywords.
        reasoning: URP's reasoning text.
        n: Votes per step.
    """
    urp = {"reasoning": reasoning, "refuse": False, "refusal_reason": "", "commands": list(commands)}
    replies = [*ope, json.dumps({"keywords": list(keywords)}), json.dumps(urp)]
    for vote in votes:
        replies += [vote] * n
    return replies


def write_replies(path: Path, replies: Sequence[str]) -> str:
    """Write ``replies`` for the fake backend; returns the ``fake:PATH`` spec."""
    path.write_text(json.dumps(list(replies)), encoding="utf-8")
    return f"fake:{path}"


def write_scene(path: Path, scene: dict[str, Any] | None = None) -> Path:
    """Write a scene file (default :data:`TINY_SCENE`)."""
    path.write_text(json.dumps(scene or TINY_SCENE), encoding="utf-8")
    return path
