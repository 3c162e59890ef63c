"""The paper's Wikipedia fallback: search a page for an object, read it, keep its risk facts.

When ConceptNet knows too little about an object, ConceptBot asks Wikipedia (paper, appendix
"Fallback Mechanism for Knowledge Extraction"):

1. search the MediaWiki API for the object's name (:meth:`WikipediaClient.search`);
2. choose a page: the paper asks the user; here a ``choose`` callback can do that (the CLI's
   interactive prompt), and without one :func:`rank_pages` decides (see there for the rule);
3. fetch the page's plain text (:meth:`WikipediaClient.page`), skipping disambiguation pages;
4. extract ``(subject, relation, object)`` triples from the first sentences
   (:func:`~conceptbot.knowledge.triples.extract_triples`);
5. keep the risk-relevant ones (:func:`~conceptbot.knowledge.triples.filter_triples`: keywords,
   and cosine similarity to target properties when an embedder is given);
6. return them as ConceptNet-like edges with ``source="wikipedia"`` (:class:`WikipediaFallback`,
   a :class:`~conceptbot.knowledge.base.KnowledgeGraph`).

The client uses only the standard library (``urllib``). Every failure to get an answer (no
network, time-out, HTTP 5xx after retries, a body that is not the API's JSON) is a
:class:`KnowledgeUnavailableError`, which the pipeline catches to go on without the fallback.
"""

from __future__ import annotations

import html
import http.client
import json
import re
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from conceptbot.core.errors import ConfigError, KnowledgeUnavailableError
from conceptbot.core.urls import check_http_url
from conceptbot.knowledge.base import DEFAULT_LIMIT, ConceptEdges, Edge
from conceptbot.knowledge.normalize import normalize, singular
from conceptbot.knowledge.triples import (
    DEFAULT_TARGETS,
    DEFAULT_THRESHOLD,
    Triple,
    extract_triples,
    filter_triples,
    load_keywords,
)
from conceptbot.models.embedder import Embedder

DEFAULT_BASE_URL = "https://en.wikipedia.org/w/api.php"
# Wikimedia's API policy asks every client to identify itself with a descriptive User-Agent.
DEFAULT_USER_AGENT = "ConceptBot/0.1 (https://github.com/conceptbot)"
OFFLINE_HINT = "offline: the fallback is unavailable; the pipeline continues without it"

DEFAULT_MAX_SENTENCES = 200
DEFAULT_MAX_CHARS = 20_000

# Status codes worth another try: rate limiting and server-side trouble.
_RETRY_STATUS = {408, 429, 500, 502, 503, 504}
_MAX_BACKOFF_S = 8.0
# Sections after which a Wikipedia article holds no prose about its subject.
_END_SECTIONS = {
    "see also",
    "references",
    "notes",
    "external links",
    "further reading",
    "bibliography",
    "sources",
    "citations",
    "footnotes",
    "gallery",
}
_HEADING = re.compile(r"(=+)\s*(.*?)\s*\1")
_QUALIFIER = re.compile(r"\s*\([^)]*\)\s*$")  # "Glass (material)" -> "Glass"


@dataclass(frozen=True)
class PageCandidate:
    """One search hit.

    Attributes:
        title: Page title ("Helleborus").
        pageid: MediaWiki page id.
        snippet: Plain-text snippet around the match (HTML removed), for showing to a user.
        size: Page size in bytes.
        wordcount: Words on the page.
    """

    title: str
    pageid: int
    snippet: str = ""
    size: int = 0
    wordcount: int = 0


#: ``choose(concept, ranked_candidates)`` returns the page to use, or None to use none.
Chooser = Callable[[str, list[PageCandidate]], PageCandidate | None]


@dataclass(frozen=True)
class WikiPage:
    """A fetched page.

    Attributes:
        title: The page's title after following redirects.
        pageid: MediaWiki page id.
        text: Plain-text extract (section headings as ``== Heading ==`` lines).
        disambiguation: Whether the page is a disambiguation page (a list of meanings, no facts).
    """

    title: str
    pageid: int
    text: str
    disambiguation: bool = False


