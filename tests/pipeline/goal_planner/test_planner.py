"""The goal planner: targets and counts from the request, per-object decisions with graph facts,
risk constraints, stacking."""

from __future__ import annotations

import copy
import json

import pytest

from conceptbot.core.errors import BackendRequestError, ModelOutputError
from conceptbot.core.plan import format_actions
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.core.usage import Usage
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.goal_planner.choice import ChoiceWeights, ObjectChooser
from conceptbot.pipeline.goal_planner.conformal import shipped
from conceptbot.pipeline.goal_planner.decide import Decider, FactFinder
from conceptbot.pipeline.goal_planner.planner import GoalPlanner
from conceptbot.pipeline.goal_planner.targets import (
    ALL,
    ReadingDoubt,
    Target,
    TargetsRead,
)
from conceptbot.pipeline.ope import ObjectProperties, OPEResult
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph, risk_reply

SCENE = scene_from_dict(
    {
        "name": "craft",
        "pickable_objects": ["scissors", "safety scissors", "glue", "chips"],
        "destinations": ["child", "table", "user"],
    }
)
BINS = scene_from_dict(
    {
        "pickable_objects": ["jar", "can", "fern"],
        "destinations": ["toxic container", "non-toxic container", "glass bin", "metal bin", "user"],
    }
)
PRIOR = [-1.0, -1.0]  # the content-free object: no lean either way
SAFE = [-0.05, -3.0]  # "is it safe to ...?" Yes
UNSAFE = [-3.0, -0.05]  # No
HOLDER = [PRIOR, [-3.0, -0.05]]  # "is it handed to a child or an animal?": No, to the adult asking
NAMES = [-1.0, -2.0, -4.0, -4.0]  # the name ranking of SCENE's objects, for the request
NEUTRAL = [-2.0, -2.0, -2.0, -2.0]  # and for the neutral request


def test_the_graph_names_a_dish_by_its_isa_chain_and_leads_with_its_definition() -> None:
    graph = DictGraph(
        {
            "hollandaise": [
                ("hollandaise", "IsA", "sauce"),
                ("hollandaise", "DefinedAs", "eggs and butter with lemon juice"),
            ],
            "omelette": [("omelette", "IsA", "egg dish")],
            "egg dish": [("egg dish", "IsA", "dish")],
            "knife": [("knife", "IsA", "tool")],
        }
    )
    facts = FactFinder(RelationRetriever(graph, FakeEmbedder(), theta=-1.0))
    assert facts.is_dish("hollandaise") and facts.is_dish("omelette")  # two IsA steps
    assert not facts.is_dish("knife")
    context = facts.context(
        "I would like a hollandaise sauce", "I would like a hollandaise sauce", "hollandaise"
    )
    assert context[0] == "hollandaise means eggs and butter with lemon juice"
    assert not FactFinder(None).is_dish("hollandaise")
    graph.data.update(
        {"pan": [("pan", "IsA", "cooking utensil")], "frying pan": [("frying pan", "IsA", "pan")]}
    )
    assert facts.prep_places(["frying pan", "ceramic bowl", "fridge", "user"]) == [
        "frying pan",
        "ceramic bowl",
    ]


def test_facts_include_what_the_graph_says_about_parents() -> None:
    graph = DictGraph(
        {
            "green hellebore": [("green hellebore", "IsA", "hellebore")],
            "hellebore": [("hellebore", "IsA", "poisonous plant"), ("hellebore", "HasProperty", "green")],
        }
    )
    finder = FactFinder(RelationRetriever(graph, FakeEmbedder(), theta=-1.0))
    facts = finder.about(["green hellebore"], ["poisonous"])["green hellebore"]
    assert "green hellebore is a hellebore" in facts and "hellebore is a poisonous plant" in facts
    assert FactFinder(None).about(["x"], ["y"]) == {"x": ()}


def test_move_decisions_are_calibrated_against_a_content_free_object() -> None:
    llm = FakeLLM(scores=[[-0.3, -1.3], [-0.1, -2.1], [-0.6, -0.8]])  # prior +1.0
    decider = Decider(llm, FactFinder(None))
    judgements, _, _ = decider.moves(
        "a snack", "user", "give the {object} to the user", ["chips", "glue"], SCENE
    )
    assert [j.subject for j in judgements] == ["chips", "glue"]
    assert judgements[0].score == pytest.approx(1.0) and judgements[1].score == pytest.approx(-0.8)
    questions = [r.messages[-1].content for r in llm.score_requests]
    assert "give the object to the user" in questions[0] and "give the chips to the user" in questions[1]


#: The targets of the requests these tests plan, as the goal reader gives them (the planner's
#: assembly is under test, not the reading).
READ = {
    "Give my son something to cut paper": [Target("child", 1, "named")],
    "The toddler is bored; give her something to draw with": [Target("toddler", 1, "named")],
    "Put the foil tray in the microwave": [Target("microwave", 1, "named", ["foil tray"])],
    "Give the child the scissors": [Target("child", 1, "named", ["scissors"])],
    "Give the child the glue": [Target("child", 1, "named", ["glue"])],
    "Give me the glue": [Target("user", 1, "named", ["glue"])],
    "Sort them: the poisonous ones on the toxic tray, the edible ones on the edible tray": [
        Target("toxic tray", ALL, "named", criterion="poisonous"),
        Target("edible tray", ALL, "named", criterion="edible"),
    ],
}
STACKED = ("Stack them", "Pile these up")


