"""One greedy loop for the step-by-step planners: the paper's Planner and the SayCan baseline.

Per step every candidate (each valid ``pick_and_place(object, destination)`` and ``done()``) gets
an LLM score and an affordance from pluggable scorers; the step is the argmax of their product,
until ``done()`` or the step limit. What differs between the planners is only the scorers: SayCan
scores a few-shot robot script and has a binary detection affordance; the paper's Planner scores
(or votes on) a prompt with OPE's properties and URP's plan, and its affordance has the gripper,
box and property factors.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from conceptbot.core.observe import SILENT, Observer
from conceptbot.core.plan import Action, CandidateScore, Done, Feedback, Step, valid_actions
from conceptbot.core.scene import Scene
from conceptbot.core.trace import Veto
from conceptbot.core.usage import Usage

TOP_K = 8  # candidates kept in the trace per step, besides done()


@dataclass(frozen=True)
class LLMScores:
    """The LLM's scores of one step's candidates.

    Attributes:
        scores: S_LLM per candidate (a distribution: softmax of log-probabilities, or vote shares).
        rejected: Completions that were not valid actions (voting), for the trace.
        usage: Tokens and time of the step's LLM calls.
        scoring: How the backend scored them (``logprob``, ``search``, ... or ``vote``: the
            :class:`conceptbot.models.llm.ScoreResponse` method).
    """

    scores: list[float]
    rejected: list[str]
    usage: Usage
    scoring: str = ""


@dataclass(frozen=True)
class PlannerResult:
    """What a step-by-step planner produced.

    Attributes:
        steps: Per step, the chosen action and the best candidates' scores.
        actions: The actions, ending with ``Done()``.
        usage: Tokens, calls and wall time of the planning.
        vetoes: Moves the LLM ranked first that were vetoed (:mod:`conceptbot.pipeline.hazards`).
    """

    steps: list[Step]
    actions: list[Action]
    usage: Usage
    vetoes: tuple[Veto, ...] = ()


LLMScorer = Callable[[list[Action], list[Action], int], LLMScores]
"""``(candidates, history, step index) -> LLMScores``."""
AffordanceScorer = Callable[[list[Action], list[Action]], list[tuple[float, dict[str, float]]]]
"""``(candidates, history) -> [(S_aff, factors)]`` per candidate."""


def step_limit(scene: Scene, max_steps: int | None) -> int:
    """The default step limit: one move per pickable object plus ``done()``, at most 12."""
    return max_steps or min(len(scene.pickable) + 1, 12)


def greedy_plan(
    scene: Scene,
    llm_scores: LLMScorer,
    affordances: AffordanceScorer,
    method: str,
    *,
    max_steps: int | None = None,
    feedback: Feedback | None = None,
    normalise: bool = False,
    label: str = "Planner",
    observer: Observer = SILENT,
) -> PlannerResult:
    """Plan greedily: the steps, the actions (ending with ``Done()``) and usage.

    Args:
        scene: Where the candidates come from.
        llm_scores, affordances: The scorers.
        method: Recorded in each step ("logprob", "vote", "saycan").
        max_steps: Step limit (None: :func:`step_limit`).
        feedback: From executing an earlier plan: the plan continues after its executed steps and
            its failed actions get affordance 0.
        normalise: Show the combined scores normalised over the step's candidates (SayCan's
            notebook does); the choice is the same either way.
        label: Names the planner in progress messages.
        observer: Gets a progress message before each step and a ``step`` event after it.
    """
    started = time.perf_counter()
    usage = Usage(calls=0)
    candidates = valid_actions(scene)
    limit = step_limit(scene, max_steps)
    history: list[Action] = list(feedback.executed) if feedback else []
    failed = feedback.failed_actions if feedback else set()
    steps: list[Step] = []
    for index in range(len(history), max(limit, len(history) + 1)):
        observer.progress(f"{label}: step {index + 1} ({len(candidates)} candidates, {method})")
        found = llm_scores(candidates, history, index)
        usage = usage + found.usage
        affs = [
            (0.0, {**factors, "failed": 0.0}) if action in failed else (s_aff, factors)
            for action, (s_aff, factors) in zip(candidates, affordances(candidates, history), strict=True)
        ]
        products = [s_llm * s_aff for s_llm, (s_aff, _) in zip(found.scores, affs, strict=True)]
        total = (sum(products) or 1.0) if normalise else 1.0
        scored = [
            CandidateScore(str(action), s_llm, s_aff, product / total, factors)
            for action, s_llm, (s_aff, factors), product in zip(
                candidates, found.scores, affs, products, strict=True
            )
        ]
        done = next(i for i, a in enumerate(candidates) if a.is_done)
        best = max(range(len(scored)), key=lambda i: scored[i].combined)  # first of equals: deterministic
        if scored[best].combined <= 0.0:
            # Nothing the LLM wants is feasible (e.g. a one-hot vote for a repeat): stop.
            best = done
        order = sorted(range(len(scored)), key=lambda i: -scored[i].combined)
        shown = [scored[i] for i in order[:TOP_K]] + [scored[i] for i in order[TOP_K:] if i == done]
        chosen = scored[best].action
        steps.append(Step(index + 1, chosen, tuple(shown), tuple(found.rejected), method, found.scoring))
        observer.event("step", steps[-1])
        if candidates[best].is_done:
            break
        history.append(candidates[best])
    return PlannerResult(steps, [*history, Done()], usage.with_latency(time.perf_counter() - started))