def validate_api_url(url: str) -> str:
    """A MediaWiki ``api.php`` URL, checked (see :func:`conceptbot.core.urls.check_http_url`).

    Raises:
        ConfigError: Not an absolute http(s) URL with a host and a valid port.
    """
    return check_http_url(url, "Wikipedia API URL", DEFAULT_BASE_URL)


class WikipediaClient:
    """A small MediaWiki API client (search and plain-text extracts), standard library only.

    Args:
        base_url: The wiki's ``api.php`` URL.
        timeout_s: Seconds to wait for each HTTP request.
        max_retries: Extra tries, with exponential backoff, after a connection error, a time-out
            or HTTP 408/429/5xx.
        user_agent: Sent with every request, as Wikimedia's API policy asks.
        backoff_s: First backoff delay; it doubles with every retry (capped at 8 s).

    Raises:
        ConfigError: Malformed ``base_url`` or a non-positive time-out / negative retry count.
    """

    def __init__(
        self,
        base_url: str = DEFAULT_BASE_URL,
        timeout_s: float = 10,
        max_retries: int = 2,
        user_agent: str = DEFAULT_USER_AGENT,
        backoff_s: float = 0.5,
    ) -> None:
        self.base_url = validate_api_url(base_url)
        if timeout_s <= 0:
            raise ConfigError(f"the Wikipedia time-out must be positive, not {timeout_s}")
        if max_retries < 0:
            raise ConfigError(f"the Wikipedia retry count must be 0 or more, not {max_retries}")
        if backoff_s < 0:
            raise ConfigError(f"the Wikipedia backoff must be 0 or more, not {backoff_s}")
        self.timeout_s = timeout_s
        self.max_retries = max_retries
        self.user_agent = user_agent
        self.backoff_s = backoff_s

    def search(self, concept: str, limit: int = 5) -> list[PageCandidate]:
        """Full-text search of article titles and text.

        Args:
            concept: What to search for ("hellebore").
            limit: At most this many hits (1-500).

        Returns:
            The hits in the API's relevance order (empty when nothing matches).

        Raises:
            KnowledgeUnavailableError: Wikipedia cannot be reached or answered something unusable.
        """
        query = concept.strip()
        if not query or limit < 1:
            return []
        data = self._get(
            {
                "action": "query",
                "list": "search",
                "srsearch": query,
                "srlimit": str(min(limit, 500)),
                "srnamespace": "0",  # articles only, not talk or user pages
            }
        )
        hits = _dig(data, "query", "search", default=None)
        if not isinstance(hits, list):
            raise _unusable("the search result is not a list")
        out: list[PageCandidate] = []
        for hit in hits:
            if not isinstance(hit, dict) or not isinstance(hit.get("title"), str):
                raise _unusable("a search hit has no title")
            out.append(
                PageCandidate(
                    title=hit["title"],
                    pageid=_int(hit.get("pageid")),
                    snippet=_plain(str(hit.get("snippet", ""))),
                    size=_int(hit.get("size")),
                    wordcount=_int(hit.get("wordcount")),
                )
            )
        return out[:limit]

    def page(self, title: str) -> WikiPage | None:
        """Fetch a page's plain text and whether it is a disambiguation page (redirects followed).

        Args:
            title: Page title.

        Returns:
            The page, or None when it does not exist (or the title is invalid).

        Raises:
            KnowledgeUnavailableError: Wikipedia cannot be reached or answered something unusable.
        """
        if not title.strip():
            return None
        data = self._get(
            {
                "action": "query",
                "prop": "extracts|pageprops",
                "explaintext": "1",
                "redirects": "1",
                "ppprop": "disambiguation",
                "titles": title,
            }
        )
        pages = _dig(data, "query", "pages", default=None)
        if isinstance(pages, dict):  # formatversion=1: {"<pageid>": {...}}
            pages = list(pages.values())
        if not isinstance(pages, list) or not pages or not isinstance(pages[0], dict):
            raise _unusable("the answer has no pages")
        page = pages[0]
        if "missing" in page or "invalid" in page:
            return None
        props = page.get("pageprops")
        return WikiPage(
            title=str(page.get("title", title)),
            pageid=_int(page.get("pageid")),
            text=str(page.get("extract") or ""),
            disambiguation=isinstance(props, dict) and "disambiguation" in props,
        )

    def page_text(self, title: str) -> str:
        """A page's plain text.

        Args:
            title: Page title.

        Returns:
            The plain-text extract; empty when the page does not exist.

        Raises:
            KnowledgeUnavailableError: Wikipedia cannot be reached or answered something unusable.
        """
        page = self.page(title)
        return page.text if page is not None else ""

    def _get(self, params: dict[str, str]) -> dict[str, Any]:
        """GET the API with bounded retries; the parsed JSON object."""
        query = urllib.parse.urlencode({**params, "format": "json"})
        url = f"{self.base_url}{'&' if '?' in self.base_url else '?'}{query}"
        request = urllib.request.Request(
            url, headers={"User-Agent": self.user_agent, "Accept": "application/json"}
        )
        problem = ""
        for attempt in range(self.max_retries + 1):
            if attempt:
                time.sleep(min(self.backoff_s * 2 ** (attempt - 1), _MAX_BACKOFF_S))
            try:
                with urllib.request.urlopen(request, timeout=self.timeout_s) as response:
                    body = response.read()
            except urllib.error.HTTPError as exc:  # before URLError: it is one
                problem = f"HTTP {exc.code}"
                if exc.code in _RETRY_STATUS:
                    continue
                raise KnowledgeUnavailableError(
                    f"Wikipedia refused the request ({problem}) at {self.base_url}", hint=OFFLINE_HINT
                ) from exc
            except (urllib.error.URLError, TimeoutError, ConnectionError, http.client.HTTPException) as exc:
                reason = getattr(exc, "reason", exc)
                problem = (
                    f"cannot connect: {reason}" if str(reason) else f"cannot connect: {type(exc).__name__}"
                )
                continue
            return self._decode(body)
        raise KnowledgeUnavailableError(
            f"Wikipedia is unreachable at {self.base_url} ({problem}; "
            f"{self.max_retries + 1} attempt{'s' if self.max_retries else ''})",
            hint=OFFLINE_HINT,
        )

    def _decode(self, body: bytes) -> dict[str, Any]:
        try:
            data = json.loads(body)
        except (ValueError, UnicodeDecodeError) as exc:
            # Captive portals and proxies answer 200 with an HTML page.
            raise _unusable(f"the answer is not JSON ({body[:60]!r})") from exc
        if not isinstance(data, dict):
            raise _unusable("the answer is not a JSON object")
        error = data.get("error")
        if isinstance(error, dict):
            raise KnowledgeUnavailableError(
                f"the Wikipedia API reported an error: {error.get('code', '?')}: {error.get('info', '')}",
                hint=OFFLINE_HINT,
            )
        return data


