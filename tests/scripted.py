"""Scripted replies for the ``fake:REPLIES.json`` backend, in the order the paper pipeline asks.

The paper's pipeline (``--config paper``, and what ``conceptbot`` runs on a backend that cannot
score) asks: one OPE answer per object, URP's keywords, URP's interpretation, then ``n`` votes per
planning step. :func:`paper_replies` lists such replies (the OPE answers from
``tests.pipeline.fakes.risk_reply`` / ``properties_reply``); :data:`TINY_SCENE` is the five-name
scene the hardening reproductions use.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tests.pipeline.fakes import urp_reply

TINY_SCENE: dict[str, Any] = {
    "objects": ["apple", "knife", "bowl", "user", "child"],
    "pickable_objects": ["apple", "knife"],
    "destinations": ["bowl", "user", "child"],
}


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
    replies = [*ope, json.dumps({"keywords": list(keywords)}), urp_reply(list(commands), reasoning)]
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
