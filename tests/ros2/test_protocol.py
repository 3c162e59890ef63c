"""The node's JSON payloads, without ROS: what a request may be and what each error says."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from conceptbot.core.limits import MAX_REQUEST_CHARS
from conceptbot.core.plan import Done, PickAndPlace, Plan
from conceptbot.core.scene import scene_from_dict
from conceptbot.core.trace import PlannerSummary
from conceptbot.ros2.protocol import (
    ERROR_CODES,
    MAX_ID_CHARS,
    MAX_PAYLOAD_BYTES,
    ProtocolError,
    encode,
    error_payload,
    event_payload,
    parse_request,
    progress_payload,
    result_payload,
)

DEFAULT = scene_from_dict({"name": "default", "pickable_objects": ["apple"], "destinations": ["user"]})
TINY = {
    "name": "tiny",
    "objects": ["cup", "user"],
    "pickable_objects": ["cup"],
    "destinations": ["user"],
    "entity_states": {"cup": "contains hot tea"},
    "detections": {"cup": {"confidence": 0.8, "bbox_px": [10, 20, 60, 90]}},
}


def _error(payload: object) -> ProtocolError:
    text = payload if isinstance(payload, str) else json.dumps(payload)
    with pytest.raises(ProtocolError) as caught:
        parse_request(text, DEFAULT)
    assert caught.value.code in ERROR_CODES
    return caught.value


def test_a_request_with_a_scene_object_keeps_states_and_detections() -> None:
    parsed = parse_request(json.dumps({"id": "r1", "request": "  Give me a drink ", "scene": TINY}), DEFAULT)
    assert (parsed.id, parsed.request, parsed.scene.name) == ("r1", "Give me a drink", "tiny")
    cup = parsed.scene.get("cup")
    assert cup is not None and cup.state == "contains hot tea"
    assert cup.confidence == 0.8 and cup.bbox_px == (10.0, 20.0, 60.0, 90.0)


def test_a_demo_scene_by_name_and_the_default_scene() -> None:
    assert parse_request('{"request": "hi", "scene": "kitchen"}', DEFAULT).scene.name == "kitchen"
    parsed = parse_request('{"request": "hi"}', DEFAULT)
    assert parsed.scene is DEFAULT
    assert parsed.id.startswith("req-") and parsed.id != parse_request('{"request": "hi"}', DEFAULT).id


@pytest.mark.parametrize(
    ("payload", "message"),
    [
        ("{not json", "not valid JSON"),
        ("[1, 2]", "must be a JSON object"),
        ({"id": "x"}, "no 'request'"),
        ({"request": "   "}, "the request is empty"),
        ({"request": 42}, "the request must be text"),
        ({"request": "a" * (MAX_REQUEST_CHARS + 1)}, f"the limit is {MAX_REQUEST_CHARS}"),
        ({"request": "hi", "id": 7}, "'id' must be a non-empty string"),
        ({"request": "hi", "id": "x" * (MAX_ID_CHARS + 1)}, f"at most {MAX_ID_CHARS} characters"),
        ({"request": "hi", "requets": "typo"}, "unknown key(s) 'requets'"),
        ({"request": "hi", "scene": ["apple"]}, "'scene' must be a scene object or the name"),
        ({"request": "hi", "scene": "no-such-scene"}, "unknown demo scene 'no-such-scene'"),
        ({"request": "hi", "scene": "/etc/passwd"}, "unknown demo scene '/etc/passwd'"),
        ({"request": "hi", "scene": {"objects": "apple"}}, "'objects' must be a list of names"),
        (
            {"request": "hi", "scene": {"pickable_objects": ["a(b)"], "destinations": ["u"]}},
            "plans cannot carry",
        ),
        ({"request": "hi", "scene": {"pickable_objects": ["a"]}}, "the scene has no destinations"),
        ({"request": "hi", "scene": {"pickable_objects": [f"o{i}" for i in range(101)]}}, "at most 100"),
        ("[" * 5000 + "]" * 5000, "nested"),
        ({"request": "hi", "scene": {"name": "x" * MAX_PAYLOAD_BYTES}}, "larger than"),
    ],
)
def test_malformed_requests_are_bad_requests_with_the_reason(payload: object, message: str) -> None:
    error = _error(payload)
    assert error.code == "bad_request"
    assert message in error.message


@pytest.mark.parametrize(
    "scene",
    [
        dict(TINY, entity_states={"teapot": "hot"}),
        dict(TINY, detections={"knife": {"confidence": 0.5}}),
    ],
)
def test_a_state_or_detection_of_an_unlisted_object_is_an_unknown_object(scene: dict) -> None:
    error = _error({"id": "u1", "request": "hi", "scene": scene})
    assert (error.code, error.request_id) == ("unknown_object", "u1")
    assert "has a state or detection but is not in the scene" in error.message


def test_an_error_keeps_the_clients_id_when_it_could_be_read() -> None:
    assert _error({"id": "mine", "request": ""}).request_id == "mine"
    assert _error("{broken").request_id.startswith("req-")


def test_the_outgoing_payloads() -> None:
    assert progress_payload("r1", "URP: keywords") == {
        "id": "r1",
        "kind": "progress",
        "message": "URP: keywords",
    }
    assert event_payload("r1", "planner", PlannerSummary("decide", 2)) == {
        "id": "r1",
        "kind": "event",
        "module": "planner",
        "data": {"method": "decide", "steps": 2},
    }
    plan = Plan([PickAndPlace("cup", "user"), Done()])
    result = result_payload("r1", plan)
    assert result["ok"] is True and result["plan"] == plan.to_dict()
    error = error_payload("r2", "busy", "full", "wait")
    assert error == {"id": "r2", "ok": False, "error": {"code": "busy", "message": "full", "hint": "wait"}}
    with pytest.raises(ValueError, match="unknown error code"):
        error_payload("r2", "oops", "no")
    assert json.loads(encode({"message": "Kaffee für dich"})) == {"message": "Kaffee für dich"}
    assert "für" in encode({"message": "für"})  # UTF-8, not \\u escapes


def test_the_protocol_imports_no_ros() -> None:
    code = (
        "import sys, conceptbot.ros2.protocol; print(sorted(m for m in sys.modules if m.startswith('rclpy')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
