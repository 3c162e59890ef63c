"""A plan's one observer gets every stage's progress messages and events, in the order the stages
run (the web page shows them as they come; the CLI prints the messages)."""

from conceptbot.core.observe import Callbacks
from conceptbot.core.plan import format_actions
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import WITH_PLACES, DictGraph, Recorder, risk_reply, spill_scene, urp_reply
from tests.pipeline.goal_planner.test_planner import NAMES, NEUTRAL, PRIOR, SAFE, SCENE, UNSAFE


def _bot(llm: FakeLLM, config: str, planner: str) -> ConceptBot:
    graph = DictGraph(WITH_PLACES)
    return ConceptBot(llm, RelationRetriever(graph, FakeEmbedder(), theta=0.1), config, planner=planner)


def test_the_step_pipeline_reports_ope_urp_and_each_step() -> None:
    replies = [risk_reply(4, [("user", 3)]) if i == 2 else risk_reply(1) for i in range(5)]
    replies += [
        '{"keywords": ["chips", "spill"]}',
        urp_reply(["pick_and_place(chips, user)", "pick_and_place(sponge, user)"]),
    ]
    scores = [[-5.0] * 7 for _ in range(3)]
    scores[0][1], scores[1][3], scores[2][6] = 0.0, 0.0, 0.0  # chips->user, sponge->user, done
    seen = Recorder()
    plan = _bot(FakeLLM(replies, scores=scores), "conceptbot", "steps").plan(
        "Bring me chips and something to wipe a spill", spill_scene(), observer=seen
    )
    assert seen.names() == [
        "event:ope",
        "URP: keywords",
        "event:urp",
        "Planner: step 1 (7 candidates, logprob)",
        "event:step",
        "Planner: step 2 (7 candidates, logprob)",
        "event:step",
        "Planner: step 3 (7 candidates, logprob)",
        "event:step",
    ]
    # Each event is the part of the trace it announces, as `plan --json` has it.
    events = {entry[1]: entry[2] for entry in seen.seen if entry[0] == "event"}
    assert plan.trace.ope is not None and events["ope"] == plan.trace.ope.to_dict()
    assert plan.trace.urp is not None and events["urp"] == plan.trace.urp.to_dict()
    steps = [entry[2] for entry in seen.seen if entry[:2] == ("event", "step")]
    assert steps == [s.to_dict() for s in plan.steps]


def test_the_goal_planner_reports_goal_decisions_risk_and_the_steps() -> None:
    # the ranking of every object (names, then neutral); the risk of each move, then plainly
    scores = [NAMES, NEUTRAL, PRIOR, UNSAFE, PRIOR, SAFE, PRIOR, SAFE]
    seen = Recorder()
    plan = _bot(FakeLLM(scores=scores), "urp", "goal").plan(
        "Give my son something to cut paper", SCENE, observer=seen
    )
    assert format_actions(plan.actions) == ["pick_and_place(safety scissors, child)", "done()"]
    assert seen.names() == [
        "Goal: where the request sends things",
        "event:goal",
        "Decide: which objects go to the child (4 objects)",
        "event:decisions",
        "Risk: is it safe to give the scissors to the child?",
        "Risk: is it safe to give the safety scissors to the child?",
        "event:risk",
        "event:step",
    ]


def test_without_an_observer_a_plan_is_the_same() -> None:
    def plan(observer):
        scores = [NAMES, NEUTRAL, PRIOR, UNSAFE, PRIOR, SAFE, PRIOR, SAFE]
        bot = _bot(FakeLLM(scores=scores), "urp", "goal")
        return bot.plan("Give my son something to cut paper", SCENE, observer=observer).to_dict()

    messages: list[str] = []
    watched, silent = plan(Callbacks(on_progress=messages.append)), plan(None)
    for result in (watched, silent):
        result["usage"] = {}  # wall times differ
    assert watched == silent and len(messages) == 4
