"""Every benchmark script imports (its imports name modules that exist) without running: a change
that moves or removes a module a script uses fails here, not on the next person's measurement."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

BENCHMARKS = sorted((Path(__file__).resolve().parents[1] / "benchmarks").glob("*.py"))


@pytest.mark.parametrize("script", BENCHMARKS, ids=[p.stem for p in BENCHMARKS])
def test_a_benchmark_script_imports(script: Path) -> None:
    spec = importlib.util.spec_from_file_location(f"benchmark_{script.stem}", script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # scripts run only under __main__
    assert callable(getattr(module, "main", None)), f"{script.name} has no main()"


def test_the_asking_benchmark_measures_calibration_error() -> None:
    spec = importlib.util.spec_from_file_location(
        "benchmark_asking", BENCHMARKS[0].parent / "bench_asking.py"
    )
    assert spec is not None and spec.loader is not None
    asking = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(asking)
    honest = [(0.25, 0.0), (0.25, 0.0), (0.25, 0.0), (0.25, 1.0)]  # 25% said, 25% happened
    assert asking.expected_calibration_error(honest) == pytest.approx(0.0)
    sure_and_wrong = [(0.95, 0.0)] * 3 + [(0.05, 1.0)]
    assert asking.expected_calibration_error(sure_and_wrong) == pytest.approx(0.95)
    assert asking.expected_calibration_error([(1.0, 1.0)]) == 0.0  # 1.0 falls in the last bin
