"""Embedded LLM backend: llama.cpp in-process through llama-cpp-python.

* ``n > 1`` runs one completion per seed (``seed + i``); the chat API has no ``n``. Greedy decoding
  (temperature 0) ignores the seed, so it runs once and the text is repeated ``n`` times.
* Shared prompt prefixes reuse the KV cache (llama-cpp-python matches the longest common token
  prefix with what is already evaluated), so callers should put stable text first.
* Scoring evaluates the prompt once, then each option's tokens on top of it, rewinding the
  context between options; options are sorted so shared beginnings are evaluated once. Scoring
  needs the logits of every evaluated position, so the model is created with ``logits_all=True``
  (``create_completion(echo=True, logprobs=...)`` is both slower and off by one token in 0.3.36).
* Chat switches that off while it runs (:func:`_logits_for_every_token`): a kept logits row costs
  about 1.7 MB resident per prompt token with a 152k vocabulary (a 2,000-token context held 3.4 GB
  that nothing read) and the output layer is computed for every prompt token instead of the last.
* ``n_ctx`` is checked against the context the model was trained on (read from the GGUF header,
  :func:`trained_context`) before loading: llama.cpp would accept more and answer worse, or fail to
  allocate it. A load that fails for the context (or memory) is reported as that, not as a damaged
  file; neither is a load failure of a catalogue model whose checksum was verified.
"""

from __future__ import annotations

import ctypes
import os
import struct
import threading
import time
from collections import OrderedDict
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from conceptbot.core.errors import (
    BackendRequestError,
    BackendUnavailableError,
    ConceptBotError,
    ConfigError,
    ModelCorruptError,
)
from conceptbot.core.extras import require
from conceptbot.core.usage import Usage
from conceptbot.models import weights
from conceptbot.models.llm import Capabilities, ChatRequest, ChatResponse, ScoreRequest, ScoreResponse

# GGUF metadata value types (https://github.com/ggml-org/ggml/blob/master/docs/gguf.md), as struct
# formats: 0-7 u8 i8 u16 i16 u32 i32 f32 bool, 10-12 u64 i64 f64 (all little-endian).
_GGUF_SCALARS = {
    kind: "<" + fmt for kind, fmt in zip((0, 1, 2, 3, 4, 5, 6, 7, 10, 11, 12), "BbHhIif?Qqd", strict=True)
}
_GGUF_STRING, _GGUF_ARRAY = 8, 9
# Bounds that no real header exceeds; past them the file is damaged and the answer is "unknown".
_GGUF_MAX_KEYS, _GGUF_MAX_STRING = 100_000, 1 << 24


def _read(stream: BinaryIO, fmt: str) -> Any:
    size = struct.calcsize(fmt)
    data = stream.read(size)
    if len(data) != size:
        raise ValueError("truncated GGUF header")
    return struct.unpack(fmt, data)[0]


def _read_string(stream: BinaryIO) -> str:
    length = _read(stream, "<Q")
    if length > _GGUF_MAX_STRING:
        raise ValueError("implausible GGUF string length")
    data = stream.read(length)
    if len(data) != length:
        raise ValueError("truncated GGUF header")
    return data.decode("utf-8")


def _read_value(stream: BinaryIO, kind: int) -> Any:
    """One metadata value; arrays are skipped (``None``): only scalars and strings are needed."""
    if kind in _GGUF_SCALARS:
        return _read(stream, _GGUF_SCALARS[kind])
    if kind == _GGUF_STRING:
        return _read_string(stream)
    if kind != _GGUF_ARRAY:
        raise ValueError(f"unknown GGUF value type {kind}")
    item, count = _read(stream, "<I"), _read(stream, "<Q")
    if item in _GGUF_SCALARS:
        stream.seek(count * struct.calcsize(_GGUF_SCALARS[item]), os.SEEK_CUR)
    else:  # strings (the tokenizer's vocabulary) or nested arrays, one by one
        for _ in range(count):
            _read_value(stream, item)
    return None


