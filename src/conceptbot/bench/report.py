"""Benchmark report: the paper's success table (categories x configurations) with the published
numbers beside ours, per-module time/tokens/cost, as Markdown, JSON and a bar chart PNG.

Records carry the task split (``"test"``: the paper's 47 tasks; ``"dev"``: our tuning tasks; records
written before splits existed count as ``"test"``). The paper's numbers are shown only beside test-split
results; the report of a dev (or mixed) results file says which split it covers instead."""

from __future__ import annotations

import statistics
from collections import defaultdict
from pathlib import Path
from typing import Any

from conceptbot.bench.grading import CATEGORIES, PAPER_RESULTS
from conceptbot.bench.provenance import code_line, commits_by_config
from conceptbot.bench.results import FLAG, NULL, NUMBER, TEXT, RecordShape, load_records, write_report_files

CONFIG_ORDER = ("saycan", "paper-nokg", "paper", "ope", "urp", "nokg", "conceptbot")

RECORD = RecordShape(
    "conceptbot bench run",
    required={"task": TEXT, "category": TEXT, "config": TEXT, "backend": TEXT, "model": TEXT, "ok": FLAG},
    optional={"split": TEXT, "reason": (str, NULL), "seconds": NUMBER},
)
"""What :func:`summarise` reads from a record (``split`` is absent from records older than splits)."""


def summarise(records: list[dict[str, Any]], allow_mixed: bool = False) -> dict[str, Any]:
    """Success rates per category and configuration, plus usage, failure reasons and the commits of
    the code that made the records.

    Raises:
        ConfigError: A configuration's records come from several commits and ``allow_mixed`` is
            false (:func:`conceptbot.bench.provenance.commits_by_config`).
    """
    commits = commits_by_config(records, allow_mixed)
    cells: dict[tuple[str, str], list[bool]] = defaultdict(list)
    usage: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    failures: dict[str, list[str]] = defaultdict(list)
    for r in records:
        cells[(r["category"], r["config"])].append(bool(r["ok"]))
        cells[("all", r["config"])].append(bool(r["ok"]))
        usage[r["config"]]["seconds"].append(r.get("seconds", 0.0))
        for module, u in (r.get("usage") or {}).items():
            usage[r["config"]][f"{module}_s"].append(u.get("latency_s", 0.0))
            tokens = u.get("prompt_tokens", 0) + u.get("completion_tokens", 0)
            usage[r["config"]][f"{module}_tokens"].append(tokens)
            if module == "total" and u.get("cost_usd") is not None:
                usage[r["config"]]["cost_usd"].append(u["cost_usd"])
        if not r["ok"]:
            failures[r["config"]].append(f"{r['task']}: {r.get('reason') or 'no reason recorded'}")
    configs = [c for c in CONFIG_ORDER if any(k[1] == c for k in cells)]
    configs += sorted({k[1] for k in cells} - set(configs))
    success = {
        cfg: {
            cat: (100.0 * sum(v) / len(v), len(v))
            for cat in (*CATEGORIES, "all")
            if (v := cells.get((cat, cfg)))
        }
        for cfg in configs
    }
    means = {cfg: {k: sum(v) / len(v) for k, v in parts.items() if v} for cfg, parts in usage.items()}
    for cfg, parts in usage.items():  # time is noisy on shared CPUs: report the median beside the mean
        if parts["seconds"]:
            means[cfg]["median_seconds"] = statistics.median(parts["seconds"])
        if parts["total_tokens"]:
            means[cfg]["median_tokens"] = statistics.median(parts["total_tokens"])
    models = sorted({f"{r['backend']}:{r['model']}" for r in records})
    splits = sorted({r.get("split", "test") for r in records}, key=lambda s: (s != "test", s))
    return {
        "splits": splits,
        "configs": configs,
        "success": success,
        "usage": means,
        "failures": failures,
        "models": models,
        "records": len(records),
        "commits": commits,
        "versions": sorted({str(r.get("version", "unknown")) for r in records}),
    }


