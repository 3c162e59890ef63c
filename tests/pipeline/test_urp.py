"""URP's messages, as the model receives them."""

from __future__ import annotations

from conceptbot.core.scene import scene_from_dict
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline import modes
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.urp import UserRequestProcessor
from tests.pipeline.fakes import urp_reply


def test_user_message_describes_people_and_states_and_the_system_message_the_properties() -> None:
    scene = scene_from_dict(
        {
            "pickable_objects": ["knife", "cup"],
            "destinations": ["user", "child", "table"],
            "entity_states": {"cup": "contains hot tea"},
        }
    )
    knife = ObjectProperties(
        "knife", modes.RISK, {"dangerous": 4, "dangerous_with": [{"object": "child", "score": 5}]}
    )
    llm = FakeLLM([urp_reply(["pick_and_place(cup, user)"])])
    result = UserRequestProcessor(llm, None).run("Bring me my tea ", scene, {"knife": knife})
    assert result.commands == ["pick_and_place(cup, user)"]
    system, user = (m.content for m in llm.requests[0].messages)
    assert user == (
        "The robot can pick up: knife, cup.\n"
        "It can put them on, in or at: user (the person asking), child (a child), table.\n"
        "State: cup contains hot tea.\n"
        "Request: Bring me my tea "
    )
    assert "\n\nObject properties:\n- knife: danger 4/5, dangerous with child (5)\n\n\nInterpret" in system
