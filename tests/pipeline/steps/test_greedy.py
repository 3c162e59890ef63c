"""The greedy loop shared by the paper's Planner and SayCan, with scripted scorers."""

from __future__ import annotations

from conceptbot.core.plan import Feedback, PickAndPlace, format_actions
from conceptbot.core.scene import scene_from_dict
from conceptbot.core.usage import Usage
from conceptbot.pipeline.steps.greedy import LLMScores, greedy_plan

SCENE = scene_from_dict({"pickable_objects": ["apple", "pear"], "destinations": ["user"]})


def _llm(prefer: list[str]):
    """An LLM scorer preferring ``prefer[step]`` at each step (0.7 to it, the rest shared)."""

    def score(candidates, history, index):
        wanted = prefer[min(index, len(prefer) - 1)]
        rest = 0.3 / (len(candidates) - 1)
        scores = [0.7 if str(a) == wanted else rest for a in candidates]
        return LLMScores(scores, [], Usage(calls=1), "search")

    return score


def _affordance(blocked: set[str] = frozenset()):
    return lambda candidates, history: [(0.0 if str(a) in blocked else 1.0, {}) for a in candidates]


def test_steps_follow_the_product_until_done() -> None:
    prefer = ["pick_and_place(pear, user)", "pick_and_place(apple, user)", "done()"]
    result = greedy_plan(SCENE, _llm(prefer), _affordance(), "logprob")
    assert format_actions(result.actions) == [
        "pick_and_place(pear, user)",
        "pick_and_place(apple, user)",
        "done()",
    ]
    assert [s.method for s in result.steps] == ["logprob"] * 3 and result.usage.calls == 3
    assert [s.to_dict()["scoring"] for s in result.steps] == ["search"] * 3  # the backend's method, per step


def test_an_infeasible_favourite_loses_and_nothing_feasible_means_done() -> None:
    prefer = ["pick_and_place(pear, user)"]
    blocked = {"pick_and_place(pear, user)", "pick_and_place(apple, user)", "done()"}
    assert format_actions(greedy_plan(SCENE, _llm(prefer), _affordance(blocked), "vote").actions) == [
        "done()"
    ]  # every product is 0: stop rather than take an infeasible move


def test_feedback_continues_after_executed_steps_and_failed_actions_get_no_affordance() -> None:
    prefer = ["pick_and_place(pear, user)", "pick_and_place(pear, user)", "done()"]
    feedback = Feedback(
        executed=(PickAndPlace("apple", "user"),), failed=((PickAndPlace("pear", "user"), "slipped"),)
    )
    result = greedy_plan(SCENE, _llm(prefer), _affordance(), "saycan", feedback=feedback)
    actions = format_actions(result.actions)
    assert actions[0] == "pick_and_place(apple, user)" and "pick_and_place(pear, user)" not in actions
    failed = [c for c in result.steps[0].candidates if c.action == "pick_and_place(pear, user)"]
    assert failed and failed[0].affordance == 0.0 and failed[0].factors["failed"] == 0.0


def test_normalised_scores_sum_to_one_and_choose_the_same() -> None:
    prefer = ["pick_and_place(pear, user)", "done()"]
    half = lambda candidates, history: [(0.5 if "apple" in str(a) else 1.0, {}) for a in candidates]  # noqa: E731
    plain = greedy_plan(SCENE, _llm(prefer), half, "saycan")
    normal = greedy_plan(SCENE, _llm(prefer), half, "saycan", normalise=True)
    assert plain.actions == normal.actions
    assert abs(sum(c.combined for c in plain.steps[0].candidates) - 1.0) > 1e-3  # raw products
    assert abs(sum(c.combined for c in normal.steps[0].candidates) - 1.0) < 1e-9
