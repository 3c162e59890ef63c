"""Checking service URLs given by users (API base URLs, MediaWiki endpoints), and keeping the
credentials some of them carry out of messages, logs and caches.

Redaction rule (:func:`redact_url`): the userinfo (``user:password@``) is dropped and the value of
every query parameter becomes ``***`` (the names stay, so a user can still tell which URL is meant);
scheme, host, port, path and fragment are kept. :func:`redact_secrets` applies the same rule to
every URL found in a free text, and also masks ``Bearer`` tokens, OpenAI-style ``sk-...`` keys and
``key=``/``token=``/``password=``/``secret=`` assignments outside URLs. Both run on anything that
is shown to a user or written to disk (error messages, the call log in ``cache.db``).
"""

from __future__ import annotations

import re
from urllib.parse import urlsplit, urlunsplit

from conceptbot.core.errors import ConfigError

MASK = "***"

# A URL ends at whitespace, quotes or brackets, as it does inside repr()s and log lines.
_URL = re.compile(r"\b[A-Za-z][A-Za-z0-9+.\-]*://[^\s'\"<>`]+")
_BEARER = re.compile(r"(?i)\b(bearer\s+)[A-Za-z0-9._~+/=\-]+")
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
    text = _SK_KEY.sub(MASK, text)
    return _ASSIGNMENT.sub(lambda m: m.group(1) + MASK, text)


def redact_secrets(text: str) -> str:
    """``text`` with credentials masked: every URL redacted (:func:`redact_url`), ``Bearer``
    tokens, OpenAI-style ``sk-...`` keys and ``key=...``-style assignments replaced by ``***``.

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
