from __future__ import annotations

from conceptbot.pipeline.goal import Goal, GoalTarget, same_goal
from conceptbot.pipeline.goal.compare import words


def _sort(first: str, second: str) -> Goal:
    return Goal(
        targets=(
            GoalTarget("shoe box", "criterion", (), first),
            GoalTarget("biscuit tin", "criterion", (), second),
        )
    )


def test_criteria_compare_by_their_content_words() -> None:
    assert words("the broken ones") == words("broken") == words("ones that are broken") == words("BROKEN")
    assert len(words("the broken ones")) == 1
    assert words("something to write with") == ("write",)
    assert words("things made entirely of glass") == ("entirely", "glass")


def test_words_that_carry_meaning_are_kept() -> None:
    # spaCy lists these as stop words; dropping them would make "the whole ones" match anything
    assert words("the whole ones") == ("whole",)
    assert words("not broken") == ("not", *words("broken"))
    assert words("made of several materials") == ("several", "material")


def test_targets_match_in_any_order_and_named_objects_as_sets() -> None:
    gold = Goal(targets=(GoalTarget("box", "named", ("a", "b"), "", 2), GoalTarget("tin", "remainder")))
    read = Goal(targets=(GoalTarget("tin", "remainder"), GoalTarget("box", "named", ("b", "a"), "", 2)))
    assert same_goal(read, gold).ok
    assert same_goal(_sort("broken", "the whole ones"), _sort("the broken ones", "ones that are whole")).ok


def test_each_difference_fails_the_match_with_a_reason() -> None:
    gold = _sort("broken", "whole")
    assert not same_goal(_sort("broken", ""), gold).ok  # a criterion lost
    swapped = same_goal(_sort("whole", "broken"), gold)
    assert not swapped.ok and "missing" in swapped.reason and "extra" in swapped.reason
    counted = Goal(targets=(GoalTarget("shoe box", "criterion", (), "broken", 1), gold.targets[1]))
    assert not same_goal(counted, gold).ok
    elsewhere = Goal(targets=(GoalTarget(None, "criterion", (), "broken"), gold.targets[1]))
    assert not same_goal(elsewhere, gold).ok
    assert not same_goal(Goal(targets=gold.targets[:1]), gold).ok
    assert "stack" in same_goal(Goal(stack=True, targets=gold.targets), gold).reason


def test_a_need_compares_by_presence_and_a_dish_by_its_words() -> None:
    need = Goal(need="my phone is dying", targets=(GoalTarget(None, "need"),))
    assert same_goal(Goal(need="the battery is nearly flat", targets=need.targets), need).ok
    assert not same_goal(Goal(targets=need.targets), need).ok
    dish = Goal(dish="fruit salads", targets=(GoalTarget(None, "ingredients"),))
    assert same_goal(Goal(dish="a fruit salad", targets=dish.targets), dish).ok
    assert not same_goal(Goal(dish="green salad", targets=dish.targets), dish).ok
