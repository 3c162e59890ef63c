import gzip
from pathlib import Path

import pytest

from conceptbot.core.errors import ImportDataError
from conceptbot.knowledge.importers.conceptnet5 import ConceptNet5Stats, concept_text, iter_conceptnet5_edges
from conceptbot.knowledge.importers.omcs import OmcsStats, iter_omcs_edges
from conceptbot.knowledge.importers.wordnet import WordNetStats, iter_wordnet_edges


def test_omcs_edges_with_bad_lines_counted(omcs_file: Path) -> None:
    stats = OmcsStats()
    seen: list[int] = []
    edges = list(iter_omcs_edges(omcs_file, stats, seen.append))
    assert [e.sentence for e in edges[:2]] == ["knife AtLocation kitchen", "knife UsedFor cut"]
    assert edges[0].weight == 17.0 and edges[0].source == "omcs"
    assert (stats.lines, stats.edges, stats.skipped_disputed, stats.skipped_malformed) == (9, 7, 1, 1)
    assert "broken" in stats.examples[0]
    assert sum(seen) == omcs_file.stat().st_size


def test_truncated_gzip_is_an_import_error(omcs_file: Path, tmp_path: Path) -> None:
    truncated = tmp_path / "cut.graph.gz"
    truncated.write_bytes(omcs_file.read_bytes()[:-12])
    with pytest.raises(ImportDataError, match="truncated or corrupt"):
        list(iter_omcs_edges(truncated, OmcsStats()))


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ImportDataError, match="no such file"):
        list(iter_omcs_edges(tmp_path / "absent.gz", OmcsStats()))


def test_wordnet_relations_and_sense_weights(wordnet_dir: Path) -> None:
    stats = WordNetStats()
    sentences = {e.sentence: e for e in iter_wordnet_edges(wordnet_dir, stats)}
    assert "knife IsA edge tool" in sentences
    assert "blade PartOf knife" in sentences  # %p: blade is part of knife
    assert "window MadeOf glass" in sentences  # %s: substance meronym
    assert "cutter Synonym edge tool" in sentences
    assert "hollandaise DefinedAs eggs and butter with lemon juice" in sentences
    assert "knife DefinedAs edge tool used as a cutting instrument" in sentences  # example quote dropped
    assert all(e.source == "wordnet" and e.weight == 2.0 for e in sentences.values())
    assert stats.synsets == 7


def test_wordnet_folder_must_have_the_files(tmp_path: Path) -> None:
    with pytest.raises(ImportDataError, match="not a WordNet"):
        list(iter_wordnet_edges(tmp_path, WordNetStats()))


def test_conceptnet5_english_only_with_datasets(cn5_file: Path) -> None:
    stats = ConceptNet5Stats()
    edges = list(iter_conceptnet5_edges(cn5_file, stats))
    assert [e.sentence for e in edges] == [
        "knife IsA tool",
        "knife UsedFor cut bread",
        "glass HasProperty fragile",
        "blade PartOf knife",
    ]
    assert edges[0].source == "conceptnet5/wordnet" and edges[1].source == "conceptnet5/conceptnet"
    assert edges[1].weight == pytest.approx(3.46)
    assert (
        stats.lines,
        stats.english,
        stats.other_language,
        stats.skipped_relation,
        stats.skipped_malformed,
    ) == (8, 4, 2, 1, 1)


def test_conceptnet5_truncated_dump(cn5_file: Path, tmp_path: Path) -> None:
    truncated = tmp_path / "cut.csv.gz"
    truncated.write_bytes(cn5_file.read_bytes()[: len(cn5_file.read_bytes()) // 2])
    with pytest.raises(ImportDataError, match="truncated or corrupt"):
        list(iter_conceptnet5_edges(truncated, ConceptNet5Stats()))


def test_conceptnet5_plain_csv(tmp_path: Path, cn5_file: Path) -> None:
    plain = tmp_path / "dump.csv"
    plain.write_bytes(gzip.decompress(cn5_file.read_bytes()))
    assert len(list(iter_conceptnet5_edges(plain, ConceptNet5Stats()))) == 4


def test_concept_text() -> None:
    assert concept_text(b"/c/en/ice_cream/n/wn/food") == "ice cream"
    assert concept_text(b"/c/en/Knife") == "knife"
