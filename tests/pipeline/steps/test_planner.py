import math

import pytest

from conceptbot.core.plan import format_actions
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline import modes
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.steps.planner import Planner, softmax
from tests.pipeline.fakes import spill_scene

# valid_actions order for the spill scene:
ORDER = [
    "pick_and_place(chips, table)",
    "pick_and_place(chips, user)",
    "pick_and_place(sponge, table)",
    "pick_and_place(sponge, user)",
    "pick_and_place(knife, table)",
    "pick_and_place(knife, user)",
    "done()",
]


def _logprobs(best: str, second: str | None = None) -> list[float]:
    return [0.0 if a == best else (-0.3 if a == second else -8.0) for a in ORDER]


def test_softmax() -> None:
    assert softmax([0.0, math.log(3.0)]) == pytest.approx([0.25, 0.75])


def test_logprob_planner_is_greedy_until_done_and_puts_history_in_the_prompt() -> None:
    llm = FakeLLM(scores=[_logprobs(ORDER[3]), _logprobs(ORDER[1]), _logprobs("done()")])
    planned = Planner(llm, method="logprob").plan(
        "wipe and chips", spill_scene(), {}, "", commands=["pick_and_place(sponge, user)"]
    )
    steps, actions = planned.steps, format_actions(planned.actions)
    assert actions == ["pick_and_place(sponge, user)", "pick_and_place(chips, user)", "done()"]
    assert [s.chosen for s in steps] == actions
    first = llm.score_requests[0]
    assert list(first.options) == [f"robot.{a}" if a != "done()" else a for a in ORDER]
    assert first.prompt is not None and first.prompt.endswith(
        "objects = [chips, sponge, knife, table, user]\n# properties: none notable\n"
        "# suggested plan: pick_and_place(sponge, user)\n# wipe and chips\n"
    )
    assert llm.score_requests[1].prompt.endswith("# wipe and chips\nrobot.pick_and_place(sponge, user)\n")


def test_affordance_can_overturn_the_llm() -> None:
    # The LLM slightly prefers handing the knife to the user, but it is dangerous to hand over.
    props = {"knife": ObjectProperties("knife", modes.PROPERTIES, {"dangerous": "Yes", "fragile": "No"})}
    llm = FakeLLM(scores=[_logprobs(ORDER[5], second=ORDER[4]), _logprobs("done()")])
    planned = Planner(llm, method="logprob").plan("knife", spill_scene(), props)
    steps, actions = planned.steps, format_actions(planned.actions)
    first = {c.action: c for c in steps[0].candidates}
    expected_knife_user = softmax(_logprobs(ORDER[5], ORDER[4]))[5] * 0.9 * 0.4
    assert first["pick_and_place(knife, user)"].combined == pytest.approx(expected_knife_user)
    assert actions[0] == "pick_and_place(knife, table)"


def test_vote_counts_valid_completions_and_logs_invalid_ones() -> None:
    replies = [
        "pick_and_place(sponge, user)",
        "pick_and_place(sponge, user)",
        "pick_and_place(banana, user)",
        "",
        "pick_and_place(chips, user)",
    ] + ["done()"] * 5
    llm = FakeLLM(replies)
    planned = Planner(llm, method="vote", n=5).plan("q", spill_scene(), {})
    steps, actions = planned.steps, format_actions(planned.actions)
    assert actions == ["pick_and_place(sponge, user)", "done()"]
    scores = {c.action: c.llm for c in steps[0].candidates}
    assert scores["pick_and_place(sponge, user)"] == pytest.approx(2 / 3)
    assert any("banana" in r for r in steps[0].rejected) and any(
        "not an action" in r for r in steps[0].rejected
    )


