"""Prompt templates (``string.Template`` text files, ``$name`` placeholders)."""

from __future__ import annotations

from functools import cache
from importlib import resources
from string import Template


@cache
def load(name: str) -> Template:
    """The template ``prompts/<name>.txt``."""
    text = resources.files("conceptbot.pipeline.prompts").joinpath(f"{name}.txt").read_text(encoding="utf-8")
    return Template(text)


def render(name: str, **values: str) -> str:
    """Fill a template; every placeholder must be given (a missing one is a bug, so it raises)."""
    return load(name).substitute(**values).strip() + "\n"