def trained_context(path: Path) -> int | None:
    """The context length a GGUF model was trained on (its ``ARCH.context_length`` metadata).

    Only the header is read, not the weights (the key comes before the tokenizer's arrays in the
    files llama.cpp writes, so this reads a few hundred bytes).

    Returns:
        The length in tokens, or ``None`` when the file does not say (not GGUF, version 1, damaged):
        llama.cpp then reports the problem itself when it loads the file.
    """
    try:
        with open(path, "rb") as stream:
            if stream.read(4) != b"GGUF" or _read(stream, "<I") < 2:
                return None
            _read(stream, "<Q")  # tensor count
            keys = _read(stream, "<Q")
            arch, lengths = None, {}
            for _ in range(min(keys, _GGUF_MAX_KEYS)):
                key = _read_string(stream)
                value = _read_value(stream, _read(stream, "<I"))
                if key == "general.architecture":
                    arch = value
                elif key.endswith(".context_length"):
                    lengths[key] = value
                if arch is not None and f"{arch}.context_length" in lengths:
                    found = lengths[f"{arch}.context_length"]
                    return int(found) if isinstance(found, int) and found > 0 else None
    except (OSError, ValueError, OverflowError, struct.error):
        return None
    return None


def _log_softmax(row: np.ndarray) -> np.ndarray:
    shifted = row - np.max(row)
    return shifted - np.log(np.sum(np.exp(shifted)))


