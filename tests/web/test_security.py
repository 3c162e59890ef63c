"""What keeps other web pages and other clients from using the server: the Host and Origin checks,
the security headers, one run per server, a taken port, and edited scenes under the scene rules."""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from conceptbot.core.errors import ConfigError
from conceptbot.core.scene import scene_from_dict
from conceptbot.web.app import local_hosts
from conceptbot.web.server import bind
from tests.web.conftest import REQUEST, events_of, held_worker

RUN = {"request": REQUEST, "scene": "example-scissors", "config": "conceptbot"}
PORT = 8765
LOCAL = f"http://127.0.0.1:{PORT}"
MakeClient = Callable[..., TestClient]


def _local_client(make_client: MakeClient, worker: Any = None, base_url: str = LOCAL) -> TestClient:
    """A client of an app that answers what ``conceptbot serve`` on 127.0.0.1:8765 answers."""
    return make_client(worker=worker, allowed_hosts=local_hosts("127.0.0.1", PORT), base_url=base_url)


def _recording_worker() -> tuple[list[str], Any]:
    started: list[str] = []

    def worker(spec, emit, out_dir, ask=None):
        started.append(spec.request)

    return started, worker


def test_local_hosts_are_the_loopback_names_and_the_bound_address() -> None:
    assert local_hosts("127.0.0.1", 8765) == {"127.0.0.1:8765", "localhost:8765", "[::1]:8765"}
    assert local_hosts("::1", 9000) == {"127.0.0.1:9000", "localhost:9000", "[::1]:9000"}
    assert "192.168.1.5:8765" in local_hosts("192.168.1.5", 8765)
    assert "[fe80::1]:8765" in local_hosts("FE80::1", 8765)
    # Browsers leave the default port out of Host.
    assert {"localhost", "localhost:80"} <= local_hosts("127.0.0.1", 80)
    assert "testserver" not in local_hosts("127.0.0.1", 8765)


@pytest.mark.parametrize("base_url", [LOCAL, f"http://localhost:{PORT}", f"http://[::1]:{PORT}"])
def test_the_servers_own_addresses_are_answered(make_client: MakeClient, base_url: str) -> None:
    client = _local_client(make_client, base_url=base_url)
    assert client.get("/").status_code == 200
    assert client.get("/api/options").status_code == 200
    origin = base_url  # what a browser sends on the page's own POST
    started = client.post("/api/runs", json=RUN, headers={"Origin": origin, "Referer": base_url + "/"})
    assert started.status_code == 201, started.text
    assert events_of(client, started.json()["id"])[-1]["type"] == "done"


@pytest.mark.parametrize(
    "host",
    [
        "evil.example",  # DNS rebinding: evil.example re-pointed at 127.0.0.1
        f"evil.example:{PORT}",
        "127.0.0.1:9999",  # the right name, another port
        "localhost",
        "testserver",  # what TestClient sends: tests add it, production must not
        "",
    ],
)
def test_a_foreign_host_is_refused_on_every_route(make_client: MakeClient, host: str) -> None:
    started, worker = _recording_worker()
    client = _local_client(make_client, worker=worker)
    for path in ("/", "/results", "/static/app.js", "/api/options", "/api/results", "/nope"):
        reply = client.get(path, headers={"Host": host})
        assert reply.status_code == 403, (path, reply.text)
        assert "not allowed" in reply.json()["detail"] and "127.0.0.1:8765" in reply.json()["detail"]
    assert client.post("/api/runs", json=RUN, headers={"Host": host}).status_code == 403
    assert started == []


@pytest.mark.parametrize(
    "origin", ["http://evil.example", f"http://evil.example:{PORT}", "null", f"https://127.0.0.1:{PORT}"]
)
def test_a_foreign_origin_is_refused(make_client: MakeClient, origin: str) -> None:
    started, worker = _recording_worker()
    client = _local_client(make_client, worker=worker)
    refused = client.post("/api/runs", json=RUN, headers={"Origin": origin})
    assert refused.status_code == 403 and "origin" in refused.json()["detail"]
    assert client.get("/api/options", headers={"Origin": origin}).status_code == 403
    assert started == []


def test_a_post_from_another_pages_referer_is_refused(make_client: MakeClient) -> None:
    started, worker = _recording_worker()
    client = _local_client(make_client, worker=worker)
    refused = client.post("/api/runs", json=RUN, headers={"Referer": "http://evil.example/attack.html"})
    assert refused.status_code == 403 and "other pages" in refused.json()["detail"]
    assert started == []
    # No Origin and no Referer (curl, scripts): the Host check alone applies.
    assert client.post("/api/runs", json=RUN).status_code == 201


def test_security_headers_on_every_response(make_client: MakeClient) -> None:
    client = _local_client(make_client)
    run_id = client.post("/api/runs", json=RUN).json()["id"]
    replies = [
        client.get("/"),
        client.get("/results"),
        client.get("/static/app.js"),
        client.get("/api/options"),
        client.get("/nope"),  # 404
        client.get("/", headers={"Host": "evil.example"}),  # 403 from the guard itself
        client.post("/api/runs", content=b"x" * 40_000, headers={"content-type": "application/json"}),
    ]
    with client.stream("GET", f"/api/runs/{run_id}/events") as stream:
        replies.append(stream)
        stream.read()
    assert [r.status_code for r in replies] == [200, 200, 200, 200, 404, 403, 413, 200]
    for reply in replies:
        headers = reply.headers
        assert headers["x-content-type-options"] == "nosniff"
        assert headers["x-frame-options"] == "DENY"
        assert headers["referrer-policy"] == "same-origin"
        csp = headers["content-security-policy"]
        assert "default-src 'self'" in csp and "frame-ancestors 'none'" in csp
        assert "unsafe-inline" not in csp and "unsafe-eval" not in csp


