"""Run ``conceptbot`` in this process, through the real entry point, and check what it printed.

:func:`invoke` calls :func:`conceptbot.cli.main.main` (the console script: it turns a
``ConceptBotError`` into ``Error: ...`` and an exit code) inside click's output capture; any other
exception propagates, so a traceback fails the test. Faster than a subprocess, so fuzz tests can
afford many runs.
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass

from click.testing import CliRunner

from conceptbot.cli.main import main

# What a terminal obeys rather than shows: C0 controls but newline and tab, DEL, C1 controls.
RAW_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


@dataclass(frozen=True)
class Outcome:
    """Exit code and the text written to stdout and stderr."""

    code: int
    stdout: str
    stderr: str

    def errors(self) -> list[str]:
        """The ``Error: ...`` lines on stderr."""
        return [line for line in self.stderr.splitlines() if line.startswith("Error: ")]


def invoke(*args: str) -> Outcome:
    """``conceptbot ARGS`` through ``main()``; the exit code of ``sys.exit`` or 0."""
    saved = sys.argv
    sys.argv = ["conceptbot", *args]
    try:
        with CliRunner().isolation() as (stdout, stderr, _):
            try:
                main()
                code = 0
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
            out, err = stdout.getvalue(), stderr.getvalue()
    finally:
        sys.argv = saved
    return Outcome(code, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"))


def assert_terminal_safe(outcome: Outcome, *, error_line: bool = True) -> None:
    """No raw control character on either stream, and (``error_line``) a failure is one message.

    ``error_line=False`` is for ``doctor``, whose failing exit status comes with its report.
    """
    both = outcome.stdout + outcome.stderr
    assert not RAW_CONTROL.search(both), f"raw control character in {both!r}"
    assert "Traceback" not in both
    if outcome.code != 0 and error_line:
        assert len(outcome.errors()) == 1, outcome.stderr
