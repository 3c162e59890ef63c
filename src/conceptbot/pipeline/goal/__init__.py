"""Reading the goal of a request: which objects go where, from the request's structure.

:class:`GoalReader` (:mod:`.reader`) parses the request with spaCy and returns a typed :class:`Goal`
(:mod:`.types`). Where the words leave a choice open (no destination, a need, a dish) the goal says
so and the planner settles it with the model: :func:`to_targets` (:mod:`.adapter`) turns a goal into
the goal planner's targets. :func:`same_goal` (:mod:`.compare`) is the goal set's exact match.
"""

from conceptbot.pipeline.goal.adapter import Chooser, GoalFinder, ScoredChooser, to_targets
from conceptbot.pipeline.goal.compare import GoalMatch, same_goal
from conceptbot.pipeline.goal.reader import GoalReader
from conceptbot.pipeline.goal.types import ALL, TAKES, Goal, GoalTarget

__all__ = [
    "ALL",
    "TAKES",
    "Chooser",
    "Goal",
    "GoalFinder",
    "GoalMatch",
    "GoalReader",
    "GoalTarget",
    "ScoredChooser",
    "same_goal",
    "to_targets",
]
