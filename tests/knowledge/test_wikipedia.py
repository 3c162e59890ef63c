import socket
from collections.abc import Iterator

import pytest

from conceptbot.core.errors import ConfigError, KnowledgeUnavailableError
from conceptbot.knowledge.base import ConceptEdges, Edge, KnowledgeGraph
from conceptbot.knowledge.wikipedia import (
    OFFLINE_HINT,
    PageCandidate,
    WikipediaClient,
    WikipediaFallback,
    clean_extract,
    rank_pages,
)
from conceptbot.models.fake import FakeEmbedder
from tests.knowledge.wikipedia_stub import StubPage, WikipediaStub

HELLEBORUS = """Helleborus is a genus of flowering plants in the family Ranunculaceae.
They are native to Europe.

== Description ==
The flowers have five sepals.

== Toxicity ==
All parts of the plant are poisonous. Hellebores contain cardiac glycosides and can cause vomiting.
The sap is a skin irritant.

== References ==
The author is toxic to readers.
"""
CHRISTMAS_ROSE = "Helleborus niger is an evergreen perennial. It is highly toxic to pets."
JACK_BEAN = "Canavalia ensiformis is a legume. The raw beans are toxic. It is used as fodder."
DISAMBIGUATION = "Hellebore may refer to:\nHelleborus, a genus\nVeratrum, false hellebore"


def _wiki(**kwargs: object) -> WikipediaStub:
    pages: dict[str, str | StubPage] = {
        "Helleborus": HELLEBORUS,
        "Hellebore": StubPage(DISAMBIGUATION, disambiguation=True),
        "Christmas rose": CHRISTMAS_ROSE,
        "Canavalia ensiformis": JACK_BEAN,
    }
    return WikipediaStub(
        pages=pages,
        search={
            "hellebore": ["Helleborus", "Hellebore", "Christmas rose"],
            "jack bean": ["Canavalia ensiformis"],
        },
        redirects={"Jack bean": "Canavalia ensiformis"},
        **kwargs,  # type: ignore[arg-type]
    )


@pytest.fixture
def wiki() -> Iterator[WikipediaStub]:
    with _wiki() as stub:
        yield stub


def _client(url: str, **kwargs: object) -> WikipediaClient:
    return WikipediaClient(url, timeout_s=kwargs.pop("timeout_s", 5), backoff_s=0, **kwargs)  # type: ignore[arg-type]


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _candidates(*titles: str) -> list[PageCandidate]:
    return [PageCandidate(title, i) for i, title in enumerate(titles)]


# --- client ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "url", ["ftp://en.wikipedia.org/w/api.php", "en.wikipedia.org", "http://host:99999/api"]
)
def test_malformed_base_url_is_a_config_error(url: str) -> None:
    with pytest.raises(ConfigError, match="malformed Wikipedia API URL"):
        WikipediaClient(url)


def test_bad_limits_are_config_errors() -> None:
    with pytest.raises(ConfigError, match="time-out"):
        WikipediaClient(timeout_s=0)
    with pytest.raises(ConfigError, match="retry"):
        WikipediaClient(max_retries=-1)


def test_search_sends_the_query_and_parses_hits(wiki: WikipediaStub) -> None:
    hits = _client(wiki.url).search("hellebore", limit=2)
    assert [h.title for h in hits] == ["Helleborus", "Hellebore"]
    assert hits[0].snippet == "The hellebore & more"  # HTML tags and entities removed
    assert hits[0].pageid == 1000 and hits[0].wordcount == len(HELLEBORUS.split())
    params = wiki.requests[0]
    assert params == {
        "action": "query",
        "list": "search",
        "srsearch": "hellebore",
        "srlimit": "2",
        "srnamespace": "0",
        "format": "json",
    }
    assert wiki.headers[0]["user-agent"].startswith("ConceptBot/")


def test_search_without_hits_and_empty_query(wiki: WikipediaStub) -> None:
    client = _client(wiki.url)
    assert client.search("zzzz unknown") == []
    assert client.search("   ") == []
    assert len(wiki.requests) == 1  # the blank query never went out


def test_page_text_and_disambiguation_flag(wiki: WikipediaStub) -> None:
    client = _client(wiki.url)
    page = client.page("Helleborus")
    assert page is not None and page.text == HELLEBORUS and not page.disambiguation
    assert page.pageid == 1000
    disambiguation = client.page("Hellebore")
    assert disambiguation is not None and disambiguation.disambiguation
    params = wiki.requests[0]
    assert params["prop"] == "extracts|pageprops" and params["explaintext"] == "1"
    assert params["redirects"] == "1" and params["titles"] == "Helleborus"


