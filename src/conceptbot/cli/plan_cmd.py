"""``conceptbot plan``: plan a request in a scene and show why."""

from __future__ import annotations

import json
from collections.abc import Mapping

import click
from rich.console import Console
from rich.table import Table

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.progress import ON_STDERR
from conceptbot.core.limits import check_request
from conceptbot.core.plan import Plan
from conceptbot.core.trace import PlanTrace, RetrievalTrace
from conceptbot.pipeline.planner import METHODS
from conceptbot.scenes import resolve_scene
from conceptbot.systems import SYSTEMS, SystemOptions, build_system


@click.command("plan")
@click.argument("request")
@click.option(
    "--scene",
    "-s",
    "scene_ref",
    default="kitchen",
    show_default=True,
    help="A scene file (JSON) or a demo scene name (see `conceptbot scenes`).",
)
@click.option(
    "--config",
    "-c",
    type=click.Choice(SYSTEMS),
    default="conceptbot",
    show_default=True,
    help="System: conceptbot (goal planner), urp (without OPE), nokg (no graph facts), saycan "
    "(baseline), paper / paper-nokg (the paper's step planner), ope (the paper's OPE-only ablation).",
)
@click.option("--risk", is_flag=True, help="Use the Risk Index (danger 1-5, DangerousWith) in OPE.")
@click.option(
    "--method",
    type=click.Choice(METHODS),
    default="auto",
    show_default=True,
    help="Planner LLM score: logprob (one pass) or vote (n completions); auto picks by backend.",
)
@click.option(
    "-n", "n", default=5, show_default=True, type=click.IntRange(1, 20), help="Completions for vote."
)
@click.option("--theta", type=click.FloatRange(-1.0, 1.0), help="Cosine threshold (default: per embedder).")
@click.option("--fallback/--no-fallback", default=None, help="Wikipedia fallback (default: settings).")
@click.option("--json", "as_json", is_flag=True, help="Print the plan as one JSON object.")
@pass_app
def plan(
    app: AppContext,
    request: str,
    scene_ref: str,
    config: str,
    risk: bool,
    method: str,
    n: int,
    theta: float | None,
    fallback: bool | None,
    as_json: bool,
) -> None:
    """Plan REQUEST in a scene; print properties, relations, reasoning, step scores and the plan."""
    request = check_request(request)
    scene = resolve_scene(scene_ref)
    options = SystemOptions(theta=theta, planner_method=method, n=n, fallback=fallback)  # SayCan has none
    bot = build_system(app.settings, config, options)
    result = bot.plan(request, scene, risk=risk, observer=ON_STDERR)
    if as_json:
        click.echo(json.dumps(result.to_dict(), indent=2, ensure_ascii=False))
        return
    show(result, Console())


def show(result: Plan, console: Console) -> None:
    """The readable trace of a plan."""
    trace = result.trace
    console.print(f"[bold]Request:[/bold] {trace.request}   [dim](scene {trace.scene}, {trace.config})[/dim]")
    ope = trace.ope
    if ope:
        console.print(f"\n[bold]Object properties[/bold] (OPE, {ope.mode}: {ope.why})")
        objects = ope.objects
        keys = [k for k in next(iter(objects.values())).values if k != "object"] if objects else []
        table = Table("object", *keys, "cached")
        for name, info in objects.items():
            cells = []
            for key in keys:
                value = info.values.get(key)
                if isinstance(value, list):
                    value = ", ".join(
                        f"{v['object']} ({v['score']})" if isinstance(v, dict) else str(v) for v in value
                    )
                cells.append(str(value)[:60])
            table.add_row(name, *cells, "yes" if info.cached else "")
        console.print(table)
        _relations(console, "Kept relations per object (similarity, source)", ope.retrieval)
    urp = trace.urp
    if urp:
        console.print(f"\n[bold]Request keywords:[/bold] {', '.join(urp.keywords) or '(none)'}")
        _relations(console, "Kept relations of the keywords (vs the request)", urp.keyword_relations)
        console.print(f"\n[bold]Reasoning (URP):[/bold] {urp.reasoning}")
        console.print(f"[bold]Commands:[/bold] {', '.join(urp.commands) or '(none)'}")
        for rejected in urp.rejected_commands:
            console.print(f"  [yellow]rejected:[/yellow] {rejected}")
    _goal(console, trace)
    for step in result.steps:
        how = step.method if step.scoring in ("", "logprob") else f"{step.method}, scored by {step.scoring}"
        table = Table("action", "S_LLM", "S_aff", "combined", "factors", title=f"Step {step.index} ({how})")
        for c in step.candidates:
            mark = "[bold green]" if c.action == step.chosen else ""
            factors = " ".join(f"{k}={v:.2f}" for k, v in c.factors.items())
            table.add_row(
                f"{mark}{c.action}", f"{c.llm:.3f}", f"{c.affordance:.2f}", f"{c.combined:.3f}", factors
            )
        console.print(table)
        for rejected in step.rejected:
            console.print(f"  [yellow]rejected LLM output:[/yellow] {rejected}")
    if result.refused:
        console.print(f"\n[bold red]Refused:[/bold red] {result.reason}")
    console.print("\n[bold]Plan:[/bold]")
    for i, action in enumerate(result.actions, 1):
        console.print(f"  {i}. {action}")
    table = Table("module", "time (s)", "tokens in", "tokens out", "LLM calls", "cost (USD)", title="Usage")
    for module, usage in result.usage.items():
        table.add_row(
            module,
            f"{usage.latency_s:.2f}",
            str(usage.prompt_tokens),
            str(usage.completion_tokens),
            str(usage.calls),
            f"{usage.cost_usd:.6f}",
        )
    console.print(table)