class LlamaCppLLM:
    """A GGUF model run in-process by llama.cpp.

    Args:
        model_path: The GGUF file (resolve catalogue names with :func:`conceptbot.models.weights.resolve`).
        model: Name to report and to key caches with (default: the file name).
        n_ctx: Context window in tokens.
        n_threads: CPU threads (default: all cores).
        n_batch: Prompt tokens evaluated per batch.
    """

    backend = "llamacpp"
    capabilities = Capabilities(scoring=True, exact_scoring=True, json_schema=True, native_n=False)

    def __init__(
        self,
        model_path: Path,
        *,
        model: str | None = None,
        n_ctx: int = 4096,
        n_threads: int | None = None,
        n_batch: int = 512,
    ) -> None:
        self.model_path = Path(model_path)
        self.model = model or self.model_path.name
        self.n_ctx = n_ctx
        self.n_threads = n_threads or os.cpu_count() or 1
        self.n_batch = n_batch
        self._llama: Any = None
        self._formatter: Any = None
        self._states = PrefixStates()
        # llama.cpp contexts are not thread-safe; one call at a time.
        self._lock = threading.Lock()

    # -- loading --------------------------------------------------------------------------------
    def _load(self) -> Any:
        if self._llama is not None:
            return self._llama
        trained = trained_context(self.model_path)
        if trained is not None and self.n_ctx > trained:
            raise ConfigError(
                f"n_ctx {self.n_ctx} is more than {self.model} was trained on ({trained} tokens)",
                hint=f"set CONCEPTBOT_N_CTX (or n_ctx in config.toml) to {trained} or less; default 4096",
            )
        require("embedded", ("llama_cpp",))
        from llama_cpp import Llama

        try:
            self._llama = Llama(
                model_path=str(self.model_path),
                n_ctx=self.n_ctx,
                n_threads=self.n_threads,
                n_batch=self.n_batch,
                logits_all=True,
                verbose=False,
            )
        except (ValueError, RuntimeError, MemoryError) as exc:
            raise self._load_error(exc) from None
        return self._llama

    def _load_error(self, exc: BaseException) -> ConceptBotError:
        """What a failed load means: the context could not be made, or the file could not be read
        (only then, and only if its checksum is not known to be good, is the file blamed)."""
        # "Failed to create llama_context" comes after the weights loaded; a MemoryError is the
        # logits array (n_ctx rows of the vocabulary) that the context needs.
        if isinstance(exc, MemoryError) or "llama_context" in str(exc):
            return BackendUnavailableError(
                f"llama.cpp could not create a context of {self.n_ctx} tokens for {self.model_path.name}: "
                f"{exc or 'out of memory'}",
                hint="lower CONCEPTBOT_N_CTX (default 4096) or free memory; the model file is fine",
            )
        if weights.checksum_known_good(self.model_path):
            return BackendUnavailableError(
                f"llama.cpp could not load {self.model_path}: {exc}",
                hint="the file's sha256 is verified, so it is not damaged: free memory, or reinstall "
                "llama-cpp-python (bash scripts/install.sh)",
            )
        return ModelCorruptError(
            f"llama.cpp could not load {self.model_path}: {exc}",
            hint="reinstall it with `conceptbot models install NAME --force`",
        )

    def _chat_formatter(self) -> Any:
        if self._formatter is None:
            from llama_cpp.llama_chat_format import Jinja2ChatFormatter

            llama = self._load()
            template = llama.metadata.get("tokenizer.chat_template")
            if not template:
                raise BackendRequestError(f"{self.model} has no chat template; score with a raw prompt")
            eos, bos = llama.token_eos(), llama.token_bos()
            self._formatter = Jinja2ChatFormatter(
                template=template,
                eos_token=llama._model.token_get_text(eos) if eos != -1 else "",
                bos_token=llama._model.token_get_text(bos) if bos != -1 else "",
                add_generation_prompt=True,
            )
        return self._formatter

    def with_module(self, module: str) -> LlamaCppLLM:
        """This backend itself: it keeps no call log to label (see :meth:`LLM.with_module`)."""
        return self

    # -- chat -----------------------------------------------------------------------------------
    def chat(self, request: ChatRequest) -> ChatResponse:
        """Chat completion; see :meth:`conceptbot.models.llm.LLM.chat`."""
        llama = self._load()
        messages = [{"role": m.role, "content": m.content} for m in request.messages]
        kwargs: dict[str, Any] = {
            "temperature": request.temperature,
            "max_tokens": request.max_tokens,
            "stop": list(request.stop),
        }
        if request.json_schema is not None:
            kwargs["response_format"] = {"type": "json_object", "schema": request.schema()}
        runs = 1 if request.temperature == 0 else request.n
        choices: list[str] = []
        reasons: list[str] = []
        usage = Usage(calls=0)
        with self._lock, _logits_for_every_token(llama, False):
            self._states.restore(llama, self._chat_tokens(request))
            for i in range(runs):
                started = time.perf_counter()
                try:
                    out = llama.create_chat_completion(messages=messages, seed=request.seed + i, **kwargs)
                except ValueError as exc:  # e.g. "Requested tokens exceed context window"
                    raise BackendRequestError(
                        f"llama.cpp refused the request: {exc}",
                        hint="shorten the prompt or raise CONCEPTBOT_N_CTX",
                    ) from None
                elapsed = time.perf_counter() - started
                choice = out["choices"][0]
                choices.append(choice["message"]["content"] or "")
                reasons.append(choice.get("finish_reason") or "stop")
                usage = usage + Usage(
                    out["usage"]["prompt_tokens"], out["usage"]["completion_tokens"], elapsed, 0.0, 1
                )
            self._states.remember(llama)
        if runs < request.n:
            choices *= request.n
            reasons *= request.n
        return ChatResponse(
            choices=tuple(choices),
            usage=usage,
            backend=self.backend,
            model=self.model,
            finish_reasons=tuple(reasons),
        )

    def _chat_tokens(self, request: ChatRequest) -> list[int]:
        """The chat prompt's tokens as the chat template renders them (to find a held state)."""
        llama = self._load()
        rendered = self._chat_formatter()(
            messages=[{"role": m.role, "content": m.content} for m in request.messages]
        ).prompt
        return list(llama.tokenize(rendered.encode("utf-8"), add_bos=False, special=True))

    # -- scoring --------------------------------------------------------------------------------
    def _prompt_tokens(self, request: ScoreRequest) -> list[int]:
        llama = self._load()
        if request.messages is not None:
            rendered = self._chat_formatter()(
                messages=[{"role": m.role, "content": m.content} for m in request.messages]
            ).prompt
            text = rendered + request.assistant_prefix
            return list(llama.tokenize(text.encode("utf-8"), add_bos=False, special=True))
        assert request.prompt is not None
        return list(llama.tokenize(request.prompt.encode("utf-8"), add_bos=True, special=True))

    def score(self, request: ScoreRequest) -> ScoreResponse:
        """Sum of token log-probabilities of each option after the prompt."""
        llama = self._load()
        started = time.perf_counter()
        with self._lock, _logits_for_every_token(llama, True):
            prompt = self._prompt_tokens(request)
            options = [
                list(llama.tokenize(o.encode("utf-8"), add_bos=False, special=False)) for o in request.options
            ]
            needed = len(prompt) + max(len(o) for o in options)
            if needed > self.n_ctx:
                raise BackendRequestError(
                    f"scoring needs {needed} tokens, more than the context window ({self.n_ctx})",
                    hint="shorten the prompt or raise CONCEPTBOT_N_CTX",
                )
            evaluated = 0
            # Reuse the already evaluated common prefix, but re-evaluate at least the last prompt
            # token so its logits row is fresh.
            self._states.restore(llama, prompt)
            common = _evaluated_prefix(llama, prompt)
            llama.n_tokens = min(common, len(prompt) - 1)
            evaluated += len(prompt) - llama.n_tokens
            # Only the last prompt token's logits are read: the tokens before it are evaluated
            # without the vocabulary-wide rows (a matrix product and a 600 KB copy per token).
            with _logits_for_every_token(llama, False):
                llama.eval(prompt[llama.n_tokens : -1])
            llama.eval(prompt[-1:])
            base = len(prompt)
            results: dict[int, float] = {}
            previous: list[int] = []
            for index in sorted(range(len(options)), key=lambda i: options[i]):
                tokens = options[index]
                if not tokens:
                    results[index] = 0.0
                    continue
                shared = 0
                for a, b in zip(previous, tokens[:-1], strict=False):
                    if a != b:
                        break
                    shared += 1
                # Logits for position base+j-1 predict tokens[j]; the last token needs no eval.
                llama.n_tokens = base + shared
                to_eval = tokens[shared:-1]
                if to_eval:
                    llama.eval(to_eval)
                    evaluated += len(to_eval)
                previous = tokens[:-1]
                total = 0.0
                for j, token in enumerate(tokens):
                    total += float(_log_softmax(llama.scores[base + j - 1])[token])
                results[index] = total
        elapsed = time.perf_counter() - started
        return ScoreResponse(
            logprobs=tuple(results[i] for i in range(len(options))),
            token_counts=tuple(len(o) for o in options),
            usage=Usage(prompt_tokens=evaluated, completion_tokens=0, latency_s=elapsed, calls=1),
            backend=self.backend,
            model=self.model,
        )


