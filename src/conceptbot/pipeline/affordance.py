"""Affordance score (paper III-C): S_aff = S_pick * S_place * S_bbox * S_prop.

* S_pick, S_place: detection confidences of the object and the destination (1.0 when unknown).
* S_bbox: the object's grasp width (the narrower horizontal side of ``size_m``, or of the pixel box
  at ``PX_PER_M``) against the gripper opening: 1 up to 75% of the opening, falling linearly to 0.5
  at the full opening; wider objects can only be grasped by a rim or edge: 0.5 * opening / width,
  never below 0.1. Unknown size: 1.
* S_prop: penalties from OPE, by the mode's answer
  (:meth:`~conceptbot.pipeline.ope_answers.OPEAnswer.penalty`). Yes/No properties are fixed:
  fragile x0.8, dangerous x0.7 (x0.4 when handed to a person). Risk scores are scaled: danger d ->
  x(1 - 0.12 (d - 1)); an interaction score s between the object and the destination ->
  x(1 - 0.2 (s - 1)). Materials: none.
* An action already executed scores 0 (the object is already there); ``done()`` scores 1.

S_prop ranks the candidates of a step against each other (:func:`relative_property_scores`): each
candidate's S_prop is divided by the best S_prop among the step's open moves, so the safest way to
go on scores 1. The paper's property score penalises objects; a penalty that every move shares
says nothing about which move to make, and against ``done()`` (which moves nothing and keeps 1) it
only made the planner stop: with a small model that rates every block of a stacking task, or every
move into a "special container", as dangerous, the plan was ``done()`` alone although the LLM gave
the right first step 0.98. Relative scores keep every preference between moves (safety scissors
over scissors for a child, a ceramic over a plastic bowl in the microwave) and leave refusing to
URP, whose job it is.
"""

from __future__ import annotations

from dataclasses import dataclass

from conceptbot.core.plan import Action, PickAndPlace
from conceptbot.core.scene import Scene, SceneObject
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.vocabulary import PERSON_WORDS

PX_PER_M = 800.0  # a 640x480 camera about 1 m above the table sees roughly 0.8 m across
Scored = list[tuple[float, dict[str, float]]]  # (S_aff, factors) per candidate


@dataclass(frozen=True)
class Gripper:
    """The gripper's maximum opening in metres (Franka Panda: 0.08)."""

    opening_m: float = 0.08


def grasp_width(obj: SceneObject) -> float | None:
    """The object's narrower horizontal side in metres, or None when unknown."""
    if obj.size_m is not None:
        return min(obj.size_m[0], obj.size_m[1])
    if obj.bbox_px is not None:
        x0, y0, x1, y1 = obj.bbox_px
        return min(abs(x1 - x0), abs(y1 - y0)) / PX_PER_M
    return None


def bbox_score(obj: SceneObject, gripper: Gripper) -> float:
    """S_bbox (see the module docstring)."""
    width = grasp_width(obj)
    if width is None or width <= 0:
        return 1.0
    ratio = width / gripper.opening_m
    if ratio <= 0.75:
        return 1.0
    if ratio <= 1.0:
        return 1.0 - 2.0 * (ratio - 0.75)
    return max(0.1, 0.5 / ratio)


def property_score(obj: str, target: str, properties: dict[str, ObjectProperties]) -> float:
    """S_prop (see the module docstring)."""
    found = properties.get(obj)
    if found is None:
        return 1.0
    partner = properties.get(target)
    to_person = target.lower() in PERSON_WORDS
    score = found.answer.penalty(obj, target, to_person, partner.answer if partner is not None else None)
    return max(score, 0.0)


def affordance(
    action: Action,
    scene: Scene,
    properties: dict[str, ObjectProperties],
    executed: list[Action],
    gripper: Gripper | None = None,
) -> tuple[float, dict[str, float]]:
    """``(S_aff, factors)`` for one candidate action."""
    if not isinstance(action, PickAndPlace):
        return 1.0, {}
    if action in executed:
        return 0.0, {"repeat": 0.0}
    obj, target = scene.get(action.obj), scene.get(action.destination)
    assert obj is not None and target is not None
    factors = {
        "pick": obj.confidence,
        "place": target.confidence,
        "bbox": bbox_score(obj, gripper or Gripper()),
        "prop": property_score(action.obj, action.destination, properties),
    }
    total = 1.0
    for value in factors.values():
        total *= value
    return total, factors


def relative_property_scores(scored: Scored) -> Scored:
    """Rescale S_prop over one step's candidates (see the module docstring).

    ``scored`` holds ``(S_aff, factors)`` per candidate as :func:`affordance` returns them. Each
    open move (S_aff above 0) gets ``prop`` divided by the highest ``prop`` among the open moves and
    its S_aff recomputed; its absolute value is kept as ``prop_abs`` where they differ. ``done()``,
    repeats and failed moves are unchanged.
    """
    open_props = [f["prop"] for total, f in scored if total > 0 and "prop" in f]
    best = max(open_props, default=0.0)
    if best <= 0.0 or best >= 1.0:
        return scored
    out = []
    for total, factors in scored:
        if total <= 0 or "prop" not in factors:
            out.append((total, factors))
            continue
        rescaled = {**factors, "prop": factors["prop"] / best, "prop_abs": factors["prop"]}
        product = 1.0
        for name, value in rescaled.items():
            if name != "prop_abs":
                product *= value
        out.append((product, rescaled))
    return out
