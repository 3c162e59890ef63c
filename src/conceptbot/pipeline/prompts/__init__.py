"""Prompt templates (``string.Template`` text files, ``$name`` placeholders)."""

from __future__ import annotations

from functools import cache
from importlib import resources
from string import Template

PACKAGE = "conceptbot.pipeline.prompts"


@cache
def load(name: str, package: str = PACKAGE) -> Template:
    """The template ``<name>.txt`` of a prompts package (the pipeline's by default)."""
    text = resources.files(package).joinpath(f"{name}.txt").read_text(encoding="utf-8")
    return Template(text)


def render(name: str, package: str = PACKAGE, **values: str) -> str:
    """Fill a template; every placeholder must be given (a missing one is a bug, so it raises)."""
    return load(name, package).substitute(**values).strip() + "\n"
