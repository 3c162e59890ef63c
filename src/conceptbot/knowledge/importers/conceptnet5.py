"""The official ConceptNet 5.7 assertions dump, English edges only, streaming.

Format (``conceptnet-assertions-5.7.0.csv.gz``, about 34M lines, 3.4M with both ends English),
tab-separated: assertion URI, relation, start node, end node, JSON info, e.g.::

    /a/[/r/IsA/,/c/en/knife/n/,/c/en/tool/n/]  /r/IsA  /c/en/knife/n  /c/en/tool/n
        {"dataset": "/d/wordnet/3.1", ..., "weight": 2.0}

Lines are handled as bytes and rejected on their start/end prefix before any decoding, which is
what makes the full dump fit in minutes: only English lines are decoded and their weight and
dataset read. Each edge's source is ``conceptnet5/<dataset>`` (``conceptnet5/wordnet``,
``conceptnet5/conceptnet`` for OMCS, ``conceptnet5/wiktionary``, ...). ``ExternalURL`` edges and
``dbpedia/...`` relations are kept out (they link to other databases, not commonsense).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from conceptbot.knowledge.base import Edge
from conceptbot.knowledge.importers.reader import Progress, open_lines

OFFICIAL_URL = "https://s3.amazonaws.com/conceptnet/downloads/2019/edges/conceptnet-assertions-5.7.0.csv.gz"
_EN = b"/c/en/"
_WEIGHT = re.compile(rb'"weight":\s*(-?[0-9.]+(?:[eE][-+]?\d+)?)')
_DATASET = re.compile(rb'"dataset":\s*"/d/([^/"]+)')


@dataclass
class ConceptNet5Stats:
    """Counts of one import."""

    lines: int = 0
    english: int = 0
    other_language: int = 0
    skipped_relation: int = 0
    skipped_malformed: int = 0
    examples: list[str] = field(default_factory=list)


def concept_text(uri: bytes) -> str:
    """``/c/en/ice_cream/n/wn/food`` -> ``ice cream``."""
    return uri[6:].split(b"/", 1)[0].replace(b"_", b" ").decode("utf-8", "replace").lower()


def iter_conceptnet5_edges(
    path: Path, stats: ConceptNet5Stats, progress: Progress | None = None
) -> Iterator[Edge]:
    """English edges of a ConceptNet 5 assertions dump (plain or gzip).

    Malformed lines are counted in ``stats`` (with up to five examples) and skipped.

    Raises:
        ImportDataError: Missing, truncated or corrupt file.
    """
    with open_lines(path, progress) as lines:
        for raw in lines:
            stats.lines += 1
            parts = raw.split(b"\t")
            if len(parts) != 5 or not parts[1].startswith(b"/r/") or not parts[2].startswith(b"/c/"):
                stats.skipped_malformed += 1
                if len(stats.examples) < 5:
                    stats.examples.append(f"line {stats.lines}: {raw[:100]!r}")
                continue
            start, end = parts[2], parts[3]
            if not (start.startswith(_EN) and end.startswith(_EN)):
                stats.other_language += 1
                continue
            relation = parts[1][3:]
            if relation == b"ExternalURL" or relation.startswith(b"dbpedia"):
                stats.skipped_relation += 1
                continue
            weight = _WEIGHT.search(parts[4])
            if weight is None:
                stats.skipped_malformed += 1
                if len(stats.examples) < 5:
                    stats.examples.append(f"line {stats.lines}: no weight in {parts[4][:60]!r}")
                continue
            dataset = _DATASET.search(parts[4])
            source = "conceptnet5/" + (dataset.group(1).decode() if dataset else "unknown")
            stats.english += 1
            yield Edge(
                concept_text(start), relation.decode(), concept_text(end), float(weight.group(1)), source
            )
