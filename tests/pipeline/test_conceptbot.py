import json

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.core.plan import format_actions
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import WITH_PLACES, DictGraph, risk_reply, spill_scene, urp_reply

SCENE_OBJECTS = 5


def _bot(llm: FakeLLM, config: str = "conceptbot") -> tuple[ConceptBot, DictGraph]:
    graph = DictGraph(WITH_PLACES)
    # These tests script the paper's pipeline (OPE -> URP -> step planner).
    return ConceptBot(
        llm, RelationRetriever(graph, FakeEmbedder(), theta=0.1), config, planner="steps"
    ), graph


def test_full_pipeline_with_relations_properties_and_refusal_free_plan() -> None:
    # A knife in the scene switches OPE to the Risk Index.
    replies = [risk_reply(4, [("user", 3)]) if i == 2 else risk_reply(1) for i in range(SCENE_OBJECTS)]
    replies += [
        '{"keywords": ["chips", "spill"]}',
        # Not in the scene's action list: fails the schema, so URP retries with constrained decoding.
        urp_reply(["pick_and_place(chips, user)", "pick_and_place(banana, user)"]),
        urp_reply(["pick_and_place(chips, user)", "pick_and_place(sponge, user)"]),
    ]
    scores = [[-5.0] * 7 for _ in range(3)]
    scores[0][1], scores[1][3], scores[2][6] = 0.0, 0.0, 0.0  # chips->user, sponge->user, done
    llm = FakeLLM(replies, scores=scores)
    bot, _ = _bot(llm)
    plan = bot.plan("Bring me chips and something to wipe a spill", spill_scene())
    assert format_actions(plan.actions) == [
        "pick_and_place(chips, user)",
        "pick_and_place(sponge, user)",
        "done()",
    ]
    assert not plan.refused
    # OPE prompt carried the object's kept relations; the knife got its property.
    ope_prompt = llm.requests[2].messages[-1].content
    assert "Object: knife" in ope_prompt and "knife is dangerous" in ope_prompt
    ope = plan.trace.ope
    assert ope is not None and ope.mode == "risk"
    assert ope.objects["knife"].values["dangerous_with"] == [{"object": "user", "score": 3}]
    # URP: keywords, system message with properties and relations, invalid command rejected.
    urp = plan.trace.urp
    assert urp is not None and urp.keywords == ("chips", "spill")
    assert urp.commands == ("pick_and_place(chips, user)", "pick_and_place(sponge, user)")
    assert urp.rejected_commands == ()
    enum = json.loads(llm.requests[SCENE_OBJECTS + 1].json_schema or "{}")["properties"]["commands"]["items"][
        "enum"
    ]
    assert "pick_and_place(sponge, user)" in enum and "pick_and_place(banana, user)" not in enum
    assert "not valid JSON for the required schema" in llm.requests[SCENE_OBJECTS + 2].messages[-1].content
    system = llm.requests[SCENE_OBJECTS + 1].messages[0].content
    assert (
        "knife: danger 4/5, dangerous with user (3)" in system and "sponge is used for wipe spill" in system
    )
    # The planner saw URP's plan.
    prompt = llm.score_requests[0].prompt or ""
    assert "# suggested plan: pick_and_place(chips, user); pick_and_place(sponge, user)" in prompt
    assert "# properties: knife: danger 4/5, dangerous with user (3)" in prompt
    assert set(plan.usage) == {"ope", "urp", "planner", "total"}
    json.dumps(plan.to_dict())  # the contract is JSON-able


def test_refusal_gives_done_only_with_a_reason() -> None:
    replies = [risk_reply(1) for _ in range(SCENE_OBJECTS)]
    replies += [
        '{"keywords": ["knife", "child"]}',
        urp_reply([], refuse=True, why="a knife can hurt a child"),
    ]
    llm = FakeLLM(replies, scores=[])
    plan = _bot(llm)[0].plan("Give the knife to the baby", spill_scene())
    assert (
        plan.refused
        and format_actions(plan.actions) == ["done()"]
        and plan.reason == "a knife can hurt a child"
    )
    assert plan.steps == [] and llm.score_requests == []


def test_nokg_uses_no_graph_and_urp_config_skips_ope() -> None:
    replies = [risk_reply(1) for _ in range(SCENE_OBJECTS)] + [urp_reply(["pick_and_place(chips, user)"])]
    llm = FakeLLM(replies, scores=[[0.0] + [-9.0] * 6, [-9.0] * 6 + [0.0]])
    bot, graph = _bot(llm, "nokg")
    plan = bot.plan("chips please", spill_scene())
    assert graph.asked == [] and plan.trace.urp is not None and plan.trace.urp.keywords == ()
    assert "Relations:\n- (none)" in llm.requests[0].messages[-1].content
    llm2 = FakeLLM(
        ['{"keywords": ["chips"]}', urp_reply(["pick_and_place(chips, user)"])],
        scores=[[-9.0, 0.0] + [-9.0] * 5, [-9.0] * 6 + [0.0]],
    )
    plan2 = _bot(llm2, "urp")[0].plan("chips please", spill_scene())
    assert plan2.trace.ope is None and format_actions(plan2.actions)[0] == "pick_and_place(chips, user)"


def test_empty_request_is_rejected() -> None:
    with pytest.raises(ConfigError, match="the request is empty"):
        _bot(FakeLLM())[0].plan("   ", spill_scene())


def test_free_text_commands_are_checked_and_invalid_ones_logged(monkeypatch) -> None:
    from conceptbot.pipeline import urp

    monkeypatch.setattr(urp, "MAX_ENUM", 0)  # as for a scene too large for an enum
    replies = [risk_reply(1) for _ in range(SCENE_OBJECTS)] + [
        '{"keywords": ["chips"]}',
        urp_reply(
            ["pick_and_place(banana, user)", "pick_and_place(chips, user)", "pick_and_place(chips, user)"]
        ),
    ]
    llm = FakeLLM(replies, scores=[[-9.0, 0.0] + [-9.0] * 5, [-9.0] * 6 + [0.0]])
    plan = _bot(llm)[0].plan("chips", spill_scene())
    urp = plan.trace.urp
    assert urp is not None and urp.commands == ("pick_and_place(chips, user)",)
    assert "object not in the scene: 'banana'" in urp.rejected_commands[0]


def test_the_planner_is_told_urps_reasoning_and_its_numbered_commands() -> None:
    from conceptbot.pipeline.conceptbot import guidance_from
    from conceptbot.pipeline.urp import URPResult

    urp = URPResult(["tea"], "Tea is $hot.", ["pick_and_place(cup, user)", "done()"], False, None)
    assert guidance_from(urp) == (
        "Analysis: Tea is $hot.\nPlan from the analysis: 1. pick_and_place(cup, user); 2. done();"
    )
    nothing = URPResult([], "Nothing fits.", [], False, None)
    assert guidance_from(nothing) == "Analysis: Nothing fits.\nThe analysis found nothing to move."
