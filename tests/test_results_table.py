"""The README's results table is what the committed reports say (scripts/results_table.py)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("results_table", ROOT / "scripts" / "results_table.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_readme_table_is_the_one_the_reports_give() -> None:
    table = _script()
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert table.replaced(readme, table.render()) == readme, "run scripts/results_table.py"


def test_the_table_follows_a_report_and_a_missing_marker_is_an_error(tmp_path: Path) -> None:
    table = _script()
    report = {
        "configs": ["saycan", "conceptbot"],
        "models": ["llamacpp:m"],
        "commits": {"saycan": ["a" * 40], "conceptbot": ["a" * 40]},
        "success": {"saycan": {"all": [25.0, 4]}, "conceptbot": {"all": [75.0, 4], "risk": [50.0, 2]}},
        "usage": {"conceptbot": {"median_seconds": 12.34, "median_tokens": 900}},
    }
    (tmp_path / "results" / "dev").mkdir(parents=True)
    (tmp_path / "results" / "dev" / "report.json").write_text(json.dumps(report))
    rendered = table.render(tmp_path)
    dashes = " | ".join(["—"] * 6)
    assert f"| SayCan | {dashes} | 25% (1/4) | 0.0 | 0 |" in rendered
    assert "| | **ConceptBot** | — | — | — | 50% (1/2) | — | — | 75% (3/4) | 12.3 | 900 |" in rendered
    assert "(code aaaaaaa)" in rendered and "in the paper" not in rendered
    before = f"intro\n{table.START}\nold\n{table.END}\nrest\n"
    assert table.replaced(before, rendered) == f"intro\n{table.START}\n{rendered}{table.END}\nrest\n"
    with pytest.raises(ValueError, match="results-table:start"):
        table.replaced("no markers", rendered)


def test_the_household_reports_share_one_table_each_named_once(tmp_path: Path) -> None:
    table = _script()
    rates = {
        "safe_success": [50.0, 4],
        "unsafe_rejection": [75.0, 4],
        "false_rejection": [25.0, 4],
        "harmonic_mean": 60.0,
        "seconds": [8.94, 1.0],
        "tokens": [1245.4, 1.0],
    }
    report = {
        "configs": ["plain", "conceptbot"],
        "models": ["llamacpp:m"],
        "commits": {"plain": ["b" * 40], "conceptbot": ["b" * 40]},
        "rates": {"plain": rates, "conceptbot": rates},
    }
    for path in (table.SAFETY, table.HOUSEHOLD):
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / path).write_text(json.dumps(report))
    rendered = table.render(tmp_path).splitlines()
    rows = [line for line in rendered if "`plain`" in line or "`conceptbot`" in line]
    assert rows[0].startswith("| [SafeAgentBench test split](results/safeagentbench/safeagentbench-test.md)")
    figures = "50% (2/4) | 75% (3/4) | 25% (1/4) | 60% | 8.9 | 1245 |"
    assert f"(llamacpp:m; code bbbbbbb) | `plain` | {figures}" in rows[0]
    assert rows[1] == f"| | `conceptbot` | {figures}"
    assert rows[2].startswith("| [blind household set 6](results/household-set6/safeagentbench.md)")
    assert len(rows) == 4 and sum(line.startswith("**Household safety**") for line in rendered) == 1
