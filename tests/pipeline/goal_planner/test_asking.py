"""Where a calibrated decision is unsure, a question; an answer replaces the decision."""

from __future__ import annotations

import math

import pytest

from conceptbot.core.trace import ClarifyingQuestion, DecisionTrace
from conceptbot.pipeline.goal_planner.asking import ANSWERED, MAX_OPTIONS, clarify, reading_question
from conceptbot.pipeline.goal_planner.decide import Judgement
from conceptbot.pipeline.goal_planner.targets import ALL, ReadingDoubt, Target, TargetsRead
from conceptbot.pipeline.tracing import judgement_trace, target_trace

QHAT = 0.6956  # the shipped 0.9 threshold: an answer stays in the set at P >= 0.3044
BOWL = Target("bowl", ALL, "named", criterion="an ingredient of hollandaise")


def _combined(obj: str, p: float) -> Judgement:
    score = math.log(p / (1 - p)) if 0 < p < 1 else 0.0
    return Judgement(obj, BOWL.criterion, p, score, model=score - 0.5)


def _case(*pairs: tuple[str, float]) -> tuple[dict[int, list[Judgement]], tuple[DecisionTrace, ...]]:
    judgements = sorted((_combined(o, p) for o, p in pairs), key=lambda j: -j.score)
    decision = DecisionTrace(target_trace(BOWL), True, tuple(judgement_trace(j) for j in judgements))
    return {0: judgements}, (decision,)


def test_an_unsure_decision_is_a_question_and_the_plan_acts_on_the_likelier_answer() -> None:
    ranked, decisions = _case(("lemon", 0.55), ("butter", 0.95), ("cup", 0.1))
    found = clarify([BOWL], ranked, decisions, QHAT)
    assert found.questions == (
        ClarifyingQuestion(
            "Should I put the lemon in or on the bowl (an ingredient of hollandaise)?",
            "bowl",
            ("lemon",),
            (0.55,),
        ),
    )
    assert found.questions[0].options == ("yes", "no")
    assert found.ranked == ranked  # nobody asked: the decisions stand
    # The confidence is read from the final moves: what the plan does after the risk checks.
    assert found.confidence([("butter", "bowl"), ("lemon", "bowl")]) == pytest.approx(0.55 * 0.95 * 0.9)
    assert found.confidence([("butter", "bowl")]) == pytest.approx(0.45 * 0.95 * 0.9)  # lemon dropped
    answers = {o.object: o.answers for o in found.decisions[0].objects}
    assert answers == {"butter": ("yes",), "lemon": ("yes", "no"), "cup": ("no",)}


def test_a_confirm_answer_replaces_the_decision_and_counts_as_sure() -> None:
    ranked, decisions = _case(("lemon", 0.55), ("butter", 0.95), ("cup", 0.1))
    found = clarify([BOWL], ranked, decisions, QHAT, ask=lambda q: " No ")
    assert [q.answer for q in found.questions] == ["no"]
    assert found.ranked[0][-1].subject == "lemon" and found.ranked[0][-1].score == -ANSWERED
    assert found.confidence([("butter", "bowl")]) == pytest.approx(0.95 * 0.9)


def test_several_unsure_decisions_of_a_target_are_one_question_and_its_answer_settles_them() -> None:
    ranked, decisions = _case(("lemon", 0.55), ("butter", 0.95), ("cup", 0.4))
    asked: list[ClarifyingQuestion] = []

    def person(question: ClarifyingQuestion) -> str:
        asked.append(question)
        return "Cup"

    found = clarify([BOWL], ranked, decisions, QHAT, ask=person)
    assert (
        len(asked) == 1 and asked[0].kind == "choose" and asked[0].objects == ("lemon", "cup")
    )  # most uncertain first
    assert asked[0].text == (
        "Which of these should I put in or on the bowl (an ingredient of hollandaise): "
        "the lemon or the cup? Name them, or say all or none."
    )
    assert [q.answer for q in found.questions] == ["cup"]
    order = [(j.subject, j.score) for j in found.ranked[0]]
    assert order == [("cup", ANSWERED), ("butter", pytest.approx(math.log(19))), ("lemon", -ANSWERED)]
    assert found.confidence([("cup", "bowl"), ("butter", "bowl")]) == pytest.approx(0.95)
    answers = {o.object: o.answers for o in found.decisions[0].objects}
    assert answers["lemon"] == ("no",) and answers["cup"] == ("yes",)
    none = clarify([BOWL], ranked, decisions, QHAT, ask=lambda q: "none")
    assert none.questions[0].answer == "none" and all(
        j.score < 0 for j in none.ranked[0] if j.subject != "butter"
    )


