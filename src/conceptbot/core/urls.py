"""Checking service URLs given by users (API base URLs, MediaWiki endpoints), and keeping the
credentials some of them carry out of messages, logs and caches.

Redaction rule (:func:`redact_url`): the userinfo (``user:password@``) is dropped and the value of
every query parameter becomes ``***`` (the names stay, so a user can still tell which URL is meant);
scheme, host, port, path and fragment are kept. :func:`redact_secrets` applies the same rule to
every URL found in a free text, and also masks ``Bearer`` tokens, OpenAI-style ``sk-...`` keys and
``key=``/``token=``/``password=``/``secret=`` assignments outside URLs. Both run on anything that
is shown to a user or written to disk (error messages, the call log in ``cache.db``).

Patterns cannot know a key that looks like nothing in particular ("boom for key ck-456"), so a backend
also masks the secrets it was configured with, by value (:class:`Redactor`): its API key, its base
URL's password and the ``Basic`` form an HTTP client makes of ``user:password@``, and its base URL's
query values, whatever the text around them.
"""

from __future__ import annotations

import base64
import re
from urllib.parse import parse_qsl, quote, unquote, urlsplit, urlunsplit

from conceptbot.core.errors import ConfigError

MASK = "***"

# A URL ends at whitespace, quotes or brackets, as it does inside repr()s and log lines.
_URL = re.compile(r"\b[A-Za-z][A-Za-z0-9+.\-]*://[^\s'\"<>`]+")
_BEARER = re.compile(r"(?i)\b(bearer\s+)[A-Za-z0-9._~+/=\-]+")
# HTTP Basic credentials (base64 of "user:password"); a digit, "+", "/" or "=" is required so that
# English ("basic authentication") is left alone.
_BASIC = re.compile(r"\b(Basic\s+)(?=[A-Za-z0-9+/]*[0-9+/=])[A-Za-z0-9+/]{8,}={0,2}")
# Configured secrets shorter than this are not masked by value: masking "1" or "v2" everywhere would
# garble messages, and so short a value protects nothing (the patterns above still apply).
MIN_SECRET_CHARS = 4
# OpenAI keys: sk-..., sk-proj-...; 16+ characters so "sk-learn" and the like are left alone.
_SK_KEY = re.compile(r"\bsk-[A-Za-z0-9_\-]{16,}")
_ASSIGNMENT = re.compile(
    r"(?i)\b((?:api[_-]?key|access[_-]?token|auth[_-]?token|token|key|password|passwd|secret|sig)"
    r"\s*[=:]\s*)([^\s&'\",;]+)"
)


def check_http_url(url: str, what: str, example: str, *, allow_query: bool = True) -> str:
    """``url`` without surrounding spaces or a trailing slash, if it is an absolute http(s) URL.

    Args:
        url: The URL as the user gave it.
        what: What it is, for the message ("base URL", "Wikipedia API URL").
        example: A correct URL for the hint.
        allow_query: Whether a query string or fragment is acceptable.

    Raises:
        ConfigError: ``malformed <what> '<url>'``: not http(s), no host, a bad port, or a query where
            none is allowed. The URL in the message is redacted (see :func:`redact_url`).
    """
    text = str(url).strip()
    try:
        parts = urlsplit(text)
        port_ok = parts.port is None or 0 < parts.port < 65536
    except ValueError:
        parts, port_ok = None, False
    if (
        parts is None
        or parts.scheme not in ("http", "https")
        or not parts.hostname
        or not port_ok
        or (not allow_query and (parts.query or parts.fragment))
    ):
        raise ConfigError(
            f"malformed {what} {redact_url(str(url))!r}",
            hint=f"use an absolute http(s) URL such as {example}",
        )
    return text.rstrip("/")


def _redact_query(query: str) -> str:
    if not query:
        return query
    fields = []
    for field in query.split("&"):
        name, sep, _value = field.partition("=")
        # A bare field ("?SECRET") may itself be a token: mask it whole.
        fields.append(f"{name}={MASK}" if sep else (MASK if name else name))
    return "&".join(fields)


def redact_url(url: str) -> str:
    """``url`` with its credentials removed, fit to show or store.

    The ``user:password@`` part is dropped and every query value is replaced by ``***``
    (``http://u:p@h:8000/v1?key=S&x=1#m`` -> ``http://h:8000/v1?key=***&x=***#m``). Text that does not
    parse as a URL is passed through :func:`redact_secrets`' other patterns instead.

    Args:
        url: Any URL (or URL-like text).

    Returns:
        The redacted URL; a URL without credentials comes back unchanged.
    """
    text = str(url)
    try:
        parts = urlsplit(text)
        host = parts.hostname or ""
        port = parts.port
    except ValueError:
        return _redact_plain(_redact_userinfo_loosely(text))
    netloc = parts.netloc
    if "@" in netloc:
        if ":" in host:  # IPv6 literal: urlsplit strips the brackets
            host = f"[{host}]"
        netloc = host + (f":{port}" if port is not None else "")
    if netloc == parts.netloc and not parts.query:
        return text
    return urlunsplit((parts.scheme, netloc, parts.path, _redact_query(parts.query), parts.fragment))


