"""Split conformal prediction for the yes/no decisions: the threshold, the sets, the shipped data."""

from __future__ import annotations

import json
import math
import random

import pytest

from conceptbot.pipeline.goal_planner.conformal import (
    COVERAGES,
    conformal_threshold,
    decision_set,
    shipped,
)


def test_the_threshold_is_the_finite_sample_quantile() -> None:
    scores = [i / 10 for i in range(10)]  # 0.0 .. 0.9
    assert conformal_threshold(scores, 0.5) == pytest.approx(0.5)  # ceil(11 * 0.5) = 6th smallest
    assert conformal_threshold(scores, 0.8) == pytest.approx(0.8)  # ceil(8.8) = 9th
    assert conformal_threshold(scores, 0.95) == 1.0  # ceil(10.45) = 11 > 10: keep everything
    for bad in ([], [0.2, math.nan], [1.5]):
        with pytest.raises(ValueError):
            conformal_threshold(bad, 0.9)
    with pytest.raises(ValueError, match="coverage"):
        conformal_threshold(scores, 1.0)


def test_sets_from_exchangeable_scores_cover_as_promised() -> None:
    rng = random.Random(7)
    # A calibrated model: P(yes) drawn uniformly, the label drawn with that probability.
    rows = [(p, rng.random() < p) for p in (rng.random() for _ in range(4000))]
    calibration, test = rows[:2000], rows[2000:]
    scores = [1.0 - p if label else p for p, label in calibration]
    for coverage in COVERAGES:
        q = conformal_threshold(scores, coverage)
        covered = [("yes" if label else "no") in decision_set(p, q).answers for p, label in test]
        assert abs(sum(covered) / len(covered) - coverage) < 0.03, coverage


def test_a_decision_is_sure_only_when_one_answer_is_likely_enough() -> None:
    assert decision_set(0.95, 0.3).answers == ("yes",) and decision_set(0.95, 0.3).sure
    assert decision_set(0.05, 0.3).answers == ("no",)
    unsure = decision_set(0.5, 0.6)
    assert unsure.answers == ("yes", "no") and not unsure.sure
    assert decision_set(0.5, 0.3).answers == () and not decision_set(0.5, 0.3).sure
    broken = decision_set(math.nan, 0.3)  # a decision that cannot be made asks, never guesses
    assert broken.answers == ("yes", "no") and not broken.sure


def test_the_shipped_calibration_has_every_coverage_in_order() -> None:
    calibration = shipped()
    assert set(calibration.qhat) == set(COVERAGES) and "dev tasks" in calibration.fitted_on
    decisions = shipped(level="decision")
    assert set(decisions.qhat) == set(COVERAGES) and "1028 rows" in decisions.fitted_on
    # All of a plan's decisions at once need a wider set than one decision does.
    assert all(calibration.qhat[c] >= decisions.qhat[c] for c in COVERAGES)
    assert shipped("nograph").qhat != calibration.qhat
    # Both which-one rules are fitted on the same plans; the default is the softmax's.
    fits = shipped(rule="fits")
    assert calibration.rule == "softmax" and fits.rule == "fits" and set(fits.qhat) == set(COVERAGES)
    # The rules score which-one decisions apart, so their thresholds differ (yes/no ones may not).
    assert fits.qhat_one != calibration.qhat_one and shipped("nograph", rule="fits").qhat_one != fits.qhat_one
    with pytest.raises(ValueError, match="no plan-level conformal calibration"):
        shipped("other")
    with pytest.raises(ValueError, match="no conformal level"):
        shipped(level="task")
    thresholds = [calibration.threshold(c) for c in COVERAGES]
    assert thresholds == sorted(thresholds) and all(0.5 <= q <= 1.0 for q in thresholds)
    # Each kind's own thresholds: at 0.9 the shipped which-one one keeps fewer candidates than the
    # single plan-level threshold would; the yes/no ones rise with the coverage.
    yes_no = [calibration.threshold_yes_no(c) for c in COVERAGES]
    assert yes_no == sorted(yes_no) and all(0.5 <= q <= 1.0 for q in yes_no)
    assert all(0.0 < calibration.threshold_one(c) <= 1.0 for c in COVERAGES)
    assert calibration.threshold_one(0.9) < calibration.threshold(0.9)
    # The reading decisions' own, fitted on held-out paraphrases for both rules and combinations
    # (the readings depend on neither), rising with the coverage.
    readings = [calibration.threshold_reading(c) for c in COVERAGES]
    assert readings == sorted(readings) and all(0.0 < q <= 1.0 for q in readings)
    assert fits.qhat_reading == calibration.qhat_reading == shipped("nograph").qhat_reading
    with pytest.raises(ValueError, match=r"no conformal threshold for coverage 0\.7"):
        calibration.threshold(0.7)


