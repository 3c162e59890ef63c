"""Shared fixtures: every test gets its own home directory and a clean environment."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from conceptbot.core.config import Settings, load_settings

pytest_plugins = ["tests.kg_sources"]

_VARS = ("CONCEPTBOT_", "OPENAI_")


@pytest.fixture(autouse=True)
def isolated_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Point HOME and CONCEPTBOT_HOME at a temp dir and drop user configuration variables."""
    for var in list(os.environ):
        if var.startswith(_VARS):
            monkeypatch.delenv(var)
    home = tmp_path / "home"
    monkeypatch.setenv("HOME", str(tmp_path / "user"))
    monkeypatch.setenv("CONCEPTBOT_HOME", str(home))
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    return home


@pytest.fixture
def settings(isolated_home: Path) -> Settings:
    """Settings resolved inside the isolated home."""
    return load_settings()


@pytest.fixture(scope="session")
def smollm2_models_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A models folder with the small real model (SmolLM2-135M) joined into it, once per session."""
    from conceptbot.models import weights

    folder = tmp_path_factory.mktemp("models")
    weights.install(folder, "smollm2-135m")
    return folder


@pytest.fixture(scope="session")
def smollm2_path(smollm2_models_dir: Path) -> Path:
    """Path of the joined SmolLM2-135M GGUF file."""
    from conceptbot.models import weights

    return weights.model_path(smollm2_models_dir, weights.get_entry("smollm2-135m"))
