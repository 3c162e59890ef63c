"""Imports flow one way between the package's layers (the list in ``conceptbot/__init__.py``).

The check reads each module's source with :mod:`ast` (nothing is imported) and names every
conceptbot module it imports, at the top, inside functions or under ``if TYPE_CHECKING:``. An
import counts as upward when it reaches a layer of equal or higher rank than the importer's own, or
when it reaches the package top (``conceptbot/__init__.py``) itself: the top re-exports the API
(``conceptbot.api``, which sits on ``systems``), so ``import conceptbot`` or
``from conceptbot import __version__`` from inside a layer depends on everything above it. Only the
top-level ``api`` and ``__main__`` modules, which rank highest, may import the top. ``from conceptbot
import core`` names a layer, not the top, and counts as an import of that layer.

The checking functions take source text, so the tests at the bottom run them on small fakes.
"""

from __future__ import annotations

import ast
from pathlib import Path, PurePosixPath

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

#: What :func:`_layer` returns for ``conceptbot`` itself: the package top, which re-exports the API.
TOP = "conceptbot"

#: Only modules of this rank (``api``, ``__main__``) may import the package top.
TOP_RANK = max(RANK.values())


def own_layer(name: str) -> str:
    """The layer of a source file named relative to the package: ``pipeline/ope.py`` -> ``pipeline``."""
    return PurePosixPath(name).parts[0].removesuffix(".py")


def _layer(module: str) -> str | None:
    """``conceptbot.pipeline.ope`` -> ``pipeline``; :data:`TOP` for ``conceptbot``; None for others."""
    parts = module.split(".")
    if parts[0] != "conceptbot":
        return None
    return parts[1] if len(parts) > 1 else TOP


def imported_modules(source: str, name: str) -> set[str]:
    """Every conceptbot module the source of ``name`` (e.g. ``pipeline/ope.py``) imports.

    ``import conceptbot`` and ``from conceptbot import __version__`` give ``conceptbot`` (the top);
    ``from conceptbot import core`` gives ``conceptbot.core``. Relative imports are resolved against
    ``name``'s package, so ``from .. import __version__`` in ``knowledge/x.py`` gives the top too.
    """
    package = ["conceptbot", *PurePosixPath(name).parent.parts]  # the package ``name`` lives in
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            if module == "conceptbot":  # a layer by name, else a name the top defines or re-exports
                found |= {f"conceptbot.{a.name}" if a.name in RANK else TOP for a in node.names}
            elif module:
                found.add(module)
    return {m for m in found if m.split(".")[0] == "conceptbot"}


def upward_imports(source: str, name: str) -> list[str]:
    """The imports in the source of ``name`` that break the layering, as ``"<name> imports <module>"``."""
    own = own_layer(name)
    upward = []
    for module in sorted(imported_modules(source, name)):
        other = _layer(module)
        if other == TOP:
            bad = RANK[own] < TOP_RANK
        else:
            bad = other is not None and other != own and RANK.get(other, 99) >= RANK[own]
        if bad:
            upward.append(f"{name} imports {module}")
    return upward


def _sources() -> dict[str, Path]:
    """Layer-qualified source files: ``pipeline/ope.py`` -> its path (the package top excluded)."""
    return {
        p.relative_to(PACKAGE).as_posix(): p
        for p in PACKAGE.rglob("*.py")
        if p.parent != PACKAGE or p.stem in RANK
    }


def _imports(path: Path) -> set[str]:
    """Every conceptbot module the package's source file ``path`` imports."""
    return imported_modules(path.read_text(encoding="utf-8"), path.relative_to(PACKAGE).as_posix())


def test_every_layer_has_a_rank() -> None:
    layers = {own_layer(name) for name in _sources()}
    assert layers <= set(RANK), f"add {sorted(layers - set(RANK))} to RANK and to the layer list"


def test_no_layer_imports_a_higher_one() -> None:
    upward = [
        line
        for name, path in _sources().items()
        for line in upward_imports(path.read_text(encoding="utf-8"), name)
    ]
    assert upward == []


def test_cli_commands_never_import_the_command_group() -> None:
    # cli.main imports every command module; a command importing cli.main back is a cycle.
    commands = [p for p in (PACKAGE / "cli").glob("*.py") if p.stem != "main"]
    assert [p.name for p in commands if "conceptbot.cli.main" in _imports(p)] == []


# The check itself, on fake sources: it must report each kind of upward import and pass legal ones.


def test_checker_reports_the_version_from_the_package_top() -> None:
    """``from conceptbot import __version__`` in a layer imports the top, and with it the API."""
    source = "from conceptbot import __version__\n"
    assert upward_imports(source, "knowledge/conceptnet_api.py") == [
        "knowledge/conceptnet_api.py imports conceptbot"
    ]
    assert upward_imports(source, "cli/main.py") == ["cli/main.py imports conceptbot"]


def test_checker_reports_a_plain_import_of_the_package_top() -> None:
    """``import conceptbot`` (then ``conceptbot.something``) in a layer, even inside a function."""
    source = "def f():\n    import conceptbot\n\n    return conceptbot.open_planner()\n"
    assert upward_imports(source, "pipeline/ope.py") == ["pipeline/ope.py imports conceptbot"]
    assert upward_imports("import conceptbot as cb\n", "core/x.py") == ["core/x.py imports conceptbot"]


def test_checker_reports_a_relative_import_of_the_package_top() -> None:
    """``from .. import __version__`` in ``knowledge/x.py`` is ``from conceptbot import __version__``."""
    assert upward_imports("from .. import __version__\n", "knowledge/x.py") == [
        "knowledge/x.py imports conceptbot"
    ]
    assert upward_imports("from ...pipeline import ope\n", "core/sub/x.py") == [
        "core/sub/x.py imports conceptbot.pipeline"
    ]


def test_checker_reports_an_upward_import_between_layers() -> None:
    """core importing pipeline, in each import form, and a layer of equal rank (models <-> scenes)."""
    for source in (
        "from conceptbot.pipeline.ope import run\n",
        "import conceptbot.pipeline.ope\n",
        "from conceptbot import pipeline\n",
        "from typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n    from conceptbot.pipeline import ope\n",
    ):
        [found] = upward_imports(source, "core/plan.py")
        assert found.startswith("core/plan.py imports conceptbot.pipeline"), source
    assert upward_imports("from conceptbot.scenes import x\n", "models/llm.py") == [
        "models/llm.py imports conceptbot.scenes"
    ]


def test_checker_passes_downward_and_own_layer_imports() -> None:
    """Lower layers, the layer's own modules, a layer named from the top, the core version module."""
    source = (
        "import json\n"
        "from conceptbot.core.version import __version__\n"
        "from conceptbot.core.errors import ConfigError\n"
        "from conceptbot.knowledge.base import Edge\n"
        "from conceptbot import models\n"
        "from . import normalize\n"
        "import conceptbot.pipeline.goal.reader\n"
    )
    assert upward_imports(source, "pipeline/ope.py") == []
    assert imported_modules(source, "pipeline/ope.py") == {
        "conceptbot.core.version",
        "conceptbot.core.errors",
        "conceptbot.knowledge.base",
        "conceptbot.models",
        "conceptbot.pipeline",
        "conceptbot.pipeline.goal.reader",
    }


def test_checker_lets_the_api_modules_import_the_package_top() -> None:
    """``api`` and ``__main__`` rank highest, level with the top they are re-exported from."""
    for name in ("api.py", "__main__.py"):
        assert upward_imports("import conceptbot\nfrom conceptbot import __version__\n", name) == []
