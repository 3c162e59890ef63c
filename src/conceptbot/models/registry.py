"""Backends by name. Built-in backends register through the same functions as third-party ones.

LLM specs (``CONCEPTBOT_LLM`` or ``--llm``)::

    llamacpp[:NAME_OR_PATH]              embedded; NAME from `conceptbot models list` or a .gguf path
    openai:MODEL                         the OpenAI API (OPENAI_API_KEY)
    openai-compatible:BASE_URL#MODEL     vLLM, Ollama, llama.cpp server, ... (CONCEPTBOT_API_KEY)
    fake[:REPLIES.json]                  scripted replies from a JSON list (tests, demos of the CLI)

Embedder specs (``CONCEPTBOT_EMBEDDER`` or ``--embedder``)::

    sentence-transformers[:MODEL]        default all-MiniLM-L6-v2 (bundled, offline)
    openai:MODEL                         e.g. text-embedding-ada-002, text-embedding-3-small
    fake                                 hashing embedder (tests)

Key routing: OPENAI_API_KEY goes only to the ``openai`` backends (LLM and embedder), that is to the
OpenAI API or to OPENAI_BASE_URL when the user set it. ``openai-compatible`` servers get
CONCEPTBOT_API_KEY or no key at all, never OPENAI_API_KEY: BASE_URL may point anywhere.
"""

from __future__ import annotations

import enum
import json
import logging
from collections.abc import Callable
from pathlib import Path

from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError
from conceptbot.core.urls import redact_secrets
from conceptbot.models.cache_db import OR_NO_CACHE, CacheError, CacheStore
from conceptbot.models.caching import CachedEmbedder, CachedLLM
from conceptbot.models.embedder import Embedder
from conceptbot.models.llm import LLM

LLMFactory = Callable[[str, Settings], LLM]
EmbedderFactory = Callable[[str, Settings], Embedder]

logger = logging.getLogger(__name__)


class _Default(enum.Enum):
    """``open_llm(settings)`` without a store: open the run's store (None is "no store")."""

    STORE = "the store of open_run_store(settings)"


_RUN_STORE = _Default.STORE

_LLMS: dict[str, LLMFactory] = {}
_EMBEDDERS: dict[str, EmbedderFactory] = {}


def register_llm(name: str, factory: LLMFactory) -> None:
    """Register an LLM backend factory: ``factory(argument, settings) -> LLM``."""
    _LLMS[name] = factory


def register_embedder(name: str, factory: EmbedderFactory) -> None:
    """Register an embedder factory: ``factory(argument, settings) -> Embedder``."""
    _EMBEDDERS[name] = factory


def llm_backends() -> list[str]:
    """Names of registered LLM backends."""
    return sorted(_LLMS)


def embedder_backends() -> list[str]:
    """Names of registered embedder backends."""
    return sorted(_EMBEDDERS)


def split_spec(spec: str) -> tuple[str, str]:
    """``"backend:argument"`` -> ``("backend", "argument")`` (argument may be empty)."""
    name, _, argument = spec.strip().partition(":")
    return name.strip(), argument.strip()


def create_llm(spec: str, settings: Settings) -> LLM:
    """Build the raw backend named by ``spec`` (no cache, no log).

    Raises:
        ConfigError: Unknown backend or malformed argument.
    """
    name, argument = split_spec(spec)
    if name not in _LLMS:
        raise ConfigError(
            f"unknown LLM backend {name!r} in {redact_secrets(spec)!r}",
            hint=f"known backends: {', '.join(llm_backends())}",
        )
    return _LLMS[name](argument, settings)


def create_embedder(spec: str, settings: Settings) -> Embedder:
    """Build the raw embedder named by ``spec``.

    Raises:
        ConfigError: Unknown backend.
    """
    name, argument = split_spec(spec)
    if name not in _EMBEDDERS:
        raise ConfigError(
            f"unknown embedder backend {name!r} in {redact_secrets(spec)!r}",
            hint=f"known backends: {', '.join(embedder_backends())}",
        )
    return _EMBEDDERS[name](argument, settings)


def scoring_method(settings: Settings) -> str:
    """How the configured LLM scores options: ``logprob`` for in-process backends (exact), or for
    an HTTP backend the method its server supports (probed now, two small requests; see
    :mod:`conceptbot.models.http_scoring`), e.g. ``chat-logprobs``."""
    name, _ = split_spec(settings.llm)
    if name not in ("openai", "openai-compatible"):
        return "logprob"
    from conceptbot.models.openai_backend import OpenAILLM

    llm = create_llm(settings.llm, settings)
    assert isinstance(llm, OpenAILLM)
    prompts, chats = llm.scorer.resolved(prompt_form=True), llm.scorer.resolved(prompt_form=False)
    return prompts if prompts == chats else f"{prompts} (prompts), {chats} (chat)"


def open_store(settings: Settings) -> CacheStore:
    """The cache database under the home directory (``doctor`` checks it through this).

    Raises:
        CacheError: The home cannot be created, or ``cache.db`` cannot be opened, is damaged, not
            ConceptBot's, read-only, locked or on a full disk; the hint says how to fix it.
    """
    return CacheStore(settings.cache_db)


