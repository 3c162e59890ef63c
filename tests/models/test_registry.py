import json
from pathlib import Path

import pytest

from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError, ModelNotInstalledError
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.models.openai_backend import OpenAILLM
from conceptbot.models.registry import create_embedder, create_llm, open_llm, split_spec


def test_split_spec() -> None:
    assert split_spec("openai-compatible:http://h:1/v1#m") == ("openai-compatible", "http://h:1/v1#m")
    assert split_spec("fake") == ("fake", "")


def test_unknown_backend_lists_the_known_ones(settings: Settings) -> None:
    with pytest.raises(ConfigError, match="unknown LLM backend 'gpt'") as info:
        create_llm("gpt:4", settings)
    assert "llamacpp" in str(info.value)
    with pytest.raises(ConfigError, match="unknown embedder"):
        create_embedder("word2vec", settings)


@pytest.mark.parametrize(
    "spec",
    [
        "openai-compatible:localhost:8000#m",
        "openai-compatible:ftp://host/v1#m",
        "openai-compatible:http://#m",
        "openai-compatible:http://host:99999/v1#m",
    ],
)
def test_malformed_base_url(settings: Settings, spec: str) -> None:
    with pytest.raises(ConfigError, match="malformed base URL"):
        create_llm(spec, settings)


def test_compatible_spec_needs_a_model(settings: Settings) -> None:
    with pytest.raises(ConfigError, match="BASE_URL#MODEL"):
        create_llm("openai-compatible:http://127.0.0.1:8000/v1", settings)


def test_openai_needs_a_key(settings: Settings) -> None:
    with pytest.raises(ConfigError, match="OPENAI_API_KEY"):
        create_llm("openai:gpt-4o-mini", settings)


def test_openai_compatible_builds_without_a_key(settings: Settings) -> None:
    llm = create_llm("openai-compatible:http://127.0.0.1:8000/v1/#qwen", settings)
    assert isinstance(llm, OpenAILLM) and llm.model == "qwen" and llm.base_url == "http://127.0.0.1:8000/v1"


def test_missing_local_model_names_the_install_command(settings: Settings) -> None:
    with pytest.raises(ModelNotInstalledError, match=r"conceptbot models install qwen2\.5-coder-0\.5b"):
        create_llm("llamacpp:qwen2.5-coder-0.5b", settings)


def test_a_path_to_an_installed_catalogue_file_is_that_model(settings: Settings, tmp_path: Path) -> None:
    from conceptbot.models import weights

    installed = weights.model_path(settings.models_dir, weights.get_entry("qwen2.5-coder-0.5b"))
    installed.parent.mkdir(parents=True, exist_ok=True)
    installed.write_bytes(b"GGUF")  # not loaded: the backend opens the file on its first call
    assert create_llm(f"llamacpp:{installed}", settings).model == "qwen2.5-coder-0.5b"
    own = tmp_path / "mine.gguf"
    own.write_bytes(b"GGUF")
    assert create_llm(f"llamacpp:{own}", settings).model == "mine.gguf"


def test_fake_backends(settings: Settings, tmp_path: Path) -> None:
    replies = tmp_path / "r.json"
    replies.write_text(json.dumps(["hello"]))
    llm = create_llm(f"fake:{replies}", settings)
    assert isinstance(llm, FakeLLM)
    assert isinstance(create_embedder("fake", settings), FakeEmbedder)
    bad = tmp_path / "bad.json"
    bad.write_text('{"not": "a list"}')
    with pytest.raises(ConfigError, match="JSON list"):
        create_llm(f"fake:{bad}", settings)


def test_open_llm_wraps_with_cache(settings: Settings, tmp_path: Path) -> None:
    replies = tmp_path / "r.json"
    replies.write_text(json.dumps(["hello"]))
    llm = open_llm(settings.with_overrides(llm=f"fake:{replies}"), module="cli")
    assert llm.module == "cli" and llm.store is not None and llm.store.path == settings.cache_db
