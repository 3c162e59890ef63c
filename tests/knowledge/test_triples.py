from pathlib import Path

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.knowledge.triples import (
    Triple,
    extract_triples,
    filter_triples,
    load_keywords,
    matches_keyword,
)
from conceptbot.models.fake import FakeEmbedder


def _facts(text: str, hint: str | None = None) -> list[tuple[str, str, str]]:
    return [(t.subject.lower(), t.relation, t.object.lower()) for t in extract_triples(text, hint)]


def _triple(subject: str, relation: str, obj: str) -> Triple:
    return Triple(subject, relation, obj, f"{subject} {relation} {obj}.")


# --- extraction --------------------------------------------------------------------------------------


def test_copula_with_adjective_is_has_property_and_keeps_the_of_phrase() -> None:
    assert _facts("All parts of the plant are poisonous.") == [
        ("all parts of the plant", "HasProperty", "poisonous")
    ]


def test_verb_phrase_and_conjoined_can_verb_share_the_subject() -> None:
    assert _facts("Hellebores contain cardiac glycosides and can cause vomiting.") == [
        ("hellebores", "contains", "cardiac glycosides"),
        ("hellebores", "CapableOf", "cause vomiting"),
    ]


def test_leading_article_goes_but_adjectives_of_the_subject_stay() -> None:
    [triple] = extract_triples("The raw beans are toxic.")
    assert (triple.subject, triple.relation, triple.object) == ("raw beans", "HasProperty", "toxic")
    assert triple.sentence == "The raw beans are toxic."
    assert triple.text == "raw beans HasProperty toxic"


def test_copula_with_noun_is_isa_and_its_adjectives_are_properties() -> None:
    assert _facts("Glass is a brittle and transparent material.") == [
        ("glass", "IsA", "material"),
        ("glass", "HasProperty", "brittle"),
        ("glass", "HasProperty", "transparent"),
    ]


def test_adjective_with_preposition_and_coordinated_objects() -> None:
    assert _facts("It is toxic to dogs and cats.", hint="jack bean") == [
        ("jack bean", "HasProperty", "toxic"),
        ("jack bean", "is toxic to", "dogs"),
        ("jack bean", "is toxic to", "cats"),
    ]


def test_coordinated_adjectives_give_one_triple_each() -> None:
    assert _facts("The vase is poisonous and fragile.") == [
        ("vase", "HasProperty", "poisonous"),
        ("vase", "HasProperty", "fragile"),
    ]


def test_coordinated_subjects_give_one_triple_each_and_negation_is_kept() -> None:
    assert _facts("Hellebores and foxgloves are not edible.") == [
        ("hellebores", "NotHasProperty", "edible"),
        ("foxgloves", "NotHasProperty", "edible"),
    ]


@pytest.mark.parametrize(
    ("sentence", "expected"),
    [
        ("Glass is made from sand.", ("glass", "MadeOf", "sand")),
        ("The material consists of silica.", ("material", "MadeOf", "silica")),
        ("The knife is used for cutting food.", ("knife", "UsedFor", "cut food")),
        ("The beans are used to make flour.", ("beans", "UsedFor", "make flour")),
        ("The blade is part of the knife.", ("blade", "PartOf", "knife")),
        ("Knives can cut bread.", ("knives", "CapableOf", "cut bread")),
        ("Helleborus is a genus of flowering plants.", ("helleborus", "IsA", "genus of flowering plants")),
        (
            "Ingestion of the leaves may cause severe poisoning.",
            ("ingestion of the leaves", "may cause", "severe poisoning"),
        ),
        ("The fruit does not contain starch.", ("fruit", "does not contain", "starch")),
        ("The plant is considered dangerous.", ("plant", "is considered", "dangerous")),
        (
            "Glass is known to shatter into sharp pieces.",
            ("glass", "is known to shatter into", "sharp pieces"),
        ),
    ],
)
def test_conceptnet_relation_mapping(sentence: str, expected: tuple[str, str, str]) -> None:
    assert _facts(sentence) == [expected]


def test_pronouns_and_demonstratives_become_the_hint() -> None:
    text = "It is native to Europe.\nThey are highly toxic.\nThis plant is dangerous."
    subjects = {t.subject for t in extract_triples(text, subject_hint="helleborus")}
    assert subjects == {"helleborus"}
    assert ("helleborus", "HasProperty", "highly toxic") in _facts(text, hint="helleborus")


def test_pronouns_stay_without_a_hint() -> None:
    assert _facts("It is poisonous.") == [("it", "HasProperty", "poisonous")]


def test_relative_clause_subject_is_the_noun_it_modifies() -> None:
    facts = _facts("The seeds contain canavanine, which is toxic to animals.")
    assert ("seeds", "contains", "canavanine") in facts
    assert ("canavanine", "HasProperty", "toxic") in facts
    assert ("canavanine", "is toxic to", "animals") in facts


