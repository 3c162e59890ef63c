"""`conceptbot serve` stopped by a signal, as systemd and docker stop it (SIGTERM) or as Ctrl-C does:
a clean exit that removes the server's temporary folder, even while a page follows a run."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx
import pytest

from tests.misbehaving import MisbehavingServer

START_S = 60.0  # generous: the first start imports the whole pipeline


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@contextmanager
def serving(tmp: Path, *llm: str) -> Iterator[tuple[subprocess.Popen[str], str]]:
    """``conceptbot [--llm ...] --embedder fake serve`` on a free port, with its own TMPDIR; yields
    once it answers. The environment (the isolated home, PYTHONPATH) passes through."""
    port = _free_port()
    env = {**os.environ, "TMPDIR": str(tmp), "CONCEPTBOT_MAX_RETRIES": "0"}
    process = subprocess.Popen(
        [sys.executable, "-m", "conceptbot", *llm, "--embedder", "fake", "serve", "--port", str(port)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # A child of a non-interactive shell may inherit SIGINT ignored; a user's Ctrl-C is not.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + START_S
        while True:
            assert process.poll() is None, process.communicate()
            try:
                if httpx.get(f"{url}/api/options", timeout=5).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            assert time.monotonic() < deadline, "the server did not answer"
            time.sleep(0.2)
        yield process, url
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()


def _stopped(process: subprocess.Popen[str], sig: signal.Signals) -> tuple[int, str]:
    process.send_signal(sig)
    _, err = process.communicate(timeout=30)
    return process.returncode, err


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_stops_the_server_cleanly_and_removes_its_folder(
    tmp_path: Path, sig: signal.Signals
) -> None:
    with serving(tmp_path, "--llm", "fake") as (process, _):
        assert len(list(tmp_path.glob("conceptbot-web-*"))) == 1
        code, err = _stopped(process, sig)
    assert code == 0, err
    assert list(tmp_path.glob("conceptbot-web-*")) == []
    assert "Traceback" not in err


def test_sigterm_does_not_wait_for_a_run_a_page_is_following(tmp_path: Path) -> None:
    # A backend that takes a minute a call: the run is still planning when the server is stopped.
    with MisbehavingServer() as slow:
        spec = f"openai-compatible:{slow.url('slow/60')}#m"
        with (
            serving(tmp_path, "--llm", spec) as (process, url),
            httpx.Client(base_url=url, timeout=20) as page,
        ):
            assert page.get("/").status_code == 200  # the session cookie
            started = page.post("/api/runs", json={"request": "Bring me an apple", "config": "nokg"})
            assert started.status_code == 201, started.text
            with page.stream("GET", f"/api/runs/{started.json()['id']}/events") as events:
                lines = events.iter_lines()
                assert next(line for line in lines if line.startswith("data: "))  # the run is going
                code, err = _stopped(process, signal.SIGTERM)
                # The stream ended with the server, not with the run (which never finished).
                rest = [json.loads(line[6:]) for line in lines if line.startswith("data: ")]
                assert not {"done", "error"} & {event["type"] for event in rest}
    assert code == 0, err
    assert list(tmp_path.glob("conceptbot-web-*")) == []