def test_missing_page_is_none_and_redirects_are_followed(wiki: WikipediaStub) -> None:
    client = _client(wiki.url)
    assert client.page("No such plant") is None
    assert client.page_text("No such plant") == ""
    page = client.page("Jack bean")
    assert page is not None and page.title == "Canavalia ensiformis"
    assert client.page_text("Jack bean") == JACK_BEAN


def test_server_error_then_success_is_retried() -> None:
    with _wiki(responses=[(500, b"oops")]) as stub:
        assert _client(stub.url, max_retries=2).page_text("Christmas rose") == CHRISTMAS_ROSE
    assert len(stub.requests) == 2


def test_persistent_server_error_is_knowledge_unavailable() -> None:
    with _wiki(responses=[(503, b"busy")] * 3) as stub, pytest.raises(KnowledgeUnavailableError) as info:
        _client(stub.url, max_retries=2).search("hellebore")
    assert "HTTP 503" in str(info.value) and "3 attempts" in str(info.value)
    assert info.value.hint == OFFLINE_HINT
    assert len(stub.requests) == 3


def test_client_error_is_not_retried() -> None:
    with (
        _wiki(responses=[(403, b"forbidden")]) as stub,
        pytest.raises(KnowledgeUnavailableError, match="403"),
    ):
        _client(stub.url, max_retries=2).search("hellebore")
    assert len(stub.requests) == 1


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (b"<html>captive portal</html>", "not JSON"),
        (b"[1, 2]", "not a JSON object"),
        ({"batchcomplete": ""}, "not a list"),
        ({"error": {"code": "maxlag", "info": "Waiting for a database server"}}, "maxlag"),
    ],
)
def test_unusable_answers_are_knowledge_unavailable(body: bytes | dict, message: str) -> None:
    with _wiki(responses=[(200, body)]) as stub, pytest.raises(KnowledgeUnavailableError, match=message):
        _client(stub.url, max_retries=2).search("hellebore")
    assert len(stub.requests) == 1  # a garbled answer is not retried


def test_server_down_is_knowledge_unavailable_with_the_offline_hint() -> None:
    client = _client(f"http://127.0.0.1:{_free_port()}/w/api.php", max_retries=1)
    with pytest.raises(KnowledgeUnavailableError, match="unreachable") as info:
        client.search("hellebore")
    assert "offline" in str(info.value)


def test_silent_server_times_out() -> None:
    with socket.socket() as sock:  # accepts connections (backlog) but never answers
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        client = _client(f"http://127.0.0.1:{sock.getsockname()[1]}/w/api.php", timeout_s=0.3, max_retries=0)
        with pytest.raises(KnowledgeUnavailableError, match="unreachable"):
            client.page("Helleborus")


# --- page choice -------------------------------------------------------------------------------------


def test_ranking_rule_orders_by_tier_then_api_order() -> None:
    ranked = rank_pages(
        "glass",
        _candidates(
            "Volcanic glass",
            "Glass (disambiguation)",
            "Glassblowing",
            "Glass (material)",
            "List of glass artists",
            "Glass",
        ),
    )
    assert [c.title for c in ranked] == [
        "Glass",
        "Glass (material)",
        "Volcanic glass",
        "Glassblowing",
        "Glass (disambiguation)",
        "List of glass artists",
    ]


def test_ranking_treats_plurals_as_the_same_and_uses_the_head_noun() -> None:
    assert rank_pages("Knives", _candidates("Kitchen", "Knife"))[0].title == "Knife"
    ranked = rank_pages("ceramic bowls", _candidates("Ceramic", "Pottery", "Bowl"))
    assert [c.title for c in ranked] == ["Bowl", "Ceramic", "Pottery"]
    assert rank_pages("x", []) == []


def test_clean_extract_drops_headings_and_reference_sections() -> None:
    text = clean_extract(HELLEBORUS)
    assert "==" not in text and "author" not in text
    toxicity = "All parts of the plant are poisonous. Hellebores contain cardiac glycosides and can cause"
    assert f"{toxicity} vomiting." in text.splitlines()
    short = clean_extract("One is toxic. Two is sharp. Three is hot.", max_chars=30)
    assert short == "One is toxic. Two is sharp."


# --- fallback ----------------------------------------------------------------------------------------


