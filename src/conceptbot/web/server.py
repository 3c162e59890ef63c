"""The listening socket of ``conceptbot serve``, bound before anything says the server is up."""

from __future__ import annotations

import errno
import os
import socket

from conceptbot.core.errors import ConfigError


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
