"""Rich progress bars behind the library's plain progress callbacks, and the plan commands' observer."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

import click
from rich.console import Console
from rich.progress import (
    BarColumn,
    DownloadColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
    TransferSpeedColumn,
)

from conceptbot.core.observe import Callbacks
from conceptbot.core.text import terminal_safe


def say(message: str) -> None:
    """Print a progress message, dimmed, on stderr (stdout stays the command's output, e.g. JSON).

    Messages quote requests and object names, so they are made terminal-safe first.
    """
    click.secho(terminal_safe(message), dim=True, err=True)


ON_STDERR = Callbacks(on_progress=say)
"""The observer ``plan`` and ``sim run`` attach to a plan: its progress messages on stderr; its
events are not shown (the command prints the whole trace when the plan is done)."""


@contextmanager
def byte_progress() -> Iterator[Callable[[str, int | None], Callable[[int], None]]]:
    """Yield a factory ``task(description, total_bytes) -> advance(n)``; one bar per task."""
    columns = (
        # Descriptions quote file names and requests: plain text, never Rich markup.
        TextColumn("{task.description:<40}", markup=False),
        BarColumn(),
        DownloadColumn(),
        TransferSpeedColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    with Progress(*columns) as progress:

        def task(description: str, total: int | None) -> Callable[[int], None]:
            task_id = progress.add_task(terminal_safe(description), total=total)
            return lambda n: progress.advance(task_id, n)

        yield task


@contextmanager
def count_progress(total: int, description: str = "planning") -> Iterator[Callable[[str], None]]:
    """Yield ``step(description)``: advance one bar of ``total`` items by one and relabel it."""
    columns = (
        TextColumn("{task.description}", markup=False),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
    )
    # On stderr: stdout is the command's output (a table, or JSON another tool reads).
    with Progress(*columns, console=Console(stderr=True)) as progress:
        task_id = progress.add_task(terminal_safe(description), total=total)
        yield lambda text: progress.update(task_id, advance=1, description=terminal_safe(text))