def test_fallback_end_to_end_returns_filtered_wikipedia_edges(wiki: WikipediaStub) -> None:
    fallback = WikipediaFallback(_client(wiki.url))
    assert isinstance(fallback, KnowledgeGraph) and fallback.name == "wikipedia"
    result = fallback.edges("Hellebore")
    assert isinstance(result, ConceptEdges)
    assert (result.query, result.matched, result.match) == ("Hellebore", "Helleborus", "fallback")
    # Exact title "Hellebore" is ranked first but is a disambiguation page: skipped.
    assert wiki.fetched_titles == ["Hellebore", "Helleborus"]
    assert result.edges == (
        Edge("all parts of the plant", "HasProperty", "poisonous", 1.0, "wikipedia"),
        Edge("hellebores", "CapableOf", "cause vomiting", 1.0, "wikipedia"),
        Edge("sap", "IsA", "skin irritant", 1.0, "wikipedia"),
    )
    # Neutral facts ("a genus of flowering plants") and the references section are filtered out.
    assert all("genus" not in e.tail and "readers" not in e.tail for e in result.edges)


def test_fallback_relation_filter_limit_and_cache(wiki: WikipediaStub) -> None:
    fallback = WikipediaFallback(_client(wiki.url))
    only = fallback.edges("hellebore", relations=["HasProperty"])
    assert [e.tail for e in only.edges] == ["poisonous"]
    assert len(fallback.edges("hellebore", limit=1).edges) == 1
    none = fallback.edges("hellebore", relations=["MadeOf"])
    assert (none.match, none.matched, none.edges) == ("none", None, ())
    assert len(wiki.requests) == 3  # one search and two page fetches, then the cache answers


def test_pronoun_subjects_become_the_page_subject(wiki: WikipediaStub) -> None:
    result = WikipediaFallback(_client(wiki.url)).edges("jack bean")
    assert result.matched == "Canavalia ensiformis"
    assert Edge("raw beans", "HasProperty", "toxic", 1.0, "wikipedia") in result.edges


def test_choose_callback_picks_the_page(wiki: WikipediaStub) -> None:
    asked: list[tuple[str, list[str]]] = []

    def choose(concept: str, candidates: list[PageCandidate]) -> PageCandidate | None:
        asked.append((concept, [c.title for c in candidates]))
        return candidates[-1]

    result = WikipediaFallback(_client(wiki.url), choose=choose).edges("Hellebore")
    assert asked == [("hellebore", ["Hellebore", "Helleborus", "Christmas rose"])]
    assert result.matched == "Christmas rose"
    assert wiki.fetched_titles == ["Christmas rose"]
    assert Edge("christmas rose", "HasProperty", "highly toxic", 1.0, "wikipedia") in result.edges


def test_choose_none_or_a_disambiguation_page_means_no_fallback(wiki: WikipediaStub) -> None:
    declined = WikipediaFallback(_client(wiki.url), choose=lambda concept, candidates: None)
    assert declined.edges("hellebore").match == "none"
    assert wiki.fetched_titles == []
    picked = WikipediaFallback(_client(wiki.url), choose=lambda concept, candidates: candidates[0])
    assert picked.edges("hellebore").match == "none"  # "Hellebore" is a disambiguation page
    assert wiki.fetched_titles == ["Hellebore"]


def test_no_search_hits_means_no_edges(wiki: WikipediaStub) -> None:
    result = WikipediaFallback(_client(wiki.url)).edges("quantum toaster")
    assert (result.match, result.matched, result.edges) == ("none", None, ())


def test_cosine_filter_in_the_fallback(wiki: WikipediaStub) -> None:
    fallback = WikipediaFallback(
        _client(wiki.url), embedder=FakeEmbedder(), keywords=[], targets=["used as fodder"], threshold=0.5
    )
    result = fallback.edges("jack bean")
    assert [(e.head, e.relation, e.tail) for e in result.edges] == [
        ("canavalia ensiformis", "is used as", "fodder")
    ]


def test_max_sentences_bounds_the_page(wiki: WikipediaStub) -> None:
    # Sentences 1-3 are neutral; the 4th says the plant is poisonous, the 5th is cut off.
    result = WikipediaFallback(_client(wiki.url), max_sentences=4).edges("hellebore")
    assert [e.tail for e in result.edges] == ["poisonous"]


def test_fallback_raises_when_wikipedia_is_down() -> None:
    fallback = WikipediaFallback(_client(f"http://127.0.0.1:{_free_port()}/w/api.php", max_retries=0))
    with pytest.raises(KnowledgeUnavailableError) as info:
        fallback.edges("hellebore")
    assert info.value.hint == OFFLINE_HINT


def test_fallback_settings_are_checked() -> None:
    with pytest.raises(ConfigError, match="max_sentences"):
        WikipediaFallback(WikipediaClient(), max_sentences=0)
    with pytest.raises(ConfigError, match="threshold"):
        WikipediaFallback(WikipediaClient(), threshold=2.0)
