"""A small MediaWiki API server on loopback for Wikipedia tests (real HTTP, scripted wiki).

It answers ``GET /w/api.php`` the way the real API does (``format=json``, formatversion 1) for the
two queries the client makes: ``list=search`` and ``prop=extracts|pageprops``. Scripted raw replies
(``responses``) are served first, to simulate outages and garbage.
"""

from __future__ import annotations

import json
import threading
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any
from urllib.parse import parse_qsl, urlsplit

API_PATH = "/w/api.php"


@dataclass(frozen=True)
class StubPage:
    """A page of the scripted wiki."""

    text: str
    disambiguation: bool = False


class WikipediaStub:
    """Serves a scripted wiki; records every request's query parameters and headers.

    Args:
        pages: Title -> page text (or :class:`StubPage`).
        search: Search query (lower case) -> titles, in the order the API should return them;
            queries not listed return the titles that contain the query.
        redirects: Title -> target title.
        responses: Raw ``(status, body)`` replies served, in order, before the wiki answers.
    """

    def __init__(
        self,
        pages: dict[str, str | StubPage] | None = None,
        search: dict[str, list[str]] | None = None,
        redirects: dict[str, str] | None = None,
        responses: list[tuple[int, bytes | dict[str, Any]]] | None = None,
    ) -> None:
        self.pages = {t: p if isinstance(p, StubPage) else StubPage(p) for t, p in (pages or {}).items()}
        self.search = search or {}
        self.redirects = redirects or {}
        self.responses = list(responses or [])
        self.requests: list[dict[str, str]] = []
        self.headers: list[dict[str, str]] = []
        self._ids = {title: 1000 + i for i, title in enumerate(self.pages)}
        stub = self

        class _Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:
                parts = urlsplit(self.path)
                params = dict(parse_qsl(parts.query))
                stub.requests.append(params)
                stub.headers.append({k.lower(): v for k, v in self.headers.items()})
                if stub.responses:
                    status, body = stub.responses.pop(0)
                elif parts.path != API_PATH:
                    status, body = 404, b"not found"
                else:
                    status, body = 200, stub.answer(params)
                data = body if isinstance(body, bytes) else json.dumps(body).encode()
                self.send_response(status)
                self.send_header("Content-Type", "application/json; charset=utf-8")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def log_message(self, *args: Any) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), _Handler)
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)

    @property
    def url(self) -> str:
        """The stub's ``api.php`` URL."""
        return f"http://127.0.0.1:{self.server.server_address[1]}{API_PATH}"

    @property
    def fetched_titles(self) -> list[str]:
        """Titles asked for with ``prop=extracts``, in order."""
        return [p["titles"] for p in self.requests if "titles" in p]

    def answer(self, params: dict[str, str]) -> dict[str, Any]:
        """The API's JSON answer to a query."""
        if params.get("format") != "json":
            return {"error": {"code": "badformat", "info": "only format=json is scripted"}}
        if params.get("action") == "query" and params.get("list") == "search":
            return self._search(params["srsearch"], int(params.get("srlimit", 10)))
        if params.get("action") == "query" and "extracts" in params.get("prop", "").split("|"):
            return self._page(params["titles"], follow=params.get("redirects") == "1")
        return {"error": {"code": "badquery", "info": f"unscripted query {params}"}}

    def _search(self, query: str, limit: int) -> dict[str, Any]:
        titles = self.search.get(query.lower())
        if titles is None:
            titles = [t for t in self.pages if query.lower() in t.lower()]
        hits = []
        for title in titles[:limit]:
            text = self.pages[title].text if title in self.pages else ""
            hits.append(
                {
                    "ns": 0,
                    "title": title,
                    "pageid": self._ids.get(title, 1),
                    "size": len(text.encode()),
                    "wordcount": len(text.split()),
                    "snippet": f'The <span class="searchmatch">{query}</span> &amp; more',
                    "timestamp": "2024-01-01T00:00:00Z",
                }
            )
        return {
            "batchcomplete": "",
            "continue": {"sroffset": limit, "continue": "-||"},
            "query": {"searchinfo": {"totalhits": len(titles)}, "search": hits},
        }

    def _page(self, title: str, follow: bool) -> dict[str, Any]:
        query: dict[str, Any] = {}
        if follow and title in self.redirects:
            query["redirects"] = [{"from": title, "to": self.redirects[title]}]
            title = self.redirects[title]
        page = self.pages.get(title)
        if page is None:
            query["pages"] = {"-1": {"ns": 0, "title": title, "missing": ""}}
        else:
            pageid = self._ids[title]
            entry: dict[str, Any] = {"pageid": pageid, "ns": 0, "title": title, "extract": page.text}
            if page.disambiguation:
                entry["pageprops"] = {"disambiguation": ""}
            query["pages"] = {str(pageid): entry}
        return {"batchcomplete": "", "query": query}

    def __enter__(self) -> WikipediaStub:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.server.shutdown()
        self.server.server_close()
