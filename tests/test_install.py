"""`pip install .` with no extras: a fresh virtual environment without torch, PyBullet or llama.cpp
builds a graph and plans through an OpenAI-compatible server (llama.cpp's server with the small real
model on loopback, embeddings from a loopback server in OpenAI's format)."""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.loopback import LoopbackServer, Request
from tests.models.test_llama_server import server_url  # noqa: F401 (the llama.cpp server fixture)

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("torch", "pybullet", "llama_cpp", "sentence_transformers")
SCENE = {
    "name": "tiny",
    "objects": ["apple", "sponge", "user"],
    "pickable_objects": ["apple", "sponge"],
    "destinations": ["user"],
}


class EmbeddingServer(LoopbackServer):
    """``POST /v1/embeddings`` in OpenAI's format: a hashed bag of words per input (unit length)."""

    def respond(self, request: Request) -> tuple[int, dict[str, Any]]:
        body = json.loads(request.body or b"{}")
        texts = body.get("input") or []
        texts = [texts] if isinstance(texts, str) else texts
        data = [{"object": "embedding", "index": i, "embedding": _vector(t)} for i, t in enumerate(texts)]
        used = sum(len(t.split()) for t in texts)
        return 200, {
            "object": "list",
            "data": data,
            "model": body.get("model", ""),
            "usage": {"prompt_tokens": used, "total_tokens": used},
        }


def _vector(text: str, size: int = 64) -> list[float]:
    vec = [0.0] * size
    for word in re.findall(r"[a-z]+", text.lower()):
        vec[int(hashlib.sha256(word.encode()).hexdigest(), 16) % size] += 1.0
    norm = math.sqrt(sum(v * v for v in vec)) or 1.0
    return [v / norm for v in vec]


@pytest.fixture(scope="module")
def bare_venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A fresh virtual environment with ``pip install .`` and no extras (versions as locked)."""
    venv = tmp_path_factory.mktemp("bare") / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "-q", "--disable-pip-version-check"]
    done = subprocess.run(
        [*pip, "-c", str(ROOT / "requirements.lock"), str(ROOT)],
        capture_output=True,
        text=True,
        timeout=1500,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return venv


@pytest.fixture
def embeddings() -> Iterator[str]:
    with EmbeddingServer() as server:
        yield f"{server.base_url}/v1"


def _env(home: Path, embeddings_url: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CONCEPTBOT_", "OPENAI_"))}
    env.update(CONCEPTBOT_HOME=str(home), OPENAI_BASE_URL=embeddings_url, OPENAI_API_KEY="loopback")
    return env


def _install_graph(cli: list[str], env: dict[str, str], omcs_file: Path, wordnet_dir: Path) -> None:
    """``conceptbot kg install`` from the small local OMCS and WordNet files, into ``env``'s home."""
    graph = subprocess.run(
        [*cli, "kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir)],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert graph.returncode == 0, graph.stderr[-2000:]


def test_a_plain_install_has_none_of_the_heavy_runtimes(bare_venv: Path) -> None:
    found = f"{{m: bool(u.find_spec(m)) for m in {HEAVY!r}}}"
    probe = f"import importlib.util as u, json; print(json.dumps({found}))"
    python = str(bare_venv / "bin" / "python")
    out = subprocess.run([python, "-c", probe], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == dict.fromkeys(HEAVY, False)


def test_a_plain_install_builds_a_graph_and_plans_through_an_openai_compatible_server(
    bare_venv: Path,
    server_url: str,  # noqa: F811
    embeddings: str,
    omcs_file: Path,
    wordnet_dir: Path,
    tmp_path: Path,
) -> None:
    cli = str(bare_venv / "bin" / "conceptbot")
    env = _env(tmp_path / "home", embeddings)
    _install_graph([cli], env, omcs_file, wordnet_dir)
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SCENE))
    llm = f"openai-compatible:{server_url}#smollm2"
    args = ["--llm", llm, "--embedder", "openai:hashed-words", "plan", "Bring me an apple"]
    out = subprocess.run(
        [cli, *args, "--scene", str(scene), "--json", "--no-fallback"],
        capture_output=True,
        text=True,
        env=env,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    data = json.loads(out.stdout)
    assert data["plan"][-1] == "done()"
    assert data["trace"]["goal"]["targets"][0]["named"] == ["apple"]
    if not data["refused"]:
        assert data["plan"] == ["pick_and_place(apple, user)", "done()"]
    assert data["usage"]["total"]["prompt_tokens"] > 0


def test_planning_over_http_never_imports_the_heavy_runtimes(
    server_url: str,  # noqa: F811
    embeddings: str,
    omcs_file: Path,
    wordnet_dir: Path,
    tmp_path: Path,
) -> None:
    """Where they are installed (this environment), planning through a server still leaves PyBullet,
    llama.cpp and sentence-transformers out. (torch is imported by spaCy's thinc whenever it is
    installed: the bare environment above shows a plan needs none of it.)"""
    env = _env(tmp_path / "home", embeddings)
    _install_graph([sys.executable, "-m", "conceptbot"], env, omcs_file, wordnet_dir)
    script = f"""
import json, sys
import conceptbot
planner = conceptbot.open_planner(
    llm="openai-compatible:{server_url}#smollm2", embedder="openai:hashed-words", kg_fallback=False
)
plan = planner.plan("Bring me an apple", conceptbot.scene_from_dict({SCENE!r}))
loaded = [m for m in {HEAVY!r} if m in sys.modules]
print(json.dumps({{"plan": conceptbot.format_actions(plan.actions), "loaded": loaded}}))
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    data = json.loads(out.stdout.strip().splitlines()[-1])
    assert data["plan"][-1] == "done()" and set(data["loaded"]) <= {"torch"}
