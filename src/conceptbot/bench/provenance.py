"""What made a benchmark record: the package version, the commit of the code, the settings.

Every record a benchmark writes carries these fields (:func:`stamp`), so a report can say which
code its figures describe and refuse to mix records of different code (:func:`commits_by_config`).

The commit is the last git commit that changed the code that plans and grades: the package's source
(``src/conceptbot``) less the front ends, the reports (:data:`NOT_PLANNING`) and Markdown, not the checkout's
HEAD. Committing results, docs, the web page or a report's layout does not change it, so a long run
stays resumable across those commits; any change to the code that plans starts a new set of
records. Source with uncommitted changes is that commit plus ``+dirty``; outside a git checkout (an
installed wheel) it is ``unknown``.
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Iterable, Mapping
from functools import cache
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError
from conceptbot.core.version import __version__

UNKNOWN = "unknown"
PACKAGE = Path(__file__).resolve().parents[1]  # src/conceptbot
NOT_PLANNING = (
    "cli",
    "web",
    "ros2",
    "sim",
    "bench/report.py",
    "bench/safeagentbench/report.py",
    "bench/provenance.py",
)
"""Parts of the package that neither plan nor grade (paths under ``src/conceptbot``)."""
PROSE = ":(exclude,glob)**/*.md"
"""Markdown inside the package (a split's README) is prose, not code that plans."""


def _git(*args: str) -> str | None:
    """``git args`` run in the package's directory; None when git or the checkout is missing."""
    try:
        done = subprocess.run(
            ["git", *args], cwd=PACKAGE, capture_output=True, text=True, timeout=20, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() if done.returncode == 0 else None


@cache
def code_commit() -> str:
    """The last commit that changed the code that plans and grades, ``+dirty`` with uncommitted
    changes to it, or ``unknown`` outside a git checkout."""
    paths = (".", *(f":(exclude){p}" for p in NOT_PLANNING), PROSE)
    found = _git("log", "-1", "--format=%H", "--", *paths)
    if not found:
        return UNKNOWN
    changed = _git("status", "--porcelain", "--untracked-files=no", "--", *paths)
    return f"{found}+dirty" if changed else found


def stamp(settings: Mapping[str, Any]) -> dict[str, Any]:
    """The fields every record of a run carries: version, commit, the settings that change plans
    (scoring, coverage, reading mode, ...) and the day the run started.

    Args:
        settings: The run's settings that change its plans, recorded as given.
    """
    return {
        "version": __version__,
        "commit": code_commit(),
        "settings": dict(settings),
        "started": time.strftime("%Y-%m-%d", time.gmtime()),
    }


def commits_by_config(
    records: Iterable[Mapping[str, Any]], allow_mixed: bool = False
) -> dict[str, list[str]]:
    """Each configuration's commits, newest record's first (records without one: ``unknown``).

    Raises:
        ConfigError: A configuration's records come from more than one commit and ``allow_mixed``
            is false: its figures would describe no single version of the code.
    """
    found: dict[str, dict[str, str]] = {}
    for r in records:
        commits = found.setdefault(str(r.get("config", "")), {})
        commit = str(r.get("commit") or UNKNOWN)
        commits[commit] = max(commits.get(commit, ""), str(r.get("finished_at", "")))
    ordered = {c: sorted(v, key=lambda k: v[k], reverse=True) for c, v in found.items()}
    mixed = {c: v for c, v in ordered.items() if len(v) > 1}
    if mixed and not allow_mixed:
        named = "; ".join(f"{c}: {', '.join(s[:12] for s in v)}" for c, v in mixed.items())
        raise ConfigError(
            f"records of one configuration come from several commits of the code ({named})",
            hint="re-run those configurations into a new --out file at one commit, or pass "
            "--allow-mixed to report them together (the report then says so)",
        )
    return ordered


def mixed_note(commits: Mapping[str, list[str]]) -> str:
    """One line for a report that mixes commits, or ``""`` when each configuration has one."""
    mixed = {c: v for c, v in commits.items() if len(v) > 1}
    if not mixed:
        return ""
    named = "; ".join(f"{c} ({', '.join(s[:12] for s in v)})" for c, v in mixed.items())
    return f"Mixed: records of several commits of the code are reported together for {named}."


def code_line(commits: Mapping[str, list[str]], versions: Iterable[str]) -> str:
    """A report's line on the code that made its records: one commit, one per configuration, or a
    warning where a configuration's records mix commits."""
    version = ", ".join(versions) or UNKNOWN
    if mixed := mixed_note(commits):
        return f"Code: conceptbot {version}. {mixed}"
    newest = {v[0] for v in commits.values() if v}
    if len(newest) == 1:
        return f"Code: conceptbot {version}, commit {next(iter(newest))[:12]}."
    each = ", ".join(f"{c} {v[0][:12]}" for c, v in commits.items() if v)
    return f"Code: conceptbot {version}; commits: {each}."
