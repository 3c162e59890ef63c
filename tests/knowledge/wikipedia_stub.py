"""A small MediaWiki API server on loopback for Wikipedia tests (real HTTP, scripted wiki).

It answers ``GET /w/api.php`` the way the real API does (``format=json``, formatversion 1) for the
two queries the client makes: ``list=search`` and ``prop=extracts|pageprops``. Scripted raw replies
(``responses``) are served first, to simulate outages and garbage.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any
from urllib.parse import parse_qsl, urlsplit

from tests.loopback import LoopbackServer, Request

API_PATH = "/w/api.php"


@dataclass(frozen=True)
class StubPage:
    """A page of the scripted wiki."""

    text: str
    disambiguation: bool = False


class WikipediaStub(LoopbackServer):
    """Serves a scripted wiki; records every request's query parameters and headers.

    Args:
        pages: Title -> page text (or :class:`StubPage`).
        search: Search query (lower case) -> titles, in the order the API should return them;
            queries not listed return the titles that contain the query.
        redirects: Title -> target title.
        responses: Raw ``(status, body)`` replies served, in order, before the wiki answers.
    """

    content_type = "application/json; charset=utf-8"

    def __init__(
        self,
        pages: dict[str, str | StubPage] | None = None,
        search: dict[str, list[str]] | None = None,
        redirects: dict[str, str] | None = None,
        responses: list[tuple[int, bytes | dict[str, Any]]] | None = None,
    ) -> None:
        super().__init__()
        self.pages = {t: p if isinstance(p, StubPage) else StubPage(p) for t, p in (pages or {}).items()}
        self.search = search or {}
        self.redirects = redirects or {}
        self.responses = list(responses or [])
        self._ids = {title: 1000 + i for i, title in enumerate(self.pages)}

    @property
    def requests(self) -> list[dict[str, str]]:
        """Every request's query parameters, in order."""
        return [dict(parse_qsl(urlsplit(r.path).query)) for r in self.received]

    @property
    def headers(self) -> list[dict[str, str]]:
        """Every request's headers (lower-case names), in order."""
        return [r.headers for r in self.received]

    def respond(self, request: Request) -> tuple[int, bytes | dict[str, Any]]:
        """A scripted raw reply first, else the wiki's answer (404 off the API path)."""
        parts = urlsplit(request.path)
        if self.responses:
            return self.responses.pop(0)
        if parts.path != API_PATH:
            return 404, b"not found"
        return 200, self.answer(dict(parse_qsl(parts.query)))

    @property
    def url(self) -> str:
        """The stub's ``api.php`` URL."""
        return f"{self.base_url}{API_PATH}"

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