def markdown(summary: dict[str, Any]) -> str:
    """The success table (ours, with the paper's published numbers in brackets for the test split) and
    usage."""
    configs = summary["configs"]
    splits = summary.get("splits", ["test"])
    with_paper = splits == ["test"]
    lines = [f"Model: {', '.join(summary['models'])}; {summary['records']} graded plans."]
    lines.append(code_line(summary.get("commits", {}), summary.get("versions", [])))
    if not with_paper:
        mixed = " (mixed in one table: give each split its own results file)" if len(splits) > 1 else ""
        lines.append(
            f"Task split: {', '.join(splits)}{mixed}; the paper's numbers apply to the test split only."
        )
    lines.append("")
    lines.append("| category | " + " | ".join(configs) + " |")
    lines.append("|---|" + "---|" * len(configs))
    for cat in (*CATEGORIES, "all"):
        row = [cat]
        for cfg in configs:
            cell = summary["success"][cfg].get(cat)
            paper = PAPER_RESULTS.get(cfg, {}).get(cat) if with_paper else None
            text = f"{cell[0]:.0f}% (n={cell[1]})" if cell else "—"
            if paper is not None:
                text += f" [paper {paper:.0f}%]"
            row.append(text)
        lines.append("| " + " | ".join(row) + " |")
    lines += [
        "",
        "| configuration | median s/plan | mean s/plan | mean s per module | median tokens/plan | "
        "mean tokens/plan | cost USD/plan |",
        "|---|---|---|---|---|---|---|",
    ]
    for cfg in configs:
        u = summary["usage"].get(cfg, {})
        modules = ", ".join(
            f"{k.removesuffix('_s')} {v:.1f}" for k, v in u.items() if k.endswith("_s") and k != "total_s"
        )
        lines.append(
            f"| {cfg} | {u.get('median_seconds', 0):.1f} | {u.get('seconds', 0):.1f} | {modules} | "
            f"{u.get('median_tokens', 0):.0f} | {u.get('total_tokens', 0):.0f} | {u.get('cost_usd', 0):.5f} |"
        )
    return "\n".join(lines) + "\n"


def bar_chart(summary: dict[str, Any], path: Path) -> None:
    """Success per category and configuration as a grouped bar chart (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    configs = summary["configs"]
    width = 0.8 / max(len(configs), 1)
    fig, ax = plt.subplots(figsize=(10, 4.5))
    for i, cfg in enumerate(configs):
        values = [summary["success"][cfg].get(cat, (0.0, 0))[0] for cat in CATEGORIES]
        ax.bar([x + i * width for x in range(len(CATEGORIES))], values, width, label=cfg)
    ax.set_xticks([x + width * (len(configs) - 1) / 2 for x in range(len(CATEGORIES))], CATEGORIES)
    ax.set_ylabel("success rate (%)")
    ax.set_ylim(0, 100)
    split = "" if summary.get("splits", ["test"]) == ["test"] else f", {'+'.join(summary['splits'])} split"
    ax.set_title(f"ConceptBot benchmark ({', '.join(summary['models'])}{split})")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_report(results: Path, out_dir: Path, allow_mixed: bool = False) -> dict[str, Path]:
    """Write ``report.md``, ``report.json`` and ``success.png`` for a results file (``allow_mixed``:
    report a configuration's records of several commits together, saying so).

    Returns:
        The paths written, by kind: ``markdown``, ``json``, ``chart``.

    Raises:
        ConfigError: The results file does not exist, holds no records, or a line is not a
            benchmark record (:data:`RECORD`; the error names the line), or a configuration's
            records come from several commits without ``allow_mixed``.
    """
    summary = summarise(load_records(results, shape=RECORD), allow_mixed)
    return write_report_files(
        summary, out_dir, ("report.md", "report.json", "success.png"), markdown, bar_chart
    )
