"""OPE's typed answers: read from the JSON the model gives and the cache holds, used by the planners."""

from __future__ import annotations

import json

import pytest

from conceptbot.pipeline import modes
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.ope_answers import Materials, Partner, RiskIndex, YesNoProperties

# A Risk Index answer as an OPE cache entry holds it (JSON text, written by earlier versions too).
CACHED_RISK = (
    '{"object": "knife", "dangerous": 4, "reason": "sharp", '
    '"dangerous_with": [{"object": "child", "score": 5}]}'
)


def test_the_json_form_is_kept_and_the_answer_is_typed() -> None:
    values = json.loads(CACHED_RISK)
    props = ObjectProperties("knife", modes.RISK, values, cached=True)
    assert props.values is values and json.dumps(props.values) == CACHED_RISK  # trace and cache unchanged
    assert props.answer == RiskIndex(4, (Partner("child", 5),), "sharp")
    assert props.answer.rated_danger() == 4
    assert props.answer.move_summary("knife", "child") == "knife: danger 4/5, dangerous with the child 5/5"
    assert props.answer.move_summary("knife", "table") == "knife: danger 4/5"


def test_each_mode_reads_its_answer_and_tolerates_missing_fields() -> None:
    yes_no = ObjectProperties("egg", modes.PROPERTIES, {"safe": "Yes", "fragile": "Yes", "stable": "No"})
    assert yes_no.answer == YesNoProperties(("fragile", "safe")) and yes_no.answer.has("fragile")
    assert yes_no.answer.rated_danger() == 0 and yes_no.notable()
    assert not ObjectProperties("box", modes.PROPERTIES, {"safe": "Yes", "stable": "Yes"}).notable()
    empty = ObjectProperties("rock", modes.RISK, {})
    assert empty.answer == RiskIndex(None) and empty.summary() == "rock: danger None/5"
    assert not empty.notable() and empty.answer.rated_danger() == 0
    mats = ObjectProperties("can", modes.MATERIALS, {"materials": ["metal"], "single_material": True})
    assert (
        mats.answer == Materials(("metal",), True)
        and mats.summary() == "can: made of metal (single material)"
    )
    with pytest.raises(ValueError, match="unknown OPE mode"):
        ObjectProperties("can", "standard", {})


def test_penalties_per_mode() -> None:
    fragile_knife = YesNoProperties(("fragile", "dangerous"))
    assert fragile_knife.penalty("knife", "user", True, None) == pytest.approx(0.8 * 0.4)
    assert fragile_knife.penalty("knife", "table", False, None) == pytest.approx(0.8 * 0.7)
    tray = RiskIndex(2, (Partner("oven", 5),))
    oven = RiskIndex(3, (Partner("tray", 2),))
    assert tray.penalty("tray", "oven", False, oven) == pytest.approx(0.88 * 0.2 * 0.8)
    assert tray.penalty("tray", "oven", False, fragile_knife) == pytest.approx(0.88 * 0.2)
    assert Materials(("glass",), True).penalty("cup", "user", True, None) == 1.0


def test_a_partner_listed_twice_counts_at_its_worst() -> None:
    # the model may list a partner twice with different scores: a risk decision takes the highest
    ball = RiskIndex(2, (Partner("bowl", 1), Partner("dog", 4), Partner("bowl", 5)))
    assert ball.score_with("bowl") == 5 and ball.score_with("dog") == 4 and ball.score_with("cup") is None
