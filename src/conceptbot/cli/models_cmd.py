"""``conceptbot models``: list and install local models."""

from __future__ import annotations

import click
from rich.console import Console
from rich.progress import (
    BarColumn,
    DownloadColumn,
    Progress,
    TextColumn,
    TimeRemainingColumn,
    TransferSpeedColumn,
)
from rich.table import Table

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.richtext import line, plain
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.text import terminal_safe
from conceptbot.models import weights


@click.group()
def models() -> None:
    """List and install local (embedded) models."""


def _status(app: AppContext, name: str) -> str:
    try:
        weights.source_files(weights.get_entry(name))
        parts = "parts available"
    except ConceptBotError:
        parts = "parts missing"
    entry = weights.get_entry(name)
    path = weights.model_path(app.settings.models_dir, entry)
    if not path.is_file():
        return f"not installed ({parts})"
    if path.stat().st_size != entry.size:
        return "corrupt (wrong size)"
    return "installed"


@models.command("list")
@pass_app
def list_models(app: AppContext) -> None:
    """Show the models ConceptBot can run locally and whether they are installed."""
    table = Table(show_header=True, header_style="bold")
    for column in ("name", "size", "status", "description"):
        table.add_column(column)
    for name, entry in weights.catalogue().items():
        size = f"{entry.size / 1e6:,.0f} MB"
        table.add_row(plain(name), size, plain(_status(app, name)), plain(entry.description))
    Console().print(table)
    click.echo(terminal_safe(f"Models folder: {app.settings.models_dir}"))


@models.command("install")
@click.argument("name")
@click.option("--force", is_flag=True, help="Re-join and re-verify even if a good copy is present.")
@pass_app
def install_model(app: AppContext, name: str, force: bool) -> None:
    """Join NAME's parts into the models folder and verify its sha256."""
    entry = weights.get_entry(name)
    with Progress(
        # File names are plain text, not Rich markup.
        TextColumn("{task.description}", style="progress.description", markup=False),
        BarColumn(),
        DownloadColumn(),
        TransferSpeedColumn(),
        TimeRemainingColumn(),
        transient=False,
    ) as progress:
        task = progress.add_task(terminal_safe(f"joining {name}"), total=None)
        path = weights.install(
            app.settings.models_dir,
            name,
            force=force,
            progress=lambda n: progress.advance(task, n),
            on_total=lambda total: progress.update(task, total=total),
            on_cleaned=lambda stale, size: progress.console.print(
                line(f"removed {stale.name} ({size / 1e6:,.1f} MB), left by an interrupted install"),
                soft_wrap=True,
            ),
        )
    click.echo(terminal_safe(f"{name}: installed and verified (sha256 {entry.sha256[:16]}...) at {path}"))
