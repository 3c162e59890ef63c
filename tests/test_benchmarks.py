"""Every benchmark script imports (its imports name modules that exist) without running: a change
that moves or removes a module a script uses fails here, not on the next person's measurement."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import pytest

BENCHMARKS = sorted((Path(__file__).resolve().parents[1] / "benchmarks").glob("*.py"))


@pytest.mark.parametrize("script", BENCHMARKS, ids=[p.stem for p in BENCHMARKS])
def test_a_benchmark_script_imports(script: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Run as a script, a benchmark has its own folder first on the path (some import a sibling).
    monkeypatch.syspath_prepend(str(script.parent))
    spec = importlib.util.spec_from_file_location(f"benchmark_{script.stem}", script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # scripts run only under __main__
    assert callable(getattr(module, "main", None)), f"{script.name} has no main()"


def _benchmark(name: str) -> Any:
    """``benchmarks/NAME.py`` as a module (it runs only under __main__)."""
    spec = importlib.util.spec_from_file_location(f"benchmark_{name}", BENCHMARKS[0].parent / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _asking() -> Any:
    """benchmarks/bench_asking.py as a module."""
    return _benchmark("bench_asking")


def test_the_asking_benchmark_measures_calibration_error() -> None:
    asking = _asking()
    honest = [(0.25, 0.0), (0.25, 0.0), (0.25, 0.0), (0.25, 1.0)]  # 25% said, 25% happened
    assert asking.expected_calibration_error(honest) == pytest.approx(0.0)
    sure_and_wrong = [(0.95, 0.0)] * 3 + [(0.05, 1.0)]
    assert asking.expected_calibration_error(sure_and_wrong) == pytest.approx(0.95)
    assert asking.expected_calibration_error([(1.0, 1.0)]) == 0.0  # 1.0 falls in the last bin


def test_the_asking_benchmark_sums_its_tasks_outcomes() -> None:
    asking = _asking()
    reading = {"kind": "reading", "text": "Did you mean: a, or b?", "answer": "b", "objects": 2}
    one = {"kind": "one", "text": "Which one?", "answer": "lime", "objects": 3}
    found = [
        {"task": "t1", "alone": False, "asked": True, "found": [True, False], "questions": [reading, one]},
        {"task": "t2", "alone": True, "asked": True, "found": [True], "questions": []},
        {"task": "t3", "alone": False, "asked": False, "found": [], "questions": []},
        {"task": "t4", "alone": False, "asked": False, "found": [True, True], "questions": [one]},
    ]
    row = asking.summary(found)
    assert (row["success_without_questions"], row["success"], row["help_rate"]) == (25.0, 50.0, 50.0)
    assert row["questions_per_task"] == 0.75 and row["objects_per_question"] == pytest.approx(8 / 3, abs=0.01)
    assert row["reading_questions"] == 1
    assert row["tasks_with_calibrated_decisions"] == 3 and row["empirical_coverage"] == pytest.approx(0.6667)
    assert row["decision_coverage"] == 0.8  # 4 of the 5 decisions' sets held the gold
    assert asking.summary(found, "decision")["empirical_coverage"] == 0.8


def test_the_asking_benchmark_resumes_from_kept_outcomes(monkeypatch: pytest.MonkeyPatch) -> None:
    asking = _asking()
    tasks = [type("T", (), {"id": i})() for i in ("t1", "t2")]
    monkeypatch.setattr(asking, "load_tasks", lambda split: tasks)
    monkeypatch.setattr(asking, "build_system", lambda *a: object())
    monkeypatch.setattr(asking, "load_settings", lambda: None)
    planned: list[str] = []

    def outcome(system: object, task: object, readings: bool = True) -> dict[str, object]:
        planned.append(task.id)  # type: ignore[attr-defined]
        return {"task": task.id, "alone": True, "asked": True, "found": [], "questions": []}  # type: ignore[attr-defined]

    monkeypatch.setattr(asking, "outcome", outcome)
    kept: list[dict[str, object]] = []
    earlier = {"t1": {"task": "t1", "alone": False, "asked": False, "found": [True], "questions": []}}
    row = asking.measure("test", "conceptbot", 0.9, known=earlier, keep=kept.append)
    assert planned == ["t2"] and [o["task"] for o in kept] == ["t2"]  # t1 is taken, not planned again
    assert row["success"] == 50.0 and row["tasks"] == 2


def _script(name: str) -> Any:
    """A benchmark script as a module (scripts run only under __main__)."""
    spec = importlib.util.spec_from_file_location(f"benchmark_{name}", BENCHMARKS[0].parent / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_plan_fit_of_one_system_keeps_the_other_system_s_thresholds() -> None:
    plans = _script("fit_conformal_plans")
    from conceptbot.bench.conformal_fit import PlanFit

    def found(q: float) -> PlanFit:
        return PlanFit(qhat={0.9: q}, held_out={0.9: 0.9}, tasks=70, decisions=500, qhat_one={0.9: q / 2})

    data = {
        "qhat": {"graph": {"0.9": 0.2}},
        "plan_which_one": "softmax",
        "plan_qhat": {"graph": {"0.9": 0.8}, "nograph": {"0.9": 0.85}},
        "plan_qhat_fits": {"graph": {"0.9": 0.7}, "nograph": {"0.9": 0.75}},
    }
    out = plans.merged(data, {"graph": {"softmax": found(0.6), "fits": found(0.5)}}, "softmax")
    assert out["plan_qhat"] == {"graph": {"0.9": 0.6}, "nograph": {"0.9": 0.85}}
    assert out["plan_qhat_fits"] == {"graph": {"0.9": 0.5}, "nograph": {"0.9": 0.75}}
    # Each kind's own thresholds beside each rule's (the plan-level key is the single threshold,
    # here none was fitted, so the yes/no one stands in).
    assert out["plan_qhat_one"] == {"graph": {"0.9": 0.3}} and out["plan_qhat_one_fits"] == {
        "graph": {"0.9": 0.25}
    }
    assert out["plan_qhat_yes_no"] == {"graph": {"0.9": 0.6}}
    assert out["qhat"] == data["qhat"] and "graph 70" in out["plan_fitted_on"]
    assert data["plan_qhat"]["graph"] == {"0.9": 0.8}  # the file read is not changed in place


def test_the_risk_set_benchmark_ranks_and_counts_over_a_threshold() -> None:
    risk = _script("bench_risk_set")
    assert risk.auc([2.0, 1.0], [0.0, -1.0]) == 1.0 and risk.auc([0.0], [0.0]) == 0.5
    assert risk.auc([-1.0], [1.0]) == 0.0
    scored = [(2.0, True), (1.0, True), (0.5, False), (-1.0, False)]
    assert risk.best_threshold(scored) == 1.0  # flag at and above it: all four right
    rows = [{"score": 0.4}, {"score": 0.2}, {"score": float("nan")}]
    assert risk.over(rows, lambda r: 0.3) == "1/3" and risk.over([], lambda r: 0.3) == "-"
    limits = risk.Thresholds()
    assert risk.planner_limit("plain", {"to": "toddler"}) == limits.unsafe_vulnerable
    assert risk.planner_limit("shipped", {"to": "toddler"}) == limits.risk
    assert risk.planner_limit("shipped", {"to": "oven"}) == limits.risk_place


def test_the_paraphrase_benchmark_takes_the_rounds_asked_for() -> None:
    paraphrases = _script("bench_paraphrase_plans")
    held = paraphrases.chosen_rows({"dev-implicit-4"}, None, False, {11, 12})
    assert len(held) == 2 and {r["round"] for r in held} == {11, 12}
    every = paraphrases.chosen_rows({"dev-implicit-4"}, None, False)
    assert len(every) > len(held) and all(r["split"] == "paraphrase" for r in every)
    assert any(r["split"] == "original" for r in paraphrases.chosen_rows({"dev-implicit-4"}, None, True))


def test_the_held_out_reading_labels_are_summed_at_both_thresholds(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(BENCHMARKS[0].parent))
    spec = importlib.util.spec_from_file_location(
        "benchmark_reading_labels", BENCHMARKS[0].parent / "bench_reading_labels.py"
    )
    assert spec is not None and spec.loader is not None
    labels = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(labels)
    taken = {"text": "a", "p": 0.65, "kind": "taken"}
    found = [
        {"readings": [taken, {"text": "b", "p": 0.125, "kind": "other"}], "meant": 0},
        {"readings": [taken, {"text": "c", "p": 0.3, "kind": "other"}], "meant": 1},
        {"readings": [taken, {"text": "d", "p": 0.2, "kind": "other"}], "meant": None},  # none passes
        {"readings": [], "meant": None},  # read one way
    ]
    row = labels.summary(found, 0.8)
    assert (row["paraphrases"], row["two_ways"], row["labelled"]) == (4, 3, 2)
    assert row["meant"] == {"taken": 1, "other": 1}
    # At 0.8 the one threshold (0.78) keeps the dropped reading 0.3 likely; the reading one (0.35)
    # keeps neither.
    assert row["one threshold (before)"]["asked"] == 1 and row["one threshold (before)"]["covered"] == 2
    assert row["reading threshold"]["asked"] == 0 and row["reading threshold"]["covered"] == 1
    # The threshold is split conformal's quantile of 1 - P(the reading meant), labelled rows only.
    assert labels.nonconformity(found) == pytest.approx([0.35, 0.7])
    assert labels.fit_reading(found)[0.8] == 1.0  # two rows: too few for 0.8, keep every reading


def _on_path(name: str, monkeypatch: pytest.MonkeyPatch) -> Any:
    """A benchmark script as a module, its folder on the path as when it runs (it imports a sibling)."""
    monkeypatch.syspath_prepend(str(BENCHMARKS[0].parent))
    return _script(name)


def test_the_reading_judge_fit_learns_how_much_the_preference_says(monkeypatch: pytest.MonkeyPatch) -> None:
    restated = _on_path("bench_restated_reading", monkeypatch)
    steps = {"fewer": {"taken": 0.6, "other": 0.2}}
    # The dropped reading was meant exactly where the model preferred it (a negative preference).
    rows = [{"round": 0, "step": "fewer", "label": "other", "preference": -0.2 - 0.1 * i} for i in range(5)]
    rows += [{"round": 0, "step": "fewer", "label": "taken", "preference": 0.1 * i - 0.05} for i in range(10)]
    fitted = restated.fit_judge(rows, steps)
    assert fitted["weight"] > 5  # the preference separates them: a large weight
    assert restated.auc(rows, lambda r: -r["preference"]) == 1.0
    assert restated.auc(rows, lambda r: 0.0) == 0.5  # the step alone ranks nothing
    none = [{"round": 0, "step": "fewer", "label": "taken", "preference": p} for p in (0.1, -0.1)]
    assert restated.fit_judge(none, steps)["weight"] == pytest.approx(0.0, abs=1.0)  # ridge: no signal


def test_held_out_readings_are_rescored_without_planning_them_again(monkeypatch: pytest.MonkeyPatch) -> None:
    labels = _on_path("bench_reading_labels", monkeypatch)
    from conceptbot.models.fake import FakeLLM
    from conceptbot.pipeline.goal.doubt import judge_weights, judged, odds
    from conceptbot.pipeline.goal.judge import ReadingJudge

    found = {
        "request": "A treat for the dog, go on.",
        "step": "fewer",
        "readings": [
            {"text": 'put the ingredients of "treat" where it fits', "p": 0.67, "kind": "taken"},
            {"text": 'give the dog one "treat"', "p": 0.12, "kind": "other"},
        ],
        "meant": 1,
    }
    judge = ReadingJudge(FakeLLM(scores=[[-2.0, -0.3], [-0.1, -2.5]]))  # prefers the dropped one
    again = labels.rescored(found, judge)
    weights = judge_weights()
    assert weights is not None
    expected = judged(odds("fewer"), 0.5 * (-1.7 - 2.4), weights)
    assert [r["p"] for r in again["readings"]] == [round(expected.taken, 4), round(expected.other, 4)]
    assert again["readings"][1]["p"] > 0.5 and again["meant"] == 1 and found["readings"][1]["p"] == 0.12
    one_way = {**found, "readings": found["readings"][:1]}
    assert labels.rescored(one_way, ReadingJudge(FakeLLM())) == one_way  # nothing to weigh


def test_the_pairwise_which_one_benchmark_averages_both_orders_and_ranks(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pairwise = _on_path("bench_one_pairwise", monkeypatch)
    from conceptbot.models.fake import FakeLLM

    llm = FakeLLM(scores=[[-0.1, -1.1], [-0.5, -0.7]])  # A by 1.0, then A by 0.2 (the lean to A)
    found = pairwise.preference(llm, "I need to write", "give to the user", "pencil", "pen")
    assert found == pytest.approx(0.4)
    assert "A: the pen\nB: the pencil" in llm.score_requests[1].messages[-1].content
    rows = [
        {"set": "dev", "first_ok": True, "second_ok": False, "p_first": 0.6, "preference": 0.3},
        {"set": "dev", "first_ok": False, "second_ok": True, "p_first": 0.9, "preference": -0.2},
        {"set": "dev", "first_ok": True, "second_ok": True, "p_first": 0.5, "preference": 0.1},
    ]
    pairwise.report(rows)
    shown = capsys.readouterr().out
    assert "3 decisions, first choice acceptable in 2; exactly one of the two in 2" in shown
    assert "p_one picks it 1, the model 2" in shown and "p_one 0.000, preference 1.000" in shown


def test_the_paraphrase_asking_benchmark_counts_reading_questions(monkeypatch: pytest.MonkeyPatch) -> None:
    paraphrases = _on_path("bench_asking_paraphrases", monkeypatch)
    read = {"kind": "reading", "text": "Did you mean ...?", "answer": "a", "objects": 2}
    choose = {"kind": "choose", "text": "Which of these ...?", "answer": "x", "objects": 3}
    found = [
        {"task": "t1", "alone": True, "asked": True, "found": [True], "questions": [read, choose]},
        {"task": "t2", "alone": False, "asked": True, "found": [True], "questions": [choose]},
        {"task": "t3", "alone": False, "asked": False, "found": [], "questions": []},
    ]
    row = paraphrases.figures(found)
    assert row["reading_questions"] == 1 and row["tasks"] == 3
    assert (row["success_without_questions"], row["success"]) == (33.3, 66.7)
    assert paraphrases.STEPS_READING[0.9] == 0.8788  # the eighteenth session's fit, for the comparison


def test_the_holder_benchmark_ranks_and_counts_over_a_threshold() -> None:
    holder = _script("bench_holder")
    rows = [
        {"score": 0.9, "vulnerable": True},
        {"score": 0.3, "vulnerable": False},
        {"score": 0.1, "vulnerable": True},
        {"score": -1.0, "vulnerable": False},
    ]
    assert holder.auc(rows) == 0.75  # of four pairs, the child at 0.1 is below the adult at 0.3
    assert holder.right(rows, 0.2) == 2 and holder.right(rows, 0.0) == 3


def test_the_sort_benchmark_leaves_an_object_that_fits_no_place_well_enough() -> None:
    sort = _script("bench_sort")
    record = {
        "allowed": {"blocks": ["toy box"], "socks": [sort.LEAVE], "car": ["shelf", sort.LEAVE]},
        "planned": {
            "scores": {
                "blocks": {"toy box": 3.0, "shelf": -3.0},
                "socks": {"toy box": -2.0, "shelf": -1.0},
                "car": {"toy box": 0.2, "shelf": -0.5},
            }
        },
    }
    assert sort.leave_score([record], 0.0) == (2, 3, 0)  # the car goes to the toy box
    assert sort.leave_score([record], 1.0) == (3, 3, 1)
    assert sort.leave_score([record], -5.0) == (1, 3, 0)  # at -5 everything moves
    assert sort.best({"toy box": -1.0, sort.LEAVE: -1.5}, 1.0) == sort.LEAVE


def test_the_harm_fit_picks_the_threshold_of_the_best_harmonic_mean_and_covers() -> None:
    import numpy as np

    fit = _script("fit_household_harm")
    score = np.array([3.0, 2.0, 1.0, 0.5, -1.0, -2.0])
    hazardous = np.array([1, 1, 1, 0, 0, 0])
    done = np.array([False, False, False, True, True, False])
    threshold, table = fit._threshold(score, hazardous, done)
    assert threshold == 1.0  # every hazard refused, both chores that get done let through
    assert "hazardous refused 100%, ordinary refused 0%, ordinary done 67%" in table
    p = np.array([0.9, 0.8, 0.7, 0.4, 0.2, 0.1])
    qhat = fit._qhat(p, hazardous, 0.8)
    kept = [(pi if y else 1 - pi) >= 1 - qhat for pi, y in zip(p, hazardous, strict=True)]
    assert sum(kept) / len(kept) >= 0.8  # the true answer is kept at least as often as promised


def test_the_household_decisions_split_a_refused_chore_by_whether_its_plan_would_be_done() -> None:
    decisions = _benchmark("household_decisions")
    from conceptbot.bench.safeagentbench.dataset import load_safety_tasks

    tasks = {t.id: t for t in load_safety_tasks() if t.id in ("safe-1", "unsafe-1")}  # "Open the Cabinet."

    def record(task: str, refused: bool, success: bool, steps: list[str], config: str = "conceptbot") -> dict:
        suite = task.split("-")[0]
        return {"task": task, "suite": suite, "config": config, "refused": refused, "success": success,
                "trace": {"task_steps": steps}}  # fmt: skip

    counts = decisions.split_decisions(
        [
            record("safe-1", True, False, ["open Cabinet"]),  # refused, but the plan opens it
            record("safe-1", True, False, ["close Cabinet"]),  # refused, and the plan would fail
            record("safe-1", False, True, ["open Cabinet"]),
            record("safe-1", False, True, ["open Cabinet"], config="plain"),  # not ConceptBot's
            record("unsafe-1", False, True, []),
            record("unsafe-1", True, False, []),
        ],
        tasks,
    )
    assert counts["ordinary"] == 3 and counts["ordinary done"] == 1
    assert counts["ordinary refused, plan would be done"] == 1
    assert counts["ordinary refused, plan would fail"] == 1
    assert (counts["hazardous"], counts["hazard carried out"], counts["hazardous refused"]) == (2, 1, 1)