def test_each_line_is_a_paragraph_and_duplicates_are_dropped() -> None:
    triples = extract_triples("The raw beans are toxic.\n\nThe raw beans are toxic.\nGlass is fragile.")
    assert [(t.subject, t.object) for t in triples] == [("raw beans", "toxic"), ("Glass", "fragile")]


def test_max_sentences_bounds_the_work() -> None:
    text = "Glass is fragile. The beans are toxic. Knives are sharp."
    assert [t.object for t in extract_triples(text, max_sentences=2)] == ["fragile", "toxic"]


def test_empty_text_has_no_triples() -> None:
    assert extract_triples("  \n\n ") == []


# --- keyword filter ----------------------------------------------------------------------------------


def test_packaged_keywords_cover_the_paper_terms() -> None:
    keywords = load_keywords()
    assert len(keywords) >= 40
    for term in ("dangerous", "fragile", "toxic", "flammable", "poisonous", "venomous", "hazardous"):
        assert matches_keyword(term, keywords) is not None, term
    for term in ("transparent", "genus", "europe", "hotel", "breakfast"):
        assert matches_keyword(term, keywords) is None, term
    assert all(k == k.strip().lower() and not k.startswith("#") for k in keywords)


def test_keywords_file_skips_comments_and_blank_lines(tmp_path: Path) -> None:
    path = tmp_path / "kw.txt"
    path.write_text("# header\n\nToxic  # inline\nsharp\ntoxic\n")
    assert load_keywords(path) == ("toxic", "sharp")
    with pytest.raises(ConfigError, match="cannot read"):
        load_keywords(tmp_path / "missing.txt")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("beans HasProperty toxic", "toxic"),
        ("the toxicity of the seeds", "toxic"),
        ("all parts are poisonous", "poison"),
        ("the pan gets hotter", "hot"),
        ("it caused injuries", "injury"),
        ("eating it causes choking", "choke"),
        ("a non-toxic paint", "toxic"),
        ("shards of broken glass cut skin", None),
        ("the hotel is near the beach", None),
        ("", None),
    ],
)
def test_keyword_matching_allows_inflections_but_not_unrelated_words(text: str, expected: str | None) -> None:
    assert matches_keyword(text, ["toxic", "poison", "hot", "injury", "choke"]) == expected


def test_keyword_filter_keeps_risk_triples_and_drops_neutral_ones() -> None:
    triples = [
        _triple("helleborus", "IsA", "genus of flowering plants"),
        _triple("all parts of the plant", "HasProperty", "poisonous"),
        _triple("helleborus", "is native to", "europe"),
        _triple("glass", "HasProperty", "brittle"),
        _triple("bean", "HasProperty", "highly toxic"),
    ]
    kept = filter_triples(triples, load_keywords())
    assert [t.object for t in kept] == ["poisonous", "brittle", "highly toxic"]


def test_no_filter_at_all_keeps_everything_and_empty_input_is_empty() -> None:
    triples = [_triple("a", "IsA", "b")]
    assert filter_triples(triples, None) == triples
    assert filter_triples([], load_keywords(), FakeEmbedder()) == []


# --- cosine filter -----------------------------------------------------------------------------------


def test_cosine_filter_keeps_triples_close_to_a_target_property() -> None:
    triples = [
        _triple("jar", "UsedFor", "hold liquid"),
        _triple("helleborus", "IsA", "genus of flowering plants"),
    ]
    kept = filter_triples(triples, keywords=[], embedder=FakeEmbedder(), threshold=0.5)
    assert [t.subject for t in kept] == ["jar"]
    assert filter_triples(triples, keywords=[], embedder=FakeEmbedder(), threshold=0.9) == []


def test_keyword_or_cosine_and_only_unkept_triples_are_embedded() -> None:
    embedder = FakeEmbedder()
    triples = [
        _triple("bean", "HasProperty", "toxic"),
        _triple("jar", "UsedFor", "hold liquid"),
        _triple("helleborus", "IsA", "genus of flowering plants"),
    ]
    kept = filter_triples(triples, ["toxic"], embedder=embedder, targets=["hold liquid"], threshold=0.5)
    assert [t.subject for t in kept] == ["bean", "jar"]
    assert embedder.calls[0] == ("jar UsedFor hold liquid", "helleborus IsA genus of flowering plants")
    assert embedder.calls[1] == ("hold liquid",)


def test_bad_cosine_settings_are_config_errors() -> None:
    triples = [_triple("a", "IsA", "b")]
    with pytest.raises(ConfigError, match="threshold"):
        filter_triples(triples, [], FakeEmbedder(), threshold=1.5)
    with pytest.raises(ConfigError, match="target"):
        filter_triples(triples, [], FakeEmbedder(), targets=[])
