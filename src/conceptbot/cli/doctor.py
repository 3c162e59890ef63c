"""``conceptbot doctor``: what is installed and working, one line each.

Every check runs on its own: an unexpected exception in one (a corrupt database page, a broken
native library) becomes a failing line, never a stack trace, and the other checks still run.
HTTP backends are contacted once with a one-token request, so "doctor is green" means the server
is up, knows the model and accepts the key. Everything printed is passed through
:func:`conceptbot.core.urls.redact_secrets` (specs may carry keys in their URLs) and
:func:`conceptbot.core.text.terminal_safe` (details quote servers' error bodies and exceptions).
"""

from __future__ import annotations

import contextlib
import ctypes
import importlib
import importlib.metadata
import os
import sqlite3
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import click

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.core.config import DEFAULT_EMBEDDER, DEFAULT_LLM, Settings
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.text import terminal_safe
from conceptbot.core.urls import redact_secrets
from conceptbot.knowledge.registry import create_graph
from conceptbot.knowledge.sqlite_store import SQLiteGraph
from conceptbot.models import weights
from conceptbot.models.cache_db import CacheError
from conceptbot.models.llm import ChatRequest
from conceptbot.models.registry import create_embedder, create_llm, open_store, scoring_method, split_spec

HTTP_BACKENDS = ("openai", "openai-compatible")
# A health check should answer within seconds; the user's time-out is for long generations.
PROBE_TIMEOUT_S = 20.0


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
    if model not in weights.catalogue():
        return Check(f"model {model}", True, "user-supplied GGUF file (no catalogue hash)", required=True)
    started = time.perf_counter()
    try:
        path = weights.verify(settings.models_dir, model, full=True)
    except ConceptBotError as exc:
        return Check(f"model {model}", False, _one_line(exc))
    return Check(f"model {model}", True, f"sha256 ok ({time.perf_counter() - started:.1f} s) {path}")


def check_llm_server(settings: Settings) -> Check:
    """An HTTP LLM backend answers a one-token chat request (server up, model known, key accepted).

    Sent once, without retries, so a dead server fails in one time-out rather than after backoff.
    """
    name, _ = split_spec(settings.llm)
    if name not in HTTP_BACKENDS:
        return Check("LLM server", True, f"not used (LLM is {name})", required=False)
    probe = settings.with_overrides(max_retries=0, timeout_s=min(settings.timeout_s, PROBE_TIMEOUT_S))
    started = time.perf_counter()
    try:
        llm = create_llm(settings.llm, probe)
        llm.chat(ChatRequest.of("Say OK.", max_tokens=1))
    except ConceptBotError as exc:
        return Check(f"LLM server ({name})", False, _one_line(exc))
    elapsed = time.perf_counter() - started
    try:
        scoring = scoring_method(probe)
    except ConceptBotError as exc:
        scoring = f"not available ({_one_line(exc)})"
    return Check(
        f"LLM server ({name})",
        True,
        f"model {llm.model!r} answered in {elapsed:.2f} s; options scored by {scoring}",
    )


def _one_line(exc: ConceptBotError) -> str:
    return exc.message if not exc.hint else f"{exc.message} ({exc.hint})"


def check_embedder(settings: Settings) -> Check:
    """The configured embedder loads and embeds a sentence."""
    try:
        started = time.perf_counter()
        vectors = create_embedder(settings.embedder, settings).embed(["a knife is a sharp object"])
        elapsed = time.perf_counter() - started
    except ConceptBotError as exc:
        return Check("embedder", False, _one_line(exc))
    return Check(
        "embedder",
        True,
        f"{settings.embedder or DEFAULT_EMBEDDER}: dim {vectors.shape[1]}, loaded in {elapsed:.1f} s",
    )