@pytest.mark.parametrize(
    ("reply", "chosen"),
    [
        ("lemon, cup", ("lemon", "cup")),
        ("cup,lemon", ("lemon", "cup")),
        ("  LEMON ", ("lemon",)),
        ("none", ()),
        ("lemon, lemon", None),
        ("lemon, spoon", None),
        ("", None),
        ("yes", None),
        (None, None),
        (3, None),
    ],
)
def test_a_choose_question_reads_the_objects_named_and_nothing_else(reply: object, chosen: object) -> None:
    question = ClarifyingQuestion("Which ...?", "bowl", ("lemon", "cup"), (0.5, 0.4), kind="choose")
    assert question.read(reply) == chosen


def test_one_question_per_target_at_most_a_few_options_and_an_unusable_answer_leaves_it_open() -> None:
    ranked, decisions = _case(*[(f"thing {i}", 0.5 + i / 100) for i in range(MAX_OPTIONS + 2)])
    found = clarify([BOWL], ranked, decisions, QHAT, ask=lambda q: "maybe")
    assert len(found.questions) == 1
    assert found.questions[0].objects == tuple(f"thing {i}" for i in range(MAX_OPTIONS))
    assert all(q.answer is None for q in found.questions) and found.ranked == ranked


def test_a_decision_that_cannot_be_read_is_asked_about() -> None:
    ranked, decisions = _case(("lemon", 0.95))
    ranked[0].append(Judgement("egg", BOWL.criterion, math.nan, math.nan, model=0.0))
    found = clarify([BOWL], ranked, decisions, QHAT)
    assert [q.objects for q in found.questions] == [("egg",)]
    assert found.questions[0].p_yes == (0.5,)  # shown as a coin toss: JSON has no NaN
    assert found.confidence([("lemon", "bowl")]) == 0.0  # and no confidence in a plan resting on it


def _judged(obj: str, p: float, criterion: str) -> Judgement:
    score = math.log(p / (1 - p))
    return Judgement(obj, criterion, p, score, model=score)


def _sort() -> tuple[Target, Target, dict[int, list[Judgement]], tuple[DecisionTrace, ...]]:
    """A sort of a bag and a jar into a paper bin and a glass bin; the jar is unsure in both."""
    paper = Target("paper bin", ALL, "named", criterion="paper")
    glass = Target("glass bin", ALL, "named", criterion="glass")
    ranked = {
        0: [_judged("bag", 0.95, "paper"), _judged("jar", 0.45, "paper")],
        1: [_judged("jar", 0.6, "glass"), _judged("bag", 0.02, "glass")],
    }
    traces = tuple(
        DecisionTrace(target_trace(t), True, tuple(judgement_trace(j) for j in ranked[n]))
        for n, t in enumerate((paper, glass))
    )
    return paper, glass, ranked, traces


def test_a_sort_asks_per_bin_and_its_confidence_follows_where_each_object_goes() -> None:
    paper, glass, ranked, traces = _sort()
    found = clarify([paper, glass], ranked, traces, QHAT)
    assert [(q.target, q.objects) for q in found.questions] == [
        ("paper bin", ("jar",)),
        ("glass bin", ("jar",)),
    ]
    # The jar goes to the glass bin, where it fits best: the plan acts on "no" for the paper bin.
    moves = [("bag", "paper bin"), ("jar", "glass bin")]
    assert found.confidence(moves) == pytest.approx(0.95 * 0.55 * 0.6 * 0.98)
    asked = clarify(
        [paper, glass], ranked, traces, QHAT, ask=lambda q: "no" if q.target == "paper bin" else "yes"
    )
    assert [q.answer for q in asked.questions] == ["no", "yes"]
    assert asked.confidence(moves) == pytest.approx(0.95 * 0.98)


