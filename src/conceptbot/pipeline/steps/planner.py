"""Planner (paper III-C): greedy steps, each choosing argmax S_LLM(a) * S_aff(a) over every valid
``pick_and_place(object, destination)`` in the scene plus ``done()``.

S_LLM comes from one of two methods:

* ``logprob`` — one pass: the log-probability of each candidate as the assistant's reply, turned
  into a distribution with a softmax (needs a backend that scores, e.g. llama.cpp);
* ``vote`` — the paper's method: ``n`` completions, S_LLM(a) = share of completions choosing a.
  Completions that are not valid actions in the scene are rejected, kept in the trace, and the
  step is asked again once with a reminder; if none is valid then, the planner stops (``done()``).

``auto`` uses ``logprob`` when the backend scores every option exactly (embedded) and ``vote``
otherwise. Executed actions go into the prompt; the loop ends at ``done()`` or after ``max_steps``
(default: one move per pickable object plus one, at most 12).
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import replace

from conceptbot.core.observe import SILENT, Observer
from conceptbot.core.plan import (
    DONE,
    Action,
    Feedback,
    InvalidActionError,
    PickAndPlace,
    format_actions,
    parse_action,
    valid_actions,
)
from conceptbot.core.scene import Scene
from conceptbot.core.system import METHODS
from conceptbot.core.trace import Veto
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, ChatRequest, Message, ScoreRequest
from conceptbot.pipeline import prompts
from conceptbot.pipeline.affordance import Gripper, affordance, relative_property_scores
from conceptbot.pipeline.hazards import HazardCheck
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.steps.greedy import LLMScores, PlannerResult, greedy_plan


def softmax(logprobs: list[float]) -> list[float]:
    """Normalise log-probabilities into probabilities (numerically stable)."""
    top = max(logprobs)
    exps = [math.exp(lp - top) for lp in logprobs]
    total = sum(exps)
    return [e / total for e in exps]


class Planner:
    """Greedy LLM x affordance planner.

    Args:
        llm: The LLM (labelled ``planner``).
        method: ``auto``, ``logprob`` or ``vote``.
        n: Completions per step for ``vote`` (paper: 5).
        temperature: Sampling temperature for ``vote`` (paper: 0).
        max_steps: Step limit (None: pickable objects + 1, at most 12).
        gripper: Gripper opening for the affordance.
        relative_properties: Score S_prop relative to the step's safest move (default; see
            :mod:`conceptbot.pipeline.affordance`); False keeps the absolute penalties.
        hazards: Vetoes moves whose evidence names a hazard for the recipient
            (:mod:`conceptbot.pipeline.hazards`): a vetoed move gets S_aff 0 (factor ``veto``), so
            no score can choose it. None: OPE's ratings alone, without the graph.
    """

    def __init__(
        self,
        llm: LLM,
        method: str = "auto",
        n: int = 5,
        temperature: float = 0.0,
        max_steps: int | None = None,
        gripper: Gripper | None = None,
        relative_properties: bool = True,
        hazards: HazardCheck | None = None,
    ) -> None:
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}")
        self.llm = llm
        # auto: one-pass scoring where every option is scored exactly (embedded); the paper's vote
        # over HTTP, where 127 options would be a lettered choice (docs/http-scoring.md).
        exact = llm.capabilities.exact_scoring
        self.method = ("logprob" if exact else "vote") if method == "auto" else method
        self.n = n
        self.temperature = temperature
        self.max_steps = max_steps
        self.gripper = gripper or Gripper()
        self.relative_properties = relative_properties
        self.hazards = hazards if hazards is not None else HazardCheck()

    def messages(
        self,
        request: str,
        scene: Scene,
        properties: dict[str, ObjectProperties],
        guidance: str,
        history: list[Action],
    ) -> tuple[Message, Message]:
        """The system and user messages for one step."""
        props = "\n".join(f"- {p.summary()}" for p in properties.values())
        system = prompts.render(
            "planner_system",
            pickable=", ".join(scene.pickable),
            destinations=", ".join(scene.destinations),
            properties=prompts.fill("planner_properties", properties=props) if props else "",
        )
        user = prompts.render(
            "planner_user",
            request=request,
            guidance=guidance,
            history=", ".join(format_actions(history)) if history else "none",
        )
        return Message("system", system), Message("user", user)

    def completion_prompt(
        self,
        request: str,
        scene: Scene,
        properties: dict[str, ObjectProperties],
        commands: list[str],
        history: list[Action],
        feedback: Feedback | None = None,
    ) -> str:
        """The one-pass scoring prompt: a few-shot robot script (``prompts/planner_context.txt``) in
        which the object properties (OPE) and the suggested plan (URP) are comment lines; the
        candidates are scored as the next line. Code-trained models score this script form far
        better than a chat reply."""
        notable = [p.summary() for p in properties.values() if p.notable()]
        lines = [f"robot.{h}" for h in history] + (feedback.script_lines() if feedback is not None else [])
        plan = prompts.fill("planner_script_plan", commands="; ".join(commands)) if commands else ""
        return prompts.fill(
            "planner_script",
            examples=prompts.load("planner_context").template.rstrip("\n"),
            objects=", ".join(scene.names),
            properties="; ".join(notable) if notable else "none notable",
            suggested_plan=plan,
            request=request.strip(),
            history="".join(f"{line}\n" for line in lines),
        )

    def _llm_scores(
        self,
        candidates: list[Action],
        messages: tuple[Message, Message],
        scene: Scene,
        step: int,
        prompt: str = "",
    ) -> LLMScores:
        if self.method == "logprob":
            options = tuple(DONE if a.is_done else f"robot.{a}" for a in candidates)
            scored = self.llm.score(ScoreRequest(options=options, prompt=prompt))
            return LLMScores(softmax(list(scored.logprobs)), [], scored.usage, scored.method)
        usage = Usage(calls=0)
        rejected: list[str] = []
        votes: Counter[Action] = Counter()
        request = ChatRequest(
            messages=messages,
            n=self.n,
            temperature=self.temperature,
            max_tokens=40,
            stop=("\n",),
            seed=step * 101,
        )
        for attempt in range(2):
            response = self.llm.chat(request)
            usage = usage + response.usage
            for text in response.choices:
                try:
                    votes[parse_action(text, scene)] += 1
                except InvalidActionError as exc:
                    rejected.append(f"{text.strip()[:80]!r}: {exc}")
            if votes or attempt == 1:
                break
            reminder = Message(
                "user", prompts.fill("planner_reminder", actions="; ".join(str(a) for a in candidates))
            )
            request = ChatRequest(
                messages=(*messages, reminder),
                n=self.n,
                temperature=self.temperature,
                max_tokens=40,
                stop=("\n",),
                seed=step * 101 + 1,
            )
        if not votes:
            rejected.append("no valid action in any completion: stopping")
            return LLMScores([1.0 if a.is_done else 0.0 for a in candidates], rejected, usage, "vote")
        total = sum(votes.values())
        return LLMScores([votes.get(a, 0) / total for a in candidates], rejected, usage, "vote")

    def plan(
        self,
        request: str,
        scene: Scene,
        properties: dict[str, ObjectProperties],
        guidance: str = "",
        commands: list[str] | None = None,
        feedback: Feedback | None = None,
        observer: Observer = SILENT,
    ) -> PlannerResult:
        """Plan greedily (:func:`conceptbot.pipeline.steps.greedy.greedy_plan`): the steps, the action
        texts (ending with ``done()``) and usage.

        With ``feedback`` (from executing an earlier plan) the plan starts with the executed steps, the
        failures are shown to the LLM and failed actions get affordance 0. ``observer`` gets a
        progress message as each step starts and a ``step`` event as it is chosen.
        """
        if feedback and feedback.failed:
            guidance = "\n".join([guidance, *feedback.script_lines()]).strip()
        last: list[float] = []  # the step's S_LLM, for telling which vetoes changed the choice
        vetoed: dict[Action, Veto] = {}  # vetoes of moves the LLM ranked first at their step
        # A veto depends on the move and OPE's answers only, so each move is judged once per plan.
        vetoes = {
            a: v
            for a in valid_actions(scene, include_done=False)
            if isinstance(a, PickAndPlace)
            and (v := self.hazards.veto(a.obj, a.destination, properties)) is not None
        }

        def llm_scores(candidates: list[Action], history: list[Action], index: int) -> LLMScores:
            messages = self.messages(request, scene, properties, guidance, history)
            prompt = self.completion_prompt(request, scene, properties, commands or [], history, feedback)
            found = self._llm_scores(candidates, messages, scene, index, prompt)
            last[:] = found.scores
            return found

        def affordances(
            candidates: list[Action], history: list[Action]
        ) -> list[tuple[float, dict[str, float]]]:
            found = [affordance(a, scene, properties, history, self.gripper) for a in candidates]
            top = max(last, default=0.0)
            for i, action in enumerate(candidates):
                veto = vetoes.get(action)
                if veto is None:
                    continue
                # Vetoed before the relative scaling, so a vetoed move is never the step's best S_prop.
                found[i] = (0.0, {**found[i][1], "veto": 0.0})
                if i < len(last) and last[i] >= top > 0.0:
                    vetoed.setdefault(action, veto)
            return relative_property_scores(found) if self.relative_properties else found

        result = greedy_plan(
            scene,
            llm_scores,
            affordances,
            self.method,
            max_steps=self.max_steps,
            feedback=feedback,
            label="Planner",
            observer=observer,
        )
        return replace(result, vetoes=tuple(vetoed.values()))
