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
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from conceptbot.core.errors import BackendRequestError, BackendUnavailableError, ModelCorruptError
from conceptbot.core.usage import Usage
from conceptbot.models.llm import Capabilities, ChatRequest, ChatResponse, ScoreRequest, ScoreResponse


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
        # llama.cpp contexts are not thread-safe; one call at a time.
        self._lock = threading.Lock()

    # -- loading --------------------------------------------------------------------------------
    def _load(self) -> Any:
        if self._llama is not None:
            return self._llama
        try:
            from llama_cpp import Llama
        except ImportError as exc:
            raise BackendUnavailableError(
                f"llama-cpp-python is not installed ({exc})",
                hint="run the project's install script: bash scripts/install.sh",
            ) from None
        try:
            self._llama = Llama(
                model_path=str(self.model_path),
                n_ctx=self.n_ctx,
                n_threads=self.n_threads,
                n_batch=self.n_batch,
                logits_all=True,
                verbose=False,
            )
        except (ValueError, RuntimeError) as exc:
            raise ModelCorruptError(
                f"llama.cpp could not load {self.model_path}: {exc}",
                hint="reinstall it with `conceptbot models install NAME --force`",
            ) from None
        return self._llama

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
            common = _evaluated_prefix(llama, prompt)
            llama.n_tokens = min(common, len(prompt) - 1)
            evaluated += len(prompt) - llama.n_tokens
            llama.eval(prompt[llama.n_tokens :])
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


def _evaluated_prefix(llama: Any, tokens: list[int]) -> int:
    """Length of the prefix of ``tokens`` already evaluated in the llama context."""
    common = 0
    for a, b in zip(llama._input_ids, tokens, strict=False):  # _input_ids = input_ids[:n_tokens]
        if a != b:
            break
        common += 1
    return common
