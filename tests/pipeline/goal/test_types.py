from __future__ import annotations

import pytest

from conceptbot.pipeline.goal import ALL, Goal, GoalTarget


def test_a_goal_survives_its_json_form() -> None:
    goal = Goal(
        stack=False,
        dish="guacamole",
        need=None,
        targets=(GoalTarget(None, "ingredients"), GoalTarget("box", "named", ("shell",), "", 1)),
    )
    assert Goal.from_dict(goal.to_dict()) == goal
    assert goal.to_dict()["targets"][0] == {
        "to": None,
        "takes": "ingredients",
        "named": [],
        "criterion": "",
        "count": "all",
    }


@pytest.mark.parametrize("count", [0, -1, "some", 1.5])
def test_a_count_is_a_positive_number_or_all(count: object) -> None:
    with pytest.raises(ValueError, match="count"):
        GoalTarget("box", "criterion", count=count)  # type: ignore[arg-type]
    assert GoalTarget("box", "criterion", count=ALL).count == "all"


def test_an_unknown_kind_of_target_is_refused() -> None:
    with pytest.raises(ValueError, match="takes"):
        GoalTarget("box", "everything")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="takes"):
        Goal.from_dict({"targets": [{"to": "box"}]})
