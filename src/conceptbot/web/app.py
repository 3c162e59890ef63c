"""``conceptbot serve``: a local web page to ask, watch the reasoning, and see the plan executed.

Endpoints (JSON unless noted):

* ``GET /`` (HTML) — the page; sets the session cookie. ``GET /results`` (HTML) — benchmark results.
* ``GET /api/options`` — configurations, backends (names only), demo scenes, whether the simulator
  is installed.
* ``GET /api/scenes/{name}`` — a demo scene's objects.
* ``POST /api/runs`` — start a run: ``{"request", "scene" (demo name) or "objects" {objects,
  pickable_objects, destinations}, "config", "backend", "risk", "simulate"}`` -> ``{"id"}``;
  409 while any run on this server is going (the model is shared).
* ``GET /api/runs/{id}/events`` (``text/event-stream``) — the run's events from the first; 429 while
  :data:`~conceptbot.web.runs.MAX_STREAMS` streams of the run are open.
* ``GET /api/runs/{id}/files/{name}`` — before.png, after.png, execution.gif.
* ``GET /api/results`` — the latest reports in the results folder; ``GET /api/results/files/{name}``
  — their charts.

Safe by default: the CLI binds 127.0.0.1; request bodies over 32 KiB are refused; no path comes from
the browser (scenes by demo name or inline objects, files by fixed names); backend choices are names
from a server-side list and API keys stay on the server; one run at a time per server.

Other web pages cannot use it (see :class:`_Guard`): a request whose ``Host`` is not one of the
server's own addresses (:func:`local_hosts`) is refused with 403, which defeats DNS rebinding (a
foreign name re-pointed at 127.0.0.1 still carries its own name in ``Host``); so is a request whose
``Origin`` is not ``http://`` one of those addresses, or a state-changing request (POST, ...) without
``Origin`` whose ``Referer`` names another site. Every response carries :data:`SECURITY_HEADERS`.
"""

from __future__ import annotations

import json
import secrets
from collections.abc import AsyncIterator, Callable, Iterable
from importlib import resources
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from fastapi import FastAPI, HTTPException, Request, Response
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, StreamingResponse
from pydantic import BaseModel, Field
from starlette.datastructures import Headers, MutableHeaders
from starlette.middleware.base import BaseHTTPMiddleware, RequestResponseEndpoint
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from conceptbot.core.errors import ConceptBotError
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.core.urls import redact_secrets
from conceptbot.scenes import demo_scene_names, load_demo_scene
from conceptbot.sim import PICTURES
from conceptbot.systems import SYSTEMS
from conceptbot.web.runs import MAX_STREAMS, BusyError, Run, RunManager, RunSpec

COOKIE = "conceptbot_session"
MAX_BODY = 32 * 1024
REPORTS = {
    "the paper's 47 tasks": ("paper47/report.md", "paper47/success.png"),
    "dev tasks": ("dev/report.md", "dev/success.png"),
    "SafeAgentBench (test split)": (
        "safeagentbench/safeagentbench-test.md",
        "safeagentbench/safeagentbench-test.png",
    ),
}
"""The reports the results page shows, as (Markdown, chart) under the results folder (results/README.md)."""
MEDIA = {".png": "image/png", ".gif": "image/gif"}
# The pages load only their own scripts, styles, pictures (run files, charts) and API: no inline
# script or style (app.js sets bar widths through element.style, which CSP allows), no data: or
# blob: URLs, no frames.
CSP = (
    "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self'; connect-src 'self'; "
    "object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'"
)
SECURITY_HEADERS = {
    "Content-Security-Policy": CSP,
    "X-Content-Type-Options": "nosniff",
    "X-Frame-Options": "DENY",
    # Not no-referrer: under no-referrer a browser sends "Origin: null" on the page's own POSTs,
    # which the origin check must refuse. same-origin sends nothing to other sites either.
    "Referrer-Policy": "same-origin",
}
UNSAFE_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})


class ObjectsIn(BaseModel):
    """An edited object list."""

    # No limits here: scene_from_dict's (object count, name length and characters) apply, the same
    # as for scene files, and the 32 KiB body limit bounds what reaches it.
    objects: list[str] = Field(default_factory=list)
    pickable_objects: list[str] = Field(default_factory=list)
    destinations: list[str] = Field(default_factory=list)


