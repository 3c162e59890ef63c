"""The goal planner, ConceptBot's default: read where the request sends things, decide which
objects go with one scored yes/no question each (the graph's statements weighed with the model's
answer), check each move's risk, and plan the moves.

* :mod:`.targets` — the destinations and how many objects each takes, from the goal the reader
  (:mod:`conceptbot.pipeline.goal`) finds in the request's parse;
* :mod:`.decide` — the per-object questions and their calibrated scores;
* :mod:`.evidence` and :mod:`.combine` — what the graph states about an object, as evidence, and
  the fitted combination of it with the model's answer;
* :mod:`.facts` — what the graph states about objects, dishes and places, for the questions;
* :mod:`.planner` — :class:`~conceptbot.pipeline.goal_planner.planner.GoalPlanner`: the stages in
  order, the plan and its trace; :mod:`.risk` its risk checks and vetoes, :mod:`.placing` the
  things used together, mats under hot things and piles.

How it was designed and measured: ``docs/planning.md``.
"""
