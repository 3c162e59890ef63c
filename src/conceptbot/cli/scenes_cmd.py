"""``conceptbot scenes``: the demo scenes shipped with the package."""

from __future__ import annotations

import json

import click
from rich.console import Console
from rich.table import Table

from conceptbot.scenes import demo_scene_names, load_demo_scene


@click.command("scenes")
@click.argument("name", required=False)
def scenes(name: str | None) -> None:
    """List the demo scenes (the paper's), or print one as JSON to start your own from."""
    if name:
        click.echo(json.dumps(load_demo_scene(name).to_dict(), indent=2, ensure_ascii=False))
        return
    table = Table("name", "objects", "pickable", "destinations", "from")
    for scene_name in demo_scene_names():
        scene = load_demo_scene(scene_name)
        table.add_row(
            scene_name,
            str(len(scene.names)),
            str(len(scene.pickable)),
            ", ".join(scene.destinations)[:40],
            scene.description[:50],
        )
    Console().print(table)
