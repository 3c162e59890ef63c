"""Imports flow one way between the package's layers (the list in ``conceptbot/__init__.py``)."""

from __future__ import annotations

import ast
from pathlib import Path

import conceptbot

PACKAGE = Path(conceptbot.__file__).parent

# A layer may import its own modules and those of lower rank, never a higher or equal other layer.
RANK = {
    "core": 0,
    "schemas": 0,  # data only (JSON Schema files core reads as package resources)
    "models": 1,
    "scenes": 1,
    "knowledge": 2,
    "pipeline": 3,
    "baselines": 4,
    "household": 4,
    "systems": 5,
    "sim": 6,
    "bench": 6,
    "web": 7,
    "ros2": 7,  # the ROS 2 node: plans through systems, like the web page
    "cli": 8,
    "api": 9,
    "__main__": 9,
}


def _layer(module: str) -> str | None:
    """``conceptbot.pipeline.ope`` -> ``pipeline``; None for the package top itself."""
    parts = module.split(".")
    return parts[1] if parts[0] == "conceptbot" and len(parts) > 1 else None


def _imports(path: Path) -> set[str]:
    """Every conceptbot module ``path`` imports, at the top or inside functions."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "conceptbot":  # from conceptbot import core / __version__
                found |= {f"conceptbot.{a.name}" for a in node.names if a.name in RANK}
            found.add(node.module)
    return {m for m in found if m.split(".")[0] == "conceptbot"}


def _sources() -> dict[str, Path]:
    """Layer-qualified source files: ``pipeline/ope.py`` -> its path (the package top excluded)."""
    return {
        str(p.relative_to(PACKAGE)): p for p in PACKAGE.rglob("*.py") if p.parent != PACKAGE or p.stem in RANK
    }


def test_every_layer_has_a_rank() -> None:
    layers = {Path(name).parts[0].removesuffix(".py") for name in _sources()}
    assert layers <= set(RANK), f"add {sorted(layers - set(RANK))} to RANK and to the layer list"


def test_no_layer_imports_a_higher_one() -> None:
    upward = []
    for name, path in _sources().items():
        own = Path(name).parts[0].removesuffix(".py")
        for module in _imports(path):
            other = _layer(module)
            if other is not None and other != own and RANK.get(other, 99) >= RANK[own]:
                upward.append(f"{name} imports {module}")
    assert upward == []


def test_cli_commands_never_import_the_command_group() -> None:
    # cli.main imports every command module; a command importing cli.main back is a cycle.
    commands = [p for p in (PACKAGE / "cli").glob("*.py") if p.stem != "main"]
    assert [p.name for p in commands if "conceptbot.cli.main" in _imports(p)] == []
