"""Options and output shared by the two benchmark command groups (``bench``, ``safebench``)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import click

F = TypeVar("F", bound=Callable[..., object])


def workers_option(command: F) -> F:
    """Add ``--workers``: plans at once, for HTTP backends (see :func:`effective_workers`)."""
    return click.option(
        "--workers",
        default=1,
        show_default=True,
        type=click.IntRange(1, 16),
        help="Plans at once (HTTP backends only; the embedded model runs one at a time).",
    )(command)


def results_option(default: Path) -> Callable[[F], F]:
    """Add ``--out``: the JSONL results file a run appends to and resumes from."""
    return click.option(
        "--out",
        type=click.Path(dir_okay=False, path_type=Path),
        default=default,
        show_default=True,
        help="JSONL results file; finished runs in it are skipped (resume).",
    )


def out_dir_option(command: F) -> F:
    """Add ``--out-dir`` for report commands (default: beside the results file)."""
    return click.option(
        "--out-dir", type=click.Path(file_okay=False, path_type=Path), help="Default: beside RESULTS."
    )(command)


def effective_workers(backend: str, workers: int) -> int:
    """One worker for the embedded model: one llama.cpp context cannot serve two plans at once."""
    return 1 if backend == "llamacpp" else workers


def echo_report(paths: dict[str, Path]) -> None:
    """Print a written report's Markdown and the list of files written."""
    click.echo(paths["markdown"].read_text(encoding="utf-8"))
    click.echo("written: " + ", ".join(str(p) for p in paths.values()))
