"""Untrusted text through the CLI: markup, control characters and escapes are shown, never obeyed.

Requests, object names and a model's words reach ``conceptbot plan``'s trace; before the fix a
``[/x]`` in any of them crashed Rich's markup parser after planning, and an ESC reached the
terminal raw. Every outcome must be normal output or one error message, with no raw control
character on stdout or stderr.
"""

from __future__ import annotations

import json
import random
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.cli.inprocess import Outcome, assert_terminal_safe, invoke
from tests.misbehaving import MisbehavingServer
from tests.pipeline.fakes import risk_reply
from tests.scripted import TINY_SCENE, paper_replies, write_replies, write_scene

# Rich markup, emoji codes, terminal escapes (OSC title and hyperlink, CSI clear/colour/alternate
# screen, DCS, 8-bit CSI/OSC), lone controls, bidi overrides, and harmless look-alikes.
NASTY = [
    "[/x]",
    "[bold]",
    "[/]",
    "[red]hot[/red]",
    "[link=https://evil.example]",
    ":knife:",
    "[[x]]",
    "\\[",
    "\x1b]0;pwned\x07",
    "\x1b]8;;https://evil.example\x1b\\click\x1b]8;;\x1b\\",
    "\x1b[2J",
    "\x1b[31m",
    "\x1b[?1049h",
    "\x1bP1$r\x1b\\",
    "\x9b2J",
    "\x9d0;t\x9c",
    "\x07",
    "\x00",
    "\x08",
    "\r",
    "\x7f",
    "\u202e",
    "\u2066",
    "crème brûlée",
    "日本",
    "%s {0}",
    "\\x1b",
    "\t",
    "\n",
]
PRINTABLE = [f for f in NASTY if f.isprintable()]
ACTION = "pick_and_place({}, user)"

Home = Callable[[], Path]


