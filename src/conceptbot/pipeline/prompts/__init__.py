"""Prompt templates (``string.Template`` text files, ``$name`` placeholders).

Two ways to fill one, both raising on a missing placeholder (a missing one is a bug):

* :func:`render` for system prompts and other whole texts: surrounding blank space is stripped and
  the text ends with one newline.
* :func:`fill` for user messages and the headings put into other prompts: the file's text exactly,
  values untouched (a request's own spaces reach the model as before), except that the file's last
  newline is dropped. A message that ends with a newline is a file that ends with an empty line.
"""

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


def render(name: str, package: str = PACKAGE, /, **values: str) -> str:
    """Fill a template, stripped, ending with one newline.

    Raises:
        KeyError: A placeholder of the template has no value.
    """
    return load(name, package).substitute(**values).strip() + "\n"


def fill(name: str, package: str = PACKAGE, /, **values: str) -> str:
    """Fill a message template exactly as written, less the file's last newline.

    Raises:
        KeyError: A placeholder of the template has no value.
    """
    template = load(name, package)
    text = template.substitute(**values)
    # The template's own last character is the last character of the filled text too.
    return text[:-1] if template.template.endswith("\n") else text
