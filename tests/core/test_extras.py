"""A missing extra is named with its install command, not raised as an ImportError."""

from __future__ import annotations

import importlib.util
import sys

import pytest

from conceptbot.core import extras
from conceptbot.core.errors import BackendUnavailableError


def test_an_installed_extra_passes_and_a_missing_one_names_the_install_command(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    extras.require("sim")  # this environment has everything (the README's install)
    monkeypatch.setitem(sys.modules, "pybullet", None)  # as Python marks a module that cannot load
    assert extras.missing("sim") == ["pybullet"]
    with pytest.raises(BackendUnavailableError, match="simulator needs pybullet, which is not") as info:
        extras.require("sim")
    assert "pip install 'conceptbot[sim]'" in (info.value.hint or "")
    extras.require("sim", ("PIL",))  # only the modules asked for
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None if name == "uvicorn" else real(name))
    monkeypatch.delitem(sys.modules, "uvicorn", raising=False)
    assert extras.missing("web") == ["uvicorn"]  # never imported, and not on the path


def test_every_extra_in_pyproject_is_known_here() -> None:
    import tomllib
    from pathlib import Path

    project = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())["project"]
    declared = set(project["optional-dependencies"]) - {"all", "dev"}
    assert declared == set(extras.EXTRAS)
    assert not any(d.startswith(("torch", "pybullet", "llama-cpp")) for d in project["dependencies"])