class RunIn(BaseModel):
    """A run request from the page."""

    request: str = Field(max_length=500)
    scene: str | None = Field(default=None, max_length=80)
    objects: ObjectsIn | None = None
    config: str = "conceptbot"
    backend: str | None = Field(default=None, max_length=200)
    risk: bool = False
    simulate: bool = False
    ask: bool = True


class AnswerIn(BaseModel):
    """The page's answer to the run's open question."""

    # yes or no, or (a choose question) the chosen objects joined by ", ", or none: checked against
    # the open question by Run.answer.
    answer: str = Field(min_length=1, max_length=4000)


class _LimitBody(BaseHTTPMiddleware):
    async def dispatch(self, request: Request, call_next: RequestResponseEndpoint) -> Response:
        length = request.headers.get("content-length")
        if length is not None and (not length.isdigit() or int(length) > MAX_BODY):
            return JSONResponse({"detail": f"request body over {MAX_BODY} bytes"}, status_code=413)
        if length is None and request.method in ("POST", "PUT", "PATCH"):
            body = await request.body()  # chunked upload: read it once, then check
            if len(body) > MAX_BODY:
                return JSONResponse({"detail": f"request body over {MAX_BODY} bytes"}, status_code=413)
        return await call_next(request)


def local_hosts(host: str, port: int) -> frozenset[str]:
    """The ``Host`` header values (``name:port``, lower case) of a server bound to ``host:port``.

    Args:
        host: The address bound (``--host``), an IPv6 address with or without brackets.
        port: The port bound.

    Returns:
        The loopback names (``127.0.0.1``, ``localhost``, ``[::1]``) and ``host`` itself, each with
        ``port``; on port 80 also without it, as browsers leave the default port out.
    """
    names = {"127.0.0.1", "localhost", "[::1]", host.lower()}
    names = {f"[{n}]" if ":" in n and not n.startswith("[") else n for n in names}
    hosts = {f"{n}:{port}" for n in names}
    if port == 80:
        hosts |= names
    return frozenset(hosts)


class _Guard:
    """Refuses requests meant for another site and adds :data:`SECURITY_HEADERS` to every response.

    A pure ASGI middleware (not ``BaseHTTPMiddleware``) so that the event streams pass through it
    unbuffered. Refusals are 403 with a JSON ``detail``.
    """

    def __init__(self, app: ASGIApp, allowed_hosts: Iterable[str]) -> None:
        self.app = app
        self.hosts = frozenset(h.lower() for h in allowed_hosts)
        self.origins = frozenset(f"http://{h}" for h in self.hosts)
        self.listed = ", ".join(sorted(self.hosts)) or "no host"

    def refusal(self, method: str, headers: Headers) -> str | None:
        """Why a request is refused, or ``None``."""
        host = headers.get("host", "").lower()
        if host not in self.hosts:
            return f"host {host!r} is not allowed (DNS-rebinding protection); allowed: {self.listed}"
        origin = headers.get("origin")
        if origin is not None and origin.lower() not in self.origins:
            return f"requests from origin {origin!r} are not allowed: use the page at http://{host}/"
        referer = headers.get("referer")
        if method in UNSAFE_METHODS and origin is None and referer is not None:
            parts = urlsplit(referer)
            if parts.scheme != "http" or parts.netloc.lower() not in self.hosts:
                return f"requests from other pages are not allowed: use the page at http://{host}/"
        return None

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":  # lifespan; the app has no websockets
            await self.app(scope, receive, send)
            return

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                for name, value in SECURITY_HEADERS.items():
                    headers[name] = value
            await send(message)

        reason = self.refusal(scope["method"], Headers(scope=scope))
        if reason is not None:
            await JSONResponse({"detail": reason}, status_code=403)(scope, receive, send_with_headers)
            return
        await self.app(scope, receive, send_with_headers)


class _EventStream(StreamingResponse):
    """A run's ``text/event-stream`` that calls ``on_end`` once it is over, however it ends.

    In ``__call__`` rather than in the body generator: a generator that never started (the client
    left before the first byte) never runs its ``finally``.
    """

    def __init__(self, body: AsyncIterator[str], on_end: Callable[[], None]) -> None:
        super().__init__(body, media_type="text/event-stream", headers={"Cache-Control": "no-cache"})
        self.on_end = on_end

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        try:
            await super().__call__(scope, receive, send)
        finally:
            self.on_end()


