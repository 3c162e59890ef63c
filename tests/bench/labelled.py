"""What the tests of the labelled sets in ``benchmarks/data`` share: reading a set's rows, and the
paper's object names that no set may use."""

from __future__ import annotations

import json
from pathlib import Path

DATA = Path(__file__).resolve().parents[2] / "benchmarks" / "data"


def set_rows(name: str) -> list[dict]:
    """The rows of the JSON-lines set ``name`` (blank lines skipped)."""
    text = (DATA / name).read_text(encoding="utf-8")
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def paper_objects() -> set[str]:
    """The paper's object names, lower-case (``paper_objects.txt``; ``#`` lines are comments)."""
    lines = (DATA / "paper_objects.txt").read_text(encoding="utf-8").splitlines()
    return {line.strip().lower() for line in lines if line.strip() and not line.startswith("#")}