@pytest.mark.parametrize("page", ["/", "/results"])
def test_the_pages_need_nothing_the_policy_refuses(make_client: MakeClient, page: str) -> None:
    """The CSP allows only the server's own files: no inline script, style or event handler in the
    HTML, no style attribute or data:/blob: URL made by the scripts."""
    client = make_client()
    html = client.get(page).text
    scripts = re.findall(r"<script\b[^>]*>", html)
    assert scripts and all('src="/static/' in tag for tag in scripts)
    assert re.search(r"<script\b[^>]*>\s*[^<\s]", html) is None  # no inline code
    assert "<style" not in html and not re.search(r"\sstyle=", html)
    assert not re.search(r"\son[a-z]+=", html)
    for name in re.findall(r'src="/static/([^"]+)"', html):
        script = client.get(f"/static/{name}").text
        assert not re.search(r"[{,]\s*style\s*:|setAttribute\(\s*['\"]style", script), name
        assert "data:" not in script and "blob:" not in script and "eval(" not in script, name


def test_one_run_at_a_time_per_server_whatever_the_cookie(make_client: MakeClient) -> None:
    release = threading.Event()
    client = make_client(worker=held_worker(release))
    first = client.post("/api/runs", json=RUN)
    assert first.status_code == 201
    fresh = TestClient(client.app)  # another page, or the same client with a new cookie
    assert fresh.get("/").cookies["conceptbot_session"] != client.cookies["conceptbot_session"]
    busy = fresh.post("/api/runs", json=RUN)
    assert busy.status_code == 409
    assert "another run is already in progress on this server" in busy.json()["detail"]
    assert client.post("/api/runs", json=RUN).status_code == 409  # and the page's own second run
    release.set()
    assert events_of(client, first.json()["id"])[-1]["type"] == "done"
    assert fresh.post("/api/runs", json=RUN).status_code == 201  # free again, for anyone


NAMES = ["apple, pear", "apple(1)", "apple)", "joe's cup", 'a "cup"', "a `cup`", "x" * 200, "cup"]


MANY = [[f"thing {i}" for i in range(n)] for n in (61, 500)]  # over the old page-only cap of 60


@pytest.mark.parametrize("objects", [[n] for n in NAMES] + MANY)
def test_edited_objects_obey_the_scene_rules(make_client: MakeClient, objects: list[str]) -> None:
    """The web path answers exactly what scene_from_dict says about the same objects: a 400 with its
    message when it refuses them, a run when it accepts them (no cap of the web page's own)."""
    client = make_client(worker=lambda spec, emit, out_dir, ask=None: None)
    lists = {"objects": objects, "pickable_objects": objects[:1], "destinations": ["table"]}
    reply = client.post("/api/runs", json={"request": "tidy up", "objects": lists})
    try:
        scene_from_dict({"name": "edited", **lists}, "objects")
    except ConfigError as exc:
        assert reply.status_code == 400 and reply.json()["detail"] == exc.message
    else:
        assert reply.status_code == 201, reply.text
        assert events_of(client, reply.json()["id"])[-1]["type"] == "done"


@pytest.fixture
def taken_port() -> Any:
    """A port on 127.0.0.1 that another program is listening on."""
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        holder.listen()
        yield holder.getsockname()[1]


def test_bind_names_a_taken_port_and_the_option_to_change_it(taken_port: int) -> None:
    with pytest.raises(ConfigError) as caught:
        bind("127.0.0.1", taken_port)
    assert caught.value.message.startswith(f"port {taken_port} on 127.0.0.1 is already in use")
    assert "--port" in (caught.value.hint or "")
    with bind("127.0.0.1", 0) as sock:  # a free one is bound and handed over
        assert sock.getsockname()[1] > 0


def test_serve_on_a_taken_port_is_a_one_line_error(taken_port: int, isolated_home: Path) -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CONCEPTBOT_", "OPENAI_"))}
    env["CONCEPTBOT_HOME"] = str(isolated_home)
    result = subprocess.run(
        [sys.executable, "-m", "conceptbot", "serve", "--port", str(taken_port)],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert result.returncode != 0
    assert "ConceptBot on" not in result.stdout  # nothing claims to be serving
    assert "Traceback" not in result.stderr
    assert f"Error: port {taken_port} on 127.0.0.1 is already in use" in result.stderr
    assert "--port" in result.stderr


def test_backend_names_shown_to_the_page_hide_credentials(make_client: MakeClient) -> None:
    spec = "openai-compatible:http://127.0.0.1:9/v1?key=SECRET123#m"
    client = make_client(backends=[spec, "fake"])
    shown = client.get("/api/options").json()["backends"]
    assert shown[0] == "openai-compatible:http://127.0.0.1:9/v1?key=***#m" and "SECRET123" not in str(shown)
    assert (
        client.post("/api/runs", json={"request": "hi", "scene": "kitchen", "backend": spec}).status_code
        == 400
    )
