"""Options and output shared by the two benchmark command groups (``bench``, ``safebench``)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TypeVar

import click

from conceptbot.bench.results import OnRecord, Record
from conceptbot.cli.progress import count_progress
from conceptbot.core.urls import redact_secrets
from conceptbot.models.registry import split_spec

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


def allow_mixed_option(command: F) -> F:
    """Add ``--allow-mixed`` for report commands: report records of several commits together."""
    return click.option(
        "--allow-mixed",
        is_flag=True,
        help="Report a configuration's records from several commits of the code together (the "
        "report says so); by default such a file is refused.",
    )(command)


def backend_and_model(llm_spec: str) -> tuple[str, str]:
    """The backend and model a run records (and resumes by) for an LLM spec; the model with any
    secret redacted, as an openai-compatible URL may carry a key."""
    backend, model = split_spec(llm_spec)
    return backend, redact_secrets(model)


def effective_workers(backend: str, workers: int) -> int:
    """One worker for the embedded model: one llama.cpp context cannot serve two plans at once."""
    return 1 if backend == "llamacpp" else workers


def echo_report(paths: dict[str, Path]) -> None:
    """Print a written report's Markdown and the list of files written."""
    click.echo(paths["markdown"].read_text(encoding="utf-8"))
    click.echo("written: " + ", ".join(str(p) for p in paths.values()))


@contextmanager
def record_progress(total: int, describe: Callable[[Record], str]) -> Iterator[OnRecord]:
    """Yield an ``on_record`` callback for a runner: each record advances a bar of ``total`` plans,
    labelled ``describe(record)``."""
    with count_progress(total) as step:
        yield lambda record: step(describe(record))
