"""Settings: where ConceptBot keeps its files and which backends it uses.

Precedence, lowest to highest: built-in defaults, ``$CONCEPTBOT_HOME/config.toml``, environment
variables, explicit overrides (CLI flags). Settings are a frozen value passed to whatever needs them;
there is no global configuration object.

Environment variables:
    CONCEPTBOT_HOME        home directory (default: the user's cache dir, e.g. ~/.cache/conceptbot)
    CONCEPTBOT_LLM         LLM backend spec, e.g. ``llamacpp:qwen2.5-coder-1.5b``,
                           ``openai:gpt-4o-mini``,
                           ``openai-compatible:http://127.0.0.1:8000/v1#llama-3.3-70b``
    CONCEPTBOT_EMBEDDER    embedder spec, e.g. ``sentence-transformers:all-MiniLM-L6-v2``,
                           ``openai:text-embedding-ada-002``
    CONCEPTBOT_API_KEY     key for ``openai-compatible`` servers (never OPENAI_API_KEY: that key
                           goes only to the OpenAI API or OPENAI_BASE_URL)
    OPENAI_API_KEY         key for the ``openai`` backends
    OPENAI_BASE_URL        base URL for the ``openai`` backends (default: the official API)
    CONCEPTBOT_TIMEOUT     HTTP time-out in seconds (default 60)
    CONCEPTBOT_MAX_RETRIES bounded retries for HTTP backends (default 3, exponential backoff)
    CONCEPTBOT_SCORING     how HTTP backends score options: ``auto`` (default: the best the server
                           supports, found once), ``echo``, ``search``, ``chat-logprobs`` or ``vote``
    CONCEPTBOT_THREADS     CPU threads for the embedded LLM (default: all cores)
    CONCEPTBOT_N_CTX       context window of the embedded LLM (default 4096; 512 to 131072, and at
                           most what the model was trained on, 32768 for the shipped Qwen2.5 models)
    CONCEPTBOT_KG          knowledge graph: ``sqlite`` (default, offline), ``conceptnet-api[:URL]``,
                           ``conceptnet-api-cache`` (the API's local cache only, no network)
    CONCEPTBOT_KG_FALLBACK ``1``/``0``: ask Wikipedia when the graph knows too little (default 1)
    CONCEPTBOT_WIKIPEDIA_URL  MediaWiki API of the fallback (default English Wikipedia)
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import platformdirs

from conceptbot.core.errors import ConfigError
from conceptbot.core.urls import redact_secrets

DEFAULT_LLM = "llamacpp:qwen2.5-coder-1.5b"
DEFAULT_EMBEDDER = "sentence-transformers:all-MiniLM-L6-v2"


@dataclass(frozen=True)
class Settings:
    """Resolved settings. Secrets are excluded from ``repr`` so they never reach a log.

    Attributes:
        home: Directory for models, knowledge graph, caches and logs.
        llm: LLM backend spec.
        embedder: Embedder backend spec.
        use_cache: Whether the caches (LLM replies, embeddings, OPE results) are read and written.
        openai_api_key: Key for the official OpenAI API.
        openai_base_url: Base URL override for the ``openai`` backend.
        compatible_api_key: Key for ``openai-compatible`` servers.
        timeout_s: HTTP time-out per request.
        max_retries: Retries after a failed HTTP request (exponential backoff).
        scoring: How HTTP backends score options (``conceptbot.models.http_scoring.METHODS``).
        n_threads: CPU threads for the embedded LLM (None: all cores).
        n_ctx: Context window of the embedded LLM in tokens.
        kg: Knowledge graph backend spec.
        kg_fallback: Whether the Wikipedia fallback is consulted.
        wikipedia_url: MediaWiki API endpoint of the fallback.
    """

    home: Path
    llm: str = DEFAULT_LLM
    embedder: str = DEFAULT_EMBEDDER
    use_cache: bool = True
    openai_api_key: str | None = field(default=None, repr=False)
    openai_base_url: str | None = None
    compatible_api_key: str | None = field(default=None, repr=False)
    timeout_s: float = 60.0
    max_retries: int = 3
    scoring: str = "auto"
    n_threads: int | None = None
    n_ctx: int = 4096
    kg: str = "sqlite"
    kg_fallback: bool = True
    wikipedia_url: str = "https://en.wikipedia.org/w/api.php"

    @property
    def models_dir(self) -> Path:
        """Where local model files are kept."""
        return self.home / "models"

    @property
    def cache_db(self) -> Path:
        """The SQLite file holding LLM/embedding caches and the call log."""
        return self.home / "cache.db"

    @property
    def calibration_dir(self) -> Path:
        """Where ``conceptbot calibrate --conformal`` keeps each model's own calibration."""
        return self.home / "calibration"

    @property
    def kg_path(self) -> Path:
        """The SQLite knowledge graph."""
        return self.home / "kg" / "conceptnet.db"

    @property
    def config_file(self) -> Path:
        """The optional TOML configuration file."""
        return self.home / "config.toml"

    def with_overrides(self, **overrides: Any) -> Settings:
        """Return a copy with the given non-``None`` fields replaced."""
        return replace(self, **{k: v for k, v in overrides.items() if v is not None})


