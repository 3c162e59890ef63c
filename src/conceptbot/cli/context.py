"""What every ``conceptbot`` sub-command receives from the command group.

Its own module, so the command group (:mod:`conceptbot.cli.main`) imports the command modules and
they import this, never each other.
"""

from __future__ import annotations

from dataclasses import dataclass

import click

from conceptbot.core.config import Settings


@dataclass
class AppContext:
    """What every sub-command gets: resolved settings."""

    settings: Settings


pass_app = click.make_pass_decorator(AppContext)
"""Decorator giving a command the :class:`AppContext` as its first argument."""
