"""The listening socket of ``conceptbot serve``, bound before anything says the server is up, and
the uvicorn server that serves the app on it."""

from __future__ import annotations

import errno
import os
import socket
from collections.abc import Callable
from typing import TYPE_CHECKING

from conceptbot.core.errors import ConfigError

if TYPE_CHECKING:
    from starlette.types import ASGIApp

GRACEFUL_S = 5
"""Seconds a stopping server waits for requests still being answered before it cancels them."""


def bind(host: str, port: int) -> socket.socket:
    """A socket bound to ``host:port``, for uvicorn to listen on.

    Bound before the CLI prints "ConceptBot on http://...", so that a taken port is a one-line error
    instead of that line followed by uvicorn's failure; uvicorn then serves on this same socket, which
    leaves no moment for another program to take the port between the check and the serving.

    Args:
        host: Address to bind (an IPv6 address without brackets), or a name such as ``localhost``.
        port: TCP port (0: any free one).

    Raises:
        ConfigError: The port is taken, or ``host`` is not an address of this machine.
    """
    # The family uvicorn picks for --host: IPv6 for an address with a colon.
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    if os.name != "nt":
        # As uvicorn does: a port left in TIME_WAIT by a server that has just stopped may be reused.
        # (On Windows SO_REUSEADDR would let two servers share one port.)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        if exc.errno == errno.EADDRINUSE:
            other = port + 1 if port < 65535 else 8765
            raise ConfigError(
                f"port {port} on {host} is already in use (another conceptbot serve?)",
                hint=f"choose another port, e.g. conceptbot serve --port {other}",
            ) from None
        raise ConfigError(
            f"cannot listen on {host}:{port}: {exc.strerror or exc}",
            hint="give --host an address of this machine, e.g. 127.0.0.1",
        ) from None
    return sock


def serve(app: ASGIApp, sock: socket.socket, *, on_shutdown: Callable[[], None]) -> None:
    """Serve ``app`` on ``sock`` with uvicorn until SIGINT or SIGTERM, then shut down gracefully.

    uvicorn waits for every open connection before it stops, and an event stream stays open until
    its run ends: ``on_shutdown`` (the run manager's ``stop_streams``) runs first, on the event loop,
    so the streams end and the server stops at once; :data:`GRACEFUL_S` bounds anything else.

    After shutting down, uvicorn raises the signal it caught again (so SIGTERM's handler, or
    Python's default action, still runs): the caller decides what SIGTERM does.

    Args:
        app: The web app.
        sock: A socket from :func:`bind` (uvicorn closes it).
        on_shutdown: Called once the server begins to shut down.
    """
    import uvicorn  # not at the top: `bind` runs before the slow imports

    class Server(uvicorn.Server):
        async def shutdown(self, sockets: list[socket.socket] | None = None) -> None:
            on_shutdown()
            await super().shutdown(sockets=sockets)

    config = uvicorn.Config(app, log_level="warning", timeout_graceful_shutdown=GRACEFUL_S)
    Server(config).run(sockets=[sock])
