"""Option types and options shared by the commands."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, TypeVar

import click

from conceptbot.core.system import READINGS

F = TypeVar("F", bound=Callable[..., object])


class FiniteFloatRange(click.FloatRange):
    """``click.FloatRange`` that also refuses ``nan``.

    Python's ``float()`` reads "nan", "inf" and "-inf", and NaN compares false with both bounds,
    so a plain FloatRange lets ``-t nan`` through to places that cannot hold it (JSON cache keys,
    samplers, thresholds). Infinities are outside any bounded range already; an open-ended range
    refuses them here too.
    """

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        """The float, if it is a finite number inside the range (usage error otherwise)."""
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{number} is not a finite number.", param, ctx)
        return number


def reading_option(command: F) -> F:
    """Add ``--reading``: how the goal planner reads a request (``SystemOptions.reading``)."""
    return click.option(
        "--reading",
        type=click.Choice(list(READINGS)),
        default="restated",
        show_default=True,
        help="How the goal planner reads the request: restated (the model says it plainly first and "
        "the better of the two readings is kept; one more model call) or words (the rules alone).",
    )(command)
