"""``conceptbot scenes``: the demo scenes shipped with the package."""

from __future__ import annotations

import click
from rich.console import Console
from rich.table import Table

from conceptbot.cli.richtext import plain
from conceptbot.core.text import safe_json_dumps
from conceptbot.scenes import demo_scene_names, load_demo_scene


@click.command("scenes")
@click.argument("name", required=False)
def scenes(name: str | None) -> None:
    """List the demo scenes (the paper's), or print one as JSON to start your own from."""
    if name:
        click.echo(safe_json_dumps(load_demo_scene(name).to_dict(), indent=2))
        return
    table = Table("name", "objects", "pickable", "destinations", "from")
    for scene_name in demo_scene_names():
        scene = load_demo_scene(scene_name)
        table.add_row(
            plain(scene_name),
            str(len(scene.names)),
            str(len(scene.pickable)),
            plain(", ".join(scene.destinations)[:40]),
            plain(scene.description[:50]),
        )
    Console().print(table)
