"""A small ConceptNet 5 REST API on loopback for backend tests (real HTTP, the API's JSON shape).

It serves ``GET /query?node=/c/en/<term>&other=/c/en&limit=N`` from a list of edges built with
:func:`edge`, in the shape api.conceptnet.io answers with (``@context``, ``@id``, ``edges`` and, when
there are more results than ``limit``, a ``view`` with ``nextPage``). It deliberately ignores
``other=``, so non-English and ExternalURL edges reach the client and its own filter is tested.

Scripted :class:`Reply` objects (errors, garbage, slow answers) are served first, in order; then
``always`` if set; then the normal answer. Every request path is recorded.
"""

from __future__ import annotations

import time
import urllib.parse
from dataclasses import dataclass
from typing import Any

from tests.loopback import LoopbackServer, Request

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


class ConceptNetStub(LoopbackServer):
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
        super().__init__()
        self.edges = list(edges or [])
        self.script = list(script or [])
        self.always = always

    @property
    def requests(self) -> list[str]:
        """Every request's path, in order."""
        return [r.path for r in self.received]

    def respond(self, request: Request) -> tuple[int, bytes | dict[str, Any]]:
        """The next scripted reply (after its delay), else the API's answer."""
        with self.lock:
            reply = self.script.pop(0) if self.script else self.always
        if reply is not None and reply.delay_s:
            time.sleep(reply.delay_s)
        status = reply.status if reply is not None else 200
        body = reply.body if reply is not None else None
        if body is None:
            status, body = self.answer(request.path) if status == 200 else (status, {"error": "stub"})
        return status, body

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
        return self.base_url