@pytest.fixture
def fresh_home(isolated_home: Path, omcs_file: Path, wordnet_dir: Path, tmp_path: Path) -> Home:
    """A factory of empty homes sharing one small graph (OPE answers are cached per home)."""
    installed = invoke("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir))
    assert installed.code == 0, installed.stderr
    homes = iter(range(10_000))

    def make() -> Path:
        home = tmp_path / f"h{next(homes)}"
        home.mkdir()
        (home / "kg").symlink_to(isolated_home / "kg", target_is_directory=True)
        return home

    return make


def _replies(names: list[str], reasoning: str, votes: list[list[str]], reason: str = "r") -> list[str]:
    """The paper pipeline's replies: OPE per object, keywords, URP, five votes per step."""
    urp = {
        "reasoning": reasoning,
        "refuse": False,
        "refusal_reason": "",
        "commands": [ACTION.format(names[0])],
    }
    replies = [risk_reply(reason=reason) for _ in names]
    replies += [json.dumps({"keywords": [names[0]]}), json.dumps(urp)]
    for step in votes:
        replies += step
    return replies + ["done()"] * 10  # spare votes: a plan with an extra step still ends


def _plan(home: Path, tmp_path: Path, request: str, scene: dict, replies: list[str], *extra: str) -> Outcome:
    spec = write_replies(tmp_path / f"{home.name}-replies.json", replies)
    scene_file = write_scene(tmp_path / f"{home.name}-scene.json", scene)
    return invoke(
        "--home", str(home), "--llm", spec, "--embedder", "fake",
        "plan", request, "--scene", str(scene_file), "--no-fallback", *extra,
    )  # fmt: skip


def _scene(apple: str) -> dict:
    return {
        **TINY_SCENE,
        "objects": [apple, *TINY_SCENE["objects"][1:]],
        "pickable_objects": [apple, "knife"],
    }


def test_markup_in_the_request_is_printed_as_typed(fresh_home: Home, tmp_path: Path) -> None:
    replies = _replies(TINY_SCENE["objects"], "because", [[ACTION.format("apple")] * 5, ["done()"] * 5])
    outcome = _plan(fresh_home(), tmp_path, "bring me [/x] an apple [bold]", TINY_SCENE, replies)
    assert_terminal_safe(outcome)
    assert outcome.code == 0 and "bring me [/x] an apple [bold]" in outcome.stdout
    assert "1. pick_and_place(apple, user)" in outcome.stdout


def test_markup_in_an_object_name_is_printed_as_named(fresh_home: Home, tmp_path: Path) -> None:
    apple = "apple [/x]"
    replies = _replies([apple, *TINY_SCENE["objects"][1:]], "b", [[ACTION.format(apple)] * 5, ["done()"] * 5])
    outcome = _plan(fresh_home(), tmp_path, "bring me an apple", _scene(apple), replies)
    assert_terminal_safe(outcome)
    assert outcome.code == 0 and "1. pick_and_place(apple [/x], user)" in outcome.stdout


def test_markup_and_escapes_in_the_models_words_are_shown_not_obeyed(
    fresh_home: Home, tmp_path: Path
) -> None:
    reasoning = "the user wants [/x] an apple \x1b]0;pwned\x07\x1b[2J"
    votes = [[ACTION.format("apple")] * 3 + ["[/oops] \x1b[31m", "[bold]pear"], ["done()"] * 5]
    outcome = _plan(
        fresh_home(),
        tmp_path,
        "bring me an apple",
        TINY_SCENE,
        _replies(TINY_SCENE["objects"], reasoning, votes),
    )
    assert_terminal_safe(outcome)
    assert outcome.code == 0
    assert "the user wants [/x] an apple \\x1b]0;pwned\\x07\\x1b[2J" in outcome.stdout
    assert "[/oops] \\x1b[31m" in outcome.stdout  # a rejected vote, as the model wrote it


def test_escapes_in_a_request_are_one_clear_error(fresh_home: Home, tmp_path: Path) -> None:
    outcome = _plan(fresh_home(), tmp_path, "bring me an apple \x1b]0;pwned\x07 \x1b[31mRED", TINY_SCENE, [])
    assert_terminal_safe(outcome)
    assert (
        outcome.code == 2 and "control characters or undecodable bytes '\\x07' '\\x1b'" in outcome.errors()[0]
    )


def test_a_nan_theta_is_one_clear_error(fresh_home: Home, tmp_path: Path) -> None:
    outcome = _plan(fresh_home(), tmp_path, "bring me an apple", TINY_SCENE, [], "--theta", "nan")
    assert_terminal_safe(outcome)
    assert outcome.code == 2 and "not a finite number" in outcome.errors()[0]


@pytest.mark.parametrize(
    ("mode", "verdict"),
    [("ok", "P(unsafe) 0.50, score +0.00 -> ok"), ("lp_nan", "not decided -> dropped: vetoed")],
)
def test_the_goal_planners_trace_shows_markup_and_undecided_risk_checks(
    fresh_home: Home, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, mode: str, verdict: str
) -> None:
    # The default planner on a server that scores; with NaN log-probabilities the risk decision
    # cannot be made (P(unsafe) is None in the trace) and the move is dropped.
    monkeypatch.setenv("CONCEPTBOT_SCORING", "chat-logprobs")
    monkeypatch.setenv("CONCEPTBOT_MAX_RETRIES", "0")
    apple = "apple [/x]"
    scene_file = write_scene(tmp_path / "scene.json", _scene(apple))
    with MisbehavingServer() as server:
        outcome = invoke(
            "--home", str(fresh_home()), "--llm", f"openai-compatible:{server.url(mode)}#m",
            "--embedder", "fake", "plan", "give the apple [/x] to the child [bold]",
            "--scene", str(scene_file), "--no-fallback",
        )  # fmt: skip
    assert_terminal_safe(outcome)
    assert outcome.code == 0
    assert f"risk: give the apple [/x] to the child: {verdict}" in outcome.stdout
    assert "-> child (named in the request): 1; objects named: apple [/x]" in outcome.stdout


def test_the_step_planners_trace_names_its_vetoes(fresh_home: Home, tmp_path: Path) -> None:
    ope = [
        risk_reply(5, [("child", 5)]) if name == "knife" else risk_reply() for name in TINY_SCENE["objects"]
    ]
    move = ACTION.format("knife").replace("user", "child")
    replies = paper_replies(ope, [move], [move, "done()"], keywords=("knife",))
    outcome = _plan(fresh_home(), tmp_path, "give the knife to the child", TINY_SCENE, replies)
    assert_terminal_safe(outcome)
    assert outcome.code == 0
    assert "vetoed: pick_and_place(knife, child): OPE rates the knife 5/5 dangerous" in outcome.stdout


def _nasty(rng: random.Random, pool: list[str], most: int = 3) -> str:
    return " ".join(rng.sample(pool, rng.randint(1, most)))


@pytest.mark.parametrize("seed", range(24))
def test_fuzz_plan_with_hostile_requests_names_and_replies(
    fresh_home: Home, tmp_path: Path, seed: int
) -> None:
    rng = random.Random(seed)
    # Half the requests are printable (they reach the trace), half carry controls (refused).
    request = f"bring me an apple {_nasty(rng, PRINTABLE if seed % 2 else NASTY)}"
    # Most names are printable (they reach the trace); some carry controls (the scene is refused).
    apple = f"apple {_nasty(rng, PRINTABLE if rng.random() < 0.7 else NASTY, 1)}".strip()
    names = [apple, *TINY_SCENE["objects"][1:]]
    good = ACTION.format(apple)
    votes = [
        [good] * 3 + [_nasty(rng, NASTY), f"{good} {_nasty(rng, NASTY)}"],
        ["done()"] * 4 + [_nasty(rng, NASTY)],
    ]
    replies = _replies(names, _nasty(rng, NASTY, 5), votes, reason=_nasty(rng, NASTY))
    for extra in ((), ("--json",)):
        outcome = _plan(fresh_home(), tmp_path, request, _scene(apple), replies, *extra)
        assert_terminal_safe(outcome)
        if outcome.code != 0:
            continue  # a refused request or object name: one error line, checked above
        if extra:
            data = json.loads(outcome.stdout)
            assert data["plan"][-1] == "done()"
        else:
            assert "Plan:" in outcome.stdout and "Usage" in outcome.stdout


@pytest.mark.parametrize("seed", range(8))
def test_fuzz_llm_with_hostile_replies(tmp_path: Path, seed: int) -> None:
    rng = random.Random(seed)
    replies = [_nasty(rng, NASTY, 6) for _ in range(2)]
    spec = write_replies(tmp_path / "r.json", replies)
    for extra in ((), ("--json",)):
        outcome = invoke("--no-cache", "--llm", spec, "llm", _nasty(rng, NASTY), "-n", "2", *extra)
        assert_terminal_safe(outcome)
        assert outcome.code == 0
        if extra:
            assert json.loads(outcome.stdout)["choices"] == replies


def test_usage_errors_quoting_what_was_typed_are_terminal_safe() -> None:
    outcome = invoke("\x1b]0;pwned\x07")
    assert_terminal_safe(outcome)
    assert outcome.code == 2 and "\\x1b]0;pwned\\x07" in outcome.errors()[0]


def test_progress_messages_are_terminal_safe(capsys: pytest.CaptureFixture[str]) -> None:
    from conceptbot.cli.progress import say

    say("planning \x1b]0;pwned\x07 [/x]")
    assert capsys.readouterr().err == "planning \\x1b]0;pwned\\x07 [/x]\n"


def test_doctor_details_quoting_a_server_are_terminal_safe(monkeypatch: pytest.MonkeyPatch) -> None:
    from conceptbot.cli import doctor

    hostile = doctor.Check("LLM server", False, "server said \x1b]0;pwned\x07\x1b[2J [/x]")
    monkeypatch.setattr(doctor, "CHECKS", [("LLM server", lambda settings: hostile)])
    outcome = invoke("doctor")
    assert_terminal_safe(outcome, error_line=False)
    assert outcome.code == 1 and "server said \\x1b]0;pwned\\x07\\x1b[2J [/x]" in outcome.stdout


def test_bytes_that_are_not_utf8_in_a_request_are_one_clear_error(fresh_home: Home, tmp_path: Path) -> None:
    # Python reads the argument's \xff as the lone surrogate U+DCFF, which no cache key can encode.
    for extra in ((), ("--json",)):
        outcome = _plan(fresh_home(), tmp_path, "bring me an apple \udcff", TINY_SCENE, [], *extra)
        assert outcome.code == 2 and "undecodable bytes '\\udcff'" in outcome.errors()[0], outcome.stderr


def test_plan_with_standard_input_closed_plans(fresh_home: Home, tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    home = fresh_home()
    spec = write_replies(
        tmp_path / "r.json", _replies(TINY_SCENE["objects"], "because", [[ACTION.format("apple")] * 5])
    )
    scene = write_scene(tmp_path / "scene.json", TINY_SCENE)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CONCEPTBOT_", "OPENAI_"))}
    argv = [
        sys.executable, "-m", "conceptbot", "--home", str(home), "--llm", spec, "--embedder", "fake",
        "plan", "bring me an apple", "--scene", str(scene), "--no-fallback",
    ]  # fmt: skip
    for extra in ((), ("--json", "--no-ask")):
        done = subprocess.run(
            [*argv, *extra],
            capture_output=True,
            text=True,
            env=env,
            timeout=300,
            preexec_fn=lambda: os.close(0),
        )
        assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
        assert "pick_and_place(apple, user)" in done.stdout