@contextmanager
def _logits_for_every_token(llama: Any, enabled: bool) -> Iterator[None]:
    """Keep logits for every evaluated token (scoring) or only for the last one (generation).

    llama-cpp-python 0.3.36 reads the private ``_logits_all`` flag on every ``eval``; the ``scores``
    array is sized for ``n_ctx`` rows at load time, and its untouched pages cost no memory.
    Scoring never reads a row that chat evaluated: it re-evaluates at least the prompt's last
    token and every option token itself.
    """
    previous = llama._logits_all
    llama._logits_all = enabled
    try:
        yield
    finally:
        llama._logits_all = previous


class PrefixStates:
    """The KV cache of the last few chat prompts (llama.cpp's sequence 0), put back where a new
    prompt shares a longer prefix with one of them than with what the context holds.

    The planner's questions replace one another in the one context, so the restating prompt's
    550-token instructions were evaluated again for every request (about 9 s of a plan on 2 cores);
    restored, only the request's own tokens are. A state is about 29 KB per token for Qwen2.5-1.5B.
    """

    def __init__(self, size: int = 4, least: int = 64) -> None:
        self.size = size  # states kept, least recently used dropped first
        self.least = least  # a state is kept, and put back, only for a prefix this much longer
        self._held: OrderedDict[tuple[int, ...], bytes] = OrderedDict()

    def remember(self, llama: Any) -> None:
        """Keep the state of what the context holds now."""
        tokens = tuple(int(t) for t in llama._input_ids)
        if len(tokens) < self.least:
            return
        import llama_cpp

        ctx = llama._ctx.ctx
        size = llama_cpp.llama_state_seq_get_size(ctx, 0)
        buffer = (ctypes.c_uint8 * size)()
        written = llama_cpp.llama_state_seq_get_data(ctx, buffer, size, 0)
        self._held[tokens] = bytes(buffer)[:written]
        self._held.move_to_end(tokens)
        while len(self._held) > self.size:
            self._held.popitem(last=False)

    def restore(self, llama: Any, tokens: Sequence[int]) -> None:
        """Put back the kept state sharing the longest prefix with ``tokens``, where it shares at
        least ``least`` more tokens than the context does; the caller evaluates the rest."""
        best, shared = None, _evaluated_prefix(llama, list(tokens)) + self.least
        for key in self._held:
            common = _common_prefix(key, tokens)
            if common > shared:
                best, shared = key, common
        if best is None:
            return
        import llama_cpp

        data = self._held[best]
        buffer = (ctypes.c_uint8 * len(data)).from_buffer_copy(data)
        if not llama_cpp.llama_state_seq_set_data(llama._ctx.ctx, buffer, len(data), 0):
            llama.reset()  # nothing usable is held: evaluate from the start
            return
        llama.input_ids[: len(best)] = best
        llama.n_tokens = len(best)
        llama._requires_eval = True  # the logits are not the state's: evaluate at least one token


def _common_prefix(a: Sequence[int], b: Sequence[int]) -> int:
    """How many leading tokens ``a`` and ``b`` share."""
    common = 0
    for x, y in zip(a, b, strict=False):
        if x != y:
            break
        common += 1
    return common


def _evaluated_prefix(llama: Any, tokens: list[int]) -> int:
    """Length of the prefix of ``tokens`` already evaluated in the llama context."""
    common = 0
    for a, b in zip(llama._input_ids, tokens, strict=False):  # _input_ids = input_ids[:n_tokens]
        if a != b:
            break
        common += 1
    return common