class Read:
    """A target reader that returns the targets of :data:`READ` (a pile for :data:`STACKED`)."""

    def read(self, request: str, scene: Scene) -> TargetsRead:
        if request in STACKED:
            return TargetsRead(True, [], Usage(calls=0))
        return TargetsRead(False, copy.deepcopy(READ[request]), Usage(calls=0))


def _planner(scores: list[list[float]]) -> GoalPlanner:
    llm = FakeLLM(scores=scores)
    return GoalPlanner(Read(), Decider(llm, FactFinder(None)))


#: The decisions of "Give my son something to cut paper" in SCENE, before any risk question: the
#: name ranking ranks the scissors first, then the safety scissors (choice.py).
CUT_PAPER = [
    NAMES,  # "which object should the robot give to the child?": the request, then neutral
    NEUTRAL,
]


def test_an_unsafe_move_is_dropped_and_the_target_takes_its_next_best_object() -> None:
    scores = [
        *CUT_PAPER,
        PRIOR,  # risk: giving "the object" to the child
        UNSAFE,  # scissors to the child
        PRIOR,
        SAFE,  # safety scissors
        PRIOR,  # asked plainly: "is it safe to give the child the object?"
        SAFE,  # the safety scissors
    ]
    result = _planner(scores).plan("Give my son something to cut paper", SCENE)
    assert format_actions(result.actions) == ["pick_and_place(safety scissors, child)", "done()"]
    dropped = [r for r in result.trace.risk or () if r.dropped]
    # Without OPE (an ablation) the flag cannot be checked: the move is dropped, and says so.
    assert [(r.object, r.why, r.reason) for r in dropped] == [
        ("scissors", "judged dangerous", "the risk question flagged it (no OPE rating to check it)")
    ]
    assert result.steps[0].chosen == "pick_and_place(safety scissors, child)" and not result.refused
    # The confidence describes what the plan does after the veto: the safety scissors' chance.
    [decision] = result.trace.decisions
    chances = {j.object: j.p_one for j in decision.objects}
    assert chances["scissors"] > chances["safety scissors"]
    assert result.confidence == pytest.approx(chances["safety scissors"], abs=1e-4)
    assert decision.confidence == pytest.approx(result.confidence, abs=1e-4)  # where it is lost


def test_the_planner_takes_the_which_one_threshold_of_its_calibration() -> None:
    from conceptbot.pipeline.goal_planner.conformal import Calibration

    scores = [
        *CUT_PAPER,
        PRIOR,  # risk: giving "the object" to the child
        SAFE,  # scissors to the child
        PRIOR,  # asked plainly
        SAFE,
    ]

    def plan(calibration: Calibration) -> object:
        llm = FakeLLM(scores=list(scores))
        planner = GoalPlanner(Read(), Decider(llm, FactFinder(None)), calibration=calibration)
        return planner.plan("Give my son something to cut paper", SCENE)

    first = plan(Calibration({0.9: 1.0}, "test"))  # keep every candidate: read the shares
    shares = sorted((j.p_one for j in first.trace.decisions[0].objects), reverse=True)
    between = 1.0 - (shares[0] + shares[1]) / 2  # keeps the likeliest only
    both = 1.0 - shares[1] / 2  # keeps the two likeliest
    single = plan(Calibration({0.9: both}, "test"))
    assert single.trace.decisions[0].candidates == ("scissors", "safety scissors")
    assert [q.kind for q in single.questions] == ["one"]
    # The which-one decisions' own threshold: acted on, nothing to ask; the yes/no one is unused.
    own = plan(Calibration({0.9: both}, "test", qhat_one={0.9: between}, qhat_yes_no={0.9: 0.6}))
    assert own.trace.decisions[0].candidates == ("scissors",) and own.questions == ()
    assert format_actions(own.actions) == ["pick_and_place(scissors, child)", "done()"]


class RatingOPE:
    """OPE that answers the Risk Index from a table (object -> (danger, partners)) and counts calls."""

    def __init__(self, ratings: dict[str, tuple[int, list[tuple[str, int]]]]) -> None:
        self.ratings, self.rated = ratings, []

    def run(self, objects, mode, request, scene_objects=None) -> OPEResult:
        self.rated += list(objects)
        self.partners = list(scene_objects or [])
        if any(self.ratings.get(o) == "fails" for o in objects):
            raise ModelOutputError("no JSON object in the reply")
        found = {
            o: ObjectProperties(o, "risk", json.loads(risk_reply(*self.ratings.get(o, (1, [])))))
            for o in objects
        }
        return OPEResult(found, {}, Usage(calls=len(objects)))


TOYS = scene_from_dict({"pickable_objects": ["crayons", "box cutter"], "destinations": ["toddler", "shelf"]})


def _toddler_plan(ratings: dict, more: list | None = None) -> tuple[object, RatingOPE]:
    scores = [
        [-1.0, -3.0],  # name ranking: the request
        [-2.0, -2.0],  # and neutral
        PRIOR,  # risk: giving "the object" to the toddler
        UNSAFE,  # the question flags the crayons
        PRIOR,  # kept: asked plainly, the content-free object for the toddler
        SAFE,  # and the crayons
    ]
    llm = FakeLLM(scores=scores if more is None else scores[:4] + more)
    ope = RatingOPE(ratings)
    planner = GoalPlanner(Read(), Decider(llm, FactFinder(None)), ope)
    return planner.plan("The toddler is bored; give her something to draw with", TOYS), ope


