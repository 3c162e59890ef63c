import json
from pathlib import Path

from conceptbot.models.cache_db import CacheStore
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline import modes
from conceptbot.pipeline.modes import known_partners
from conceptbot.pipeline.ope import ObjectProperties, ObjectPropertiesExtractor
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph, properties_reply, risk_reply


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