def rank_pages(concept: str, candidates: Sequence[PageCandidate]) -> list[PageCandidate]:
    """Order search hits by how likely they are the page about ``concept``.

    The rule, by tier (a stable sort, so the API's relevance order decides within a tier):

    0. the normalised title equals the concept (plural and singular count as equal:
       "Knives" = "knife");
    1. the title without a parenthetical qualifier equals it ("Glass (material)" for "glass");
    2. the title contains the concept's head noun, its last word ("Green hellebore" for
       "hellebore", "Bowl" for "ceramic bowl");
    3. any other hit;
    4. lists and disambiguation titles ("List of poisonous plants", "Glass (disambiguation)"),
       which hold no facts about one object.

    Disambiguation pages whose titles do not say so are recognised, and skipped, only when their
    text is fetched (:class:`WikipediaFallback`).

    Args:
        concept: The object name asked for.
        candidates: Search hits in the API's order.

    Returns:
        The same hits, best first.
    """
    phrase = normalize(concept)
    words = phrase.split(" ") if phrase else []
    head = singular(words[-1]) if words else ""

    def tier(candidate: PageCandidate) -> int:
        raw = candidate.title.strip().lower()
        if raw.startswith("list of") or raw.endswith("(disambiguation)"):
            return 4
        title = normalize(candidate.title)
        if _same_concept(title, phrase):
            return 0
        base = normalize(_QUALIFIER.sub("", candidate.title))
        if _same_concept(base, phrase):
            return 1
        if head and head in {singular(w) for w in re.findall(r"[a-z0-9]+", base)}:
            return 2
        return 3

    return sorted(candidates, key=tier)