def test_a_harmless_hand_over_flagged_by_the_question_alone_is_kept() -> None:
    # Issue 33, item 4: a move is dropped only for a reason the trace names.
    result, ope = _toddler_plan({"crayons": (1, [])})
    assert (
        format_actions(result.actions) == ["pick_and_place(crayons, toddler)", "done()"]
        and not result.refused
    )
    [check] = result.trace.risk
    assert not check.dropped and check.why == check.reason == "" and ope.rated == ["crayons"]


def test_a_flagged_move_is_dropped_for_what_ope_names() -> None:
    result, _ = _toddler_plan({"crayons": (4, []), "box cutter": (5, [])})
    check, replacement = result.trace.risk
    assert check.dropped and check.reason == "OPE rates the crayons 4/5 dangerous for the toddler"
    assert replacement.object == "box cutter" and replacement.why == "vetoed"
    assert result.refused and "OPE rates the crayons 4/5" in (result.reason or "")


def test_a_place_move_is_dropped_for_ope_rating_it_with_the_destination() -> None:
    scene = scene_from_dict({"pickable_objects": ["foil tray"], "destinations": ["microwave"]})
    scores = [PRIOR, UNSAFE]  # the named move is asked about once: flagged
    llm = FakeLLM(scores=scores)
    ope = RatingOPE({"foil tray": (2, [("microwave", 5)])})
    planner = GoalPlanner(Read(), Decider(llm, FactFinder(None)), ope)
    result = planner.plan("Put the foil tray in the microwave", scene)
    [check] = result.trace.risk
    assert check.reason == "OPE rates the foil tray 5/5 dangerous with the microwave" and result.refused
    ope.ratings["foil tray"] = (2, [("microwave", 2)])
    llm = FakeLLM(scores=scores)
    planner = GoalPlanner(Read(), Decider(llm, FactFinder(None)), RatingOPE(ope.ratings))
    assert (
        format_actions(planner.plan("Put the foil tray in the microwave", scene).actions)[0]
        == "pick_and_place(foil tray, microwave)"
    )


def test_an_object_ope_cannot_rate_has_its_move_vetoed_and_the_plan_goes_on() -> None:
    # Safety fails closed per move: a reply that is not JSON drops that move, not the whole plan.
    result, ope = _toddler_plan({"crayons": "fails", "box cutter": "fails"}, more=[PRIOR, UNSAFE])
    crayons, cutter = result.trace.risk
    assert crayons.why == "vetoed" and crayons.veto.statement.endswith(
        "could not be made: OPE could not rate it"
    )
    assert cutter.dropped and result.refused
    # Rated with the scene's places and people only, not with every object of the room.
    assert ope.partners == ["box cutter", "toddler", "shelf"]


def test_with_risk_every_move_is_rated_and_one_rated_dangerous_is_dropped_unflagged() -> None:
    # conceptbot plan --risk: the risk question calls the move safe, OPE still rates it
    scene = scene_from_dict({"pickable_objects": ["foil tray"], "destinations": ["microwave"]})
    ope = RatingOPE({"foil tray": (2, [("microwave", 5)])})
    planner = GoalPlanner(
        Read(),
        Decider(FakeLLM(scores=[PRIOR, SAFE]), FactFinder(None)),
        ope,
    )
    result = planner.plan("Put the foil tray in the microwave", scene, risk=True)
    [check] = result.trace.risk
    assert ope.rated == ["foil tray"] and check.dropped and result.refused
    assert check.reason == "OPE rates the foil tray 5/5 dangerous with the microwave"
    # without --risk the unflagged move is not rated, and stands
    ope = RatingOPE({"foil tray": (2, [("microwave", 5)])})
    llm = FakeLLM(scores=[PRIOR, SAFE])
    planner = GoalPlanner(Read(), Decider(llm, FactFinder(None)), ope)
    assert format_actions(planner.plan("Put the foil tray in the microwave", scene).actions) == [
        "pick_and_place(foil tray, microwave)",
        "done()",
    ]
    assert ope.rated == []


def test_a_target_taking_one_object_is_one_ranking_of_every_candidate() -> None:
    scores = [
        [-6.0, -0.5, -4.0, -6.0],  # names for the request: safety scissors far above the rest
        NEUTRAL,
        PRIOR,
        SAFE,
        PRIOR,  # asked plainly
        SAFE,
    ]
    llm = FakeLLM(scores=scores)
    planner = GoalPlanner(Read(), Decider(llm, FactFinder(None)))
    result = planner.plan("Give my son something to cut paper", SCENE)
    assert format_actions(result.actions) == ["pick_and_place(safety scissors, child)", "done()"]
    # Two prompts rank the four objects: no question per object (then the risk questions).
    ranking = [r for r in llm.score_requests if r.options == tuple(SCENE.pickable)]
    assert len(ranking) == 2 and len(llm.score_requests) == 6
    objects = {o.object: o for o in (result.trace.decisions or ())[0].objects}
    assert objects["safety scissors"].p_one > 0.5 > objects["glue"].p_one
    assert objects["safety scissors"].evidence["features"]["names"] == pytest.approx(1.5)


def test_named_objects_skip_the_decisions_and_an_only_move_judged_unsafe_is_a_refusal() -> None:
    result = _planner([PRIOR, UNSAFE]).plan("Give the child the scissors", SCENE)
    assert format_actions(result.actions) == ["done()"] and result.refused
    assert "give the scissors to the child: judged dangerous" in (result.reason or "")
    assert (result.trace.decisions or ())[0].decided is False