USER = Target("user", 1, "scored")


def _one_of(*pairs: tuple[str, float]) -> tuple[dict[int, list[Judgement]], tuple[DecisionTrace, ...]]:
    judgements = [Judgement(o, "user", 0.5, 0.0, scoring="logprob", p_one=p) for o, p in pairs]
    judgements.sort(key=lambda j: -(j.p_one or 0.0))
    decision = DecisionTrace(target_trace(USER), True, tuple(judgement_trace(j) for j in judgements))
    return {0: judgements}, (decision,)


def test_a_target_taking_one_object_asks_which_one_when_its_set_holds_several() -> None:
    ranked, decisions = _one_of(("coke", 0.5), ("water", 0.35), ("sponge", 0.15))
    found = clarify([USER], ranked, decisions, 0.8)  # keeps candidates at P >= 0.2
    [question] = found.questions
    assert question.kind == "one" and question.objects == ("coke", "water")
    assert (
        question.text
        == "Which one should I give to the user: the coke or the water? One of them, another, or none."
    )
    assert found.decisions[0].candidates == ("coke", "water")
    assert found.confidence([("coke", "user")]) == pytest.approx(0.5)  # acts on the likeliest
    assert found.confidence([("water", "user")]) == pytest.approx(0.35)  # the coke was vetoed
    assert found.confidence([]) == pytest.approx(1.0)  # emptied by the risk checks: theirs
    asked = clarify([USER], ranked, decisions, 0.8, ask=lambda q: "water")
    assert asked.questions[0].answer == "water"
    assert asked.confidence([("water", "user")]) == pytest.approx(1.0)
    assert (asked.ranked[0][0].subject, asked.ranked[0][0].score) == ("water", ANSWERED)
    assert all(j.score == -ANSWERED for j in asked.ranked[0][1:])  # the others, listed or not, do not go
    assert asked.decisions[0].candidates == ("water",)
    none = clarify([USER], ranked, decisions, 0.8, ask=lambda q: "none")
    assert all(j.score == -ANSWERED for j in none.ranked[0]) and none.decisions[0].candidates == ()


def test_a_sure_choice_is_not_asked_and_an_unreadable_one_is() -> None:
    ranked, decisions = _one_of(("coke", 0.9), ("water", 0.06), ("sponge", 0.04))
    sure = clarify([USER], ranked, decisions, 0.8)
    assert sure.questions == () and sure.decisions[0].candidates == ("coke",)
    assert sure.confidence([("coke", "user")]) == pytest.approx(0.9)
    broken, traces = _one_of(("coke", math.nan), ("water", math.nan))
    unreadable = clarify([USER], broken, traces, 0.8)
    assert unreadable.questions[0].objects == ("coke", "water")
    assert unreadable.confidence([("coke", "user")]) == 0.0


def test_a_which_one_decision_takes_its_own_threshold_where_the_calibration_has_one() -> None:
    # A plan-level threshold that keeps a candidate 20% likely asks; the which-one decisions' own
    # (0.5: keep what is at least half likely) acts on the coke; a yes/no decision keeps its own.
    ranked, decisions = _one_of(("coke", 0.6), ("water", 0.3), ("sponge", 0.1))
    assert [q.objects for q in clarify([USER], ranked, decisions, 0.8).questions] == [("coke", "water")]
    own = clarify([USER], ranked, decisions, 0.8, qhat_one=0.5)
    assert own.questions == () and own.decisions[0].candidates == ("coke",)
    flat = clarify([USER], *_one_of(("coke", 0.45), ("water", 0.45), ("sponge", 0.1)), 0.8, qhat_one=0.5)
    assert flat.questions[0].objects == ("coke", "water", "sponge")  # none half likely: ask


def _fits(*rows: tuple[str, float, float]) -> tuple[dict[int, list[Judgement]], tuple[DecisionTrace, ...]]:
    """A target taking one object: each candidate's (object, p_one, P(it fits))."""
    judgements = [Judgement(o, "user", p, 0.0, scoring="logprob", p_one=one) for o, one, p in rows]
    judgements.sort(key=lambda j: -(j.p_one or 0.0))
    decision = DecisionTrace(target_trace(USER), True, tuple(judgement_trace(j) for j in judgements))
    return {0: judgements}, (decision,)