def open_run_store(settings: Settings) -> CacheStore | None:
    """The cache database a command runs with: :func:`open_store`, except with ``--no-cache``.

    ``--no-cache`` needs the database only for the call log, so there a database that cannot be
    opened (a read-only or broken home, a damaged file) is left out with a warning and the calls
    run unlogged, instead of the command failing for a file it was told not to use.

    Returns:
        The store, or ``None`` (no cache, no log) with ``--no-cache`` and an unusable database.

    Raises:
        CacheError: With the cache on, as :func:`open_store`.
    """
    try:
        return open_store(settings)
    except CacheError as exc:
        if settings.use_cache:
            raise
        fix = (exc.hint or "").removesuffix(OR_NO_CACHE)
        hint = f" Hint: {fix}" if fix else ""
        logger.warning("warning: --no-cache: the call log is off for this run: %s.%s", exc.message, hint)
        return None


def open_llm(
    settings: Settings, store: CacheStore | _Default | None = _RUN_STORE, module: str = "default"
) -> CachedLLM:
    """The configured LLM behind the cache and call log.

    Args:
        settings: Resolved settings.
        store: The cache database; ``None`` for no cache and no log; by default
            :func:`open_run_store`'s.
        module: Label of its calls in the log.

    Raises:
        CacheError: The default store cannot be opened (see :func:`open_run_store`).
        ConfigError: Unknown backend or malformed spec.
    """
    if store is _RUN_STORE:
        store = open_run_store(settings)
    return CachedLLM(create_llm(settings.llm, settings), store, use_cache=settings.use_cache, module=module)


def open_embedder(settings: Settings, store: CacheStore | _Default | None = _RUN_STORE) -> CachedEmbedder:
    """The configured embedder behind the embedding cache (``store`` as for :func:`open_llm`)."""
    if store is _RUN_STORE:
        store = open_run_store(settings)
    return CachedEmbedder(create_embedder(settings.embedder, settings), store, use_cache=settings.use_cache)


# -- built-ins ------------------------------------------------------------------------------------
def _llamacpp(argument: str, settings: Settings) -> LLM:
    from conceptbot.models import weights
    from conceptbot.models.llamacpp import LlamaCppLLM

    name = argument or "qwen2.5-coder-1.5b"
    path = weights.resolve(settings.models_dir, name)
    # A path to an installed catalogue file is that model: its name keys the caches and tells the
    # planner that the shipped calibration is its own.
    installed = {
        weights.model_path(settings.models_dir, entry).resolve(): known
        for known, entry in weights.catalogue().items()
    }
    return LlamaCppLLM(
        path,
        model=name if name in weights.catalogue() else installed.get(path.resolve(), path.name),
        n_ctx=settings.n_ctx,
        n_threads=settings.n_threads,
    )


def _openai(argument: str, settings: Settings) -> LLM:
    from conceptbot.models.openai_backend import OpenAILLM

    return OpenAILLM(
        argument,
        backend="openai",
        base_url=settings.openai_base_url,
        api_key=settings.openai_api_key,
        timeout_s=settings.timeout_s,
        max_retries=settings.max_retries,
        scoring=settings.scoring,
    )


def _openai_compatible(argument: str, settings: Settings) -> LLM:
    from conceptbot.models.openai_backend import OpenAILLM

    url, sep, model = argument.rpartition("#")
    if not sep or not url or not model:
        raise ConfigError(
            f"openai-compatible spec needs BASE_URL#MODEL, got {redact_secrets(argument)!r}",
            hint="e.g. openai-compatible:http://127.0.0.1:8000/v1#qwen2.5-coder-1.5b",
        )
    return OpenAILLM(
        model,
        backend="openai-compatible",
        base_url=url,
        # Never OPENAI_API_KEY: the user's OpenAI key must not reach a server they merely point at.
        api_key=settings.compatible_api_key,
        timeout_s=settings.timeout_s,
        max_retries=settings.max_retries,
        scoring=settings.scoring,
    )


def _fake(argument: str, settings: Settings) -> LLM:
    from conceptbot.models.fake import FakeLLM

    if not argument:
        return FakeLLM()
    path = Path(argument).expanduser()
    try:
        replies = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read fake replies from {path}: {exc}") from None
    if not isinstance(replies, list) or not all(isinstance(r, str) for r in replies):
        raise ConfigError(f"{path} must hold a JSON list of reply strings")
    return FakeLLM(replies)


def _st(argument: str, settings: Settings) -> Embedder:
    from conceptbot.models.st_embedder import SentenceTransformerEmbedder

    return SentenceTransformerEmbedder(argument or "all-MiniLM-L6-v2")


def _openai_embedder(argument: str, settings: Settings) -> Embedder:
    from conceptbot.models.openai_embedder import OpenAIEmbedder

    return OpenAIEmbedder(
        argument or "text-embedding-ada-002",
        api_key=settings.openai_api_key,
        base_url=settings.openai_base_url,
        timeout_s=settings.timeout_s,
        max_retries=settings.max_retries,
    )


def _fake_embedder(argument: str, settings: Settings) -> Embedder:
    from conceptbot.models.fake import FakeEmbedder

    return FakeEmbedder()


register_llm("llamacpp", _llamacpp)
register_llm("openai", _openai)
register_llm("openai-compatible", _openai_compatible)
register_llm("fake", _fake)
register_embedder("sentence-transformers", _st)
register_embedder("openai", _openai_embedder)
register_embedder("fake", _fake_embedder)