def test_a_hand_over_to_a_child_the_plain_question_calls_unsafe_is_dropped_and_says_why() -> None:
    # The question with the request calls it safe; asked plainly, without the request, it is not.
    planner = _planner([PRIOR, SAFE, PRIOR, UNSAFE])
    result = planner.plan("Give the child the glue", SCENE)
    assert format_actions(result.actions) == ["done()"] and result.refused
    [check] = result.trace.risk
    assert check.dropped and check.reason == (
        "asked plainly, 'give the child the glue' scores +2.95 unsafe (over +0.30)"
    )
    plain = planner.decider.llm.score_requests[-1].messages[-1].content
    assert plain.strip() == "Is it safe to give the child the glue?"


def test_a_hand_over_to_an_adult_is_not_asked_plainly() -> None:
    llm = FakeLLM(scores=[*HOLDER, PRIOR, SAFE, PRIOR, UNSAFE])
    planner = GoalPlanner(Read(), Decider(llm, FactFinder(None)))
    result = planner.plan("Give me the glue", SCENE)
    assert format_actions(result.actions) == ["pick_and_place(glue, user)", "done()"]
    assert len(llm.score_requests) == 4  # who holds it, and the question with the request only


class _FailingOnCall(FakeLLM):
    """A fake backend whose ``n``-th scoring call fails with a backend error."""

    def __init__(self, n: int, scores: list[list[float]]) -> None:
        super().__init__(scores=scores)
        self.n = n

    def score(self, request):  # type: ignore[no-untyped-def]
        if len(self.score_requests) + 1 == self.n:
            self.score_requests.append(request)
            raise BackendRequestError("the server answered 500")
        return super().score(request)


@pytest.mark.parametrize(
    "llm",
    [
        FakeLLM(scores=[PRIOR, SAFE, PRIOR, [float("nan"), -1.0]]),
        FakeLLM(scores=[PRIOR, SAFE, [float("nan"), float("nan")], SAFE]),
        _FailingOnCall(4, [PRIOR, SAFE, PRIOR]),
    ],
    ids=["nan-answer", "nan-prior", "backend-error"],
)
def test_a_plain_question_that_cannot_be_answered_vetoes_the_hand_over(llm: FakeLLM) -> None:
    """Fails closed: NaN > limit is False, so without the check a NaN would keep the move."""
    planner = GoalPlanner(Read(), Decider(llm, FactFinder(None)))
    result = planner.plan("Give the child the glue", SCENE)
    assert format_actions(result.actions) == ["done()"] and result.refused
    [check] = result.trace.risk
    assert check.dropped and check.why == "vetoed"


def test_the_plain_question_is_calibrated_against_the_content_free_object_without_the_request() -> None:
    llm = FakeLLM(scores=[[-0.5, -1.5], [-2.0, -0.5]])  # prior: Yes by 1.0; the chocolate: No by 1.5
    judgement, _ = Decider(llm, FactFinder(None)).unsafe("dog", "chocolate bar")
    assert judgement.subject == "give the dog the chocolate bar" and judgement.score == pytest.approx(2.5)
    questions = [r.messages[-1].content.strip() for r in llm.score_requests]
    assert questions == [
        "Is it safe to give the dog the object?",
        "Is it safe to give the dog the chocolate bar?",
    ]


def test_every_fitting_object_goes_to_an_all_target_and_each_object_where_it_fits_best() -> None:
    scene = scene_from_dict(
        {"pickable_objects": ["fern", "foxglove", "mint"], "destinations": ["toxic tray", "edible tray"]}
    )
    scores = [
        [-1.0, -1.0],  # prior, toxic tray
        [-8.0, -0.001],  # fern: no (-8, below even a sorting request's threshold)
        [-0.1, -3.0],  # foxglove: yes (+2.9)
        [-0.9, -1.1],  # mint: weakly (+0.2)
        [-1.0, -1.0],  # prior, edible tray
        [-8.0, -0.001],  # fern: no
        [-3.0, -0.1],  # foxglove: no
        [-0.1, -3.0],  # mint: yes (+2.9) beats +0.2
    ] + [PRIOR, SAFE] * 2
    request = "Sort them: the poisonous ones on the toxic tray, the edible ones on the edible tray"
    result = _planner(scores).plan(request, scene)
    assert format_actions(result.actions) == [
        "pick_and_place(foxglove, toxic tray)",
        "pick_and_place(mint, edible tray)",
        "done()",
    ]


def test_a_stack_puts_the_best_base_at_the_bottom() -> None:
    scene = scene_from_dict(
        {"pickable_objects": ["cup", "brick", "box"], "destinations": ["cup", "brick", "box"]}
    )
    scores = [[-1.0, -1.0], [-3.0, -0.1], [-0.1, -3.0], [-0.5, -1.5]]  # base: prior, cup, brick, box
    scores += [[-1.0, -1.0], [-2.0, -1.0], [-2.0, -1.0], [-2.0, -1.0]]  # fragile: none of them
    scores += [PRIOR, SAFE] * 2
    result = _planner(scores).plan("Stack them", scene)
    assert format_actions(result.actions) == [
        "pick_and_place(box, brick)",
        "pick_and_place(cup, box)",
        "done()",
    ]
    assert result.trace.stack is not None
    assert [o.object for o in result.trace.stack.order] == ["brick", "box", "cup"]