def test_vote_with_no_valid_output_is_asked_again_then_stops() -> None:
    llm = FakeLLM(["bring chips"] * 5 + ["pick_and_place(chips, user)"] * 5 + ["nonsense"] * 10)
    planned = Planner(llm, method="vote", n=5).plan("q", spill_scene(), {})
    steps, actions = planned.steps, format_actions(planned.actions)
    assert actions[0] == "pick_and_place(chips, user)"
    assert "Answer with exactly one of" in llm.requests[1].messages[-1].content
    assert steps[-1].chosen == "done()" and "no valid action" in steps[-1].rejected[-1]


def test_step_limit() -> None:
    llm = FakeLLM(scores=[_logprobs(a) for a in ORDER[:4]])
    planned = Planner(llm, method="logprob", max_steps=2).plan("q", spill_scene(), {})
    steps, actions = planned.steps, format_actions(planned.actions)
    assert len(steps) == 2 and actions[-1] == "done()" and len(actions) == 3


def test_auto_method_follows_the_backend() -> None:
    assert Planner(FakeLLM(scores=[])).method == "logprob"
    assert Planner(FakeLLM()).method == "vote"


def test_when_nothing_wanted_is_feasible_the_planner_stops() -> None:
    # A one-hot vote for an action already done: every combined score is 0, so done() is chosen.
    llm = FakeLLM(["pick_and_place(chips, user)"] * 10)
    planned = Planner(llm, method="vote", n=5).plan("q", spill_scene(), {})
    steps, actions = planned.steps, format_actions(planned.actions)
    assert actions == ["pick_and_place(chips, user)", "done()"] and steps[1].chosen == "done()"


def test_feedback_continues_after_executed_steps_and_rules_out_failed_actions() -> None:
    from conceptbot.core.plan import Feedback, PickAndPlace

    feedback = Feedback(
        executed=(PickAndPlace("sponge", "user"),),
        failed=((PickAndPlace("chips", "user"), "too_wide: chips is 9 cm across"),),
    )
    # The LLM still prefers the failed action; its affordance is 0, so the second choice wins.
    llm = FakeLLM(scores=[_logprobs(ORDER[1], second=ORDER[0]), _logprobs("done()")])
    planned = Planner(llm, method="logprob").plan("chips", spill_scene(), {}, feedback=feedback)
    steps, actions = planned.steps, format_actions(planned.actions)
    assert actions == ["pick_and_place(sponge, user)", "pick_and_place(chips, table)", "done()"]
    assert steps[0].index == 2
    failed = next(c for c in steps[0].candidates if c.action == ORDER[1])
    assert failed.affordance == 0.0 and failed.factors["failed"] == 0.0
    prompt = llm.score_requests[0].prompt
    assert prompt.endswith(
        "robot.pick_and_place(sponge, user)\n"
        "# failed: pick_and_place(chips, user) (too_wide: chips is 9 cm across)\n"
    )


def test_a_penalty_every_move_shares_does_not_make_the_planner_stop() -> None:
    # Every object rated dangerous 5 (S_prop 0.52 for any move): the LLM's first choice still wins
    # over done(); the paper's absolute score (relative_properties=False) stopped here.
    props = {
        name: ObjectProperties(name, modes.RISK, {"dangerous": 5, "dangerous_with": []})
        for name in ("chips", "sponge", "knife")
    }

    def plan(relative: bool) -> tuple[list, list[str]]:
        llm = FakeLLM(scores=[_logprobs(ORDER[1], second="done()"), _logprobs("done()")])
        planned = Planner(llm, method="logprob", relative_properties=relative).plan(
            "chips", spill_scene(), props
        )
        steps, actions = planned.steps, format_actions(planned.actions)
        return steps, actions

    steps, actions = plan(relative=True)
    assert actions == ["pick_and_place(chips, user)", "done()"]
    chosen = {c.action: c for c in steps[0].candidates}["pick_and_place(chips, user)"]
    assert chosen.factors["prop"] == pytest.approx(1.0) and chosen.factors["prop_abs"] == pytest.approx(0.52)
    assert plan(relative=False)[1] == ["done()"]
