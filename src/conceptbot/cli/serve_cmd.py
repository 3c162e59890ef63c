"""``conceptbot serve``: the local web page."""

from __future__ import annotations

import contextlib
import ipaddress
import socket
from pathlib import Path

import click

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.signals import Terminated, sigterm_raises
from conceptbot.core.extras import require


@click.command("serve")
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to bind (keep it local).")
@click.option("--port", default=8765, show_default=True, type=click.IntRange(1, 65535))
@click.option(
    "--results-dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=Path("results"),
    show_default=True,
    help="Where the benchmark reports are (for the results page).",
)
@pass_app
def serve(app: AppContext, host: str, port: int, results_dir: Path) -> None:
    """Start the web page: pick a scene, type a request, watch each module's reasoning and the plan."""
    require("web")
    from conceptbot.web.server import bind

    sock = bind(host, port)  # first: a taken port fails at once, before the slow imports
    # SIGTERM (systemd, docker) stops the server as Ctrl-C does, cleanup included: by default it
    # would end the process when uvicorn raises it again after shutting down, skipping `finally`.
    # Terminated suppressed: a stop asked for is a clean exit (code 0), as after Ctrl-C.
    with sock, sigterm_raises(), contextlib.suppress(Terminated):
        _serve_on(sock, app, host, port, results_dir)


def _serve_on(sock: socket.socket, app: AppContext, host: str, port: int, results_dir: Path) -> None:
    from conceptbot.web.app import create_app, local_hosts
    from conceptbot.web.runs import RunManager
    from conceptbot.web.server import serve
    from conceptbot.web.worker import available_backends, cached_systems, make_worker, simulator_available

    try:
        local = ipaddress.ip_address(host).is_loopback
    except ValueError:
        local = host == "localhost"
    if not local:
        click.secho(
            f"warning: binding {host}: anyone who can reach this address can run plans on this machine",
            fg="yellow",
            err=True,
        )
    can_simulate = simulator_available()
    manager = RunManager(make_worker(cached_systems(app.settings), can_simulate))
    try:
        web = create_app(
            manager,
            backends=available_backends(app.settings),
            results_dir=results_dir,
            can_simulate=can_simulate,
            # The Host values of the address bound: a page that reaches the server under any other
            # name (DNS rebinding) is refused.
            allowed_hosts=local_hosts(host, port),
        )
        shown = f"[{host}]" if ":" in host else host
        click.echo(f"ConceptBot on http://{shown}:{port}/  (Ctrl-C to stop)")
        serve(web, sock, on_shutdown=manager.stop_streams)
    except KeyboardInterrupt:
        pass  # uvicorn re-raises Ctrl-C after shutting down; uvicorn.run() swallows it too
    finally:
        manager.close()  # the runs' pictures; also on SIGTERM (Terminated passes through here)
