from __future__ import annotations

from conceptbot.core.errors import BackendRequestError
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline.goal import GoalReader, GoalTarget
from conceptbot.pipeline.goal.aided import AidedReader
from conceptbot.pipeline.goal.restate import Restater
from tests.pipeline.goal.scenes import SHELLS

READER = GoalReader()


def _aided(reply: str | Exception, policy: str = "plain") -> AidedReader:
    return AidedReader(READER, Restater(FakeLLM([reply])), policy)  # type: ignore[arg-type]


def test_two_readings_that_agree_are_not_in_doubt() -> None:
    reading = _aided("Put the conch shell in the shoe box.").read(
        "Put the conch shell in the shoe box.", SHELLS
    )
    assert reading.source == "both" and not reading.doubtful
    assert reading.goal.targets == (GoalTarget("shoe box", "named", ("conch shell",), "", 1),)


def test_where_they_differ_the_policy_picks_and_the_reading_is_in_doubt() -> None:
    request = "Oh, before I forget, would you be a dear and pop the conch shell in the shoe box?"
    reply = "Put the conch shell in the shoe box."
    plain = _aided(reply).read(request, SHELLS)
    assert plain.doubtful and plain.source == "plain" and plain.plain == reply
    assert plain.goal.targets == (GoalTarget("shoe box", "named", ("conch shell",), "", 1),)
    words = _aided(reply, "words").read(request, SHELLS)
    assert words.doubtful and words.goal == words.words != plain.goal


def test_without_a_plain_form_the_words_are_read_alone() -> None:
    reading = _aided(BackendRequestError("timed out")).read("Put the conch shell in the shoe box.", SHELLS)
    assert reading.restated is None and reading.source == "words" and not reading.doubtful
    assert reading.goal.targets == (GoalTarget("shoe box", "named", ("conch shell",), "", 1),)
