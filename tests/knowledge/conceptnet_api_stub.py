"""A small ConceptNet 5 REST API on loopback for backend tests (real HTTP, the API's JSON shape).

It serves ``GET /query?node=/c/en/<term>&other=/c/en&limit=N`` from a list of edges built with
:func:`edge`, in the shape api.conceptnet.io answers with (``@context``, ``@id``, ``edges`` and, when
there are more results than ``limit``, a ``view`` with ``nextPage``). It deliberately ignores
``other=``, so non-English and ExternalURL edges reach the client and its own filter is tested.

Scripted :class:`Reply` objects (errors, garbage, slow answers) are served first, in order; then
``always`` if set; then the normal answer. Every request path is recorded.
"""

from __future__ import annotations

import json
import threading
import time
import urllib.parse
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

CONTEXT = ["http://api.conceptnet.io/ld/conceptnet5.7/context.ld.json"]


@dataclass(frozen=True)
class Reply:
    """One scripted answer.

    Attributes:
        status: HTTP status.
        body: Raw bytes, a JSON-able object, or None for the normal answer to the query.
        delay_s: Seconds to wait before answering (to provoke client time-outs).
    """

    status: int = 200
    body: bytes | dict[str, Any] | list[Any] | None = None
    delay_s: float = 0.0


def node(text: str, lang: str = "en", sense: str | None = None) -> dict[str, Any]:
    """A ConceptNet node, e.g. ``node("sharp object")`` or ``node("couteau", "fr", sense="n")``."""
    term = f"/c/{lang}/{text.replace(' ', '_')}"
    out: dict[str, Any] = {
        "@id": term + (f"/{sense}" if sense else ""),
        "@type": "Node",
        "label": text,
        "language": lang,
        "term": term,
    }
    if sense:
        out["sense_label"] = sense
    return out


def external(url: str) -> dict[str, Any]:
    """The end node of an ExternalURL edge (a web page, not a concept)."""
    site = "/".join(url.split("/")[:3])
    return {
        "@id": url,
        "@type": "Node",
        "label": url.rsplit("/", 1)[-1],
        "site": site,
        "site_available": True,
    }


def edge(rel: str, start: dict[str, Any], end: dict[str, Any], weight: float = 1.0) -> dict[str, Any]:
    """An edge in the API's shape.

    Example: ``edge("IsA", node("knife", sense="n"), node("sharp object"), 3.464)``.
    """
    return {
        "@id": f"/a/[/r/{rel}/,{start['@id']}/,{end['@id']}/]",
        "@type": "Edge",
        "dataset": "/d/conceptnet/4/en",
        "license": "cc:by/4.0",
        "rel": {"@id": f"/r/{rel}", "@type": "Relation", "label": rel},
        "start": start,
        "end": end,
        "sources": [
            {
                "@id": "/and/[/s/activity/omcs/vote/,/s/contributor/omcs/bedume/]",
                "@type": "Source",
                "activity": "/s/activity/omcs/vote",
                "contributor": "/s/contributor/omcs/bedume",
            }
        ],
        "surfaceText": f"[[{start.get('label')}]] {rel} [[{end.get('label')}]]",
        "weight": weight,
    }


def _touches(e: dict[str, Any], uri: str) -> bool:
    """Whether an edge's start or end is ``uri`` or one of its senses (as ConceptNet matches nodes)."""
    for side in (e["start"], e["end"]):
        ident = side.get("term") or side["@id"]
        if ident == uri or side["@id"] == uri or side["@id"].startswith(uri + "/"):
            return True
    return False


class ConceptNetStub:
    """Serves ``GET /query`` on 127.0.0.1; ``url`` is the base URL to hand to the client.

    Args:
        edges: Every edge the stub knows.
        script: Replies served first, one per request.
        always: Reply served for every request once ``script`` is used up (e.g. a persistent 500).
    """

    def __init__(
        self,
        edges: list[dict[str, Any]] | None = None,
        script: list[Reply] | None = None,
        always: Reply | None = None,
    ) -> None:
        self.edges = list(edges or [])
        self.script = list(script or [])
        self.always = always
        self.requests: list[str] = []
        self._lock = threading.Lock()
        stub = self

        class _Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:
                with stub._lock:
                    stub.requests.append(self.path)
                    reply = stub.script.pop(0) if stub.script else stub.always
                if reply is not None and reply.delay_s:
                    time.sleep(reply.delay_s)
                status = reply.status if reply is not None else 200
                body = reply.body if reply is not None else None
                if body is None:
                    status, body = stub.answer(self.path) if status == 200 else (status, {"error": "stub"})
                data = body if isinstance(body, bytes) else json.dumps(body).encode()
                try:
                    self.send_response(status)
                    self.send_header("Content-Type", "application/json")
                    self.send_header("Content-Length", str(len(data)))
                    self.end_headers()
                    self.wfile.write(data)
                except (BrokenPipeError, ConnectionResetError):
                    pass  # the client gave up (time-out test)

            def log_message(self, *args: Any) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), _Handler)
        # A short poll interval makes shutdown() (and so every test) fast.
        self.thread = threading.Thread(target=self.server.serve_forever, args=(0.05,), daemon=True)

    def answer(self, path: str) -> tuple[int, dict[str, Any]]:
        """The normal ``(status, body)`` for a request path, as the real API answers it."""
        parts = urllib.parse.urlsplit(path)
        query = dict(urllib.parse.parse_qsl(parts.query))
        if parts.path != "/query" or "node" not in query:
            return 404, {"error": "not found", "details": f"{parts.path} is not a valid path"}
        uri, limit = query["node"], int(query.get("limit", 20))
        found = [e for e in self.edges if _touches(e, uri)]
        base = f"/query?node={uri}&other=/c/en"
        body: dict[str, Any] = {"@context": CONTEXT, "@id": base, "edges": found[:limit]}
        if len(found) > limit:
            body["view"] = {
                "@id": f"{base}&offset=0&limit={limit}",
                "@type": "PartialCollectionView",
                "comment": "There are more results. Follow the 'nextPage' link for more.",
                "firstPage": f"{base}&offset=0&limit={limit}",
                "nextPage": f"{base}&offset={limit}&limit={limit}",
                "paginatedProperty": "edges",
            }
        return 200, body

    @property
    def nodes(self) -> list[str]:
        """The decoded ``node`` parameter of every request, in order."""
        return [
            dict(urllib.parse.parse_qsl(urllib.parse.urlsplit(p).query)).get("node", "")
            for p in self.requests
        ]

    @property
    def url(self) -> str:
        """Base URL of the stub API."""
        return f"http://127.0.0.1:{self.server.server_address[1]}"

    def __enter__(self) -> ConceptNetStub:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.server.shutdown()
        self.server.server_close()
