"""``conceptbot serve``: a local web page to ask, watch the reasoning, and see the plan executed.

Endpoints (JSON unless noted):

* ``GET /`` (HTML) — the page; sets the session cookie. ``GET /results`` (HTML) — benchmark results.
* ``GET /api/options`` — configurations, backends (names only), demo scenes, whether the simulator
  is installed.
* ``GET /api/scenes/{name}`` — a demo scene's objects.
* ``POST /api/runs`` — start a run: ``{"request", "scene" (demo name) or "objects" {objects,
  pickable_objects, destinations}, "config", "backend", "risk", "simulate"}`` -> ``{"id"}``;
  409 while the page's previous run is going.
* ``GET /api/runs/{id}/events`` (``text/event-stream``) — the run's events from the first.
* ``GET /api/runs/{id}/files/{name}`` — before.png, after.png, execution.gif.
* ``GET /api/results`` — the latest reports in the results folder; ``GET /api/results/files/{name}``
  — their charts.

Safe by default: the CLI binds 127.0.0.1; request bodies over 32 KiB are refused; no path comes from
the browser (scenes by demo name or inline objects, files by fixed names); backend choices are names
from a server-side list and API keys stay on the server; one run at a time per session.
"""

from __future__ import annotations

import json
import secrets
from collections.abc import AsyncIterator, Iterator
from importlib import resources
from pathlib import Path
from typing import Any

import anyio
from fastapi import FastAPI, HTTPException, Request, Response
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, StreamingResponse
from pydantic import BaseModel, Field
from starlette.middleware.base import BaseHTTPMiddleware, RequestResponseEndpoint

from conceptbot.baselines.factory import SYSTEMS
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.scenes import demo_scene_names, load_demo_scene
from conceptbot.web.runs import BusyError, Run, RunManager, RunSpec
from conceptbot.web.worker import PICTURES

COOKIE = "conceptbot_session"
MAX_BODY = 32 * 1024
MAX_OBJECTS = 60
MAX_NAME = 60
REPORTS = {
    "paper benchmark": ("report.md", "success.png"),
    "SafeAgentBench": ("safeagentbench.md", "safeagentbench.png"),
}
MEDIA = {".png": "image/png", ".gif": "image/gif"}


class ObjectsIn(BaseModel):
    """An edited object list."""

    objects: list[str] = Field(default_factory=list, max_length=MAX_OBJECTS)
    pickable_objects: list[str] = Field(default_factory=list, max_length=MAX_OBJECTS)
    destinations: list[str] = Field(default_factory=list, max_length=MAX_OBJECTS)


class RunIn(BaseModel):
    """A run request from the page."""

    request: str = Field(max_length=500)
    scene: str | None = Field(default=None, max_length=80)
    objects: ObjectsIn | None = None
    config: str = "conceptbot"
    backend: str | None = Field(default=None, max_length=200)
    risk: bool = False
    simulate: bool = False


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


def _static(name: str) -> str:
    return resources.files("conceptbot.web").joinpath(f"static/{name}").read_text(encoding="utf-8")


def _scene_for(body: RunIn) -> Scene:
    if body.objects is not None:
        lists = body.objects.model_dump()
        names = [n for values in lists.values() for n in values]
        if any(not isinstance(n, str) or not n.strip() or len(n) > MAX_NAME for n in names):
            raise HTTPException(400, f"object names must be 1-{MAX_NAME} characters")
        cleaned = {k: [n.strip() for n in v] for k, v in lists.items()}
        try:
            return scene_from_dict({"name": "edited", **cleaned}, "objects")
        except ConceptBotError as exc:
            raise HTTPException(400, exc.message) from None
    name = body.scene or "kitchen"
    if name not in demo_scene_names():
        raise HTTPException(400, f"unknown demo scene {name!r}")
    return load_demo_scene(name)


def create_app(
    manager: RunManager,
    *,
    backends: list[str],
    results_dir: Path,
    can_simulate: bool,
) -> FastAPI:
    """The web app.

    Args:
        manager: Starts and keeps runs (its worker does the planning).
        backends: LLM backend specs a page may choose (the first is the default).
        results_dir: Where ``conceptbot bench report`` / ``safebench report`` wrote their files.
        can_simulate: Whether runs may be executed in the simulator.
    """
    app = FastAPI(title="ConceptBot", docs_url=None, redoc_url=None, openapi_url=None)
    app.add_middleware(_LimitBody)

    def session_of(request: Request) -> str:
        session = request.cookies.get(COOKIE)
        if not session:
            raise HTTPException(403, "no session: load the page first")
        return session

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

    @app.get("/api/options")
    def options() -> dict[str, Any]:
        return {
            "configs": list(SYSTEMS),
            "default_config": "conceptbot",
            "backends": backends,
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

    @app.post("/api/runs", status_code=201)
    def start(body: RunIn, request: Request) -> dict[str, Any]:
        session = session_of(request)
        if not body.request.strip():
            raise HTTPException(400, "the request is empty")
        if body.config not in SYSTEMS:
            raise HTTPException(400, f"unknown configuration {body.config!r}")
        backend = body.backend or backends[0]
        if backend not in backends:
            raise HTTPException(400, "unknown backend: choose one of the listed backends")
        spec = RunSpec(
            body.request.strip(),
            _scene_for(body),
            body.config,
            backend,
            body.risk,
            body.simulate and can_simulate,
        )
        try:
            run = manager.start(session, spec)
        except BusyError as exc:
            raise HTTPException(409, str(exc)) from None
        return {"id": run.id}

    def run_of(run_id: str, request: Request) -> Run:
        run = manager.get(run_id)
        if run is None or run.session != session_of(request):
            raise HTTPException(404, "no such run")
        return run

    @app.get("/api/runs/{run_id}/events")
    def events(run_id: str, request: Request) -> StreamingResponse:
        run = run_of(run_id, request)

        def lines() -> Iterator[str]:
            for event in run.stream():
                yield ": keep-alive\n\n" if event is None else f"data: {json.dumps(event)}\n\n"

        async def body() -> AsyncIterator[str]:
            iterator = lines()
            while True:
                line = await anyio.to_thread.run_sync(next, iterator, None)
                if line is None:
                    return
                yield line

        return StreamingResponse(
            body(), media_type="text/event-stream", headers={"Cache-Control": "no-cache"}
        )

    @app.get("/api/runs/{run_id}/files/{name}")
    def run_file(run_id: str, name: str, request: Request) -> FileResponse:
        run = run_of(run_id, request)
        if name not in PICTURES or not (run.out_dir / name).is_file():
            raise HTTPException(404, "no such file")
        return FileResponse(run.out_dir / name, media_type=MEDIA[Path(name).suffix])

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

    @app.get("/api/results/files/{name}")
    def result_file(name: str) -> FileResponse:
        charts = {chart for _, chart in REPORTS.values()}
        if name not in charts or not (results_dir / name).is_file():
            raise HTTPException(404, "no such file")
        return FileResponse(results_dir / name, media_type="image/png")

    return app
