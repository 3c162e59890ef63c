"""``conceptbot doctor``: what is installed and working, one line each."""

from __future__ import annotations

import ctypes
import importlib
import importlib.metadata
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import click

from conceptbot.cli.main import AppContext, pass_app
from conceptbot.core.config import DEFAULT_EMBEDDER, DEFAULT_LLM, Settings
from conceptbot.core.errors import ConceptBotError
from conceptbot.knowledge.registry import create_graph
from conceptbot.knowledge.sqlite_store import SQLiteGraph
from conceptbot.models import store
from conceptbot.models.registry import create_embedder, open_store, split_spec


@dataclass(frozen=True)
class Check:
    """One diagnostic line. ``required`` failures make ``doctor`` exit 1."""

    name: str
    ok: bool
    detail: str
    required: bool = True


def _version(dist: str) -> str:
    return importlib.metadata.version(dist)


def check_llama() -> Check:
    """llama-cpp-python imports (the embedded LLM runtime)."""
    try:
        import llama_cpp  # noqa: F401

        return Check("llama.cpp runtime", True, f"llama-cpp-python {_version('llama_cpp_python')}")
    except Exception as exc:  # a broken native build raises OSError, ImportError, ...
        return Check(
            "llama.cpp runtime", False, f"cannot import llama_cpp ({exc}); run bash scripts/install.sh"
        )


def check_model(settings: Settings) -> Check:
    """The configured (or default) local model is present and its sha256 is right."""
    name, argument = split_spec(settings.llm)
    if name != "llamacpp":
        return Check("local model", True, f"not used (LLM is {name})", required=False)
    model = argument or split_spec(DEFAULT_LLM)[1]
    if model not in store.catalogue():
        return Check(f"model {model}", True, "user-supplied GGUF file (no catalogue hash)", required=True)
    started = time.perf_counter()
    try:
        path = store.verify(settings.models_dir, model, full=True)
    except ConceptBotError as exc:
        return Check(f"model {model}", False, str(exc).replace("\n", " "))
    return Check(f"model {model}", True, f"sha256 ok ({time.perf_counter() - started:.1f} s) {path}")


def check_embedder(settings: Settings) -> Check:
    """The configured embedder loads and embeds a sentence."""
    try:
        started = time.perf_counter()
        vectors = create_embedder(settings.embedder, settings).embed(["a knife is a sharp object"])
        elapsed = time.perf_counter() - started
    except ConceptBotError as exc:
        return Check("embedder", False, str(exc).replace("\n", " "))
    return Check(
        "embedder",
        True,
        f"{settings.embedder or DEFAULT_EMBEDDER}: dim {vectors.shape[1]}, loaded in {elapsed:.1f} s",
    )


def check_knowledge(settings: Settings) -> Check:
    """The configured knowledge graph opens and knows about a common object."""
    try:
        graph = create_graph(settings.kg, settings)
        found = graph.edges("knife", limit=100)
    except ConceptBotError as exc:
        return Check("knowledge graph", False, str(exc).replace("\n", " "))
    detail = f"{settings.kg}: 'knife' has {len(found.edges)} edges"
    if isinstance(graph, SQLiteGraph):
        stats = graph.stats()
        per_source = ", ".join(f"{s['name']} {s['edges']:,}" for s in stats["sources"])
        detail = f"{stats['edges']:,} edges ({per_source}); " + detail
    return Check("knowledge graph", bool(found.edges), detail)


def _import_silently(module: str) -> None:
    """Import a module whose C code writes to the process's stdout/stderr (pybullet's build time)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "wb") as devnull:
            os.dup2(devnull.fileno(), 1)
            os.dup2(devnull.fileno(), 2)
            importlib.import_module(module)
            ctypes.CDLL(None).fflush(None)  # C stdio buffers, or the text appears at exit
    finally:
        for fd, copy in zip((1, 2), saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)


def check_pybullet() -> Check:
    """The simulator imports."""
    try:
        _import_silently("pybullet")
        return Check("pybullet", True, f"pybullet {_version('pybullet')}")
    except Exception as exc:
        return Check("pybullet", False, f"cannot import pybullet ({exc})")


def check_cache(settings: Settings) -> Check:
    """The cache database opens and is migrated."""
    try:
        db = open_store(settings)
        migrations = db.applied_migrations()
        db.close()
    except Exception as exc:  # sqlite3 errors, permissions
        return Check("cache database", False, f"{settings.cache_db}: {exc}")
    return Check("cache database", True, f"{settings.cache_db} (schema v{migrations[-1][0]}, WAL)")


CHECKS: list[Callable[[Settings], Check]] = [
    lambda s: check_llama(),
    check_model,
    check_embedder,
    check_knowledge,
    lambda s: check_pybullet(),
    check_cache,
]


@click.command()
@pass_app
def doctor(app: AppContext) -> None:
    """Check what is installed and working; exit 1 when the default stack is broken."""
    settings = app.settings
    click.echo(
        f"conceptbot {_version('conceptbot')} | home {settings.home}"
        f" | llm {settings.llm} | embedder {settings.embedder}"
    )
    broken = False
    for run in CHECKS:
        check = run(settings)
        if check.ok:
            mark, colour = "ok  ", "green"
        elif check.required:
            mark, colour, broken = "FAIL", "red", True
        else:
            mark, colour = "warn", "yellow"
        click.echo(click.style(f"[{mark}] ", fg=colour) + f"{check.name}: {check.detail}")
    if broken:
        raise click.exceptions.Exit(1)
