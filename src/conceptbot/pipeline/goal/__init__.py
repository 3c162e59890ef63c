"""Reading the goal of a request: which objects go where, from the request's structure.

:class:`GoalReader` (:mod:`.reader`) parses the request with spaCy (:mod:`.mentions`: the scene's
names as noun phrases; :mod:`.parse`: chunks; :mod:`.clauses` and :mod:`.wishes`: each clause's
form, destinations and theme; :mod:`.themes`: what a theme sends; :mod:`.items`: clauses as
targets) and returns a typed
:class:`Goal` (:mod:`.types`). Where the words leave a choice open - the request names no
destination, states a need, or asks for a dish - the goal says so (``to`` None, ``takes`` "need" or
"ingredients") and the planner settles it with the model; :func:`to_targets` (:mod:`.adapter`) turns
a goal into the goal planner's :class:`~conceptbot.pipeline.goal_planner.targets.Target` list, choosing those
places with a scorer. :func:`same_goal` (:mod:`.compare`) is the exact match of the goal set
(``benchmarks/data/goal_set.json``, measured by ``benchmarks/bench_goal_reading.py``).

The goal form, as in the goal set::

    {"stack": false, "dish": "guacamole" | null, "need": "my phone battery is almost empty" | null,
     "targets": [{"to": "<scene destination>" | null, "takes": "named" | "criterion" | "remainder" |
                  "ingredients" | "need" | "all", "named": [...], "criterion": "...",
                  "count": <int> | "all"}]}

Conventions: ``to`` is a scene name or None (the request names no destination: a need, a dish, "throw
away", "out of the toddler's reach"); "me" is ``user``, a people word a person destination of that
kind, a possessor or a statement's subject never a destination. ``criterion`` is the request's words
for which objects go, without determiners or the destination ("poisonous", "made entirely of glass",
"something to write with"); a place in a sort gets the sort's key ("by material") or "" (its name
decides). ``count`` is what the words set: 1 for "a", "something" or a definite singular count noun,
a number, else "all" (plurals, "all", mass nouns, a remainder, ingredients, a need). The reader uses
no word lists tied to requests: ``words.json`` holds closed word classes of English and a few verb
classes (making, wishing, sorting, staying).

In the goal planner (a ``Target`` list, scored where the words leave the place open)::

    goal = GoalReader(is_dish=...).read(request, scene)  # is_dish: optional graph check
    chooser = ScoredChooser(target_finder, request)
    targets = to_targets(goal, scene, choose=chooser)  # [] for a stack (goal.stack)
    usage = chooser.usage
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