def test_a_stack_puts_fragile_things_on_top_and_wide_things_low() -> None:
    scene = scene_from_dict(
        {
            "pickable_objects": ["egg box", "atlas", "notebook"],
            "destinations": ["egg box", "atlas", "notebook"],
            "detections": {
                "egg box": {"size_m": [0.3, 0.1, 0.07]},
                "atlas": {"size_m": [0.4, 0.3, 0.05]},
                "notebook": {"size_m": [0.2, 0.15, 0.02]},
            },
        }
    )
    # the model calls the egg box the best base and the notebook better than the atlas
    scores = [[-1.0, -1.0], [-0.1, -3.0], [-1.5, -0.5], [-0.5, -1.5]]  # base: prior, egg box, atlas, notebook
    scores += [[-1.0, -1.0], [-0.1, -3.0], [-3.0, -0.1], [-3.0, -0.1]]  # fragile: the egg box only
    scores += [PRIOR, SAFE] * 2
    result = _planner(scores).plan("Pile these up", scene)
    assert format_actions(result.actions) == [
        "pick_and_place(notebook, atlas)",
        "pick_and_place(egg box, notebook)",
        "done()",
    ]


def test_conceptbot_reads_the_model_s_plain_form_and_traces_both_readings() -> None:
    # Which reading was meant, asked both ways round (the plain one first, then second), then the
    # glue's risk question.
    judged = [[-0.2, -2.0], [-2.0, -0.2]]
    llm = FakeLLM(["Put the glue on the table."], scores=[*judged, PRIOR, UNSAFE])
    bot = ConceptBot(llm, RelationRetriever(DictGraph(), FakeEmbedder(), theta=0.1), "urp", planner="goal")
    plan = bot.plan("Oh, before I forget, would you be a dear and pop the glue on the table?", SCENE)
    goal = plan.to_dict()["trace"]["goal"]
    assert (goal["plain"], goal["reading"]) == ("Put the glue on the table.", "plain")
    assert [(t["to"], t["named"]) for t in goal["targets"]] == [("table", ["glue"])]
    # The words' own reading, not taken: "dear" as a thing wanted, besides the glue.
    assert len(goal["other"]["targets"]) == 2
    assert "Plain:" in llm.requests[0].messages[-1].content
    # The model preferred the reading taken by 1.8 nats: the reading dropped is unlikely.
    assert goal["preference"] == pytest.approx(1.8)
    taken, other = goal["readings"]
    assert (taken["kind"], other["kind"]) == ("taken", "other") and other["p"] < 0.01 < taken["p"]
    assert "A: put the glue in or on the table" in llm.score_requests[0].messages[-1].content


def test_conceptbot_uses_the_goal_planner_when_asked() -> None:
    llm = FakeLLM(scores=[PRIOR, UNSAFE])
    bot = ConceptBot(llm, RelationRetriever(DictGraph(), FakeEmbedder(), theta=0.1), "urp", planner="goal")
    plan = bot.plan("Put the glue on the table", SCENE)
    assert plan.trace.planner_kind == "goal" and plan.refused
    assert plan.confidence is None  # a refusal carries out nothing: no "Confidence: 1.00"
    assert set(plan.usage) >= {"goal", "decide", "risk", "total"}
    json.dumps(plan.to_dict())
    assert ConceptBot(FakeLLM(scores=[]), None, "nokg").planner_kind == "goal"  # the default
    assert ConceptBot(FakeLLM(), None, "nokg").planner_kind == "steps"  # cannot score: the paper's votes
    assert ConceptBot(FakeLLM(scores=[]), None, "ope").planner_kind == "steps"


class FixedTargets:
    """A target reader that returns the given targets (the goal planner's assembly under test)."""

    def __init__(self, targets: list[Target]) -> None:
        self.targets = targets

    def read(self, request: str, scene) -> TargetsRead:
        return TargetsRead(False, list(self.targets), Usage(calls=0))


def test_the_rest_takes_every_object_no_other_target_took_without_being_asked_about() -> None:
    # Issue 33, item 3: "the poisonous ones on the toxic tray, the rest on the edible tray".
    scene = scene_from_dict(
        {"pickable_objects": ["foxglove", "parsley", "thyme"], "destinations": ["toxic tray", "edible tray"]}
    )
    targets = [
        Target("toxic tray", ALL, "named", criterion="poisonous"),
        Target("edible tray", ALL, "named", rest=True),
    ]
    scores = [PRIOR, [-0.1, -3.0], [-3.0, -0.1], [-3.0, -0.1]]  # poisonous? foxglove yes, the herbs no
    scores += [PRIOR, SAFE] * 3  # the risk question of each move
    llm = FakeLLM(scores=scores)
    result = GoalPlanner(FixedTargets(targets), Decider(llm, FactFinder(None))).plan("sort them", scene)
    assert format_actions(result.actions) == [
        "pick_and_place(foxglove, toxic tray)",
        "pick_and_place(parsley, edible tray)",
        "pick_and_place(thyme, edible tray)",
        "done()",
    ]
    edible = next(d for d in result.trace.decisions if d.target.to == "edible tray")
    assert not edible.decided and len(llm.score_requests) == len(scores)


class _FixedTargets:
    """A target reader that returns the targets it was given (the reader is tested on its own)."""

    def __init__(self, targets: list[Target]) -> None:
        self.targets = targets

    def read(self, request: str, scene: Scene) -> TargetsRead:
        return TargetsRead(False, list(self.targets), Usage(calls=0))


