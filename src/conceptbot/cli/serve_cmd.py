"""``conceptbot serve``: the local web page."""

from __future__ import annotations

import ipaddress
from pathlib import Path

import click

from conceptbot.cli.main import AppContext, pass_app


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
    import uvicorn

    from conceptbot.web.app import create_app
    from conceptbot.web.runs import RunManager
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
    web = create_app(
        manager, backends=available_backends(app.settings), results_dir=results_dir, can_simulate=can_simulate
    )
    click.echo(f"ConceptBot on http://{host}:{port}/  (Ctrl-C to stop)")
    try:
        uvicorn.run(web, host=host, port=port, log_level="warning")
    finally:
        manager.close()