def _static(name: str) -> str:
    return resources.files("conceptbot.web").joinpath(f"static/{name}").read_text(encoding="utf-8")


def _scene_for(body: RunIn) -> Scene:
    if body.objects is not None:
        # Only through scene_from_dict, so an edited scene obeys the same rules as a scene file.
        try:
            return scene_from_dict({"name": "edited", **body.objects.model_dump()}, "objects")
        except ConceptBotError as exc:
            raise HTTPException(400, exc.message) from None
    name = body.scene or "kitchen"
    if name not in demo_scene_names():
        raise HTTPException(400, f"unknown demo scene {name!r}")
    return load_demo_scene(name)


def _session_of(request: Request) -> str:
    session = request.cookies.get(COOKIE)
    if not session:
        raise HTTPException(403, "no session: load the page first")
    return session


def _add_pages(app: FastAPI) -> None:
    """``/`` (sets the session cookie on a first visit), ``/results`` and the static files."""

    def page(name: str) -> HTMLResponse:
        response = HTMLResponse(_static(name))
        response.set_cookie(COOKIE, secrets.token_urlsafe(16), httponly=True, samesite="strict")
        return response

    @app.get("/", response_class=HTMLResponse)
    def index(request: Request) -> HTMLResponse:
        if request.cookies.get(COOKIE):
            return HTMLResponse(_static("index.html"))
        return page("index.html")

    @app.get("/results", response_class=HTMLResponse)
    def results_page() -> HTMLResponse:
        return HTMLResponse(_static("results.html"))

    @app.get("/static/{name}")
    def static(name: str) -> Response:
        kinds = {"app.js": "text/javascript", "results.js": "text/javascript", "style.css": "text/css"}
        if name not in kinds:
            raise HTTPException(404, "not found")
        return Response(_static(name), media_type=kinds[name])


def _add_options(app: FastAPI, shown_backends: dict[str, str], can_simulate: bool) -> None:
    """``/api/options`` and ``/api/scenes/{name}``: what the page offers to choose from."""

    @app.get("/api/options")
    def options() -> dict[str, Any]:
        return {
            "configs": list(SYSTEMS),
            "default_config": "conceptbot",
            "backends": list(shown_backends),
            "scenes": demo_scene_names(),
            "default_scene": "kitchen",
            "simulator": can_simulate,
        }

    @app.get("/api/scenes/{name}")
    def scene(name: str) -> dict[str, Any]:
        if name not in demo_scene_names():
            raise HTTPException(404, f"unknown demo scene {name!r}")
        s = load_demo_scene(name)
        return {
            "name": s.name,
            "description": s.description,
            "objects": s.names,
            "pickable_objects": s.pickable,
            "destinations": s.destinations,
        }


def _add_runs(app: FastAPI, manager: RunManager, shown_backends: dict[str, str], can_simulate: bool) -> None:
    """``/api/runs``: start a run, stream its events, serve its pictures (each to its session only)."""

    @app.post("/api/runs", status_code=201)
    def start(body: RunIn, request: Request) -> dict[str, Any]:
        session = _session_of(request)
        if not body.request.strip():
            raise HTTPException(400, "the request is empty")
        if body.config not in SYSTEMS:
            raise HTTPException(400, f"unknown configuration {body.config!r}")
        backend = shown_backends.get(body.backend or next(iter(shown_backends)))
        if backend is None:
            raise HTTPException(400, "unknown backend: choose one of the listed backends")
        spec = RunSpec(
            body.request.strip(),
            _scene_for(body),
            body.config,
            backend,
            body.risk,
            body.simulate and can_simulate,
            body.ask,
        )
        try:
            run = manager.start(session, spec)
        except BusyError as exc:
            raise HTTPException(409, str(exc)) from None
        return {"id": run.id}

    def run_of(run_id: str, request: Request) -> Run:
        run = manager.get(run_id)
        if run is None or run.session != _session_of(request):
            raise HTTPException(404, "no such run")
        return run

    @app.get("/api/runs/{run_id}/events")
    async def events(run_id: str, request: Request) -> StreamingResponse:
        # async: neither the endpoint nor its stream takes one of the worker threads that every
        # sync endpoint shares (a stream that held one for the whole run let 40 streams stall them).
        run = run_of(run_id, request)
        if not run.open_stream():
            raise HTTPException(
                429,
                f"{MAX_STREAMS} event streams of this run are open already: close the page's other "
                "tabs or wait until the run has finished",
            )

        async def body() -> AsyncIterator[str]:
            async for event in run.follow():
                yield ": keep-alive\n\n" if event is None else f"data: {json.dumps(event)}\n\n"

        return _EventStream(body(), on_end=run.close_stream)

    @app.post("/api/runs/{run_id}/answer")
    def answer(run_id: str, body: AnswerIn, request: Request) -> dict[str, Any]:
        run = run_of(run_id, request)
        given = run.answer(body.answer)
        if given == "closed":
            raise HTTPException(409, "this run has no open question")
        if given == "invalid":
            raise HTTPException(
                422, "not an answer to the question: yes or no, or the objects that go, or none"
            )
        return {"ok": True}

    @app.get("/api/runs/{run_id}/files/{name}")
    def run_file(run_id: str, name: str, request: Request) -> FileResponse:
        run = run_of(run_id, request)
        if name not in PICTURES or not (run.out_dir / name).is_file():
            raise HTTPException(404, "no such file")
        return FileResponse(run.out_dir / name, media_type=MEDIA[Path(name).suffix])