def check_knowledge(settings: Settings) -> Check:
    """The configured knowledge graph opens and knows about a common object."""
    graph = None
    try:
        graph = create_graph(settings.kg, settings)
        found = graph.edges("knife", limit=100)
        detail = f"{settings.kg}: 'knife' has {len(found.edges)} edges"
        if isinstance(graph, SQLiteGraph):
            stats = graph.stats()
            per_source = ", ".join(f"{s['name']} {s['edges']:,}" for s in stats["sources"])
            detail = f"{stats['edges']:,} edges ({per_source}); " + detail
    except ConceptBotError as exc:
        return Check("knowledge graph", False, _one_line(exc))
    except sqlite3.DatabaseError as exc:  # pages corrupted past the header, found only when read
        where = settings.kg_path if split_spec(settings.kg)[0] == "sqlite" else settings.kg
        return Check(
            "knowledge graph", False, f"{where} is damaged ({exc}); rebuild it with `conceptbot kg install`"
        )
    finally:
        close = getattr(graph, "close", None)
        # A failure to close a read-only graph changes nothing the user can act on.
        if callable(close):
            with contextlib.suppress(Exception):
                close()
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


def check_ros2() -> Check:
    """ROS 2 for ``conceptbot ros2`` imports (optional: only the ROS 2 node needs it)."""
    try:
        _import_silently("rclpy")
        _import_silently("rmw_fastrtps_cpp")
    except ImportError:
        return Check(
            "ROS 2",
            False,
            "not installed (only `conceptbot ros2` needs it: pip install 'conceptbot[ros2]')",
            required=False,
        )
    versions = f"rclpy {_version('ros-rclpy')}, Fast DDS {_version('ros-fastdds')}"
    try:
        _import_silently("conceptbot_interfaces.action")
    except ImportError:
        versions += "; no Plan action (conceptbot_interfaces not built: bash scripts/build_interfaces.sh)"
    else:
        versions += ", conceptbot_interfaces (the Plan action)"
    return Check("ROS 2", True, versions, required=False)


def check_cache(settings: Settings) -> Check:
    """The cache database opens and is migrated."""
    try:
        db = open_store(settings)
        migrations = db.applied_migrations()
        db.close()
    except CacheError as exc:  # names the file and the fix already
        return Check("cache database", False, _one_line(exc))
    except Exception as exc:  # anything else the check did not expect
        return Check("cache database", False, f"{settings.cache_db}: {exc}")
    return Check("cache database", True, f"{settings.cache_db} (schema v{migrations[-1][0]}, WAL)")


# (name for the failing line if the check itself crashes, check)
CHECKS: list[tuple[str, Callable[[Settings], Check]]] = [
    ("llama.cpp runtime", lambda s: check_llama()),
    ("local model", check_model),
    ("LLM server", check_llm_server),
    ("embedder", check_embedder),
    ("knowledge graph", check_knowledge),
    ("pybullet", lambda s: check_pybullet()),
    ("ROS 2", lambda s: check_ros2()),
    ("cache database", check_cache),
]


def run_check(name: str, check: Callable[[Settings], Check], settings: Settings) -> Check:
    """Run one check; any exception it lets through becomes a required failure named ``name``."""
    try:
        return check(settings)
    except ConceptBotError as exc:
        return Check(name, False, _one_line(exc))
    except Exception as exc:  # doctor exists to report breakage, so it must not crash on it
        return Check(name, False, f"unexpected {type(exc).__name__}: {exc}")


def _version_or_unknown(dist: str) -> str:
    try:
        return _version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "(not installed as a package)"


@click.command()
@pass_app
def doctor(app: AppContext) -> None:
    """Check what is installed and working; exit 1 when the default stack is broken."""
    settings = app.settings
    header = (
        f"conceptbot {_version_or_unknown('conceptbot')} | home {settings.home}"
        f" | llm {settings.llm} | embedder {settings.embedder}"
    )
    click.echo(terminal_safe(redact_secrets(header)))
    broken = False
    for name, run in CHECKS:
        check = run_check(name, run, settings)
        detail = terminal_safe(redact_secrets(" ".join(str(check.detail).split())))
        if check.ok:
            mark, colour = "ok  ", "green"
        elif check.required:
            mark, colour, broken = "FAIL", "red", True
        else:
            mark, colour = "warn", "yellow"
        click.echo(click.style(f"[{mark}] ", fg=colour) + f"{terminal_safe(check.name)}: {detail}")
    if broken:
        raise click.exceptions.Exit(1)