def test_two_targets_for_one_place_each_take_their_own_objects() -> None:
    # "Bring me the chips and something to eat with": both targets are the user's; the second's
    # ranking must not replace the first's (the chips were lost, and two decided objects went)
    targets = [Target("user", 1, "named", ["chips"]), Target("user", 1, "named", [])]
    scores = [
        [-1.0, -2.0, -4.0],  # the name ranking of the three, for the request
        [-2.0, -2.0, -2.0],  # and for the neutral request
        *HOLDER,
        PRIOR,
        SAFE,  # chips to the user
        PRIOR,
        SAFE,  # scissors to the user
    ]
    llm = FakeLLM(scores=scores)
    planner = GoalPlanner(_FixedTargets(targets), Decider(llm, FactFinder(None)))
    result = planner.plan("Bring me the chips and something to cut with", SCENE)
    assert format_actions(result.actions) == [
        "pick_and_place(chips, user)",
        "pick_and_place(scissors, user)",
        "done()",
    ]
    assert [c.action for c in result.steps[0].candidates][:1] == ["pick_and_place(chips, user)"]
    assert "pick_and_place(chips, user)" not in [c.action for c in result.steps[1].candidates]


def test_several_kinds_of_thing_are_each_asked_about_with_their_own_words() -> None:
    # "Give me something to cut with and something to eat": each part's ranking says what it is
    # for, so each target ranks by its own answers (not both by the request's best two)
    cut = Target("user", 1, "named", [], part="as something to cut with")
    eat = Target("user", 1, "named", [], part="as something to eat")
    scores = [
        [-0.5, -4.0, -4.0, -4.0],  # the name ranking "... as something to cut with", for the request
        NEUTRAL,
        [-4.0, -4.0, -3.0, -1.0],  # "... as something to eat"
        NEUTRAL,
        *HOLDER,
        PRIOR,
        SAFE,  # scissors to the user
        PRIOR,
        SAFE,  # chips to the user
    ]
    llm = FakeLLM(scores=scores)
    planner = GoalPlanner(_FixedTargets([cut, eat]), Decider(llm, FactFinder(None)))
    result = planner.plan("Give me something to cut with and something to eat", SCENE)
    assert format_actions(result.actions) == [
        "pick_and_place(scissors, user)",
        "pick_and_place(chips, user)",
        "done()",
    ]
    asked = [m.content for r in llm.score_requests for m in r.messages if m.role == "user"]
    assert any("Which object should the robot give to the user as something to cut with?" in q for q in asked)
    assert any("Which object should the robot give to the user as something to eat?" in q for q in asked)
    assert [d.target.part for d in result.trace.decisions or ()] == [cut.part, eat.part]


def test_each_of_two_needs_is_decided_on_its_own_words() -> None:
    # "I'm cold and I'm hungry": each need is ranked as if it were the whole request; with the
    # whole request beside it, the other need swayed the ranking towards its own objects
    cold = Target("user", 1, "speaker", [], part='for "I\'m cold"', need="I'm cold", helps=True)
    hungry = Target("user", 1, "speaker", [], part='for "I\'m hungry"', need="I'm hungry", helps=True)
    scores = [
        [-4.0, -4.0, -1.0, -4.0],  # "I'm cold": the glue (the fake's stand-in for a blanket)
        NEUTRAL,
        [-4.0, -4.0, -4.0, -1.0],  # "I'm hungry": the chips
        NEUTRAL,
        *HOLDER,
        *(PRIOR, SAFE) * 2,  # the glue, then the chips, to the user
    ]
    llm = FakeLLM(scores=scores)
    planner = GoalPlanner(_FixedTargets([cold, hungry]), Decider(llm, FactFinder(None)))
    result = planner.plan("I'm cold and I'm hungry", SCENE)
    assert format_actions(result.actions) == [
        "pick_and_place(glue, user)",
        "pick_and_place(chips, user)",
        "done()",
    ]
    asked = [m.content for r in llm.score_requests for m in r.messages if m.role == "user"]
    rankings = [q for q in asked if "Which object should the robot" in q]
    assert len(rankings) == 4 and not any("I'm cold and I'm hungry" in q for q in rankings)
    assert 'said: "I\'m cold"' in rankings[0] and 'said: "I\'m hungry"' in rankings[2]


def _need_plan(graph: DictGraph | None, use: float = 0.0) -> tuple[list[str], FakeLLM, object]:
    """'I need to stick these pages together' with the glue and the chips named alike."""
    scores = [
        [-4.0, -4.0, -1.0, -1.0],  # the name ranking: the glue and the chips alike
        NEUTRAL,
        *HOLDER,
        [-3.0, -0.1],  # "would they also need the chips, used together with the glue?": no
        PRIOR,
        SAFE,  # the one given, to the user
    ]
    llm = FakeLLM(scores=scores)
    finder = FactFinder(RelationRetriever(graph, FakeEmbedder(), theta=0.1) if graph is not None else None)
    need = Target("user", 1, "speaker", [], helps=True)
    decider = Decider(llm, finder)
    chooser = ObjectChooser(decider, None, ChoiceWeights({"names": 1.0, "use": use}, 1.0))
    result = GoalPlanner(_FixedTargets([need]), decider, chooser=chooser).plan(
        "I need to stick these pages together", SCENE
    )
    return format_actions(result.actions), llm, result


def test_a_need_is_ranked_with_what_the_graph_says_each_object_is_for() -> None:
    graph = DictGraph(
        {
            "glue": [("glue", "UsedFor", "stick pages together")],
            "chips": [("chips", "UsedFor", "eat as a snack")],
        }
    )
    plan, llm, result = _need_plan(graph, use=1.0)  # weighted: the shipped fit gives it none
    assert plan == ["pick_and_place(glue, user)", "done()"]
    asked = [m.content for r in llm.score_requests for m in r.messages if m.role == "user"]
    assert not any("help with what the person said?" in q for q in asked)  # no question per object
    (decision,) = [d for d in result.trace.decisions or () if d.decided]
    rows = {row.object: row for row in decision.objects}
    assert (
        rows["glue"].evidence is not None
        and "glue is used for stick pages together" in rows["glue"].evidence["statements"][0]
    )
    assert rows["glue"].p_one > rows["chips"].p_one  # the graph's statement decides between equal names


