"""Checking service URLs given by users (API base URLs, MediaWiki endpoints)."""

from __future__ import annotations

from urllib.parse import urlsplit

from conceptbot.core.errors import ConfigError


def check_http_url(url: str, what: str, example: str, *, allow_query: bool = True) -> str:
    """``url`` without surrounding spaces or a trailing slash, if it is an absolute http(s) URL.

    Args:
        url: The URL as the user gave it.
        what: What it is, for the message ("base URL", "Wikipedia API URL").
        example: A correct URL for the hint.
        allow_query: Whether a query string or fragment is acceptable.

    Raises:
        ConfigError: ``malformed <what> '<url>'``: not http(s), no host, a bad port, or a query where
            none is allowed.
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
        raise ConfigError(f"malformed {what} {url!r}", hint=f"use an absolute http(s) URL such as {example}")
    return text.rstrip("/")
