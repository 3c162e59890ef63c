import socket
import sqlite3
from pathlib import Path

import pytest

from conceptbot.core.errors import ConfigError, KnowledgeUnavailableError
from conceptbot.knowledge import conceptnet_api
from conceptbot.knowledge.base import Edge, KnowledgeGraph
from conceptbot.knowledge.conceptnet_api import ConceptNetAPI
from tests.knowledge.conceptnet_api_stub import ConceptNetStub, Reply, edge, external, node

KNIFE = [
    edge("UsedFor", node("knife", sense="n"), node("cut"), 2.0),
    # The same assertion through two word senses, weaker first: merged, the stronger weight kept.
    edge("IsA", node("knife", sense="v"), node("sharp object"), 1.0),
    edge("IsA", node("knife", sense="n"), node("sharp object"), 3.464),
    edge("AtLocation", node("knife"), node("kitchen drawer", sense="n"), 4.0),
    edge("PartOf", node("blade"), node("knife"), 1.5),
    edge("Synonym", node("knife"), node("couteau", "fr", sense="n"), 2.2),
    edge("Synonym", node("cuchillo", "es"), node("knife"), 2.2),
    edge("ExternalURL", node("knife"), external("http://dbpedia.org/resource/Knife"), 1.0),
]
BOWL = [
    edge("IsA", node("bowl", sense="n"), node("dish"), 2.0),
    edge("UsedFor", node("bowl"), node("soup"), 1.0),
]
ICE_CREAM = [edge("IsA", node("ice cream"), node("dessert"), 2.5)]
ALL = KNIFE + BOWL + ICE_CREAM


def _api(tmp_path: Path, url: str, **kwargs) -> ConceptNetAPI:
    kwargs.setdefault("max_retries", 2)
    kwargs.setdefault("backoff_s", 0.001)
    kwargs.setdefault("timeout_s", 5)
    return ConceptNetAPI(tmp_path / "kg" / "conceptnet_api.db", url, **kwargs)


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_first_access_fetches_english_edges_strongest_first(tmp_path: Path) -> None:
    with ConceptNetStub(ALL) as stub:
        api = _api(tmp_path, stub.url)
        found = api.edges("knife")
    assert isinstance(api, KnowledgeGraph) and api.name == "conceptnet-api" and api.version == ""
    assert (found.query, found.matched, found.match) == ("knife", "knife", "exact")
    assert found.edges == (
        Edge("knife", "AtLocation", "kitchen drawer", 4.0, "conceptnet-api"),
        Edge("knife", "IsA", "sharp object", 3.464, "conceptnet-api"),
        Edge("knife", "UsedFor", "cut", 2.0, "conceptnet-api"),
        Edge("blade", "PartOf", "knife", 1.5, "conceptnet-api"),
    )
    assert stub.requests == ["/query?node=/c/en/knife&other=/c/en&limit=100"]


def test_non_english_and_external_url_edges_are_dropped(tmp_path: Path) -> None:
    with ConceptNetStub(KNIFE) as stub:
        found = _api(tmp_path, stub.url).edges("knife")
    assert {e.relation for e in found.edges} == {"AtLocation", "IsA", "UsedFor", "PartOf"}
    assert all("couteau" not in (e.head, e.tail) and "cuchillo" not in (e.head, e.tail) for e in found.edges)
    assert not any(e.tail.startswith("http") for e in found.edges)


def test_second_access_comes_from_the_cache_without_http(tmp_path: Path) -> None:
    with ConceptNetStub(ALL) as stub:
        first = _api(tmp_path, stub.url).edges("knife")
        assert len(stub.requests) == 1
        again = _api(tmp_path, stub.url).edges("Knife")  # a new process reading the same cache file
        assert len(stub.requests) == 1
    assert again.edges == first.edges


def test_relation_filter_and_limit_apply_to_the_cached_edges(tmp_path: Path) -> None:
    with ConceptNetStub(ALL) as stub:
        api = _api(tmp_path, stub.url)
        used = api.edges("knife", relations=["UsedFor", "PartOf"])
        top = api.edges("knife", limit=2)
        everything = api.edges("knife")
    assert [(e.relation, e.tail) for e in used.edges] == [("UsedFor", "cut"), ("PartOf", "knife")]
    assert [e.relation for e in top.edges] == ["AtLocation", "IsA"]
    assert len(everything.edges) == 4  # the filtered query did not shrink what is cached
    assert len(stub.requests) == 1


