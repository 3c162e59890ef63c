"""The HTTP backend against a real OpenAI-compatible server: llama.cpp's server with SmolLM2 on loopback."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

from conceptbot.baselines.saycan import SayCan
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.caching import CachedLLM
from conceptbot.models.http_scoring import echo_is_sound
from conceptbot.models.llm import ChatRequest, ScoreRequest
from conceptbot.models.openai_backend import OpenAILLM
from conceptbot.models.structured import chat_json
from tests.cli.test_bench_cli import bench_smoke
from tests.pipeline.fakes import spill_scene

pytestmark = pytest.mark.slow


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.fixture(scope="module")
def server_url(smollm2_path: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    port = _free_port()
    log = tmp_path_factory.mktemp("server") / "server.log"
    with open(log, "wb") as out:
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "llama_cpp.server",
                "--model",
                str(smollm2_path),
                "--model_alias",
                "smollm2",
                "--host",
                "127.0.0.1",
                "--port",
                str(port),
                "--n_ctx",
                "2048",
                "--logits_all",  # echo + logprobs on the completions endpoint needs every position's logits
                "true",
                "--verbose",
                "false",
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    url = f"http://127.0.0.1:{port}/v1"
    try:
        deadline = time.time() + 120
        while True:
            try:
                urllib.request.urlopen(url + "/models", timeout=2).read()
                break
            except OSError:
                if proc.poll() is not None or time.time() > deadline:
                    pytest.fail(f"llama_cpp.server did not start:\n{log.read_text()[-2000:]}")
                time.sleep(0.5)
        yield url
    finally:
        proc.terminate()
        proc.wait(30)


def test_chat_through_a_real_server(server_url: str) -> None:
    llm = OpenAILLM("smollm2", backend="openai-compatible", base_url=server_url, timeout_s=60, max_retries=1)
    response = llm.chat(ChatRequest.of("Name one fruit.", max_tokens=10))
    assert response.text.strip()
    assert response.usage.prompt_tokens > 0 and 0 < response.usage.completion_tokens <= 10


def test_n_and_json_schema_through_a_real_server(server_url: str) -> None:
    llm = OpenAILLM("smollm2", backend="openai-compatible", base_url=server_url, timeout_s=60, max_retries=1)
    response = llm.chat(ChatRequest.of("Write a word.", n=2, temperature=1.0, max_tokens=6, seed=5))
    assert len(response.choices) == 2
    schema = {"type": "object", "properties": {"fruit": {"type": "string"}}, "required": ["fruit"]}
    value, _ = chat_json(llm, ChatRequest.of("Name a fruit as JSON.", max_tokens=40), schema)
    assert isinstance(value["fruit"], str)


def test_cache_in_front_of_a_real_server(server_url: str, tmp_path: Path) -> None:
    inner = OpenAILLM(
        "smollm2", backend="openai-compatible", base_url=server_url, timeout_s=60, max_retries=1
    )
    llm = CachedLLM(inner, CacheStore(tmp_path / "cache.db"), module="test")
    first = llm.chat(ChatRequest.of("Say yes.", max_tokens=4))
    second = llm.chat(ChatRequest.of("Say yes.", max_tokens=4))
    assert not first.cached and second.cached and first.text == second.text


def test_scoring_through_a_real_server_finds_the_method_the_server_supports(server_url: str) -> None:
    llm = OpenAILLM("smollm2", backend="openai-compatible", base_url=server_url, timeout_s=60, max_retries=1)
    # llama-cpp-python 0.3.36 echoes each prompt token's log-probability after itself, not before
    # (abetlen/llama-cpp-python#1983): the probe must refuse it; its completions' top log-probabilities
    # of a generated token are sound, so prompts are scored by search, chat questions by chat ones.
    assert echo_is_sound(llm) is False
    question = ChatRequest.of("Is an apple a fruit? Answer Yes or No.").messages
    yes_no = llm.score(ScoreRequest(options=("Yes", "No"), messages=question))
    assert yes_no.method == "chat-logprobs" and all(lp <= 0.0 for lp in yes_no.logprobs)
    options = ("pick_and_place(apple, user)", "pick_and_place(sponge, user)", "done()")
    script = "objects = [apple, sponge, user]\n# Bring me a fruit.\n"
    searched = llm.score(ScoreRequest(options=options, prompt=script))
    assert searched.method == "search" and len(searched.logprobs) == 3
    best = max(range(3), key=searched.logprobs.__getitem__)
    alone = llm.score(ScoreRequest(options=options[best : best + 1], prompt=script))  # read to its end
    assert alone.logprobs[0] == pytest.approx(searched.logprobs[best], abs=0.05)  # the best is exact
    plan = SayCan(llm, max_steps=2).plan("Bring me the chips", spill_scene())
    assert [step.to_dict()["scoring"] for step in plan.steps] == ["search"] * len(plan.steps)


def test_bench_run_through_a_real_server(
    server_url: str, isolated_home: Path, omcs_file: Path, wordnet_dir: Path, tmp_path: Path
) -> None:
    out = tmp_path / "http.jsonl"
    llm = f"openai-compatible:{server_url}#smollm2"
    _, stdout, records = bench_smoke(llm, "risk", isolated_home, omcs_file, wordnet_dir, out, limit=2)
    assert "options scored by search (prompts), chat-logprobs (chat) (openai-compatible)" in stdout
    assert len(records) == 4 and all(
        r["backend"] == "openai-compatible" and r["plan"][-1] == "done()" for r in records
    ), records
    assert {r["scoring"] for r in records} == {"search (prompts), chat-logprobs (chat)"}