_ENV: dict[str, str] = {
    "CONCEPTBOT_LLM": "llm",
    "CONCEPTBOT_EMBEDDER": "embedder",
    "CONCEPTBOT_API_KEY": "compatible_api_key",
    "OPENAI_API_KEY": "openai_api_key",
    "OPENAI_BASE_URL": "openai_base_url",
    "CONCEPTBOT_TIMEOUT": "timeout_s",
    "CONCEPTBOT_MAX_RETRIES": "max_retries",
    "CONCEPTBOT_SCORING": "scoring",
    "CONCEPTBOT_THREADS": "n_threads",
    "CONCEPTBOT_N_CTX": "n_ctx",
    "CONCEPTBOT_KG": "kg",
    "CONCEPTBOT_KG_FALLBACK": "kg_fallback",
    "CONCEPTBOT_WIKIPEDIA_URL": "wikipedia_url",
}


def default_home(env: Mapping[str, str] | None = None) -> Path:
    """The home directory: ``$CONCEPTBOT_HOME`` or the user's cache dir."""
    env = os.environ if env is None else env
    if env.get("CONCEPTBOT_HOME"):
        return Path(env["CONCEPTBOT_HOME"]).expanduser()
    return Path(platformdirs.user_cache_dir("conceptbot"))


# Each setting's type and the range a working install needs; checked for every source (file,
# environment, CLI), so a bad value is named where it was given instead of failing later as a
# "corrupt model" or a time-out of -1 s.
_TYPES: dict[str, type] = {
    "llm": str,
    "embedder": str,
    "use_cache": bool,
    "openai_api_key": str,
    "openai_base_url": str,
    "compatible_api_key": str,
    "timeout_s": float,
    "max_retries": int,
    "scoring": str,
    "n_threads": int,
    "n_ctx": int,
    "kg": str,
    "kg_fallback": bool,
    "wikipedia_url": str,
}
_MINIMUM: dict[str, tuple[float, str]] = {
    "timeout_s": (0.1, "a number of seconds >= 0.1"),
    "max_retries": (0, "a whole number >= 0"),
    "n_threads": (1, "a whole number >= 1"),
    "n_ctx": (512, "a whole number of tokens >= 512"),
}
# The longest trained context of the GGUF models in common use (Llama 3.x, Qwen2.5 with YaRN); an
# absurd value (1,000,000,000) would otherwise pass and fail at load as if the model file were bad.
# Each model's own trained context is checked when it is loaded (models/llamacpp.py).
MAX_N_CTX = 131_072
_MAXIMUM: dict[str, tuple[float, str, str]] = {
    "n_ctx": (
        MAX_N_CTX,
        f"at most {MAX_N_CTX} tokens",
        "the shipped models were trained on 32768 tokens or fewer; the default is 4096",
    ),
}
# API keys: never quoted in a message (a type error must not print the key), and sent in an HTTP
# header, so they must be printable ASCII on one line.
_API_KEYS = frozenset({"openai_api_key", "compatible_api_key"})


def api_key_problem(key: str) -> str | None:
    """What makes ``key`` unusable as an API key, or ``None`` when it is fine.

    A key goes into the ``Authorization`` header, which HTTP clients encode as ASCII and refuse with
    a line break in it (an opaque UnicodeEncodeError, or a "cannot connect" from the SDK), so that is
    checked where the key is given. The answer never quotes the key.

    Args:
        key: The key as given (after stripping surrounding whitespace).

    Returns:
        A phrase such as ``"holds a line break"``, or ``None``.
    """
    if any(c in "\r\n" for c in key):
        return "holds a line break"
    if any(ord(c) > 126 for c in key):
        return "holds a non-ASCII character"
    if any(ord(c) < 32 or ord(c) == 127 for c in key):
        return "holds a control character"
    return None


API_KEY_HINT = "an API key is printable ASCII on one line: copy it again, without quotes or line breaks"


