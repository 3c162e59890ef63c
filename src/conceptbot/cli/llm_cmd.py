"""``conceptbot llm``: one call to the configured LLM."""

from __future__ import annotations

import json
from pathlib import Path

import click

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.params import FiniteFloatRange
from conceptbot.core.errors import ConfigError
from conceptbot.core.limits import check_text
from conceptbot.core.text import terminal_safe
from conceptbot.models.llm import ChatRequest
from conceptbot.models.registry import open_llm
from conceptbot.models.structured import chat_json, compile_schema


@click.command("llm")
@click.argument("prompt")
@click.option("--system", "-s", help="System message.")
@click.option("--max-tokens", default=256, show_default=True, type=click.IntRange(1, 32768))
@click.option("--temperature", "-t", default=0.0, show_default=True, type=FiniteFloatRange(0.0, 2.0))
@click.option(
    "-n", "n", default=1, show_default=True, type=click.IntRange(1, 64), help="Number of completions."
)
@click.option("--seed", default=0, show_default=True, type=int)
@click.option(
    "--schema",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    help="JSON schema file: the reply must be JSON matching it.",
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (reply, usage, timing).")
@pass_app
def llm(
    app: AppContext,
    prompt: str,
    system: str | None,
    max_tokens: int,
    temperature: float,
    n: int,
    seed: int,
    schema: Path | None,
    as_json: bool,
) -> None:
    """Send PROMPT to the configured LLM once; print the reply, tokens and time."""
    # The schema is checked before the model is loaded: a bad file costs no model time.
    schema_value = _read_schema(schema) if schema is not None else None
    check_text(prompt, "prompt")
    if system is not None:
        check_text(system, "system message")
    model = open_llm(app.settings, module="cli")
    request = ChatRequest.of(
        prompt, system=system, max_tokens=max_tokens, temperature=temperature, n=n, seed=seed
    )
    parsed = None
    if schema_value is not None:
        parsed, response = chat_json(model, request, schema_value)
    else:
        response = model.chat(request)
    usage = response.usage
    if as_json:
        click.echo(
            json.dumps(
                {
                    "backend": response.backend,
                    "model": response.model,
                    "choices": list(response.choices),
                    "parsed": parsed,
                    "cached": response.cached,
                    "usage": {
                        "prompt_tokens": usage.prompt_tokens,
                        "completion_tokens": usage.completion_tokens,
                        "latency_s": round(usage.latency_s, 3),
                        "cost_usd": usage.cost_usd,
                    },
                },
                indent=2,
            )
        )
        return
    for i, choice in enumerate(response.choices):
        if n > 1:
            click.secho(f"--- completion {i + 1}", dim=True)
        # A model can emit ESC and friends; shown as escapes, never obeyed by the terminal.
        click.echo(terminal_safe(choice.strip()))
    click.secho(
        f"[{terminal_safe(response.backend)}:{terminal_safe(response.model)}]"
        f" tokens: {usage.prompt_tokens} in, {usage.completion_tokens} out"
        f" | {usage.latency_s:.2f} s | {'cached' if response.cached else 'fresh'}"
        f" | cost ${usage.cost_usd:.6f}",
        dim=True,
        err=True,
    )


def _read_schema(path: Path) -> dict[str, object]:
    """The JSON Schema in ``path``, checked (see :func:`~conceptbot.models.structured.compile_schema`).

    Raises:
        ConfigError: Unreadable, not JSON, nested past the decoder's recursion limit, or not a
            usable schema.
    """
    try:
        value = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise ConfigError(f"{path} is not UTF-8 text") from None
    except ValueError as exc:
        raise ConfigError(f"{path} is not valid JSON: {exc}") from None
    except RecursionError:
        raise ConfigError(f"{path} is nested too deeply to be a JSON Schema") from None
    except OSError as exc:
        raise ConfigError(f"cannot read {path}: {exc.strerror or exc}") from None
    compile_schema(value, where=str(path))
    return value
