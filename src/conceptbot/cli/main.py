"""The ``conceptbot`` command."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import click

from conceptbot.cli.context import AppContext
from conceptbot.core.config import load_settings
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.text import terminal_safe
from conceptbot.core.version import __version__


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(__version__, prog_name="conceptbot")
@click.option(
    "--home",
    type=click.Path(path_type=Path),
    help="Home directory (default: $CONCEPTBOT_HOME or the user cache dir).",
)
@click.option(
    "--llm",
    "llm",
    metavar="SPEC",
    help="LLM backend, e.g. llamacpp:qwen2.5-coder-1.5b, openai:gpt-4o-mini, openai-compatible:URL#MODEL.",
)
@click.option(
    "--embedder",
    metavar="SPEC",
    help="Embedder backend, e.g. sentence-transformers:all-MiniLM-L6-v2, openai:text-embedding-ada-002.",
)
@click.option(
    "--kg",
    metavar="SPEC",
    help="Knowledge graph: sqlite (default), conceptnet-api[:URL], conceptnet-api-cache.",
)
@click.option(
    "--no-cache",
    is_flag=True,
    help="Neither read nor write the caches (LLM replies, embeddings, OPE results); calls are still logged.",
)
@click.pass_context
def cli(
    ctx: click.Context,
    home: Path | None,
    llm: str | None,
    embedder: str | None,
    kg: str | None,
    no_cache: bool,
) -> None:
    """ConceptBot: turn a request to a robot into a safe, feasible plan, grounded in ConceptNet."""
    settings = load_settings(
        home=home, llm=llm, embedder=embedder, kg=kg, use_cache=False if no_cache else None
    )
    ctx.obj = AppContext(settings=settings)


def _register() -> None:
    from conceptbot.cli import (
        bench_cmd,
        calibrate_cmd,
        doctor,
        kg_cmd,
        llm_cmd,
        models_cmd,
        plan_cmd,
        ros2_cmd,
        safebench_cmd,
        scenes_cmd,
        serve_cmd,
        sim_cmd,
    )

    cli.add_command(models_cmd.models)
    cli.add_command(kg_cmd.kg)
    cli.add_command(llm_cmd.llm)
    cli.add_command(doctor.doctor)
    cli.add_command(calibrate_cmd.calibrate)
    cli.add_command(plan_cmd.plan)
    cli.add_command(scenes_cmd.scenes)
    cli.add_command(bench_cmd.bench)
    cli.add_command(safebench_cmd.safebench)
    cli.add_command(sim_cmd.sim)
    cli.add_command(serve_cmd.serve)
    cli.add_command(ros2_cmd.ros2)


_register()


def main() -> None:
    """Entry point: run the CLI, turning user errors into a message and a non-zero exit.

    Every message printed here passes through :func:`~conceptbot.core.text.terminal_safe`: error
    messages quote requests, file names and servers' error bodies, any of which can hold escapes.
    """
    try:
        # With standalone_mode=False click returns the exit code of ctx.exit()/Exit instead of exiting.
        code = cli.main(standalone_mode=False)
        if isinstance(code, int) and code != 0:
            sys.exit(code)
    except ConceptBotError as exc:
        click.secho(f"Error: {terminal_safe(exc.message)}", fg="red", err=True)
        if exc.hint:
            click.echo(f"Hint: {terminal_safe(exc.hint)}", err=True)
        sys.exit(exc.exit_code)
    except click.exceptions.Abort:
        click.echo("Aborted.", err=True)
        sys.exit(130)
    except click.ClickException as exc:
        # Usage errors quote what was typed ("No such command '...'"), escapes included.
        shown = io.StringIO()
        exc.show(file=shown)
        click.echo(terminal_safe(shown.getvalue()), err=True, nl=False)
        sys.exit(exc.exit_code)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