def _kind(value: Any) -> str:
    """A value's type in words, for messages that must not quote it."""
    if isinstance(value, str):
        return "a string" if value.strip() else "an empty string"
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, (list, tuple)):
        return "an array"
    if isinstance(value, dict):
        return "a table"
    return f"a {type(value).__name__}"


def _shown(name: str, value: Any) -> str:
    """How a rejected value is quoted: never for a secret or a structure (an array may hold the key
    meant for the setting), URLs and keys in text masked (a spec may carry ``user:password@``)."""
    if name in _API_KEYS or not isinstance(value, (str, int, float)):
        return _kind(value)
    if isinstance(value, str):
        return repr(redact_secrets(value))
    return repr(value)


def _coerce(name: str, value: Any, kind: type, origin: str) -> Any:
    got = _shown(name, value)
    if kind is bool:
        if isinstance(value, bool):
            return value
        lowered = str(value).strip().lower()
        if lowered not in ("1", "0", "true", "false", "yes", "no", "on", "off"):
            raise ConfigError(f"{origin}: {name} must be 1/0 or true/false, got {got}")
        return lowered in ("1", "true", "yes", "on")
    if kind is str:
        if not isinstance(value, str) or not value.strip():
            raise ConfigError(f"{origin}: {name} must be a non-empty string, got {got}")
        text = value.strip()
        problem = api_key_problem(text) if name in _API_KEYS else None
        if problem:
            raise ConfigError(f"{origin}: {name} {problem} (the key is not shown)", hint=API_KEY_HINT)
        return text
    if isinstance(value, bool) or (kind is int and isinstance(value, float) and not value.is_integer()):
        raise ConfigError(f"{origin}: {name} must be a{'n int' if kind is int else ' number'}, got {got}")
    try:
        number = kind(value)
    except (TypeError, ValueError, OverflowError):
        label = "whole number" if kind is int else "number"
        raise ConfigError(f"{origin}: {name} must be a {label}, got {got}") from None
    if number != number or number in (float("inf"), float("-inf")):
        raise ConfigError(f"{origin}: {name} must be a finite number, got {got}")
    if name in _MINIMUM and number < _MINIMUM[name][0]:
        raise ConfigError(f"{origin}: {name} must be {_MINIMUM[name][1]}, got {got}")
    if name in _MAXIMUM and number > _MAXIMUM[name][0]:
        _limit, wanted, hint = _MAXIMUM[name]
        raise ConfigError(f"{origin}: {name} must be {wanted}, got {got}", hint=hint)
    return number


def load_settings(env: Mapping[str, str] | None = None, **overrides: Any) -> Settings:
    """Resolve settings from defaults, the config file, the environment and overrides.

    Args:
        env: Environment to read (default: ``os.environ``); tests pass their own.
        **overrides: Field values that win over everything else (``None`` means "not given").

    Returns:
        The resolved :class:`Settings`.

    Raises:
        ConfigError: The config file is not valid UTF-8 TOML, or has an unknown key; a setting from
            any source has the wrong type or is out of range, or an API key holds a line break or a
            non-ASCII character (the message names the setting and where it came from, and never
            quotes an API key).
    """
    env = os.environ if env is None else env
    home = Path(overrides.pop("home", None) or default_home(env))
    values: dict[str, Any] = {}
    known = {f.name: f for f in fields(Settings)}
    config_file = home / "config.toml"
    if config_file.is_file():
        try:
            data = tomllib.loads(config_file.read_text(encoding="utf-8"))
        except UnicodeDecodeError:
            raise ConfigError(
                f"{config_file} is not UTF-8 text", hint="save it as UTF-8 (plain TOML, no binary data)"
            ) from None
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"{config_file} is not valid TOML: {exc}") from None
        except OSError as exc:
            raise ConfigError(f"cannot read {config_file}: {exc.strerror or exc}") from None
        for key, value in data.items():
            if key not in known or key == "home":
                raise ConfigError(
                    f"{config_file}: unknown setting {key!r}",
                    hint=f"known settings: {', '.join(sorted(set(known) - {'home'}))}",
                )
            values[key] = _coerce(key, value, _TYPES[key], str(config_file))
    for var, name in _ENV.items():
        if env.get(var):
            values[name] = _coerce(name, env[var], _TYPES[name], f"environment variable {var}")
    for key, value in overrides.items():
        if value is not None:
            values[key] = _coerce(key, value, _TYPES[key], "command line") if key in _TYPES else value
    return Settings(home=home, **values)
