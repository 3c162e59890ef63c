"""`conceptbot plan` against a server whose log-probabilities are NaN or infinite (issue 32, item 2):
the risk decision cannot be made, so the move is refused; the output stays strict JSON."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.cli.test_cli import run
from tests.cli.test_plan_cli import graph_home  # noqa: F401  (a fixture)
from tests.misbehaving import MisbehavingServer
from tests.scripted import write_scene


def _strict(text: str) -> dict:
    def refuse(token: str) -> float:
        raise AssertionError(f"{token} in the plan JSON")

    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("mode", ["lp_nan", "lp_neginf", "lp_posinf"])
def test_non_finite_log_probabilities_refuse_the_move(
    mode: str,
    graph_home: Path,  # noqa: F811
    tmp_path: Path,
) -> None:
    scene = write_scene(tmp_path / "tiny.json")
    with MisbehavingServer() as server:
        out = run(
            "--llm",
            f"openai-compatible:{server.url(mode)}#m",
            "--embedder",
            "fake",
            "plan",
            "give the apple to the child",
            "--scene",
            str(scene),
            "--json",
            "--no-fallback",
            home=graph_home,
            extra_env={"CONCEPTBOT_SCORING": "chat-logprobs", "CONCEPTBOT_MAX_RETRIES": "0"},
        )
    data = _strict(out.stdout)
    assert data["plan"] == ["done()"] and data["refused"] is True
    assert "the risk decision could not be made" in data["reason"]
    check = data["trace"]["risk"][0]
    assert check["why"] == "vetoed" and check["p_unsafe"] is None
    assert [v["source"] for v in data["trace"]["vetoes"]] == ["error"]
