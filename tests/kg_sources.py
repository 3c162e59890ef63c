"""Fixtures: small knowledge source files in the real formats (OMCS graph, WordNet, ConceptNet 5 dump)."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import pytest

OMCS_LINES = [
    "knife\tkitchen\t{'freq': 5, 'score': 17, 'rel': u'AtLocation'}",
    "knife\tcut\t{'freq': 5, 'score': 8, 'rel': u'UsedFor'}",
    "knife\tweapon\t{'freq': 5, 'score': 7, 'rel': u'IsA'}",
    "bowl\thold liquid\t{'freq': 5, 'score': 3, 'rel': u'UsedFor'}",
    "glass\tfragile\t{'freq': 5, 'score': 4, 'rel': u'HasProperty'}",
    "ceramic\tfragile\t{'freq': 5, 'score': 2, 'rel': u'HasProperty'}",
    "apple\tfruit\t{'freq': 5, 'score': 9, 'rel': u'IsA'}",
    "apple\tred\t{'freq': 5, 'score': -1, 'rel': u'HasProperty'}",  # disputed: skipped
    "this line is broken",  # malformed: skipped
]

# WordNet 3.0 format: offset lex_filenum ss_type w_cnt(hex) word lex_id ... p_cnt ptr... | gloss
WN_DATA = [
    "  1 This software and database is being provided to you, the LICENSEE, by  ",
    "00000001 06 n 01 knife 0 002 @ 00000002 n 0000 %p 00000003 n 0000 | "
    'edge tool used as a cutting instrument; "he cut it with a knife"  ',
    "00000002 06 n 02 edge_tool 0 cutter 0 000 | any cutting tool with a sharp cutting edge  ",
    "00000003 06 n 01 blade 0 001 @ 00000002 n 0000 | the flat part of a knife  ",
    "00000004 13 n 01 hollandaise 0 001 @ 00000005 n 0000 | eggs and butter with lemon juice  ",
    "00000005 13 n 01 sauce 0 000 | flavorful relish or dressing  ",
    "00000006 06 n 01 window 0 001 %s 00000007 n 0000 | a framework of wood or metal that contains glass  ",
    "00000007 27 n 01 glass 0 000 | a brittle transparent solid  ",
]
WN_INDEX = [
    "  1 This software and database is being provided to you, the LICENSEE, by  ",
    "blade n 1 1 @ 1 0 00000003  ",
    "edge_tool n 1 0 1 0 00000002  ",
    "glass n 1 0 1 0 00000007  ",
    "hollandaise n 1 1 @ 1 0 00000004  ",
    "knife n 1 2 @ %p 1 0 00000001  ",
]


def cn5_line(rel: str, start: str, end: str, weight: float = 1.0, dataset: str = "/d/conceptnet/4/en") -> str:
    info = {
        "dataset": dataset,
        "license": "cc:by/4.0",
        "sources": [{"contributor": "/s/contributor/omcs/x"}],
        "weight": weight,
    }
    return f"/a/[/r/{rel}/,{start}/,{end}/]\t/r/{rel}\t{start}\t{end}\t{json.dumps(info)}"


CN5_LINES = [
    cn5_line("IsA", "/c/en/knife/n", "/c/en/tool/n", 2.0, "/d/wordnet/3.1"),
    cn5_line("UsedFor", "/c/en/knife", "/c/en/cut_bread", 3.46),
    cn5_line("HasProperty", "/c/en/glass", "/c/en/fragile", 4.0),
    cn5_line("IsA", "/c/fr/couteau", "/c/fr/outil", 1.0, "/d/wiktionary/fr"),  # not English
    cn5_line("Synonym", "/c/en/knife", "/c/de/messer", 1.0, "/d/wiktionary/en"),  # end not English
    cn5_line("ExternalURL", "/c/en/knife", "/c/en/knife", 1.0),  # link edge: dropped
    "/a/[/r/IsA/,/c/en/x/]\t/r/IsA\t/c/en/x",  # malformed: too few fields
    cn5_line("PartOf", "/c/en/blade", "/c/en/knife", 1.5),
]


@pytest.fixture
def omcs_file(tmp_path: Path) -> Path:
    path = tmp_path / "conceptnet_en.graph.gz"
    with gzip.open(path, "wt") as handle:
        handle.write("\n".join(OMCS_LINES) + "\n")
    return path


@pytest.fixture
def wordnet_dir(tmp_path: Path) -> Path:
    folder = tmp_path / "wordnet"
    folder.mkdir()
    (folder / "data.noun").write_text("\n".join(WN_DATA) + "\n")
    (folder / "index.noun").write_text("\n".join(WN_INDEX) + "\n")
    return folder


@pytest.fixture
def cn5_file(tmp_path: Path) -> Path:
    path = tmp_path / "conceptnet-assertions-5.7.0.csv.gz"
    with gzip.open(path, "wt") as handle:
        handle.write("\n".join(CN5_LINES) + "\n")
    return path