def clean_extract(text: str, max_chars: int = DEFAULT_MAX_CHARS) -> str:
    """A page's prose: headings dropped, reference sections cut off, at most ``max_chars``.

    Args:
        text: A plain-text extract with ``== Heading ==`` lines.
        max_chars: Keep at most this many characters, cut at the end of a sentence where possible.

    Returns:
        One paragraph a line.
    """
    lines: list[str] = []
    for line in text.splitlines():
        stripped = line.strip()
        heading = _HEADING.fullmatch(stripped)
        if heading:
            if heading.group(2).lower() in _END_SECTIONS:
                break
            continue
        if stripped:
            lines.append(stripped)
    out = "\n".join(lines)
    if len(out) <= max_chars:
        return out
    cut = out[:max_chars]
    end = max(cut.rfind(". "), cut.rfind("\n"))
    # A half sentence would give a wrong triple; but do not throw away most of the budget for it.
    return cut[: end + 1].rstrip() if end > max_chars // 2 else cut


class WikipediaFallback:
    """Risk facts from Wikipedia, as a :class:`~conceptbot.knowledge.base.KnowledgeGraph`.

    Results are cached per concept for the object's lifetime, so the user is asked (``choose``) and
    Wikipedia is queried at most once per concept.

    Args:
        client: The MediaWiki client.
        choose: ``choose(concept, ranked_candidates) -> candidate or None``, e.g. the CLI's
            interactive prompt (the paper's page selection); None uses :func:`rank_pages`.
        embedder: Turns on the cosine filter (a triple is kept if a keyword OR the cosine keeps it).
        keywords: Risk keywords; None reads the packaged ``risk_keywords.txt``, an empty list turns
            the keyword filter off.
        max_sentences: Analyse at most this many sentences of the page (bounds spaCy's time).
        max_chars: Analyse at most this many characters of the page.
        threshold: Cosine threshold (the paper's 0.75).
        targets: Target properties for the cosine filter.
        search_limit: Search hits to ask for.
        max_pages: Without ``choose``, fetch at most this many ranked pages looking for one that is
            not a disambiguation page and has text.

    Raises:
        ConfigError: A limit below 1.
    """

    name = "wikipedia"
    version = ""  # live pages are not versioned; see KnowledgeGraph.version

    def __init__(
        self,
        client: WikipediaClient,
        choose: Chooser | None = None,
        embedder: Embedder | None = None,
        keywords: Sequence[str] | None = None,
        max_sentences: int = DEFAULT_MAX_SENTENCES,
        max_chars: int = DEFAULT_MAX_CHARS,
        threshold: float = DEFAULT_THRESHOLD,
        targets: Sequence[str] = DEFAULT_TARGETS,
        search_limit: int = 5,
        max_pages: int = 3,
    ) -> None:
        for label, value in (
            ("max_sentences", max_sentences),
            ("max_chars", max_chars),
            ("search_limit", search_limit),
            ("max_pages", max_pages),
        ):
            if value < 1:
                raise ConfigError(f"the Wikipedia fallback's {label} must be at least 1, not {value}")
        if not -1.0 <= threshold <= 1.0:
            raise ConfigError(f"the cosine threshold must be in [-1, 1], not {threshold}")
        self.client = client
        self.choose = choose
        self.embedder = embedder
        self.keywords = tuple(load_keywords() if keywords is None else (k.lower() for k in keywords))
        self.max_sentences = max_sentences
        self.max_chars = max_chars
        self.threshold = threshold
        self.targets = tuple(targets)
        self.search_limit = search_limit
        self.max_pages = max_pages
        self._cache: dict[str, tuple[str | None, tuple[Edge, ...]]] = {}

    def edges(
        self, concept: str, relations: Sequence[str] | None = None, limit: int = DEFAULT_LIMIT
    ) -> ConceptEdges:
        """Risk-relevant edges read from the Wikipedia page about ``concept``.

        Args:
            concept: Object name ("hellebore", "Jack Bean").
            relations: Keep only these relations. Triples whose relation is a verb phrase
                ("contains") pass only if that text is listed.
            limit: At most this many edges, in page order.

        Returns:
            ``match="fallback"`` and ``matched`` = the page title when edges were found; otherwise
            no edges, ``match="none"``.

        Raises:
            KnowledgeUnavailableError: Wikipedia cannot be reached or answered something unusable.
        """
        phrase = normalize(concept)
        if not phrase:
            return ConceptEdges(concept, None, "none", ())
        if phrase not in self._cache:
            self._cache[phrase] = self._lookup(phrase)
        title, edges = self._cache[phrase]
        if relations is not None:
            wanted = set(relations)
            edges = tuple(e for e in edges if e.relation in wanted)
        edges = edges[: max(limit, 0)]
        if not edges:
            return ConceptEdges(concept, None, "none", ())
        return ConceptEdges(concept, title, "fallback", edges)

    def find_page(self, concept: str) -> WikiPage | None:
        """The page the fallback reads for ``concept`` (search, then ``choose`` or the ranking rule).

        Args:
            concept: Object name.

        Returns:
            The page, or None: no hit, the user chose none, or only disambiguation / empty pages.

        Raises:
            KnowledgeUnavailableError: Wikipedia cannot be reached or answered something unusable.
        """
        phrase = normalize(concept)
        candidates = rank_pages(phrase, self.client.search(phrase, limit=self.search_limit))
        if not candidates:
            return None
        if self.choose is not None:
            picked = self.choose(phrase, candidates)
            # The user's choice is final: an unusable page means no fallback, not a silent substitute.
            return _usable(self.client.page(picked.title)) if picked is not None else None
        for candidate in candidates[: self.max_pages]:
            page = _usable(self.client.page(candidate.title))
            if page is not None:
                return page
        return None

    def page_triples(self, page: WikiPage) -> list[Triple]:
        """The filtered triples of a page (the first ``max_sentences`` / ``max_chars`` only).

        Args:
            page: A fetched page.

        Returns:
            Risk-relevant triples, pronouns replaced by the page's subject.

        Raises:
            KnowledgeUnavailableError: The spaCy model is not installed.
            BackendUnavailableError: The embedder cannot run.
        """
        subject = normalize(_QUALIFIER.sub("", page.title))  # "Glass (material)" talks about glass
        text = clean_extract(page.text, self.max_chars)
        triples = extract_triples(text, subject_hint=subject or None, max_sentences=self.max_sentences)
        return filter_triples(triples, self.keywords, self.embedder, self.targets, self.threshold)

    def _lookup(self, phrase: str) -> tuple[str | None, tuple[Edge, ...]]:
        page = self.find_page(phrase)
        if page is None:
            return None, ()
        edges: dict[Edge, None] = {}
        for triple in self.page_triples(page):
            head, tail = normalize(triple.subject), normalize(triple.object)
            if head and tail:
                edges.setdefault(Edge(head, triple.relation, tail, 1.0, "wikipedia"), None)
        return page.title, tuple(edges)


def _usable(page: WikiPage | None) -> WikiPage | None:
    if page is None or page.disambiguation or not page.text.strip():
        return None
    return page


def _same_concept(title: str, phrase: str) -> bool:
    if not title or not phrase:
        return False
    if title == phrase:
        return True
    a, b = title.split(" "), phrase.split(" ")
    return len(a) == len(b) and a[:-1] == b[:-1] and singular(a[-1]) == singular(b[-1])


def _dig(data: dict[str, Any], *keys: str, default: Any) -> Any:
    value: Any = data
    for key in keys:
        if not isinstance(value, dict) or key not in value:
            return default
        value = value[key]
    return value


def _int(value: Any) -> int:
    try:
        return int(value)
    except (TypeError, ValueError):
        return 0


def _plain(snippet: str) -> str:
    return html.unescape(re.sub(r"<[^>]+>", "", snippet))


def _unusable(detail: str) -> KnowledgeUnavailableError:
    return KnowledgeUnavailableError(f"Wikipedia's answer could not be used: {detail}", hint=OFFLINE_HINT)
