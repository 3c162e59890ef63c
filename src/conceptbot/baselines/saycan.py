"""SayCan baseline, after Google's open-source SayCan pick-and-place notebook.

Per step, every candidate option (each valid ``robot.pick_and_place(object, destination)`` in the
scene, and ``done()``) is scored by the LLM's token log-probability of the option after a few-shot
prompt (``prompts/saycan_context.txt``, then ``objects = [...]``, ``# <instruction>`` and the steps
so far). The affordance is binary, as ViLD's detections are: 1 when both the object and the
destination are detected (confidence > 0), else 0; ``done()`` has a fixed affordance of 0.2. The
combined score exp(log p) * affordance is normalised over the options and the best one is taken,
greedily, until ``done()`` or the step limit (the loop the paper's Planner uses too:
:mod:`conceptbot.pipeline.steps.greedy`). Same LLM as ConceptBot; no knowledge graph, no OPE/URP.

The scene's objects are listed in the prompt (as the notebook does): without that line ``done()``
wins the first step most of the time.
"""

from __future__ import annotations

import math
import time
from importlib import resources

from conceptbot.core.limits import check_request
from conceptbot.core.observe import SILENT, Observer
from conceptbot.core.plan import DONE, Action, Feedback, PickAndPlace, Plan
from conceptbot.core.scene import Scene
from conceptbot.core.system import Ask
from conceptbot.core.trace import PlanTrace
from conceptbot.models.llm import LLM, ScoreRequest
from conceptbot.pipeline.steps.greedy import LLMScores, greedy_plan
from conceptbot.pipeline.steps.planner import softmax

DONE_AFFORDANCE = 0.2


def _context() -> str:
    return (
        resources.files("conceptbot.baselines")
        .joinpath("prompts/saycan_context.txt")
        .read_text(encoding="utf-8")
    )


def option_text(action: Action) -> str:
    """The option as SayCan writes it."""
    return DONE if action.is_done else f"robot.{action}"


class SayCan:
    """The SayCan planner.

    Args:
        llm: An LLM that can score options (``capabilities.scoring``), e.g. the llama.cpp backend.
        max_steps: Step limit (None: pickable objects + 1, at most 12).
    """

    config = "saycan"

    def __init__(self, llm: LLM, max_steps: int | None = None) -> None:
        self.llm = llm
        self.max_steps = max_steps

    def prompt(self, request: str, scene: Scene, history: list[Action]) -> str:
        """The scoring prompt for the next step."""
        lines = [_context().rstrip("\n"), "", f"objects = [{', '.join(scene.names)}]", f"# {request.strip()}"]
        lines += [option_text(h) for h in history]
        return "\n".join(lines) + "\n"

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        feedback: Feedback | None = None,
        observer: Observer | None = None,
        ask: Ask | None = None,
    ) -> Plan:
        """Plan greedily (``risk`` and ``ask`` are ignored: SayCan has no risk assessment and no
        calibrated decision to ask about).

        With ``feedback`` the plan continues from the executed steps and failed actions are
        infeasible (affordance 0), as SayCan's affordance would report after a failed attempt.
        ``observer`` gets a progress message as each step starts and a ``step`` event as it is
        chosen.
        """
        started = time.perf_counter()
        request = check_request(request)

        def detection(candidates: list[Action]) -> list[float]:
            return [
                _detected(scene, a) if isinstance(a, PickAndPlace) else DONE_AFFORDANCE for a in candidates
            ]

        def llm_scores(candidates: list[Action], history: list[Action], index: int) -> LLMScores:
            # The affordances go along as priors: a backend that scores only the best option
            # exactly (HTTP search) then finds the best product, which is what the step takes.
            priors = tuple(math.log(a) if a > 0 else -math.inf for a in detection(candidates))
            scored = self.llm.score(
                ScoreRequest(
                    options=tuple(option_text(a) for a in candidates),
                    prompt=self.prompt(request, scene, history),
                    priors=priors,
                )
            )
            return LLMScores(softmax(list(scored.logprobs)), [], scored.usage, scored.method)

        def affordances(
            candidates: list[Action], history: list[Action]
        ) -> list[tuple[float, dict[str, float]]]:
            return [(a, {"detected": a}) for a in detection(candidates)]

        result = greedy_plan(
            scene,
            llm_scores,
            affordances,
            "saycan",
            max_steps=self.max_steps,
            feedback=feedback,
            normalise=True,
            label="SayCan",
            observer=observer if observer is not None else SILENT,
        )
        total = result.usage.with_latency(time.perf_counter() - started)
        trace = PlanTrace(config=self.config, request=request, scene=scene.name)
        return Plan(result.actions, result.steps, False, None, trace, {"planner": total, "total": total})


def _detected(scene: Scene, action: PickAndPlace) -> float:
    obj, target = scene.get(action.obj), scene.get(action.destination)
    return 1.0 if obj and target and obj.confidence > 0 and target.confidence > 0 else 0.0
