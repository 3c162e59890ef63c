"""Household steps for tests: written as text, passed typed (as a planner's reply would be read)."""

from __future__ import annotations

from collections.abc import Iterable

from conceptbot.core.plan import HouseholdAction, format_actions, parse_household_actions


def acts(texts: Iterable[str]) -> tuple[HouseholdAction, ...]:
    """The steps, parsed."""
    return parse_household_actions(texts)


def texts(actions: Iterable[HouseholdAction]) -> list[str]:
    """The steps' text, as a results file holds them."""
    return format_actions(actions)