def test_by_the_fits_rule_two_candidates_that_both_fit_are_no_reason_to_ask() -> None:
    # The softmax splits its mass between the water and the juice (0.5 and 0.45): asked by it.
    ranked, decisions = _fits(("water", 0.5, 0.97), ("juice", 0.45, 0.95), ("sponge", 0.05, 0.02))
    assert clarify([USER], ranked, decisions, 0.8).questions[0].objects == ("water", "juice")
    sure = clarify([USER], ranked, decisions, 0.8, rule="fits")  # "no" needs P(no) >= 0.2
    assert sure.questions == () and sure.decisions[0].candidates == ("water",)
    assert sure.confidence([("water", "user")]) == pytest.approx(0.97)  # P(the water fits)
    assert sure.confidence([("juice", "user")]) == pytest.approx(0.95)  # the water was vetoed


def test_by_the_fits_rule_an_unsure_likeliest_asks_among_those_that_may_fit() -> None:
    ranked, decisions = _fits(("coke", 0.6, 0.7), ("water", 0.3, 0.5), ("sponge", 0.1, 0.1))
    [question] = clarify([USER], ranked, decisions, 0.8, rule="fits").questions
    # The sponge's set is "no" alone (P(yes) 0.1 < 0.2): not listed, but offered as another.
    assert question.kind == "one" and question.objects == ("coke", "water") and question.others == ("sponge",)
    assert question.p_yes == (0.7, 0.5)  # P(it fits), the rule's probability
    # Only the likeliest may fit, and not surely: the two likeliest, so that there is a choice.
    alone, traces = _fits(("coke", 0.6, 0.7), ("water", 0.3, 0.1), ("sponge", 0.1, 0.1))
    assert clarify([USER], alone, traces, 0.8, rule="fits").questions[0].objects == ("coke", "water")
    asked = clarify([USER], ranked, decisions, 0.8, ask=lambda q: "water", rule="fits")
    assert asked.decisions[0].candidates == ("water",) and asked.confidence([("water", "user")]) == 1.0


def test_by_the_fits_rule_an_unreadable_probability_is_asked_about() -> None:
    ranked, decisions = _fits(("coke", 0.9, math.nan), ("water", 0.1, 0.2))
    found = clarify([USER], ranked, decisions, 0.8, rule="fits")
    assert found.questions[0].objects == ("coke", "water")
    assert found.confidence([("coke", "user")]) == 0.0  # NaN: no confidence
    broken, traces = _fits(("coke", math.nan, 0.99), ("water", math.nan, 0.99))
    assert clarify([USER], broken, traces, 0.8, rule="fits").questions[0].kind == "one"


@pytest.mark.parametrize(
    ("reply", "chosen"),
    [
        ("water", ("water",)),
        (" COKE", ("coke",)),
        ("sponge", ("sponge",)),
        ("none", ()),
        ("coke, water", None),
        ("coke, sponge", None),
        ("yes", None),
        ("spoon", None),
    ],
)
def test_a_which_one_question_takes_one_object_or_none(reply: str, chosen: object) -> None:
    question = ClarifyingQuestion(
        "Which one ...?", "user", ("coke", "water"), (0.5, 0.4), kind="one", others=("sponge",)
    )
    assert question.read(reply) == chosen


def test_a_which_one_question_offers_the_targets_other_candidates_and_takes_one() -> None:
    ranked, decisions = _one_of(("coke", 0.5), ("water", 0.35), ("sponge", 0.15))
    found = clarify([USER], ranked, decisions, 0.8)
    [question] = found.questions
    assert question.others == ("sponge",) and question.text.endswith("One of them, another, or none.")
    assert question.to_dict()["others"] == ["sponge"]
    asked = clarify([USER], ranked, decisions, 0.8, ask=lambda q: "sponge")
    assert asked.questions[0].answer == "sponge" and asked.decisions[0].candidates == ("sponge",)
    assert (asked.ranked[0][0].subject, asked.ranked[0][0].score) == ("sponge", ANSWERED)
    with pytest.raises(ValueError, match="which-one"):
        ClarifyingQuestion("Which ...?", "bowl", ("lemon",), (0.5,), kind="choose", others=("cup",))