def _goal(console: Console, trace: PlanTrace) -> None:
    """The goal planner's targets, per-object decisions and risk checks (absent for the step planner)."""
    goal = trace.goal
    if not goal:
        return
    console.print("\n[bold]Goal[/bold]" + (" (stack)" if goal.stack else ""))
    for target in goal.targets:
        how = {"named": "named in the request", "speaker": "the speaker", "scored": "scored"}[target.how]
        named = f"; objects named: {', '.join(target.named)}" if target.named else ""
        criterion = f"; objects that fit {target.criterion!r}" if target.criterion else ""
        criterion += f"; a dish the graph knows: {target.dish}" if target.dish else ""
        console.print(f"  -> {target.to} ({how}): {target.count}{named}{criterion}")
    for decision in trace.decisions or ():
        if not decision.decided:
            continue
        title = f"Decisions for the {decision.target.to} (calibrated log-odds of yes)"
        # The name ranking (which object, all listed in one question) exists for targets taking N.
        names = any(row.name_score is not None for row in decision.objects)
        columns = ["object", "P(yes)", "score", *(["name"] if names else []), "graph facts in the question"]
        table = Table(*columns, title=title)
        for row in sorted(decision.objects, key=lambda r: -r.score):
            facts = "; ".join(row.facts)[:80]
            name = [f"{row.name_score:+.2f}" if row.name_score is not None else ""] if names else []
            table.add_row(row.object, f"{row.p_yes:.2f}", f"{row.score:+.2f}", *name, facts)
        if decision.context:
            console.print("  facts about the request: " + "; ".join(decision.context))
        console.print(table)
    if trace.stack:
        console.print("  stack, bottom first: " + ", ".join(o.object for o in trace.stack.order))
    for check in trace.risk or ():
        verdict = f"[red]dropped: {check.why}[/red]" if check.dropped else "ok"
        numbers = f"P(unsafe) {check.p_unsafe:.2f}, score {check.score:+.2f}"
        console.print(f"  risk: {check.move}: {numbers} -> {verdict}")


def _relations(
    console: Console, title: str, retrievals: Mapping[str, RetrievalTrace], per_concept: int = 5
) -> None:
    lines = []
    for name, info in retrievals.items():
        kept = sorted(info.kept, key=lambda e: -e.similarity)
        shown = "; ".join(f"{e.relation} ({e.similarity:.2f}, {e.source})" for e in kept[:per_concept])
        note = f" [dim]{'; '.join(info.notes)}[/dim]" if info.notes else ""
        lines.append(f"  {name} [{info.match}: {info.matched}] {len(kept)} kept: {shown or '-'}{note}")
    if lines:
        console.print(f"\n[bold]{title}[/bold]")
        for line in lines:
            console.print(line)
