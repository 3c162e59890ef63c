"""The Embedder protocol: text in, unit-length float32 vectors out."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Embedder(Protocol):
    """A sentence-embedding backend.

    Attributes:
        backend: Registry name (``sentence-transformers``, ``openai``, ``fake``).
        model: Model identifier; part of the embedding cache key.
    """

    backend: str
    model: str

    def embed(self, texts: Sequence[str]) -> np.ndarray:
        """Embed texts.

        Args:
            texts: Sentences to embed.

        Returns:
            A ``(len(texts), dim)`` float32 array of L2-normalised rows, so a dot product is the
            cosine similarity.

        Raises:
            BackendUnavailableError: The model cannot be loaded or the service reached.
        """
        ...


def normalise(vectors: np.ndarray) -> np.ndarray:
    """L2-normalise rows (zero rows stay zero)."""
    vectors = np.asarray(vectors, dtype=np.float32)
    norms = np.linalg.norm(vectors, axis=1, keepdims=True)
    return vectors / np.where(norms == 0, 1.0, norms)


def cosine_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cosine similarities between the rows of two normalised matrices."""
    return np.asarray(a, dtype=np.float32) @ np.asarray(b, dtype=np.float32).T
