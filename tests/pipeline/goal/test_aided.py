from __future__ import annotations

from conceptbot.core.errors import BackendRequestError
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline.goal import Goal, GoalReader, GoalTarget
from conceptbot.pipeline.goal.aided import AidedReader, choose
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


NEED = Goal(need="I've got a splinter in my finger", targets=(GoalTarget(None, "need"),))


def test_a_need_stays_where_the_plain_command_makes_a_thing_of_it() -> None:
    request = "I've got a splinter in my finger."
    made_up = Goal(targets=(GoalTarget("user", "criterion", (), "splinter", 1),))
    assert choose(NEED, made_up, "grounded", request, "Give me the splinter.").source == "words"
    trashed = Goal(targets=(GoalTarget(None, "criterion", (), "splinter in the trash", 1),))
    assert choose(NEED, trashed, "grounded", request, "Put the splinter in the trash.").source == "words"


def test_a_grounded_command_wins_over_a_need_the_rules_fell_back_to() -> None:
    request = "It'd be lovely if the conch shell were back in the shoe box."
    command = Goal(targets=(GoalTarget("shoe box", "named", ("conch shell",), "", 1),))
    plain = "Put the conch shell in the shoe box."
    assert choose(NEED, command, "grounded", request, plain).source == "plain"


def test_the_words_stay_where_the_plain_form_drops_or_moves_what_they_place() -> None:
    request = "Put the conch shell in the shoe box and pass me the sand dollar."
    own = Goal(
        targets=(
            GoalTarget("shoe box", "named", ("conch shell",), "", 1),
            GoalTarget("user", "named", ("sand dollar",), "", 1),
        )
    )
    dropped = Goal(targets=own.targets[:1])
    assert choose(own, dropped, "grounded", request, "Put the conch shell in the shoe box.").source == "words"
    moved = Goal(targets=(GoalTarget("shoe box", "named", ("conch shell", "sand dollar"), "", 2),))
    plain = "Put the conch shell in the shoe box. Put the sand dollar in the shoe box."
    assert choose(own, moved, "grounded", request, plain).source == "words"


def test_the_words_stay_where_the_plain_form_gives_the_thing_to_someone_else() -> None:
    # "Hand him the marker" said plainly as "Give me the marker": the model lost who it is for. Both
    # readings call it "the marker" where the scene has two: no reason to doubt the words more.
    request = "My son wants to colour in his picture: hand him the marker."
    own = Goal(targets=(GoalTarget("child", "criterion", (), "marker", 1),))
    lost = Goal(targets=(GoalTarget("user", "criterion", (), "him the marker", "all"),))
    names = ("permanent marker", "washable marker", "user", "child")
    found = choose(own, lost, "grounded", request, "Give him the marker.", names)
    assert (found.source, found.step) == ("words", "moved")
    # Without the scene's objects, "the marker" is a sign the words made a thing up, as before.
    assert choose(own, lost, "grounded", request, "Give him the marker.").source == "plain"
    # A sort's other place is another kind, not the same one sent elsewhere.
    sort = Goal(
        targets=(
            GoalTarget("toxic tray", "criterion", (), "toxic plants", "all"),
            GoalTarget("safe tray", "criterion", (), "non-toxic plants", "all"),
        )
    )
    swapped = Goal(
        targets=(
            GoalTarget("safe tray", "criterion", (), "non-toxic plants", "all"),
            GoalTarget("toxic tray", "criterion", (), "poisonous plants", "all"),
        )
    )
    said = "Put the non-toxic plants on the safe tray and the poisonous plants on the toxic tray."
    assert choose(sort, swapped, "grounded", "Sort the plants.", said).step != "moved"


def test_only_a_criterion_s_wording_differing_keeps_the_person_s_words() -> None:
    request = "have you got something I could dry them with?"
    own = Goal(targets=(GoalTarget("user", "criterion", (), "something I could dry them with", 1),))
    other = Goal(targets=(GoalTarget("user", "criterion", (), "something to dry my hands with", 1),))
    said = "Give me something to dry my hands with."
    assert choose(own, other, "grounded", request, said).source == "words"
