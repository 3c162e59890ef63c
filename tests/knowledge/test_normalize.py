import pytest

from conceptbot.knowledge.base import Edge
from conceptbot.knowledge.normalize import candidates, lookup, modifiers, normalize, singular


@pytest.mark.parametrize(
    ("raw", "expected"),
    [
        ("Knife", "knife"),
        ("ice_cream", "ice cream"),
        ("  The Green  Hellebore ", "green hellebore"),
        ("a knife.", "knife"),
        ("Coke", "coke"),
    ],
)
def test_normalize(raw: str, expected: str) -> None:
    assert normalize(raw) == expected


@pytest.mark.parametrize(
    ("word", "expected"),
    [
        ("knives", "knife"),
        ("berries", "berry"),
        ("boxes", "box"),
        ("dishes", "dish"),
        ("bowls", "bowl"),
        ("scissors", "scissors"),
        ("glass", "glass"),
        ("glasses", "glasses"),
        ("tomatoes", "tomato"),
        ("chips", "chip"),
        ("cactus", "cactus"),
    ],
)
def test_singular(word: str, expected: str) -> None:
    assert singular(word) == expected


def test_candidates_order() -> None:
    assert candidates("Ceramic Bowls") == [
        ("ceramic bowls", "exact"),
        ("ceramic bowl", "lemma"),
        ("bowl", "head"),
    ]
    assert candidates("knife") == [("knife", "exact")]
    assert candidates("  ") == []


def _fetcher(known: dict[str, list[Edge]]):
    def fetch(concept, relations, limit):
        return [e for e in known.get(concept, []) if relations is None or e.relation in relations][:limit]

    return fetch


def _edges(concept: str, n: int) -> list[Edge]:
    return [Edge(concept, "IsA", f"thing {i}", 1.0, "test") for i in range(n)]


def test_lookup_prefers_exact_then_lemma() -> None:
    fetch = _fetcher({"ceramic bowl": _edges("ceramic bowl", 3), "bowl": _edges("bowl", 3)})
    result = lookup("Ceramic Bowls", fetch, None, 10)
    assert (result.matched, result.match, len(result.edges)) == ("ceramic bowl", "lemma", 3)


def test_lookup_head_noun_with_modifier_edges() -> None:
    fetch = _fetcher({"bowl": _edges("bowl", 10), "ceramic": _edges("ceramic", 10)})
    result = lookup("ceramic bowl", fetch, None, 10)
    assert result.match == "head+modifier" and result.matched == "bowl + ceramic"
    assert [e.head for e in result.edges].count("ceramic") == 5 and len(result.edges) == 10


def test_lookup_modifier_only_and_nothing() -> None:
    fetch = _fetcher({"aluminum": _edges("aluminum", 2)})
    result = lookup("aluminum frobnicator", fetch, None, 10)
    assert (result.matched, result.match) == ("aluminum", "modifier")
    empty = lookup("zzyzx", fetch, None, 10)
    assert (empty.matched, empty.match, empty.edges, bool(empty)) == (None, "none", (), False)


def test_compound_modifiers_are_tried_whole_first() -> None:
    assert modifiers("Black Widow Spider") == ["black widow", "black", "widow"]
    assert modifiers("ceramic bowl") == ["ceramic"]
    fetch = _fetcher(
        {
            "spider": _edges("spider", 10),
            "black widow": _edges("black widow", 10),
            "black": _edges("black", 10),
        }
    )
    result = lookup("Black Widow Spider", fetch, None, 10)
    assert result.matched == "spider + black widow"
    assert {e.head for e in result.edges} == {"spider", "black widow"}