def _redact_userinfo_loosely(text: str) -> str:
    # For text urlsplit rejects: drop anything between "//" and the last "@" of the authority.
    return re.sub(r"//[^/?#@\s]*@", "//", text)


def _redact_plain(text: str) -> str:
    text = _BEARER.sub(lambda m: m.group(1) + MASK, text)
    text = _BASIC.sub(lambda m: m.group(1) + MASK, text)
    text = _SK_KEY.sub(MASK, text)
    return _ASSIGNMENT.sub(lambda m: m.group(1) + MASK, text)


def redact_secrets(text: str) -> str:
    """``text`` with credentials masked: every URL redacted (:func:`redact_url`), ``Bearer`` and
    ``Basic`` tokens, OpenAI-style ``sk-...`` keys and ``key=...``-style assignments replaced by ``***``.

    Used on error messages before they are shown or written to the call log, since a backend's
    message may quote the URL it was given (query string and userinfo included) or the key itself.
    """
    text = str(text)
    # URLs and the text between them are masked separately: a URL's own redaction keeps what is
    # safe in it (the "#MODEL" of a spec), which the plain patterns would swallow.
    out, last = [], 0
    for match in _URL.finditer(text):
        out.append(_redact_plain(text[last : match.start()]))
        out.append(redact_url(match.group(0)))
        last = match.end()
    out.append(_redact_plain(text[last:]))
    return "".join(out)


def split_query(url: str) -> tuple[str, dict[str, str]]:
    """``url`` without its query and fragment, and the query's fields.

    HTTP clients that append endpoint paths to a base URL (the OpenAI SDK: ``BASE + "chat/completions"``)
    would put the path after a query (``/v1?key=Xchat/completions``); they take the query apart
    (``default_query``) and send it with every request instead.

    Args:
        url: An absolute URL (already checked with :func:`check_http_url`).

    Returns:
        ``(base, fields)``: ``http://h/v1?api_key=X#m`` -> ``("http://h/v1", {"api_key": "X"})``.
        Values are percent-decoded (the client encodes them again); a bare field (``?TOKEN``)
        becomes ``{"TOKEN": ""}``.

    Raises:
        ConfigError: A field is named twice (one value per name can be sent as a default).
    """
    parts = urlsplit(str(url))
    fields: dict[str, str] = {}
    for name, value in parse_qsl(parts.query, keep_blank_values=True):
        if name in fields:
            raise ConfigError(
                f"base URL {redact_url(str(url))!r} names query parameter {name!r} twice",
                hint="give each query parameter once",
            )
        fields[name] = value
    base = urlunsplit((parts.scheme, parts.netloc, parts.path.rstrip("/"), "", ""))
    return base, fields


def url_secrets(url: str | None) -> list[str]:
    """The secret parts of ``url`` in every form a server may quote them back.

    The password of ``user:password@`` (as written and percent-decoded), the ``Basic`` credential an
    HTTP client builds from it (base64 of ``user:password``), and each query value (and bare field).

    Args:
        url: A URL, or ``None``.

    Returns:
        The values, possibly with repeats; none for a URL without credentials.
    """
    if not url:
        return []
    try:
        parts = urlsplit(str(url))
        username, password = parts.username, parts.password
    except ValueError:
        return []
    found: list[str] = []
    if password is not None:
        user, secret = unquote(username or ""), unquote(password)
        found += [password, secret]
        for creds in {f"{user}:{secret}", f"{username}:{password}"}:
            encoded = base64.b64encode(creds.encode("utf-8")).decode("ascii")
            found += [encoded, encoded.rstrip("=")]
    for field in parts.query.split("&") if parts.query else []:
        name, sep, value = field.partition("=")
        raw = value if sep else name
        found += [raw, unquote(raw.replace("+", " "))]
    return found


class Redactor:
    """Masks the secrets a backend was configured with, by value, then by pattern.

    Servers and proxies quote keys back in forms no pattern recognises ("boom for key ck-456",
    "token ck-456"), so the key, the base URL's password (and its ``Basic`` form) and query values
    are replaced by ``***`` wherever they appear; :func:`redact_secrets` then masks URLs and the
    usual ``Bearer``/``sk-``/``key=`` forms. Values shorter than :data:`MIN_SECRET_CHARS` are not
    masked by value.

    Args:
        keys: API keys.
        urls: URLs whose credentials are secret (the base URL).
    """

    def __init__(self, keys: tuple[str | None, ...] = (), urls: tuple[str | None, ...] = ()) -> None:
        values = {k for k in keys if k}
        values |= {quote(k, safe="") for k in keys if k}
        for url in urls:
            values.update(url_secrets(url))
        # Longest first, so a secret that contains another is masked whole.
        self._values = tuple(sorted((v for v in values if len(v) >= MIN_SECRET_CHARS), key=len, reverse=True))

    def __repr__(self) -> str:
        # Never the values: a repr can end up in a log or a traceback.
        return f"Redactor({len(self._values)} secrets)"

    def __call__(self, text: str) -> str:
        """``text`` with every configured secret and every pattern-recognised credential masked."""
        text = str(text)
        for value in self._values:
            text = text.replace(value, MASK)
        return redact_secrets(text)