def test_a_models_own_calibration_is_read_before_the_shipped_one(tmp_path) -> None:
    from conceptbot.pipeline.goal_planner.conformal import calibration_for, user_file

    path = user_file(tmp_path, "openai-compatible", "my/model:7b")
    assert path.parent == tmp_path and path.name == "conformal-openai-compatible-my-model-7b.json"
    assert calibration_for(tmp_path, "openai-compatible", "my/model:7b") == shipped()  # none written yet
    own = {"graph": {"0.8": 0.5, "0.9": 0.6, "0.95": 0.7}, "nograph": {"0.8": 0.4, "0.9": 0.5, "0.95": 0.6}}
    path.write_text(json.dumps({"plan_qhat": own, "fitted_on": "mine"}))
    found = calibration_for(tmp_path, "openai-compatible", "my/model:7b", "nograph")
    assert found.qhat == {0.8: 0.4, 0.9: 0.5, 0.95: 0.6} and found.fitted_on == "mine" and found.which_one
    # A file written before each kind had its own thresholds: the plan-level ones for both.
    assert found.qhat_one is None and found.threshold_one(0.9) == found.threshold_yes_no(0.9) == 0.5
    ones = {"nograph": {"0.8": 0.3, "0.9": 0.35, "0.95": 0.9}}
    yes_no = {"nograph": {"0.8": 0.6, "0.9": 0.7, "0.95": 0.8}}
    kinds = {"plan_qhat_one": ones, "plan_qhat_yes_no": yes_no}
    path.write_text(json.dumps({"plan_qhat": own, **kinds, "fitted_on": "mine"}))
    found = calibration_for(tmp_path, "openai-compatible", "my/model:7b", "nograph")
    assert (found.threshold_one(0.9), found.threshold_yes_no(0.9), found.threshold(0.9)) == (0.35, 0.7, 0.5)
    assert found.threshold_one(1.0) == found.threshold_yes_no(1.0) == 1.0  # every decision asked
    assert found.qhat_reading is None and found.threshold_reading(0.9) == 0.5  # none of its own: the one
    readings = {"nograph": {"0.8": 0.6, "0.9": 0.62, "0.95": 0.64}}
    path.write_text(json.dumps({"plan_qhat": own, **kinds, "plan_qhat_reading": readings, "fitted_on": "m"}))
    found = calibration_for(tmp_path, "openai-compatible", "my/model:7b", "nograph")
    assert (found.threshold_reading(0.9), found.threshold_reading(1.0)) == (0.62, 1.0)
    assert calibration_for(tmp_path, "llamacpp", "other") == shipped()  # another model's file is not it
    assert calibration_for(tmp_path, "openai-compatible", "my/model:7b", level="decision") == shipped(
        level="decision"
    )


def test_a_calibration_holds_for_the_which_one_rule_it_was_fitted_for(tmp_path) -> None:
    from conceptbot.core.errors import ConfigError
    from conceptbot.pipeline.goal_planner.conformal import OLD_RULE, calibration_for, user_file

    path = user_file(tmp_path, "b", "m")
    fits = {"graph": {"0.8": 0.5, "0.9": 0.6, "0.95": 0.7}}
    softmax = {"graph": {"0.8": 0.7, "0.9": 0.8, "0.95": 0.9}}
    both = {"plan_which_one": "fits", "plan_qhat": fits, "plan_qhat_softmax": softmax, "fitted_on": "x"}
    path.write_text(json.dumps(both))
    assert calibration_for(tmp_path, "b", "m").rule == "fits"
    assert calibration_for(tmp_path, "b", "m").qhat[0.9] == 0.6
    other = calibration_for(tmp_path, "b", "m", rule="softmax")
    assert other.rule == "softmax" and other.qhat[0.9] == 0.8
    # A file written before the rules were named is the softmax rule's, and has no other.
    path.write_text(json.dumps({"plan_qhat": softmax, "fitted_on": "x"}))
    assert calibration_for(tmp_path, "b", "m").rule == OLD_RULE == "softmax"
    with pytest.raises(ConfigError, match="for this rule") as caught:
        calibration_for(tmp_path, "b", "m", rule="fits")
    assert "calibrate --conformal" in (caught.value.hint or "")
    with pytest.raises(ValueError, match="no which-one rule 'best'"):
        shipped(rule="best")


