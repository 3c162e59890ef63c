"""ConceptNet 4-era English OMCS assertions, as shipped in the PyPI sdist ``Divisi2==2.2.5``.

File ``divisi2/data/graphs/conceptnet_en.graph.gz``: 488,014 lines of
``head<TAB>tail<TAB>{'freq': 5, 'score': 1, 'rel': u'PartOf'}`` (a Python dict literal). The OMCS
concepts are already normalised by ConceptNet 4 (lemmatised, stop words removed). The edge weight
is the assertion's vote ``score``; assertions with a score of 0 or less (disputed) are skipped.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from conceptbot.knowledge.base import Edge
from conceptbot.knowledge.importers.reader import Progress, open_lines
from conceptbot.knowledge.normalize import normalize

SOURCE = "omcs"
_REL = re.compile(rb"'rel':\s*u?'(\w+)'")
_SCORE = re.compile(rb"'score':\s*(-?\d+)")


@dataclass
class OmcsStats:
    """Counts of one import."""

    lines: int = 0
    edges: int = 0
    skipped_malformed: int = 0
    skipped_disputed: int = 0
    examples: list[str] = field(default_factory=list)


def iter_omcs_edges(path: Path, stats: OmcsStats, progress: Progress | None = None) -> Iterator[Edge]:
    """Edges of a Divisi2 ``.graph.gz`` file, streaming.

    Args:
        path: The ``conceptnet_en.graph.gz`` file (or an uncompressed copy).
        stats: Filled in as lines are read (malformed lines are counted, not fatal).
        progress: Called with bytes read.

    Raises:
        ImportDataError: Missing, truncated or corrupt file.
    """
    with open_lines(path, progress) as lines:
        for raw in lines:
            stats.lines += 1
            parts = raw.rstrip(b"\r\n").split(b"\t")
            rel = _REL.search(parts[2]) if len(parts) == 3 else None
            score = _SCORE.search(parts[2]) if rel else None
            if rel is None or score is None:
                stats.skipped_malformed += 1
                if len(stats.examples) < 5:
                    stats.examples.append(f"line {stats.lines}: {raw[:80]!r}")
                continue
            if int(score.group(1)) <= 0:
                stats.skipped_disputed += 1
                continue
            head = normalize(parts[0].decode("utf-8", "replace"))
            tail = normalize(parts[1].decode("utf-8", "replace"))
            stats.edges += 1
            yield Edge(head, rel.group(1).decode(), tail, float(score.group(1)), SOURCE)
