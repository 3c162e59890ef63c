"""The Python API at the package top, as a user's own code calls it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import conceptbot
from conceptbot.core.plan import format_actions
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.models.registry import open_store
from tests.pipeline.fakes import DictGraph, properties_reply, urp_reply

SCENE = {
    "name": "tiny",
    "objects": ["apple", "sponge", "user"],
    "pickable_objects": ["apple", "sponge"],
    "destinations": ["user"],
}
# The paper's pipeline, one vote per step: OPE for each of the 3 objects, then URP, then the steps.
OPE = [properties_reply()] * 3
URP = [urp_reply(["pick_and_place(apple, user)"])]
STEPS = ["pick_and_place(apple, user)", "done()"]
ONE_VOTE = conceptbot.SystemOptions(n=1, theta=0.1)


def test_a_planner_from_backend_objects_plans_with_them() -> None:
    llm = FakeLLM([*OPE, '{"keywords": ["apple"]}', *URP, *STEPS])
    graph = DictGraph()
    planner = conceptbot.open_planner(
        "paper", llm=llm, graph=graph, embedder=FakeEmbedder(), options=ONE_VOTE
    )
    result = planner.plan("Bring me an apple", conceptbot.scene_from_dict(SCENE))
    assert format_actions(result.actions) == ["pick_and_place(apple, user)", "done()"]
    assert result.refused is False and result.reason is None
    assert (
        result.to_dict()["plan"] == format_actions(result.actions)
        and result.trace.ope is not None
        and result.trace.urp is not None
    )
    assert "apple" in graph.asked and len(llm.requests) == 7  # the objects given did the work
    # Like a configured backend, the model went behind the call log, each call under its module.
    modules = {call.module for call in open_store(conceptbot.load_settings()).calls() if call.kind == "chat"}
    assert modules == {"ope", "urp", "planner"}


def test_a_planner_from_settings_with_a_backend_spec(tmp_path: Path) -> None:
    replies = tmp_path / "replies.json"
    replies.write_text(json.dumps([*OPE, *URP, *STEPS]))
    planner = conceptbot.open_planner("paper-nokg", llm=f"fake:{replies}", options=ONE_VOTE, use_cache=False)
    result = planner.plan("Bring me an apple", conceptbot.load_scene(_scene_file(tmp_path)))
    assert format_actions(result.actions) == ["pick_and_place(apple, user)", "done()"]
    assert set(result.to_dict()["usage"]) == {"ope", "urp", "planner", "total"}


def test_settings_passed_in_take_the_overrides(tmp_path: Path) -> None:
    replies = tmp_path / "replies.json"
    replies.write_text(json.dumps([*OPE, *URP, *STEPS]))
    settings = conceptbot.load_settings(llm="openai:gpt-4o-mini")  # overridden below
    planner = conceptbot.open_planner(
        "paper-nokg", settings=settings, llm=f"fake:{replies}", options=ONE_VOTE, home=tmp_path / "other"
    )
    result = planner.plan("Bring me an apple", conceptbot.load_scene(_scene_file(tmp_path)))
    assert format_actions(result.actions) == ["pick_and_place(apple, user)", "done()"]
    assert (tmp_path / "other" / "cache.db").is_file()  # the cache went to the overriding home


def test_demo_scenes_load_by_name_and_files_by_path(tmp_path: Path) -> None:
    kitchen = conceptbot.load_scene("kitchen")
    assert isinstance(kitchen, conceptbot.Scene) and kitchen.name == "kitchen"
    assert conceptbot.load_scene(_scene_file(tmp_path)).name == "tiny"
    with pytest.raises(conceptbot.ConfigError, match="unknown demo scene"):
        conceptbot.load_scene("no-such-scene")


def test_unknown_system_names_the_known_ones() -> None:
    with pytest.raises(conceptbot.ConfigError, match="unknown system 'gpt'") as caught:
        conceptbot.open_planner("gpt")
    assert "saycan" in (caught.value.hint or "") and "paper-nokg" in (caught.value.hint or "")


def test_unknown_settings_and_misplaced_options_say_where_they_belong() -> None:
    with pytest.raises(conceptbot.ConfigError, match="unknown setting 'temperature'") as caught:
        conceptbot.open_planner(temperature=0.2)
    assert "use_cache" in (caught.value.hint or "")
    with pytest.raises(conceptbot.ConfigError, match="theta is a system option") as caught:
        conceptbot.open_planner(theta=0.5)
    assert "SystemOptions(theta=...)" in (caught.value.hint or "")
    with pytest.raises(conceptbot.ConfigError, match="must be a SystemOptions"):
        conceptbot.open_planner(options={"n": 3})  # type: ignore[arg-type]


def test_an_object_missing_part_of_its_protocol_is_named() -> None:
    class HalfLLM:
        backend = "mine"
        model = "m"

        def chat(self, request):  # no capabilities, score or with_module
            raise AssertionError("never called")

    with pytest.raises(conceptbot.ConfigError, match=r"llm must implement conceptbot\.LLM") as caught:
        conceptbot.open_planner(llm=HalfLLM())
    assert "capabilities, score, with_module" in str(caught.value)
    with pytest.raises(conceptbot.ConfigError, match=r"graph must implement conceptbot\.KnowledgeGraph"):
        conceptbot.open_planner(graph=object())


def test_import_is_cheap_and_the_api_loads_no_model_runtime() -> None:
    code = (
        "import sys, conceptbot\n"
        "heavy = ('torch', 'llama_cpp', 'sentence_transformers', 'conceptbot.api', 'conceptbot.pipeline')\n"
        "print(sorted(m for m in heavy if m in sys.modules))\n"
        "conceptbot.open_planner, conceptbot.SystemOptions, conceptbot.LLM\n"
        "print(sorted(m for m in heavy[:3] if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.splitlines() == ["[]", "[]"]


def test_every_listed_name_is_there() -> None:
    assert set(conceptbot.__all__) == {"__version__", *conceptbot._EXPORTS}
    assert all(getattr(conceptbot, name) is not None for name in conceptbot.__all__)
    with pytest.raises(AttributeError, match="no attribute 'plan'"):
        conceptbot.plan  # noqa: B018


def _scene_file(folder: Path) -> str:
    path = folder / "tiny.json"
    path.write_text(json.dumps(SCENE))
    return str(path)
