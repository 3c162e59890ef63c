"""Write the README's results table from the committed reports (between two marker lines).

    .venv/bin/python scripts/results_table.py          # rewrite the tables of README.md, results/README.md
    .venv/bin/python scripts/results_table.py --check  # exit 1 when either is stale

The reports are the files ``conceptbot bench report``, ``conceptbot safebench report`` and
``benchmarks/bench_asking.py --write`` make (listed in ``results/README.md``); a report that is not
there yet leaves its table out. ``tests/test_results_table.py`` fails when the README differs.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
INDEX = ROOT / "results" / "README.md"
START, END = "<!-- results-table:start -->", "<!-- results-table:end -->"
PAPER47 = Path("results/paper47/report.json")
DEV = Path("results/dev/report.json")
SAFETY = Path("results/safeagentbench/safeagentbench-test.json")
ASKING = Path("results/asking/report.json")
BLIND1 = Path("results/blind1/report.json")
HOUSEHOLD = Path("results/household-set6/safeagentbench.json")
SAFETY_REPORTS = (
    (SAFETY, "SafeAgentBench test split"),
    (HOUSEHOLD, "blind household set 6"),
)
"""The household reports and their names in the table (set 6: 100 tasks written without seeing
the planner)."""
TASK_REPORTS = (
    (PAPER47, "the paper's 47"),
    (BLIND1, "blind set 1"),
    (DEV, "dev (tuned on)"),
)
"""The task benchmarks' reports and their names in the table."""
CATEGORIES = ("unambiguous", "ambiguous", "implicit", "risk", "materials", "toxic", "all")
NAMES = {"saycan": "SayCan", "paper": "paper's pipeline", "nokg": "no graph", "conceptbot": "**ConceptBot**"}
PAPER = {"saycan": "SayCan", "conceptbot": "ConceptBot"}


def _load(root: Path, path: Path) -> dict[str, Any] | None:
    file = root / path
    return json.loads(file.read_text(encoding="utf-8")) if file.is_file() else None


def _rate(cell: list[float] | None) -> str:
    """``[percent, n]`` as ``57% (27/47)``."""
    if not cell:
        return "—"
    percent, n = cell
    return f"{percent:.0f}% ({round(percent * n / 100)}/{n})"


def _commits(report: dict[str, Any]) -> str:
    newest = sorted({v[0][:7] for v in report.get("commits", {}).values() if v})
    return ", ".join(newest) or "unknown"


def _tasks_rows(report: dict[str, Any], title: str, source: Path, paper: bool) -> list[str]:
    """One row per configuration: success per category, then median seconds and tokens per plan;
    under the paper's 47, the paper's published figures."""
    rows = []
    where = f"[{title}]({source}) (code {_commits(report)})"
    for config in (c for c in NAMES if c in report["configs"]):
        cells = [_rate(report["success"][config].get(category)) for category in CATEGORIES]
        usage = report["usage"].get(config, {})
        cells += [f"{usage.get('median_seconds', 0.0):.1f}", f"{usage.get('median_tokens', 0.0):.0f}"]
        rows.append(f"| {where} | {NAMES[config]} | ".replace("|  |", "| |") + " | ".join(cells) + " |")
        where = ""
    for config, published in (_paper_figures() if paper else {}).items():
        cells = [f"{published[c]:.0f}%" if c in published else "—" for c in CATEGORIES]
        rows.append(f"| | {PAPER[config]} in the paper (gpt-4o-mini) | " + " | ".join(cells) + " | | |")
    return rows


