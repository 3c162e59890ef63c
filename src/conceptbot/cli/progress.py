"""Rich progress bars behind the library's plain progress callbacks, and the plan commands' observer."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

import click
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


def say(message: str) -> None:
    """Print a progress message, dimmed, on stderr (stdout stays the command's output, e.g. JSON)."""
    click.secho(message, dim=True, err=True)


ON_STDERR = Callbacks(on_progress=say)
"""The observer ``plan`` and ``sim run`` attach to a plan: its progress messages on stderr; its
events are not shown (the command prints the whole trace when the plan is done)."""


@contextmanager
def byte_progress() -> Iterator[Callable[[str, int | None], Callable[[int], None]]]:
    """Yield a factory ``task(description, total_bytes) -> advance(n)``; one bar per task."""
    columns = (
        TextColumn("{task.description:<40}"),
        BarColumn(),
        DownloadColumn(),
        TransferSpeedColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    with Progress(*columns) as progress:

        def task(description: str, total: int | None) -> Callable[[int], None]:
            task_id = progress.add_task(description, total=total)
            return lambda n: progress.advance(task_id, n)

        yield task


@contextmanager
def count_progress(total: int, description: str = "planning") -> Iterator[Callable[[str], None]]:
    """Yield ``step(description)``: advance one bar of ``total`` items by one and relabel it."""
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(*columns) as progress:
        task_id = progress.add_task(description, total=total)
        yield lambda text: progress.update(task_id, advance=1, description=text)
