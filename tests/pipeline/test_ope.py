import json
import logging
import sqlite3
from dataclasses import replace
from pathlib import Path

import pytest

from conceptbot.core.config import Settings
from conceptbot.core.plan import format_actions
from conceptbot.core.scene import scene_from_dict
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline import modes
from conceptbot.pipeline.modes import known_partners
from conceptbot.pipeline.ope import ObjectProperties, ObjectPropertiesExtractor
from conceptbot.pipeline.retrieval import RelationRetriever
from conceptbot.systems import SystemOptions, build_system
from tests.pipeline.fakes import DictGraph, properties_reply, risk_reply, urp_reply


def test_summaries_are_short_and_mode_specific() -> None:
    props = ObjectProperties("egg", modes.PROPERTIES, {"fragile": "Yes", "safe": "Yes", "dangerous": "No"})
    assert props.summary() == "egg: fragile, safe"
    risk = ObjectProperties(
        "tray", modes.RISK, {"dangerous": 2, "dangerous_with": [{"object": "oven", "score": 5}]}
    )
    assert risk.summary() == "tray: danger 2/5, dangerous with oven (5)"
    mats = ObjectProperties("cup", modes.MATERIALS, {"materials": ["paper", "wax"], "single_material": False})
    assert mats.summary() == "cup: made of paper, wax (mixed materials)"


def test_results_are_cached_per_object_and_mode(tmp_path: Path) -> None:
    store = CacheStore(tmp_path / "c.db")
    retriever = RelationRetriever(DictGraph(), FakeEmbedder(), theta=0.1)
    llm = FakeLLM([properties_reply(dangerous="Yes"), properties_reply()])
    first = ObjectPropertiesExtractor(llm, retriever, store, "v1").run(["knife", "sponge"], modes.PROPERTIES)
    assert first.properties["knife"].values["dangerous"] == "Yes" and first.usage.calls == 2
    assert first.retrievals["knife"].kept  # the relations behind the answer come back with it
    again = ObjectPropertiesExtractor(FakeLLM(), retriever, store, "v1").run(
        ["knife", "sponge"], modes.PROPERTIES
    )
    knife = again.properties["knife"]
    assert knife.cached and knife.values == first.properties["knife"].values and again.usage.calls == 0
    # Another graph version is another key: the (empty) fake must be asked, and it raises.
    other = ObjectPropertiesExtractor(FakeLLM([properties_reply()]), retriever, store, "v2")
    assert not other.run(["sponge"], modes.PROPERTIES).properties["sponge"].cached
    # So are other facts from the same graph (the graph read another way): never a stale answer.
    read_otherwise = RelationRetriever(
        DictGraph({"knife": [("knife", "UsedFor", "spread butter")]}), FakeEmbedder(), theta=0.1
    )
    fresh = ObjectPropertiesExtractor(FakeLLM([properties_reply()]), read_otherwise, store, "v1")
    assert not fresh.run(["knife"], modes.PROPERTIES).properties["knife"].cached


def test_risk_mode_keeps_only_scene_partners_with_scene_spelling() -> None:
    llm = FakeLLM([risk_reply(4, [("user", 3)]), risk_reply(1)])
    result = (
        ObjectPropertiesExtractor(llm, None).run(["knife", "user"], modes.RISK, "give the knife").properties
    )
    assert result["knife"].values["dangerous_with"] == [{"object": "user", "score": 3}]
    assert "User request: give the knife" in llm.requests[0].messages[-1].content
    partners = json.loads(llm.requests[0].json_schema or "{}")["properties"]["dangerous_with"]
    assert partners["maxItems"] == 1 and partners["items"]["properties"]["object"]["enum"] == ["user"]
    # Unconstrained backends: names are mapped to the scene's spelling, unknown ones dropped.
    items = [
        {"object": "USER", "score": 3},
        {"object": "dragon", "score": 5},
        {"object": "knife", "score": 2},
    ]
    assert known_partners(items, ["knife", "user"], "knife") == [{"object": "user", "score": 3}]


def test_no_cache_neither_reads_nor_writes_ope_results(settings: Settings) -> None:
    """``--no-cache`` (``use_cache=False``) covers OPE: its results are derived from LLM answers.

    The same request twice: each run must ask OPE its questions again (a result read from the cache
    would leave the scripted replies out of step), and nothing may land in ``value_cache``.
    """
    one_run = [*[properties_reply()] * 3, '{"keywords": ["apple"]}']
    one_run += [urp_reply(["pick_and_place(apple, user)"]), "pick_and_place(apple, user)", "done()"]
    llm = FakeLLM(one_run * 2)
    planner = build_system(
        replace(settings, use_cache=False),
        "paper",
        SystemOptions(n=1, theta=0.1),
        llm=llm,
        graph=DictGraph(),
        embedder=FakeEmbedder(),
    )
    scene = scene_from_dict(
        {
            "objects": ["apple", "sponge", "user"],
            "pickable_objects": ["apple", "sponge"],
            "destinations": ["user"],
        }
    )
    for _ in range(2):
        plan = planner.plan("Bring me an apple", scene)
        assert format_actions(plan.actions) == ["pick_and_place(apple, user)", "done()"]
        assert plan.trace.ope is not None and plan.usage["ope"].calls == 3  # asked, not read
    assert len(llm.requests) == 2 * len(one_run)
    with sqlite3.connect(settings.cache_db) as conn:
        assert conn.execute("SELECT count(*) FROM value_cache").fetchone()[0] == 0
        chats = conn.execute("SELECT count(*) FROM calls WHERE kind = 'chat'").fetchone()[0]
    assert chats == 2 * len(one_run)  # the call log is kept: --no-cache is about the caches


def test_a_cache_that_fails_mid_run_costs_a_warning_not_the_answer(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    store = CacheStore(tmp_path / "c.db")
    with sqlite3.connect(tmp_path / "c.db") as other:  # the file is broken while OPE runs
        other.execute("DROP TABLE value_cache")
    llm = FakeLLM([properties_reply(dangerous="Yes")])
    with caplog.at_level(logging.WARNING):
        result = ObjectPropertiesExtractor(llm, None, store, "v1").run(["knife"], modes.PROPERTIES)
    assert result.properties["knife"].values["dangerous"] == "Yes"
    assert "could not read the cache" in caplog.text and "could not write the cache" in caplog.text
