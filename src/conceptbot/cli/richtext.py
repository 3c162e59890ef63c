"""Untrusted text for Rich: never read as markup, control characters shown, not obeyed.

A string handed to ``Console.print`` or ``Table.add_row`` is parsed as Rich markup (``[/x]`` in a
request or an object name raises ``MarkupError``; ``[bold]`` restyles the rest) and emoji codes
(``:knife:``), and Rich passes ESC through to the terminal. :class:`rich.text.Text` is never parsed,
so the CLI builds every line that holds a request, a name or a model's words from these helpers.
"""

from __future__ import annotations

from rich.text import Text

from conceptbot.core.text import terminal_safe

Part = str | tuple[str, str] | Text
"""A piece of a line: plain text, ``(text, style)``, or a :class:`Text` built already."""


def plain(value: object, style: str = "") -> Text:
    """``value`` as literal text in ``style`` (no markup, no emoji codes, escapes made visible)."""
    return Text(terminal_safe(value), style=style)


def line(*parts: Part) -> Text:
    """One line from ``parts``; every string in it is literal text (see :func:`plain`)."""
    out = Text()
    for part in parts:
        if isinstance(part, Text):
            out.append_text(part)
        elif isinstance(part, tuple):
            out.append_text(plain(*part))
        else:
            out.append_text(plain(part))
    return out