def test_plural_and_multi_word_names_resolve_with_the_shared_rule(tmp_path: Path) -> None:
    with ConceptNetStub(ALL) as stub:
        api = _api(tmp_path, stub.url)
        knives = api.edges("Knives")
        bowls = api.edges("Ceramic Bowls")
        ice_cream = api.edges("ice_cream")
    assert (knives.matched, knives.match) == ("knife", "lemma")
    assert knives.edges[0] == Edge("knife", "AtLocation", "kitchen drawer", 4.0, "conceptnet-api")
    assert (bowls.matched, bowls.match) == ("bowl", "head")
    assert [e.tail for e in bowls.edges] == ["dish", "soup"]
    assert (ice_cream.match, ice_cream.edges[0].head) == ("exact", "ice cream")
    assert stub.nodes == [
        "/c/en/knives",
        "/c/en/knife",
        "/c/en/ceramic_bowls",
        "/c/en/ceramic_bowl",
        "/c/en/bowl",
        "/c/en/ceramic",
        "/c/en/ice_cream",
    ]


def test_nodes_without_term_and_relations_without_label_still_parse(tmp_path: Path) -> None:
    raw = edge("MadeOf", node("knife", sense="n"), node("steel", sense="n"), 2.0)
    del raw["start"]["term"], raw["end"]["term"], raw["rel"]["label"]  # as older API versions answer
    with ConceptNetStub([raw]) as stub:
        found = _api(tmp_path, stub.url).edges("knife")
    assert found.edges == (Edge("knife", "MadeOf", "steel", 2.0, "conceptnet-api"),)


def test_concept_names_are_url_quoted(tmp_path: Path) -> None:
    with ConceptNetStub(ALL) as stub:
        _api(tmp_path, stub.url).edges("crème brûlée/x?y")
    assert stub.requests[0].startswith("/query?node=/c/en/cr%C3%A8me_br%C3%BBl%C3%A9e%2Fx%3Fy&other=/c/en")
    assert stub.nodes[0] == "/c/en/crème_brûlée/x?y"


def test_unknown_concept_is_empty_and_negatively_cached(tmp_path: Path) -> None:
    with ConceptNetStub(ALL) as stub:
        api = _api(tmp_path, stub.url)
        first = api.edges("xyzzy")
        second = api.edges("xyzzy")
    assert (first.matched, first.match, first.edges) == (None, "none", ())
    assert not first and second == first
    assert len(stub.requests) == 1
    assert api.cached_concepts() == ["xyzzy"]


def test_server_error_then_success_is_retried(tmp_path: Path) -> None:
    with ConceptNetStub(ALL, script=[Reply(500)]) as stub:
        found = _api(tmp_path, stub.url, max_retries=1).edges("knife")
    assert found.match == "exact" and len(found.edges) == 4
    assert len(stub.requests) == 2


@pytest.mark.parametrize("status", [500, 503, 429])
def test_persistent_transient_errors_give_up_after_max_retries(tmp_path: Path, status: int) -> None:
    with ConceptNetStub(ALL, always=Reply(status)) as stub:
        api = _api(tmp_path, stub.url, max_retries=3)
        with pytest.raises(KnowledgeUnavailableError) as info:
            api.edges("knife")
    assert len(stub.requests) == 4
    assert f"HTTP {status}" in info.value.message
    assert f"{stub.url}/query?node=/c/en/knife" in info.value.message
    assert "--cache-only" in (info.value.hint or "")
    assert api.cached_concepts() == []