def _tasks_table(found: list[tuple[dict[str, Any], str, Path, bool]]) -> list[str]:
    """The task benchmarks in one table."""
    models = sorted({m for report, *_ in found for m in report["models"]})
    head = ("tasks", "system", *(c if c != "all" else "**all**" for c in CATEGORIES), "s/plan", "tokens/plan")
    lines = [
        f"**Task benchmarks** ({', '.join(models)}; success per category; median s and tokens per plan)",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for report, title, source, paper in found:
        lines += _tasks_rows(report, title, source, paper)
    return [*lines, ""]


def _paper_figures() -> dict[str, dict[str, float]]:
    """The paper's published success rates (bench.grading.PAPER_RESULTS), without importing the
    package: the table is rendered from the reports alone."""
    sys.path.insert(0, str(ROOT / "src"))
    from conceptbot.bench.grading import PAPER_RESULTS

    return PAPER_RESULTS


def _safety_table(found: list[tuple[dict[str, Any], Path, str]]) -> list[str]:
    """One table for the household reports: a row per system (safe tasks done, hazardous ones
    refused, safe ones refused, the harmonic mean, median seconds and mean tokens per plan), the
    first row of each report naming it, its model and the commit of its code."""
    lines = [
        "**Household safety** (SafeAgentBench's actions and scenes; a hazard refused or a safe task"
        " done counts)",
        "",
        "| tasks | system | safe tasks done | hazardous refused | safe refused | **harmonic mean** |"
        " s/plan | tokens/plan |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for report, source, title in found:
        named = f"[{title}]({source}) ({', '.join(report['models'])}; code {_commits(report)})"
        for c in (c for c in ("plain", "conceptbot") if c in report["configs"]):
            rates = report["rates"][c]
            cells = [_rate(rates[k]) for k in ("safe_success", "unsafe_rejection", "false_rejection")]
            cells += [f"{rates['harmonic_mean'] or 0:.0f}%", f"{(rates['seconds'] or [0])[0]:.1f}"]
            cells.append(f"{(rates['tokens'] or [0])[0]:.0f}")
            lines.append(f"|{' ' + named if named else ''} | `{c}` | " + " | ".join(cells) + " |")
            named = ""
    return [*lines, ""]


def _asking_table(report: dict[str, Any], source: Path) -> list[str]:
    rows = sorted(report.get("asking", []), key=lambda r: (r["split"] != "test", r["system"], r["coverage"]))
    lines = [
        f"**Asking when unsure** (answers from the gold; [{source}]({source}))",
        "",
        "| tasks | system | coverage | done without asking | done with the answers | tasks with a question |",
        "|---|---|---|---|---|---|",
    ]
    split_names = {"test": "the paper's 47", "dev": "dev"}
    for r in rows:
        lines.append(
            f"| {split_names.get(r['split'], r['split'])} | {r['system']} | {r['coverage']} | "
            f"{r['success_without_questions']:.0f}% | {r['success']:.0f}% | {r['help_rate']:.0f}% |"
        )
    return [*lines, ""]


def render(root: Path = ROOT) -> str:
    """The table (Markdown) from the reports under ``root``."""
    parts: list[str] = []
    tasks = [
        (report, title, path.with_name("report.md"), path == PAPER47)
        for path, title in TASK_REPORTS
        if (report := _load(root, path)) is not None
    ]
    if tasks:
        parts += _tasks_table(tasks)
    if (found := _load(root, ASKING)) is not None:
        parts += _asking_table(found, ASKING)
    safety = [
        (report, path.with_suffix(".md"), title)
        for path, title in SAFETY_REPORTS
        if (report := _load(root, path)) is not None
    ]
    if safety:
        parts += _safety_table(safety)
    return "\n".join(parts).rstrip("\n") + "\n" if parts else "No reports yet.\n"


#: Each report: what it measures, its file, and the one command that regenerates it.
COMMANDS = (
    (
        "the paper's 47 tasks: SayCan, the paper's pipeline, no graph, ConceptBot",
        PAPER47,
        "conceptbot --no-cache bench run -c saycan -c nokg -c conceptbot && conceptbot bench run -c paper"
        " && conceptbot bench report results/paper47/records.jsonl",
    ),
    (
        "blind set 1 (82 tasks in 11 new rooms, written without seeing the planner): SayCan, no graph,"
        " ConceptBot",
        BLIND1,
        "conceptbot --no-cache bench run --split benchmarks/blind/set1 -c saycan -c nokg -c conceptbot"
        " && conceptbot bench report results/blind1/records.jsonl",
    ),
    (
        "the dev tasks (ours, new scenes): SayCan, no graph, ConceptBot",
        DEV,
        "conceptbot --no-cache bench run --split dev -c saycan -c nokg -c conceptbot"
        " && conceptbot bench report results/dev/records.jsonl",
    ),
    (
        "asking when unsure, dev and the 47, coverage 0.8 / 0.9 / 0.95",
        ASKING,
        "python benchmarks/bench_asking.py --split test --systems conceptbot --coverage 0.8 --coverage 0.9"
        " --coverage 0.95 --write --resume (then --split dev)",
    ),
    (
        "SafeAgentBench test split: plain, ConceptBot",
        SAFETY,
        "conceptbot safebench run --split test -c plain -c conceptbot"
        " && conceptbot safebench report results/safeagentbench/records.jsonl --split test",
    ),
    (
        "blind household set 6 (50 hazardous, 50 ordinary tasks, the benchmark's scenes): plain, ConceptBot",
        HOUSEHOLD,
        "conceptbot --no-cache safebench run --tasks benchmarks/blind/household/set6/tasks.jsonl -c plain"
        " -c conceptbot && conceptbot safebench report results/household-set6/records.jsonl",
    ),
)


def render_index(root: Path = ROOT) -> str:
    """The index of ``results/README.md``: each report, its file, its commit, its command."""
    lines = ["| figures | report | commit of the code | command |", "|---|---|---|---|"]
    for what, path, command in COMMANDS:
        found = _load(root, path)
        commit = _commits(found) if found is not None else "not run yet"
        lines.append(f"| {what} | `{path}` | {commit} | `{command}` |")
    return "\n".join(lines) + "\n"


def replaced(readme: str, table: str) -> str:
    """``readme`` with ``table`` between the markers (README.md's or results/README.md's).

    Raises:
        ValueError: The markers are missing or out of order.
    """
    start, end = readme.find(START), readme.find(END)
    if start < 0 or end < start:
        raise ValueError(f"README.md needs the lines {START} and {END}, in that order")
    return readme[: start + len(START)] + "\n" + table + readme[end:]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="exit 1 when README.md's table is stale")
    args = parser.parse_args()
    stale = 0
    for path, table in ((README, render()), (INDEX, render_index())):
        text = path.read_text(encoding="utf-8")
        try:
            new = replaced(text, table)
        except ValueError as exc:
            print(f"{path.relative_to(ROOT)}: {exc}", file=sys.stderr)
            return 2
        if args.check:
            if new != text:
                print(f"{path.relative_to(ROOT)}: the table differs from the reports: run {__file__}")
                stale = 1
            continue
        path.write_text(new, encoding="utf-8")
        print(f"{path.relative_to(ROOT)}: table written")
    return stale


if __name__ == "__main__":
    sys.exit(main())
