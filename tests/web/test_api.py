"""Every endpoint of the web app, with good and bad input."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from conceptbot.core.config import load_settings
from conceptbot.core.errors import BackendUnavailableError
from conceptbot.core.plan import Plan, read_actions
from conceptbot.web.worker import available_backends, make_worker
from tests.web.conftest import REQUEST, events_of, held_worker

RUN = {"request": REQUEST, "scene": "example-scissors", "config": "conceptbot"}


def test_pages_and_static_files(make_client) -> None:
    client: TestClient = make_client()
    page = client.get("/")
    assert page.status_code == 200 and "<title>ConceptBot</title>" in page.text
    fresh = TestClient(client.app)
    assert "conceptbot_session" in fresh.get("/").cookies
    assert "Benchmark results" in client.get("/results").text
    assert client.get("/static/app.js").headers["content-type"].startswith("text/javascript")
    assert client.get("/static/style.css").status_code == 200
    for bad in ("/static/../app.py", "/static/secret.txt", "/nope"):
        assert client.get(bad).status_code == 404


def test_options_and_scenes(make_client) -> None:
    client = make_client()
    options = client.get("/api/options").json()
    assert options["backends"] == ["llamacpp:qwen2.5-coder-1.5b", "llamacpp:smollm2-135m"]
    assert {"conceptbot", "saycan", "nokg"} <= set(options["configs"]) and "kitchen" in options["scenes"]
    assert options["simulator"] is False
    scene = client.get("/api/scenes/example-scissors").json()
    assert scene["pickable_objects"] == ["scissors", "knife", "safety scissors"]
    assert client.get("/api/scenes/nope").status_code == 404


def test_api_keys_never_reach_the_page(make_client, isolated_home: Path) -> None:
    settings = load_settings(env={"OPENAI_API_KEY": "sk-secret-123", "CONCEPTBOT_LLM": "openai:gpt-4o-mini"})
    client = make_client(backends=available_backends(settings))
    text = client.get("/api/options").text + client.get("/").text
    assert "openai:gpt-4o-mini" in text and "sk-secret" not in text


def test_a_run_streams_each_module_then_the_plan(make_client) -> None:
    client = make_client()
    started = client.post("/api/runs", json=RUN)
    assert started.status_code == 201
    events = events_of(client, started.json()["id"])
    kinds = [e["type"] for e in events]
    assert kinds[0] == "status" and kinds[-1] == "done"
    assert kinds.index("ope") < kinds.index("urp") < kinds.index("step") < kinds.index("plan")
    ope = next(e for e in events if e["type"] == "ope")["data"]
    assert ope["mode"] == "risk" and ope["objects"]["scissors"]["values"]["dangerous"] == 4
    steps = [e["data"] for e in events if e["type"] == "step"]
    assert steps[0]["chosen"] == "pick_and_place(safety scissors, child)" and steps[0]["candidates"]
    plan = next(e for e in events if e["type"] == "plan")
    assert plan["plan"] == ["pick_and_place(safety scissors, child)", "done()"] and not plan["refused"]
    # A page that connects again replays the run from the start.
    assert [e["type"] for e in events_of(client, started.json()["id"])] == kinds


def test_edited_objects_make_the_scene(make_client) -> None:
    seen = {}

    def worker(spec, emit, out_dir, ask=None):
        seen["scene"] = spec.scene

    client = make_client(worker=worker)
    objects = {"objects": ["cup", "sink"], "pickable_objects": ["cup"], "destinations": ["sink"]}
    run = client.post("/api/runs", json={"request": "wash up", "objects": objects})
    assert run.status_code == 201
    events_of(client, run.json()["id"])
    assert seen["scene"].pickable == ["cup"] and seen["scene"].destinations == ["sink"]


def test_bad_run_requests_are_refused_with_a_reason(make_client) -> None:
    client = make_client()
    cases = [
        ({**RUN, "request": "  "}, 400, "empty"),
        ({**RUN, "config": "gpt"}, 400, "unknown configuration"),
        ({**RUN, "backend": "openai-compatible:http://evil.example/v1"}, 400, "unknown backend"),
        ({**RUN, "scene": "../../etc/passwd"}, 400, "unknown demo scene"),
        (
            {"request": "x", "objects": {"objects": [""], "pickable_objects": [], "destinations": []}},
            400,
            "names",
        ),
        (
            {"request": "x", "objects": {"objects": [], "pickable_objects": [], "destinations": []}},
            400,
            "no objects",
        ),
        ({**RUN, "request": "x" * 501}, 422, "request"),
        ({"scene": "kitchen"}, 422, "request"),
    ]
    for body, status, words in cases:
        reply = client.post("/api/runs", json=body)
        assert reply.status_code == status, (body, reply.text)
        assert words in reply.text
    assert (
        client.post(
            "/api/runs", content=b"{not json", headers={"content-type": "application/json"}
        ).status_code
        == 422
    )
    big = client.post("/api/runs", content=b"x" * 40_000, headers={"content-type": "application/json"})
    assert big.status_code == 413 and "over" in big.json()["detail"]
    stranger = TestClient(client.app)  # never loaded the page: no session
    assert stranger.post("/api/runs", json=RUN).status_code == 403


def test_one_run_at_a_time_per_page_and_runs_are_private(make_client) -> None:
    release = threading.Event()
    client = make_client(worker=held_worker(release))
    first = client.post("/api/runs", json=RUN)
    assert first.status_code == 201
    busy = client.post("/api/runs", json=RUN)
    assert busy.status_code == 409 and "already in progress" in busy.json()["detail"]
    other = TestClient(client.app)
    other.get("/")
    assert other.get(f"/api/runs/{first.json()['id']}/events").status_code == 404
    release.set()
    assert events_of(client, first.json()["id"])[-1]["type"] == "done"
    assert client.post("/api/runs", json=RUN).status_code == 201  # free again


def test_errors_reach_the_page_with_their_hint(make_client) -> None:
    def worker(spec, emit, out_dir, ask=None):
        raise BackendUnavailableError("the model server is down", hint="start it")

    client = make_client(worker=worker)
    events = events_of(client, client.post("/api/runs", json=RUN).json()["id"])
    assert events[-1] == {"type": "error", "message": "the model server is down", "hint": "start it"}


def test_run_pictures_by_fixed_names_only(make_client) -> None:
    def worker(spec, emit, out_dir, ask=None):
        (out_dir / "before.png").write_bytes(b"\x89PNG fake")
        (out_dir / "notes.txt").write_text("private")

    client = make_client(worker=worker)
    run_id = client.post("/api/runs", json=RUN).json()["id"]
    events_of(client, run_id)
    picture = client.get(f"/api/runs/{run_id}/files/before.png")
    assert picture.status_code == 200 and picture.headers["content-type"] == "image/png"
    for name in ("after.png", "notes.txt", "..%2Fnotes.txt"):
        assert client.get(f"/api/runs/{run_id}/files/{name}").status_code == 404
    assert client.get("/api/runs/nope/files/before.png").status_code == 404


def test_results_page_data(make_client, tmp_path: Path) -> None:
    client = make_client()
    assert client.get("/api/results").json() == {"reports": []}
    results = tmp_path / "results" / "paper47"
    results.mkdir(parents=True)
    (results / "report.md").write_text("| category | saycan |\n|---|---|\n| all | 86% (n=14) |\n")
    (results / "success.png").write_bytes(b"\x89PNG fake")
    reports = client.get("/api/results").json()["reports"]
    assert reports[0]["title"] == "the paper's 47 tasks" and "86%" in reports[0]["markdown"]
    assert client.get(reports[0]["chart"]).status_code == 200
    assert client.get("/api/results/files/paper47/report.md").status_code == 404
    assert client.get("/api/results/files/../paper47/success.png").status_code == 404


class _FixedPlan:
    """A planner system that returns a given plan (or a refusal) at once."""

    def __init__(self, actions: list[str], refused: bool = False, reason: str | None = None) -> None:
        self.result = Plan(read_actions(actions), [], refused, reason)

    def plan(self, request, scene, risk=False, feedback=None, observer=None, ask=None) -> Plan:
        return self.result


def test_a_refusal_reaches_the_page_with_its_reason(make_client) -> None:
    refusing = _FixedPlan(["done()"], refused=True, reason="scissors are sharp for a child")
    client = make_client(
        worker=make_worker(lambda config, backend: refusing, can_simulate=True), can_simulate=True
    )
    events = events_of(client, client.post("/api/runs", json={**RUN, "simulate": True}).json()["id"])
    plan = next(e for e in events if e["type"] == "plan")
    assert plan["refused"] and plan["reason"] == "scissors are sharp for a child"
    assert not any(e["type"] == "sim" for e in events)  # nothing to execute


def test_a_simulated_run_plans_on_what_the_detector_sees(make_client) -> None:
    planned_on = []

    class Recording(_FixedPlan):
        def plan(self, request, scene, risk=False, feedback=None, observer=None, ask=None) -> Plan:
            planned_on.append(scene)
            return self.result

    refusing = Recording(["done()"], refused=True, reason="sharp")
    client = make_client(
        worker=make_worker(lambda config, backend: refusing, can_simulate=True), can_simulate=True
    )
    events = events_of(client, client.post("/api/runs", json={**RUN, "simulate": True}).json()["id"])
    assert [e["type"] for e in events if e["type"] in ("plan", "sim")] == ["plan"]
    # As in `conceptbot sim run`: the camera measured every object before the planner saw it.
    [scene] = planned_on
    scissors = scene.get("scissors")
    assert scissors is not None and scissors.bbox_px is not None and scissors.size_m is not None


@pytest.mark.slow
def test_simulated_run_serves_its_pictures(make_client) -> None:
    plan = _FixedPlan(["pick_and_place(safety scissors, child)", "done()"])
    client = make_client(
        worker=make_worker(lambda config, backend: plan, can_simulate=True), can_simulate=True
    )
    assert client.get("/api/options").json()["simulator"] is True
    run_id = client.post("/api/runs", json={**RUN, "simulate": True}).json()["id"]
    sim = next(e for e in events_of(client, run_id) if e["type"] == "sim")
    assert sim["files"] == ["before.png", "after.png", "execution.gif"]
    assert sim["steps"][0]["action"] == "pick_and_place(safety scissors, child)"
    assert sim["verdict"]
    gif = client.get(f"/api/runs/{run_id}/files/execution.gif")
    assert gif.status_code == 200 and gif.headers["content-type"] == "image/gif" and gif.content[:3] == b"GIF"


def test_a_goal_planner_run_streams_its_targets_decisions_and_risk_checks(make_client) -> None:
    from conceptbot.models.fake import FakeLLM
    from conceptbot.pipeline.conceptbot import ConceptBot
    from conceptbot.web.worker import make_worker
    from tests.pipeline.fakes import risk_reply

    def goal_bot(config: str, backend: str) -> ConceptBot:
        # OPE rates the scissors 4/5 for the child; the risk question itself leans safe.
        llm = FakeLLM([risk_reply(4, [])], scores=[[-1.0, -1.0], [-0.5, -1.5]])
        return ConceptBot(llm, None, "nokg", planner="goal", reading="words")  # OPE takes the reply

    client = make_client(worker=make_worker(goal_bot, can_simulate=False))
    events = events_of(client, client.post("/api/runs", json=RUN).json()["id"])
    kinds = [e["type"] for e in events]
    assert kinds.index("goal") < kinds.index("decisions") < kinds.index("risk") < kinds.index("plan")
    # The plan's progress messages arrive as status events between its own events, in order.
    assert [e.get("message", e["type"]) for e in events] == [
        "loading conceptbot on llamacpp:qwen2.5-coder-1.5b",
        "Goal: where the request sends things",
        "goal",
        "decisions",
        "OPE: properties of scissors",
        "Risk: is it safe to give the scissors to the child?",
        "risk",
        "plan",
        "done",
    ]
    goal = next(e for e in events if e["type"] == "goal")["data"]
    assert goal["targets"][0]["to"] == "child" and goal["targets"][0]["named"] == ["scissors"]
    [check] = next(e for e in events if e["type"] == "risk")["data"]["checks"]
    assert check["dropped"] and check["ope"] == "scissors: danger 4/5"
    plan = next(e for e in events if e["type"] == "plan")
    assert plan["plan"] == ["done()"] and plan["refused"]


def test_a_question_waits_for_the_pages_answer(make_client) -> None:
    from tests.web.conftest import events_of
    from tests.web.test_browser import QUESTION, asking_worker

    client = make_client(worker=asking_worker)
    started = client.post("/api/runs", json={"request": "Bring me something sour", "scene": "kitchen"})
    run_id = started.json()["id"]
    assert client.post(f"/api/runs/{run_id}/answer", json={"answer": ""}).status_code == 422
    for _ in range(200):  # the worker thread puts the question, then waits
        answered = client.post(f"/api/runs/{run_id}/answer", json={"answer": "maybe"})
        if answered.status_code != 409:
            break
        time.sleep(0.02)
    assert answered.status_code == 422, answered.text  # open, but "maybe" does not answer it
    answered = client.post(f"/api/runs/{run_id}/answer", json={"answer": " YES "})
    assert answered.status_code == 200, answered.text
    events = events_of(client, run_id)
    assert [e["type"] for e in events] == ["question", "plan", "done"]
    assert events[0]["question"] == QUESTION.to_dict()
    assert events[1]["plan"] == ["pick_and_place(apple, user)", "done()"]
    assert client.post(f"/api/runs/{run_id}/answer", json={"answer": "no"}).status_code == 409  # none open


def test_a_choose_question_takes_the_objects_that_go(make_client) -> None:
    from tests.web.conftest import events_of
    from tests.web.test_browser import CHOOSE, choosing_worker

    client = make_client(worker=choosing_worker)
    run_id = client.post("/api/runs", json={"request": "Bring me something sour", "scene": "kitchen"}).json()[
        "id"
    ]
    for _ in range(200):
        answered = client.post(f"/api/runs/{run_id}/answer", json={"answer": "lime, pear"})
        if answered.status_code != 409:
            break
        time.sleep(0.02)
    assert answered.status_code == 422  # pear is not one of the options
    assert client.post(f"/api/runs/{run_id}/answer", json={"answer": "lime,apple"}).status_code == 200
    events = events_of(client, run_id)
    assert events[0]["question"] == CHOOSE.to_dict() and events[0]["question"]["kind"] == "choose"
    assert events[1]["plan"] == ["pick_and_place(apple, user)", "pick_and_place(lime, user)", "done()"]


def test_a_lone_surrogate_in_a_json_body_is_a_4xx_not_a_500(make_client, caplog) -> None:
    # Pydantic refuses the value; FastAPI's own 422 echoes the input, which cannot be encoded.
    client = make_client()
    headers = {"Content-Type": "application/json"}
    body = b'{"request": "bring me an apple \\ud800", "scene": "kitchen"}'
    refused = client.post("/api/runs", content=body, headers=headers)
    assert 400 <= refused.status_code < 500, refused.text
    answered = client.post("/api/runs/x/answer", content=b'{"answer": "lemon\\udcff"}', headers=headers)
    assert 400 <= answered.status_code < 500, answered.text
    assert "Traceback" not in caplog.text