def _add_results(app: FastAPI, results_dir: Path) -> None:
    """``/api/results`` and ``/api/results/files/{name}``: the latest benchmark reports and charts."""

    @app.get("/api/results")
    def results() -> dict[str, Any]:
        found = []
        for title, (text, chart) in REPORTS.items():
            path = results_dir / text
            if path.is_file():
                found.append(
                    {
                        "title": title,
                        "markdown": path.read_text(encoding="utf-8"),
                        "chart": f"/api/results/files/{chart}" if (results_dir / chart).is_file() else None,
                    }
                )
        return {"reports": found}

    @app.get("/api/results/files/{name:path}")
    def result_file(name: str) -> FileResponse:  # only the charts named in REPORTS: no other path
        charts = {chart for _, chart in REPORTS.values()}
        if name not in charts or not (results_dir / name).is_file():
            raise HTTPException(404, "no such file")
        return FileResponse(results_dir / name, media_type="image/png")


def _encodable(text: object) -> str:
    """``text`` with what UTF-8 cannot carry (a lone surrogate) written as an escape."""
    return str(text).encode("utf-8", "backslashreplace").decode("utf-8")


async def _invalid_body(request: Request, exc: RequestValidationError) -> JSONResponse:
    """422 for a body that does not fit, naming where and why but not echoing the input: FastAPI's
    own reply echoes it, and one holding a lone surrogate (``"\\ud800"``) cannot be encoded (a 500)."""
    detail = [
        {"loc": [_encodable(part) for part in e.get("loc", ())], "msg": _encodable(e.get("msg", ""))}
        for e in exc.errors()
    ]
    return JSONResponse({"detail": detail}, status_code=422)


def create_app(
    manager: RunManager,
    *,
    backends: list[str],
    results_dir: Path,
    can_simulate: bool,
    allowed_hosts: Iterable[str],
) -> FastAPI:
    """The web app.

    Args:
        manager: Starts and keeps runs (its worker does the planning).
        backends: LLM backend specs a page may choose (the first is the default).
        results_dir: Where ``conceptbot bench report`` / ``safebench report`` wrote their files.
        can_simulate: Whether runs may be executed in the simulator.
        allowed_hosts: The ``Host`` values (``name:port``) to answer, usually
            ``local_hosts(host, port)`` of the address the server binds; any other gets 403.

    Returns:
        The FastAPI app, with the body limit and the host/origin guard around every route.
    """
    app = FastAPI(title="ConceptBot", docs_url=None, redoc_url=None, openapi_url=None)
    app.add_middleware(_LimitBody)
    app.add_exception_handler(RequestValidationError, _invalid_body)  # type: ignore[arg-type]
    # Added last, so outermost: it sees every request and reply (but for uncaught errors' 500s).
    app.add_middleware(_Guard, allowed_hosts=frozenset(allowed_hosts))
    # The page sees each backend under a redacted name (a spec's URL may carry a key in its query
    # string or user info); the server maps the name back to the spec.
    shown_backends = {redact_secrets(spec): spec for spec in backends}
    _add_pages(app)
    _add_options(app, shown_backends, can_simulate)
    _add_runs(app, manager, shown_backends, can_simulate)
    _add_results(app, results_dir)
    return app