def test_a_plan_without_a_calibrated_decision_has_no_confidence() -> None:
    named = Target("user", 1, "named", named=["coke"])
    judgements = [Judgement("coke", "user", 1.0, 10.0)]
    found = clarify([named], {0: judgements}, (DecisionTrace(target_trace(named), False),), QHAT)
    assert found.questions == () and found.confidence([("coke", "user")]) is None


def test_at_threshold_one_every_calibrated_decision_is_asked() -> None:
    ranked, decisions = _case(("lemon", 0.55), ("butter", 0.99), ("cup", 0.01))
    [question] = clarify([BOWL], ranked, decisions, 1.0).questions
    assert set(question.objects) == {"lemon", "butter", "cup"}
    ones, traces = _one_of(("coke", 0.98), ("water", 0.01), ("sponge", 0.01))
    [which] = clarify([USER], ones, traces, 1.0).questions
    assert which.kind == "one" and which.objects == ("coke", "water", "sponge")


def test_each_targets_share_of_the_confidence_is_reported_and_multiplies_to_it() -> None:
    paper, glass, ranked, traces = _sort()
    moves = [("bag", "paper bin"), ("jar", "glass bin")]
    found = clarify([paper, glass], ranked, traces, QHAT)
    assert found.factors(moves) == pytest.approx({0: 0.95 * 0.55, 1: 0.6 * 0.98})
    assert found.confidence(moves) == pytest.approx(0.95 * 0.55 * 0.6 * 0.98)
    # An answered target is sure: its share is 1.
    asked = clarify(
        [paper, glass], ranked, traces, QHAT, ask=lambda q: "no" if q.target == "paper bin" else ""
    )
    assert asked.factors(moves) == pytest.approx({0: 0.95, 1: 0.6 * 0.98})


def _doubt(p_taken: float, p_other: float, taken: str = "give the user the tea") -> ReadingDoubt:
    def alternative() -> TargetsRead:
        raise AssertionError("not made by the question")

    return ReadingDoubt(taken, "give the user the tea and the cake", p_taken, p_other, "fewer", alternative)


def test_a_reading_is_asked_about_unless_its_set_is_the_reading_taken_alone() -> None:
    floor = 1 - 0.9066  # the shipped plan-level 0.9 threshold
    question = reading_question(_doubt(0.65, 0.15), 0.9066)
    assert question is not None and question.kind == "reading"
    assert question.objects == ("give the user the tea", "give the user the tea and the cake")
    assert question.p_yes == (0.65, 0.15)
    assert reading_question(_doubt(0.66, floor - 0.01), 0.9066) is None
    assert reading_question(_doubt(0.66, 0.04), 1.0) is not None  # coverage 1: every doubt is asked
    assert reading_question(_doubt(0.05, 0.04), 0.9066) is not None  # neither likely: asked, not guessed
    same = _doubt(0.5, 0.5, taken="give the user the tea and the cake")
    assert reading_question(same, 0.9066) is None  # the person could not tell the two apart


def test_the_reading_set_keeps_the_reading_taken_and_what_is_likely_enough_never_a_guess() -> None:
    from conceptbot.core.trace import ReadingOption
    from conceptbot.pipeline.goal_planner.asking import reading_set

    taken, other = ReadingOption("tea", 0.65), ReadingOption("tea and cake", 0.15, "other")
    sampled = ReadingOption("cake", 0.4, "sampled")
    assert reading_set([taken, other, sampled], 0.62) == [taken, sampled]  # floor 0.38
    assert reading_set([taken, other, sampled], 0.9) == [taken, other, sampled]
    assert reading_set([taken, other, sampled], 0.5) == [taken]
    # The reading taken under the floor keeps the one dropped, however unlikely: ask, not guess.
    assert reading_set([ReadingOption("tea", 0.3), other], 0.62) == [ReadingOption("tea", 0.3), other]
    nan = float("nan")
    assert reading_set([taken, ReadingOption("tea and cake", nan, "other")], 0.5)[1].kind == "other"
    assert reading_set([ReadingOption("tea", nan), other], 0.5)[1] == other
    assert reading_set([taken, ReadingOption("cake", nan, "sampled")], 0.9) == [taken]  # no number, no offer
