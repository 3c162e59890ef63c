"""Issue 32, item 10: a context size beyond what the model was trained on is a configuration error,
and a load that fails for the context or memory does not blame (or ask to reinstall) the model file.

No real model is loaded: the files are GGUF headers written here, and llama.cpp is replaced by a
stand-in that fails the way llama-cpp-python 0.3.36 does.
"""

from __future__ import annotations

import hashlib
import struct
import sys
import types
from pathlib import Path
from typing import Any

import pytest

from conceptbot.core.errors import BackendUnavailableError, ConfigError, ModelCorruptError
from conceptbot.models import weights
from conceptbot.models.llamacpp import LlamaCppLLM
from conceptbot.models.llm import ChatRequest


def _string(text: str) -> bytes:
    data = text.encode()
    return struct.pack("<Q", len(data)) + data


def write_gguf(path: Path, context: int, arch: str = "qwen2") -> Path:
    """A GGUF v3 header: arrays first (so the reader must skip them), then the architecture and its
    context length, as llama.cpp's converter writes them."""
    kvs = [
        _string("tokenizer.ggml.tokens") + struct.pack("<IIQ", 9, 8, 2) + _string("a") + _string("bc"),
        _string("tokenizer.ggml.token_type") + struct.pack("<IIQ", 9, 4, 3) + struct.pack("<3I", 1, 1, 3),
        _string("general.architecture") + struct.pack("<I", 8) + _string(arch),
        _string("llama.context_length") + struct.pack("<II", 4, 999),  # another architecture's key
        _string(f"{arch}.context_length") + struct.pack("<II", 4, context),
    ]
    path.write_bytes(b"GGUF" + struct.pack("<IQQ", 3, 0, len(kvs)) + b"".join(kvs))
    return path


def fake_llama(monkeypatch: pytest.MonkeyPatch, error: BaseException | None) -> list[dict[str, Any]]:
    """Replace llama_cpp.Llama; returns the keyword arguments of every construction."""
    calls: list[dict[str, Any]] = []

    def build(**kwargs: Any) -> Any:
        calls.append(kwargs)
        if error is not None:
            raise error
        return types.SimpleNamespace()

    module = types.ModuleType("llama_cpp")
    module.Llama = build  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "llama_cpp", module)
    return calls


def test_the_trained_context_is_read_from_the_header(tmp_path: Path) -> None:
    from conceptbot.models.llamacpp import trained_context  # new in issue 32 (the others run on old code)

    assert trained_context(write_gguf(tmp_path / "m.gguf", 32768)) == 32768
    (tmp_path / "junk.gguf").write_bytes(b"GGUF\x03\x00\x00\x00\xff")
    assert trained_context(tmp_path / "junk.gguf") is None
    assert trained_context(tmp_path / "absent.gguf") is None


def test_a_context_beyond_the_trained_one_is_refused_before_loading(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = fake_llama(monkeypatch, None)
    llm = LlamaCppLLM(write_gguf(tmp_path / "m.gguf", 32768), model="qwen", n_ctx=40000)
    with pytest.raises(ConfigError) as info:
        llm.chat(ChatRequest.of("hi"))
    assert "n_ctx 40000 is more than qwen was trained on (32768 tokens)" in str(info.value)
    assert "CONCEPTBOT_N_CTX" in (info.value.hint or "") and calls == []


@pytest.mark.parametrize("error", [ValueError("Failed to create llama_context"), MemoryError()])
def test_a_context_that_cannot_be_created_is_not_blamed_on_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, error: BaseException
) -> None:
    fake_llama(monkeypatch, error)
    llm = LlamaCppLLM(write_gguf(tmp_path / "m.gguf", 32768), n_ctx=32768)
    with pytest.raises(BackendUnavailableError) as info:
        llm.chat(ChatRequest.of("hi"))
    text = str(info.value)
    assert "could not create a context of 32768 tokens" in text and "lower CONCEPTBOT_N_CTX" in text
    assert "models install" not in text


def _catalogued(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A models folder holding a catalogue model ("tiny": the header file) that verify() stamped."""
    models = tmp_path / "models"
    models.mkdir()
    path = write_gguf(models / "tiny.gguf", 32768)
    data = path.read_bytes()
    entry = weights.ModelEntry("tiny", "", "tiny.gguf", len(data), hashlib.sha256(data).hexdigest(), "", {})
    monkeypatch.setattr(weights, "catalogue", lambda: {"tiny": entry})
    return weights.verify(models, "tiny")


def test_a_verified_file_that_fails_to_load_is_not_called_damaged(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = _catalogued(tmp_path, monkeypatch)
    fake_llama(monkeypatch, ValueError(f"Failed to load model from file: {path}"))
    with pytest.raises(BackendUnavailableError) as info:
        LlamaCppLLM(path).chat(ChatRequest.of("hi"))
    assert "sha256 is verified" in str(info.value) and "models install" not in str(info.value)


def test_an_unverified_file_that_fails_to_load_is_still_reported_corrupt(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = _catalogued(tmp_path, monkeypatch)
    path.write_bytes(path.read_bytes() + b"changed since it was verified")
    fake_llama(monkeypatch, ValueError(f"Failed to load model from file: {path}"))
    with pytest.raises(ModelCorruptError, match="models install NAME --force"):
        LlamaCppLLM(path).chat(ChatRequest.of("hi"))
