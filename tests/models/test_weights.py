import hashlib
import os
import sys
from pathlib import Path

import pytest

from conceptbot.core.errors import ConfigError, ModelCorruptError, ModelNotInstalledError
from conceptbot.models import weights


@pytest.fixture
def fake_catalogue(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, weights.ModelEntry]:
    """A catalogue whose model is three parts in three importable packages, like the real ones."""
    chunks = [os.urandom(1000), os.urandom(2000), os.urandom(500)]
    site = tmp_path / "site"
    for i, chunk in enumerate(chunks, 1):
        package = site / f"cbtest_part{i}"
        (package / "data").mkdir(parents=True)
        (package / "data" / "part.bin").write_bytes(chunk)
        (package / "__init__.py").write_text(
            "import os\ndef get_part_path():\n"
            "    return os.path.join(os.path.dirname(__file__), 'data', 'part.bin')\n"
        )
    monkeypatch.syspath_prepend(str(site))
    joined = b"".join(chunks)

    def entry(name: str, sha: str) -> weights.ModelEntry:
        return weights.ModelEntry(
            name=name,
            description="test",
            filename=f"{name}.gguf",
            size=len(joined),
            sha256=sha,
            license="MIT",
            source={
                "type": "parts",
                "modules": [f"cbtest_part{i}" for i in (1, 2, 3)],
                "packages": ["cbtest-part1==1"],
            },
        )

    entries = {"tiny": entry("tiny", hashlib.sha256(joined).hexdigest()), "bad": entry("bad", "0" * 64)}
    monkeypatch.setattr(weights, "catalogue", lambda: entries)
    yield entries
    for i in (1, 2, 3):
        sys.modules.pop(f"cbtest_part{i}", None)


def test_install_joins_parts_in_order_and_verifies(tmp_path: Path, fake_catalogue) -> None:
    seen: list[int] = []
    path = weights.install(tmp_path / "models", "tiny", progress=seen.append)
    assert path.stat().st_size == fake_catalogue["tiny"].size
    assert hashlib.sha256(path.read_bytes()).hexdigest() == fake_catalogue["tiny"].sha256
    assert sum(seen) == fake_catalogue["tiny"].size
    assert weights.verify(tmp_path / "models", "tiny") == path


def test_hash_mismatch_leaves_no_file_behind(tmp_path: Path, fake_catalogue) -> None:
    with pytest.raises(ModelCorruptError, match="do not match"):
        weights.install(tmp_path / "models", "bad")
    assert list((tmp_path / "models").iterdir()) == []


def test_interrupted_install_leaves_no_partial_file(tmp_path: Path, fake_catalogue) -> None:
    def boom(_: int) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        weights.install(tmp_path / "models", "tiny", progress=boom)
    assert list((tmp_path / "models").iterdir()) == []


def test_missing_model_names_the_install_command(tmp_path: Path, fake_catalogue) -> None:
    with pytest.raises(ModelNotInstalledError) as info:
        weights.verify(tmp_path / "models", "tiny")
    assert "conceptbot models install tiny" in str(info.value)


def test_corrupt_model_is_detected_and_reinstalled(tmp_path: Path, fake_catalogue) -> None:
    path = weights.install(tmp_path / "models", "tiny")
    data = bytearray(path.read_bytes())
    data[10] ^= 0xFF
    path.write_bytes(bytes(data))  # same size, new mtime: the stamp no longer vouches for it
    with pytest.raises(ModelCorruptError) as info:
        weights.verify(tmp_path / "models", "tiny")
    assert "conceptbot models install tiny --force" in str(info.value)
    weights.install(tmp_path / "models", "tiny")  # a corrupt copy is rebuilt without --force
    assert weights.verify(tmp_path / "models", "tiny", full=True) == path


def test_truncated_model_is_corrupt(tmp_path: Path, fake_catalogue) -> None:
    path = weights.install(tmp_path / "models", "tiny")
    path.write_bytes(path.read_bytes()[:100])
    with pytest.raises(ModelCorruptError, match="bytes, expected"):
        weights.verify(tmp_path / "models", "tiny")


def test_missing_part_package_is_a_clear_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    entry = weights.ModelEntry(
        "ghost",
        "",
        "ghost.gguf",
        1,
        "0" * 64,
        "MIT",
        {"type": "parts", "modules": ["no_such_part_pkg"], "packages": ["no-such==1"]},
    )
    monkeypatch.setattr(weights, "catalogue", lambda: {"ghost": entry})
    with pytest.raises(ModelNotInstalledError, match="no_such_part_pkg"):
        weights.install(tmp_path, "ghost")


def test_unknown_model_lists_known_ones(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as info:
        weights.install(tmp_path, "gpt-17")
    assert "qwen2.5-coder-1.5b" in str(info.value)


def test_resolve_accepts_a_users_gguf_path(tmp_path: Path) -> None:
    own = tmp_path / "mine.gguf"
    own.write_bytes(b"GGUF")
    assert weights.resolve(tmp_path, str(own)) == own
    with pytest.raises(ModelNotInstalledError):
        weights.resolve(tmp_path, str(tmp_path / "absent.gguf"))


def test_real_catalogue_entries_are_complete() -> None:
    entries = weights.catalogue()
    assert {"qwen2.5-coder-1.5b", "qwen2.5-coder-0.5b", "smollm2-135m"} <= set(entries)
    assert len(entries["qwen2.5-coder-1.5b"].source["modules"]) == 22
    assert all(len(e.sha256) == 64 and e.size > 0 for e in entries.values())