def test_backoff_is_exponential(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    delays: list[float] = []
    monkeypatch.setattr(conceptnet_api.time, "sleep", delays.append)
    with ConceptNetStub(ALL, always=Reply(503)) as stub, pytest.raises(KnowledgeUnavailableError):
        _api(tmp_path, stub.url, max_retries=3, backoff_s=0.25).edges("knife")
    assert delays == [0.25, 0.5, 1.0]


def test_client_errors_are_not_retried(tmp_path: Path) -> None:
    with ConceptNetStub(ALL, always=Reply(404)) as stub:
        api = _api(tmp_path, stub.url, max_retries=3)
        with pytest.raises(KnowledgeUnavailableError, match="HTTP 404"):
            api.edges("knife")
    assert len(stub.requests) == 1
    assert api.cached_concepts() == []


@pytest.mark.parametrize(
    "body",
    [b"<html>Bad gateway</html>", b'{"error": "oops"}', b'{"edges": "none"}', b"[1, 2]", b'{"edges": [1]}'],
)
def test_garbage_body_is_an_error_and_nothing_is_cached(tmp_path: Path, body: bytes) -> None:
    with ConceptNetStub(ALL, script=[Reply(200, body)]) as stub:
        api = _api(tmp_path, stub.url)
        with pytest.raises(KnowledgeUnavailableError, match="malformed data"):
            api.edges("knife")
        assert api.cached_concepts() == []
        assert len(api.edges("knife").edges) == 4  # not cached, so fetched again
    assert len(stub.requests) == 2


def test_server_down_is_knowledge_unavailable(tmp_path: Path) -> None:
    url = f"http://127.0.0.1:{_free_port()}"
    api = _api(tmp_path, url, max_retries=1)
    with pytest.raises(KnowledgeUnavailableError, match="connection refused") as info:
        api.edges("knife")
    assert f"{url}/query?node=/c/en/knife" in info.value.message and "2 attempt(s)" in info.value.message
    assert api.cached_concepts() == []


def test_timeout_is_retried_then_knowledge_unavailable(tmp_path: Path) -> None:
    with ConceptNetStub(ALL, always=Reply(200, delay_s=0.6)) as stub:
        api = _api(tmp_path, stub.url, timeout_s=0.15, max_retries=1)
        with pytest.raises(KnowledgeUnavailableError, match="timed out"):
            api.edges("knife")
        assert len(stub.requests) == 2
    assert api.cached_concepts() == []


def test_cache_only_never_uses_the_network(tmp_path: Path) -> None:
    with ConceptNetStub(ALL) as stub:
        offline = _api(tmp_path, stub.url, cache_only=True)
        miss = offline.edges("knife")
        assert stub.requests == []
        _api(tmp_path, stub.url).edges("knife")  # warm the cache online
        hit = offline.edges("knives")
        assert len(stub.requests) == 1  # only the online client's "knife"; "knives" missed offline
    assert (miss.match, miss.edges) == ("none", ())
    assert (hit.matched, hit.match, len(hit.edges)) == ("knife", "lemma", 4)


def test_cache_only_needs_no_server(tmp_path: Path) -> None:
    found = _api(tmp_path, f"http://127.0.0.1:{_free_port()}", cache_only=True).edges("knife")
    assert found.match == "none"


@pytest.mark.parametrize(
    "url",
    [
        "api.conceptnet.io",
        "ftp://api.conceptnet.io",
        "",
        "http://",
        "/query",
        "http://h:port",
        "http://h/?a=1",
    ],
)
def test_malformed_base_url_is_a_config_error(tmp_path: Path, url: str) -> None:
    with pytest.raises(ConfigError, match="base URL"):
        ConceptNetAPI(tmp_path / "c.db", url)
    assert not (tmp_path / "c.db").exists()


@pytest.mark.parametrize(
    "kwargs", [{"timeout_s": 0}, {"max_retries": -1}, {"backoff_s": -1.0}, {"fetch_limit": 0}]
)
def test_out_of_range_settings_are_config_errors(tmp_path: Path, kwargs: dict) -> None:
    with pytest.raises(ConfigError):
        ConceptNetAPI(tmp_path / "c.db", **kwargs)


def test_base_url_trailing_slash_and_fetch_limit(tmp_path: Path) -> None:
    with ConceptNetStub(ALL) as stub:
        found = _api(tmp_path, stub.url + "/", fetch_limit=3).edges("knife")
    assert stub.requests == ["/query?node=/c/en/knife&other=/c/en&limit=3"]
    # Only one page is fetched: the stub's first three knife edges (two are one IsA), strongest first.
    assert [(e.relation, e.weight) for e in found.edges] == [("IsA", 3.464), ("UsedFor", 2.0)]


def test_cache_schema_wal_and_migrations(tmp_path: Path) -> None:
    path = tmp_path / "kg" / "conceptnet_api.db"
    with ConceptNetStub(ALL) as stub, ConceptNetAPI(path, stub.url) as api:
        api.edges("knife")
        assert api.applied_migrations() == [(1, "initial")]
    with ConceptNetAPI(path, cache_only=True) as reopened:  # migrations are not applied twice
        assert reopened.applied_migrations() == [(1, "initial")]
    conn = sqlite3.connect(path)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    concept, count, url, fetched_at = conn.execute(
        "SELECT concept, edge_count, url, fetched_at FROM conceptnet_cache"
    ).fetchone()
    conn.close()
    assert (concept, count) == ("knife", 4) and url.endswith("node=/c/en/knife&other=/c/en&limit=100")
    assert fetched_at > 0


def test_cache_can_share_a_file_with_the_llm_cache(tmp_path: Path) -> None:
    from conceptbot.models.cache_db import CacheStore

    path = tmp_path / "cache.db"
    store = CacheStore(path)
    with ConceptNetAPI(path, cache_only=True) as api:
        assert api.applied_migrations() == [(1, "initial")]
        assert api.cached_concepts() == []
    assert store.applied_migrations()[0][0] == 1
    store.close()


def test_corrupt_cache_file_is_knowledge_unavailable(tmp_path: Path) -> None:
    path = tmp_path / "broken.db"
    path.write_bytes(b"this is not a sqlite database" * 100)
    with pytest.raises(KnowledgeUnavailableError, match="unusable"):
        ConceptNetAPI(path, cache_only=True)