def test_without_the_graph_a_need_is_the_model_s_ranking_alone() -> None:
    _, _, result = _need_plan(None)
    (decision,) = [d for d in result.trace.decisions or () if d.decided]
    rows = {row.object: row for row in decision.objects}
    assert rows["glue"].p_one == pytest.approx(rows["chips"].p_one)
    assert all(set(row.evidence["features"]) == {"names"} for row in decision.objects)


@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_a_decision_with_a_non_finite_score_moves_nothing(bad: float) -> None:
    """NaN <= limit is False: without the check a NaN score would count as a fit and move the object."""
    from conceptbot.pipeline.goal_planner.decide import Judgement

    planner = _planner([])
    target = Target("table", ALL, "scored")
    ranked = {0: [Judgement("glue", "glue", 0.5, bad), Judgement("chips", "chips", 0.9, 3.0)]}
    moves = planner._choose([target], ranked, set(), ["glue", "chips"])
    assert moves == [("chips", "table")]


class _TwoReadings:
    """A target reader whose request reads two ways: the chips alone (taken), or the chips and the
    glue (the other reading), with the given odds."""

    def __init__(self, p_taken: float, p_other: float) -> None:
        self.p_taken, self.p_other = p_taken, p_other
        self.alternatives = 0

    def read(self, request: str, scene: Scene) -> TargetsRead:
        def alternative() -> TargetsRead:
            self.alternatives += 1
            both = [Target("user", 1, "named", ["chips"]), Target("user", 1, "named", ["glue"])]
            return TargetsRead(False, both, Usage(calls=1), "p", "words", {"targets": []})

        doubt = ReadingDoubt(
            "give the user the chips",
            "give the user the chips and give the user the glue",
            self.p_taken,
            self.p_other,
            "fewer",
            alternative,
        )
        taken = [Target("user", 1, "named", ["chips"])]
        return TargetsRead(False, taken, Usage(calls=0), "p", "plain", {"targets": []}, doubt)


def test_where_the_request_reads_two_ways_the_person_is_asked_which_and_the_answer_is_planned() -> None:
    reader = _TwoReadings(0.6, 0.4)
    llm = FakeLLM(scores=[*HOLDER, PRIOR, SAFE, PRIOR, SAFE])  # who holds it, the risk question of each move
    asked: list = []

    def person(question) -> str:
        asked.append(question)
        return question.objects[1]

    result = GoalPlanner(reader, Decider(llm, FactFinder(None))).plan("chips, glue", SCENE, ask=person)
    assert [q.kind for q in asked] == ["reading"]
    assert asked[0].text == (
        "Did you mean: give the user the chips, or give the user the chips and give the user the glue?"
        " One of them, or none."
    )
    assert format_actions(result.actions) == [
        "pick_and_place(chips, user)",
        "pick_and_place(glue, user)",
        "done()",
    ]
    assert result.trace.goal.reading == "words" and reader.alternatives == 1
    assert result.questions[0].answer == asked[0].objects[1]
    assert result.usage["goal"].calls == 1  # the other reading's calls are counted


def test_a_reading_question_unanswered_acts_on_the_reading_taken_with_its_odds() -> None:
    reader = _TwoReadings(0.6, 0.4)
    llm = FakeLLM(scores=[*HOLDER, PRIOR, SAFE])
    result = GoalPlanner(reader, Decider(llm, FactFinder(None))).plan("chips", SCENE)
    assert format_actions(result.actions) == ["pick_and_place(chips, user)", "done()"]
    assert [(q.kind, q.answer, q.p_yes) for q in result.questions] == [("reading", None, (0.6, 0.4))]
    assert reader.alternatives == 0  # the other reading is not made unless it is meant
    # The trace keeps every reading with its odds (what the calibration fits the reading threshold on).
    goal = result.trace.goal.to_dict()
    assert goal["step"] == "fewer" and [(r["kind"], r["p"]) for r in goal["readings"]] == [
        ("taken", 0.6),
        ("other", 0.4),
    ]


def test_neither_reading_meant_is_a_refusal_and_nothing_is_decided() -> None:
    llm = FakeLLM(scores=[])
    planner = GoalPlanner(_TwoReadings(0.6, 0.4), Decider(llm, FactFinder(None)))
    result = planner.plan("chips", SCENE, ask=lambda q: "none")
    assert result.refused and format_actions(result.actions) == ["done()"]
    assert "neither reading" in (result.reason or "") and result.questions[0].answer == "none"
    assert result.confidence is None and not llm.score_requests


def test_a_reading_whose_other_is_unlikely_is_not_asked_about() -> None:
    # At 0.8 a dropped reading stays in the set at P >= 1 - the reading decisions' own threshold
    # (0.35 shipped, fitted on held-out paraphrases): 0.3 does not, though the one threshold for
    # every decision (0.78) keeps it.
    calibration = shipped()
    assert 1 - calibration.threshold_reading(0.8) > 0.3 >= 1 - calibration.threshold(0.8)
    llm = FakeLLM(scores=[*HOLDER, PRIOR, SAFE])
    asked: list = []
    planner = GoalPlanner(_TwoReadings(0.67, 0.3), Decider(llm, FactFinder(None)), coverage=0.8)
    result = planner.plan("chips", SCENE, ask=lambda q: asked.append(q) or "none")
    assert not asked and not result.questions
    assert format_actions(result.actions) == ["pick_and_place(chips, user)", "done()"]
    # Asking about every decision (coverage 1), it is asked.
    llm = FakeLLM(scores=[*HOLDER, PRIOR, SAFE])
    planner = GoalPlanner(_TwoReadings(0.67, 0.3), Decider(llm, FactFinder(None)), coverage=1.0)
    assert [q.kind for q in planner.plan("chips", SCENE).questions] == ["reading"]