@pytest.mark.parametrize(
    "text", ["not json", "[]", '{"plan_qhat": {"graph": {"0.8": 0.5}}, "fitted_on": "x"}', "NAN"]
)
def test_a_broken_calibration_file_is_one_clear_error(tmp_path, text: str) -> None:
    from conceptbot.core.errors import ConfigError
    from conceptbot.pipeline.goal_planner.conformal import calibration_for, user_file

    user_file(tmp_path, "b", "m").write_text(text)
    with pytest.raises(ConfigError, match="is not a conformal calibration") as caught:
        calibration_for(tmp_path, "b", "m")
    assert "calibrate --conformal" in (caught.value.hint or "")


def test_a_threshold_out_of_range_is_refused(tmp_path) -> None:
    from conceptbot.core.errors import ConfigError
    from conceptbot.pipeline.goal_planner.conformal import calibration_for, user_file

    bad = {"graph": {"0.8": 0.5, "0.9": float("nan"), "0.95": 0.7}}
    user_file(tmp_path, "b", "m").write_text(json.dumps({"plan_qhat": bad, "fitted_on": "x"}))
    with pytest.raises(ConfigError, match=r"not a number in \[0, 1\]"):
        calibration_for(tmp_path, "b", "m")
    good = {"graph": {"0.8": 0.5, "0.9": 0.6, "0.95": 0.7}}
    ones = {"graph": {"0.8": 0.5, "0.9": 1.5, "0.95": 0.7}}
    user_file(tmp_path, "b", "m").write_text(
        json.dumps({"plan_qhat": good, "plan_qhat_one": ones, "fitted_on": "x"})
    )
    with pytest.raises(ConfigError, match=r"plan_qhat_one\.graph\.0\.9 is 1\.5, not a number in \[0, 1\]"):
        calibration_for(tmp_path, "b", "m")


def test_at_coverage_one_every_answer_is_kept_without_a_fit() -> None:
    from conceptbot.core.system import ASK_ALL, SystemOptions

    assert shipped().threshold(ASK_ALL) == 1.0 and shipped("nograph", "decision").threshold(ASK_ALL) == 1.0
    assert SystemOptions(coverage=ASK_ALL).coverage == 1.0


def test_a_calibration_says_which_model_it_was_fitted_for(tmp_path) -> None:
    from conceptbot.pipeline.goal_planner.conformal import SHIPPED_MODEL, calibration_for, user_file

    found = shipped()
    assert (found.fitted_for, found.source) == (SHIPPED_MODEL, "shipped") == ("qwen2.5-coder-1.5b", "shipped")
    assert shipped(level="decision").fitted_for == SHIPPED_MODEL
    # The embedded model's thresholds hold for it on any backend that serves it, not for another model.
    assert found.fits("llamacpp", SHIPPED_MODEL) and found.fits("openai-compatible", SHIPPED_MODEL)
    assert not found.fits("llamacpp", "qwen2.5-coder-0.5b") and not found.fits("openai", "gpt-4o-mini")
    assert not calibration_for(tmp_path, "openai", "gpt-4o-mini").fits("openai", "gpt-4o-mini")
    path = user_file(tmp_path, "openai", "gpt-4o-mini")
    own = {"graph": {"0.8": 0.5, "0.9": 0.6, "0.95": 0.7}}
    path.write_text(json.dumps({"plan_qhat": own, "fitted_on": "mine"}))
    mine = calibration_for(tmp_path, "openai", "gpt-4o-mini")
    assert (mine.fitted_for, mine.source) == ("openai:gpt-4o-mini", str(path))
    assert mine.fits("openai", "gpt-4o-mini") and not mine.fits("openai-compatible", "gpt-4o-mini")


@pytest.mark.parametrize("value", [True, False, "0.5", None, [0.5]])
def test_a_threshold_of_the_wrong_json_type_names_the_file_and_the_field(tmp_path, value: object) -> None:
    from conceptbot.core.errors import ConfigError
    from conceptbot.pipeline.goal_planner.conformal import calibration_for, user_file

    fitted = {"graph": {"0.8": 0.5, "0.9": value, "0.95": 0.7}}
    path = user_file(tmp_path, "b", "m")
    path.write_text(json.dumps({"plan_qhat": fitted, "fitted_on": "x"}))
    with pytest.raises(
        ConfigError, match=r"plan_qhat\.graph\.0\.9 is .*, not a number in \[0, 1\]"
    ) as caught:
        calibration_for(tmp_path, "b", "m")
    assert str(path) in caught.value.message


def test_a_calibration_file_nested_too_deeply_is_one_clear_error(tmp_path) -> None:
    from conceptbot.core.errors import ConfigError
    from conceptbot.pipeline.goal_planner.conformal import calibration_for, user_file

    user_file(tmp_path, "b", "m").write_text("[" * 200_000 + "]" * 200_000)
    with pytest.raises(ConfigError, match="nested too deeply") as caught:
        calibration_for(tmp_path, "b", "m")
    assert "calibrate --conformal" in (caught.value.hint or "")
