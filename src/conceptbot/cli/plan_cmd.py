"""``conceptbot plan``: plan a request in a scene and show why."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping

import click
from rich.console import Console
from rich.table import Table

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.params import FiniteFloatRange, reading_option
from conceptbot.cli.progress import ON_STDERR
from conceptbot.cli.richtext import line, plain
from conceptbot.core.limits import check_request
from conceptbot.core.plan import Plan
from conceptbot.core.system import METHODS, SystemOptions
from conceptbot.core.text import safe_json_dumps, terminal_safe
from conceptbot.core.trace import YES_NO, ClarifyingQuestion, PlanTrace, RetrievalTrace
from conceptbot.scenes import resolve_scene
from conceptbot.systems import SYSTEMS, build_system


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
@click.option(
    "--risk",
    is_flag=True,
    help="Rate with OPE's Risk Index (danger 1-5, DangerousWith): in the default system every move "
    "before it is kept (slower: a rating per object); in --config paper the scene's objects.",
)
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
@click.option("--theta", type=FiniteFloatRange(-1.0, 1.0), help="Cosine threshold (default: per embedder).")
@click.option("--fallback/--no-fallback", default=None, help="Wikipedia fallback (default: settings).")
@click.option("--json", "as_json", is_flag=True, help="Print the plan as one JSON object.")
@click.option(
    "--ask/--no-ask",
    default=None,
    help="Ask (yes/no, on the terminal) where a calibrated decision is unsure, and finish the plan "
    "with the answers. Default: on a terminal, off with --json or when not interactive (the "
    "questions are then listed, and the plan acts on the likelier answers).",
)
@click.option(
    "--coverage",
    type=click.Choice(["0.8", "0.9", "0.95", "1"]),
    default="0.9",
    show_default=True,
    help="How often a decision's prediction set must hold the right answer (higher asks more; "
    "1: ask about every calibrated decision).",
)
@reading_option
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
    ask: bool | None,
    coverage: str,
    reading: str,
) -> None:
    """Plan REQUEST in a scene; print properties, relations, reasoning, step scores and the plan."""
    request = check_request(request)  # first: bad input is the first error; the system takes it as checked
    scene = resolve_scene(scene_ref)
    options = SystemOptions(
        theta=theta, planner_method=method, n=n, fallback=fallback, coverage=float(coverage), reading=reading
    )  # SayCan has none
    bot = build_system(app.settings, config, options)
    # stdin or stderr may be closed (`<&-`): then nobody can be asked.
    interactive = _is_tty(sys.stdin) and _is_tty(sys.stderr) and not as_json
    asking = ask if ask is not None else interactive
    result = bot.plan(request, scene, risk=risk, observer=ON_STDERR, ask=_ask_on_terminal if asking else None)
    if as_json:
        # Valid JSON whose strings carry no raw control character (a model's words are in it).
        click.echo(safe_json_dumps(result.to_dict(), indent=2))
        return
    show(result, Console())


def _is_tty(stream: object) -> bool:
    """Whether ``stream`` is an open terminal (a standard stream closed at start is None)."""
    try:
        return bool(stream.isatty()) if stream is not None else False  # type: ignore[attr-defined]
    except (ValueError, OSError):  # closed while running
        return False


def _ask_on_terminal(question: ClarifyingQuestion) -> str:
    """The question on stderr (stdout stays the plan's): yes or no; or the objects listed by number,
    answered with numbers or names (``choose``: comma-separated, ``one``: one, or another's name)
    or ``none``; asked again until it is an answer."""
    text = terminal_safe(question.text)  # scene names and criteria come from files and requests
    if question.kind in YES_NO:
        while True:  # read as the page and ROS 2 read it: Yes, YES, y
            chosen = question.read(click.prompt(f"Question: {text} [yes/no]", err=True))
            if chosen is not None:
                return question.normalised(chosen)
    click.echo(f"Question: {text}", err=True)
    for number, obj in enumerate(question.objects, 1):
        click.echo(f"  {number}. {terminal_safe(obj)}", err=True)
    if question.others:  # a which-one question: the person may name what the list missed
        click.echo(f"  or another: {terminal_safe(', '.join(question.others))}", err=True)
    how = "numbers or names, comma-separated; or all" if question.kind == "choose" else "a number or a name"
    while True:
        reply = click.prompt(f"Which ({how}; or none)", err=True)
        chosen = question.read(_by_number(reply, question.objects))
        if chosen is not None:
            return question.normalised(chosen)
        click.echo(f"Give {how} from the list, or: none", err=True)


def _by_number(reply: str, objects: tuple[str, ...]) -> str:
    """``2, 3`` as the 2nd and 3rd objects' names (a part that is not a number in range stays)."""
    parts = [p.strip() for p in reply.split(",")]
    named = [objects[int(p) - 1] if p.isdigit() and 1 <= int(p) <= len(objects) else p for p in parts]
    return ", ".join(named)


def show(result: Plan, console: Console) -> None:
    """The readable trace of a plan.

    Everything in it but the labels comes from the user, the scene file or a model, so every line
    is built as literal :class:`~rich.text.Text` (:mod:`conceptbot.cli.richtext`), never as markup.
    """
    trace = result.trace
    console.print(
        line(("Request:", "bold"), f" {trace.request}   ", (f"(scene {trace.scene}, {trace.config})", "dim"))
    )
    ope = trace.ope
    if ope:
        console.print(line("\n", ("Object properties", "bold"), f" (OPE, {ope.mode}: {ope.why})"))
        objects = ope.objects
        keys = [k for k in next(iter(objects.values())).values if k != "object"] if objects else []
        table = Table()
        for header in ("object", *keys, "cached"):  # OPE's keys come from the model's JSON reply
            table.add_column(plain(header))
        for name, info in objects.items():
            cells = []
            for key in keys:
                value = info.values.get(key)
                if isinstance(value, list):
                    value = ", ".join(
                        f"{v['object']} ({v['score']})" if isinstance(v, dict) else str(v) for v in value
                    )
                cells.append(plain(str(value)[:60]))
            table.add_row(plain(name), *cells, "yes" if info.cached else "")
        console.print(table)
        _relations(console, "Kept relations per object (similarity, source)", ope.retrieval)
    urp = trace.urp
    if urp:
        keywords = ", ".join(urp.keywords) or "(none)"
        console.print(line("\n", ("Request keywords:", "bold"), f" {keywords}"))
        _relations(console, "Kept relations of the keywords (vs the request)", urp.keyword_relations)
        console.print(line("\n", ("Reasoning (URP):", "bold"), f" {urp.reasoning}"))
        console.print(line(("Commands:", "bold"), f" {', '.join(urp.commands) or '(none)'}"))
        for rejected in urp.rejected_commands:
            console.print(line("  ", ("rejected:", "yellow"), f" {rejected}"))
    _goal(console, trace)
    _steps(console, result)
    if trace.goal is None:  # the goal planner's vetoes are shown with its risk checks
        for veto in trace.vetoes or ():
            console.print(line("  ", ("vetoed:", "red"), f" {veto.move}: {veto.statement}"))
    if result.refused:
        console.print(line("\n", ("Refused:", "bold red"), f" {result.reason}"))
    console.print(line("\n", ("Plan:", "bold")))
    for i, action in enumerate(result.actions, 1):
        console.print(line(f"  {i}. {action}"))
    if result.confidence is not None:
        console.print(
            line(
                ("Confidence:", "bold"),
                f" {result.confidence:.2f} (that its calibrated decisions are all right)",
            )
        )
    calibration = trace.calibration
    if calibration is not None and not calibration.own:
        # A threshold keeps its coverage only for the scores it was fitted on.
        console.print(
            line(
                ("Note:", "yellow"),
                f" the confidence and the questions use thresholds fitted for {calibration.fitted_for},"
                f" not for {calibration.model}: the {calibration.coverage:g} coverage is not promised;"
                " `conceptbot calibrate --conformal` fits this model's own",
            )
        )
    for question in result.questions:
        answer = (
            f"answered {question.answer}" if question.answer else "not asked: acted on the likelier answers"
        )
        odds = ", ".join(f"{p:.2f}" for p in question.p_yes)
        label = {"one": "P(the one)", "reading": "P(meant)"}.get(question.kind, "P(yes)")
        console.print(line(("Question:", "bold"), f" {question.text} ({label} {odds}; {answer})"))
    table = Table("module", "time (s)", "tokens in", "tokens out", "LLM calls", "cost (USD)", title="Usage")
    for module, usage in result.usage.items():
        table.add_row(
            plain(module),
            f"{usage.latency_s:.2f}",
            str(usage.prompt_tokens),
            str(usage.completion_tokens),
            str(usage.calls),
            f"{usage.cost_usd:.6f}",
        )
    console.print(table)


def _steps(console: Console, result: Plan) -> None:
    """The step planner's candidates per step, the chosen one in bold green (absent for the goal planner)."""
    for step in result.steps:
        how = step.method if step.scoring in ("", "logprob") else f"{step.method}, scored by {step.scoring}"
        title = plain(f"Step {step.index} ({how})")
        table = Table("action", "S_LLM", "S_aff", "combined", "factors", title=title)
        for c in step.candidates:
            factors = " ".join(f"{k}={v:.2f}" for k, v in c.factors.items())
            table.add_row(
                plain(c.action, "bold green" if c.action == step.chosen else ""),
                f"{c.llm:.3f}",
                f"{c.affordance:.2f}",
                f"{c.combined:.3f}",
                plain(factors),
            )
        console.print(table)
        for rejected in step.rejected:
            console.print(line("  ", ("rejected LLM output:", "yellow"), f" {rejected}"))


#: What the goal's ``reading`` says, for the plan's print-out.
READINGS = {
    "both": "the request's own words read the same",
    "plain": "read from the plain form (the request's own words read otherwise)",
    "words": "read from the request's own words (the plain form read otherwise)",
    "sampled": "read from a sampled plain form, as the person chose",
}
#: Each reading's part, for the print-out (as the web page says it).
KINDS = {"taken": "taken", "other": "dropped", "sampled": "sampled"}


def _goal(console: Console, trace: PlanTrace) -> None:
    """The goal planner's targets, per-object decisions and risk checks (absent for the step planner)."""
    goal = trace.goal
    if not goal:
        return
    console.print(line("\n", ("Goal", "bold"), " (stack)" if goal.stack else ""))
    if goal.reading:
        console.print(line(f"  said plainly by the model: {goal.plain!r}; {READINGS[goal.reading]}"))
    if len(goal.readings) > 1:
        # Each reading with P(it is the one meant): why the person was, or was not, asked which.
        odds = "; ".join(
            f"{KINDS[r.kind]} {r.text!r} P {'?' if r.p != r.p else f'{r.p:.2f}'}" for r in goal.readings
        )
        preference = goal.preference
        if preference is not None and math.isfinite(preference):
            side = "taken" if preference >= 0 else "dropped"
            odds += f"; the model prefers the {side} one by {abs(preference):.2f} nats"
        console.print(line(f"  readings ({goal.step}): {odds}"))
    for target in goal.targets:
        how = {"named": "named in the request", "speaker": "the speaker", "scored": "scored"}[target.how]
        named = f"; objects named: {', '.join(target.named)}" if target.named else ""
        criterion = f"; objects that fit {target.criterion!r}" if target.criterion else ""
        criterion += f"; a dish the graph knows: {target.dish}" if target.dish else ""
        criterion += "; the rest (what no other target takes)" if target.rest else ""
        criterion += f"; {target.part}" if target.part else ""  # "as something to eat"
        console.print(line(f"  -> {target.to} ({how}): {target.count}{named}{criterion}"))
    for decision in trace.decisions or ():
        if not decision.decided:
            continue
        share = f"; confidence {decision.confidence:.2f}" if decision.confidence is not None else ""
        title = plain(f"Decisions for the {decision.target.to} (calibrated log-odds of yes{share})")
        # The name ranking (which object, all listed in one question) exists for targets taking N.
        names = any(row.name_score is not None for row in decision.objects)
        # Combined decisions: the model's own log-odds beside the score, and the graph's evidence.
        combined = any(row.model is not None for row in decision.objects)
        # The graph's evidence: of a combination, or what the graph states an object is for.
        evidenced = combined or any(row.evidence for row in decision.objects)
        # Where the combination also asked with the model's own description of each object.
        described = any(row.described for row in decision.objects)
        columns = [
            "object",
            "P(yes)",
            "score",
            *(["model"] if combined else []),
            *(["name"] if names else []),
            "graph evidence" if evidenced else "graph facts in the question",
            *(["the model's description"] if described else []),
        ]
        table = Table(*columns, title=title)
        for row in sorted(decision.objects, key=lambda r: -r.score):
            said = row.evidence["statements"] if evidenced and row.evidence else row.facts
            facts = "; ".join(said)[:80]
            model = [f"{row.model:+.2f}" if row.model is not None else ""] if combined else []
            name = [f"{row.name_score:+.2f}" if row.name_score is not None else ""] if names else []
            cells = (f"{row.p_yes:.2f}", f"{row.score:+.2f}", *model, *name)
            told = [plain(row.described[:80])] if described else []
            table.add_row(plain(row.object), *cells, plain(facts), *told)
        if decision.context:
            console.print(line("  facts about the request: " + "; ".join(decision.context)))
        console.print(table)
    if trace.stack:
        console.print(line("  stack, bottom first: " + ", ".join(o.object for o in trace.stack.order)))
    for pair in trace.companions or ():
        said = f"P {pair.p:.2f}" if math.isfinite(pair.p) else "no answer"
        graph = f" (graph: {pair.graph})" if pair.graph else ""
        verdict = "goes too" if pair.used else "not taken"
        console.print(line(f"  used with the {pair.anchor}? the {pair.object}: {said}{graph} -> {verdict}"))
    for check in trace.risk or ():
        why = f"{check.why} ({check.veto.statement})" if check.veto is not None else check.why
        verdict = plain(f"dropped: {why}", "red") if check.dropped else plain("ok")
        # No numbers where the decision could not be made (a backend error, a non-finite score).
        decided = check.p_unsafe is not None and check.score is not None
        numbers = f"P(unsafe) {check.p_unsafe:.2f}, score {check.score:+.2f}" if decided else "not decided"
        console.print(line(f"  risk: {check.move}: {numbers} -> ", verdict))


def _relations(
    console: Console, title: str, retrievals: Mapping[str, RetrievalTrace], per_concept: int = 5
) -> None:
    lines = []
    for name, info in retrievals.items():
        kept = sorted(info.kept, key=lambda e: -e.similarity)
        shown = "; ".join(f"{e.relation} ({e.similarity:.2f}, {e.source})" for e in kept[:per_concept])
        text = line(f"  {name} [{info.match}: {info.matched}] {len(kept)} kept: {shown or '-'}")
        if info.notes:
            text.append_text(line(" ", ("; ".join(info.notes), "dim")))
        lines.append(text)
    if lines:
        console.print(line("\n", (title, "bold")))
        for text in lines:
            console.print(text)