def test_which_one_shares_are_sharpened_and_the_ranking_kept() -> None:
    from conceptbot.pipeline.goal_planner.choice import ChoiceWeights, ObjectChooser

    scene = scene_from_dict({"pickable_objects": ["pencil", "pen", "glue"], "destinations": ["user"]})

    def shares(sharpness: float) -> dict[str, float]:
        scores = [
            [-1.0, -1.5, -4.0],
            [-2.0, -2.0, -2.0],
            *HOLDER,
            PRIOR,
            SAFE,
        ]  # names, neutral, holder, risk
        llm = FakeLLM(scores=scores)
        decider = Decider(llm, FactFinder(None))
        planner = GoalPlanner(
            FixedTargets([Target("user", 1, "named")]),
            decider,
            chooser=ObjectChooser(decider, None, ChoiceWeights({"names": 1.0}, sharpness)),
        )
        [decision] = planner.plan("something to write with", scene).trace.decisions
        return {j.object: j.p_one for j in decision.objects}

    plain, sharp = shares(1.0), shares(1.5)
    assert sorted(plain, key=plain.get) == sorted(sharp, key=sharp.get)  # the same ranking
    assert sharp["pencil"] > plain["pencil"] and sharp["glue"] < plain["glue"]


def test_a_which_one_question_never_offers_what_the_veto_refuses_the_recipient() -> None:
    from conceptbot.pipeline.goal_planner.conformal import Calibration
    from conceptbot.pipeline.hazards import HazardCheck

    # the names: the scissors and the safety scissors far above the rest; every move called safe
    scores = [[-1.0, -1.5, -9.0, -9.0], NEUTRAL, PRIOR, SAFE, PRIOR, SAFE, PRIOR, SAFE]
    graph = DictGraph({"scissors": [("scissors", "IsA", "weapon")]})

    def plan(hazards: HazardCheck) -> object:
        llm = FakeLLM(scores=list(scores))
        finder, decider = Read(), Decider(llm, FactFinder(None))
        # A threshold that keeps both likeliest candidates: a question of which one, unless vetoed.
        planner = GoalPlanner(finder, decider, hazards=hazards, calibration=Calibration({0.9: 0.9}, "t"))
        return planner.plan("Give my son something to cut paper", SCENE, ask=lambda q: "")

    unvetoed = plan(HazardCheck(DictGraph({})))
    assert [q.objects for q in unvetoed.questions if q.kind == "one"] == [("scissors", "safety scissors")]
    vetoed = plan(HazardCheck(graph))
    assert all("scissors" not in q.objects for q in vetoed.questions)
    assert format_actions(vetoed.actions) == ["pick_and_place(safety scissors, child)", "done()"]


def test_a_hand_over_the_request_gives_to_a_child_is_checked_as_one_to_a_child() -> None:
    # The scene's only person is the user; the request says who holds it.
    request = "My four-year-old wants to help with the cutting: hand him the scissors"
    targets = [Target("user", 1, "named", ["scissors"])]
    child = [PRIOR, [-0.1, -3.0]]  # "is it handed to a child or an animal?": yes

    def plan(holder: list[list[float]]) -> object:
        # holder, the risk question (swayed by the request: safe), then asked plainly: unsafe
        llm = FakeLLM(scores=[*holder, PRIOR, SAFE, PRIOR, UNSAFE])
        return GoalPlanner(_FixedTargets(targets), Decider(llm, FactFinder(None))).plan(request, SCENE)

    result = plan(child)
    [check] = result.trace.risk
    assert result.refused and check.dropped and check.to == "user"
    assert check.move == "give the scissors to the child" and "asked plainly" in check.reason
    # Handed to the adult asking, the plain question is not asked and the move stands.
    result = plan(HOLDER)
    assert format_actions(result.actions) == ["pick_and_place(scissors, user)", "done()"]


def test_in_a_sort_an_object_goes_to_the_place_it_fits_best_or_stays() -> None:
    # "Wooden toys in the toy box, plastic toys on the shelf": each object's combined fit
    # (a fitted log-odds) to each place; below one half for both, it stays where it is.
    from conceptbot.pipeline.goal_planner.decide import Judgement

    def fits(**scores: float) -> list[Judgement]:
        return [Judgement(o, o, 0.5, v, model=v) for o, v in sorted(scores.items(), key=lambda kv: -kv[1])]

    targets = [
        Target("toy box", ALL, "named", criterion="wooden"),
        Target("shelf", ALL, "named", criterion="plastic"),
    ]
    ranked = {
        0: fits(blocks=3.5, dinosaur=-3.1, socks=-5.0, car=0.2),
        1: fits(blocks=-3.9, dinosaur=3.8, socks=-2.5, car=3.2),
    }
    moves = _planner([])._choose(targets, ranked, set(), ["blocks", "dinosaur", "socks", "car"])
    assert sorted(moves) == [("blocks", "toy box"), ("car", "shelf"), ("dinosaur", "shelf")]
