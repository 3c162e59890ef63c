"""Option types shared by the commands."""

from __future__ import annotations

import math
from typing import Any

import click


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
