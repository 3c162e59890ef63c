import pytest

from conceptbot.knowledge.base import Edge
from conceptbot.knowledge.normalize import candidates, lemmatised, lookup, modifiers, normalize, singular


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


def test_a_word_kept_plural_is_lemmatised_only_as_the_lemmatised_sources_name_it() -> None:
    assert (singular("scissors"), lemmatised("scissors")) == ("scissors", "scissor")
    assert (singular("boxes"), lemmatised("boxes")) == ("box", "box")
    assert candidates("tweezers") == [("tweezers", "exact"), ("tweezer", "lemma")]
    assert candidates("kitchen scissors")[-1] == ("scissors", "head")  # the head stays the word


def test_a_kept_plural_only_wordnet_names_gets_omcs_statements_about_its_singular() -> None:
    # WordNet names "scissors" as written; OMCS lemmatised it to "scissor".
    known = {
        "scissors": [Edge("scissors", "IsA", "edge tool", 2.0, "wordnet")],
        "scissor": [
            Edge("scissor", "UsedFor", "cut", 7.0, "omcs"),
            Edge("scissor", "HasProperty", "sharp", 3.0, "omcs"),
            Edge("drawer", "AtLocation", "scissor", 1.0, "omcs"),
            Edge("scissor", "IsA", "verb sense", 1.0, "wordnet"),  # WordNet's own singular: not added
        ],
        "glasses": [Edge("glasses", "UsedFor", "see", 3.0, "omcs")],
        "glass": [Edge("glass", "HasProperty", "sharp", 4.0, "omcs")],
    }
    fetch = _fetcher(known)
    found = lookup("scissors", fetch, None, 10)
    assert (found.matched, found.match) == ("scissors", "exact")
    assert [e.sentence for e in found.edges] == [
        "scissors UsedFor cut",
        "scissors HasProperty sharp",
        "scissors IsA edge tool",
        "drawer AtLocation scissors",
    ]
    assert [e.sentence for e in lookup("scissors", fetch, None, 2).edges] == [
        "scissors UsedFor cut",
        "scissors HasProperty sharp",
    ]
    # As the head of a compound too.
    assert "scissors UsedFor cut" in [e.sentence for e in lookup("kitchen scissors", fetch, None, 10).edges]
    # A kept plural OMCS knows as written keeps its own statements: "glass" is another thing.
    assert [e.sentence for e in lookup("glasses", fetch, None, 10).edges] == ["glasses UsedFor see"]


def test_a_kept_plural_with_no_statements_is_looked_up_by_its_singular() -> None:
    fetch = _fetcher({"tweezer": [Edge("tweezer", "UsedFor", "pluck eyebrows", 2.0, "omcs")]})
    found = lookup("tweezers", fetch, None, 10)
    assert (found.matched, found.match, found.edges[0].tail) == ("tweezer", "lemma", "pluck eyebrows")
