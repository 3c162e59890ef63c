"""The paper's step planner (section III-C): one action at a time, each the argmax of the LLM's
score times the affordance over every valid move plus ``done()``.

* :mod:`.planner` — :class:`~conceptbot.pipeline.steps.planner.Planner`: the LLM's score per
  candidate (``logprob``: one scored pass; ``vote``: the paper's ``n`` completions), with OPE's
  properties and URP's commands in the prompt;
* :mod:`.greedy` — the loop both it and SayCan run: score, choose, stop at ``done()`` or when
  nothing feasible is left, with the hazard veto on each chosen move.

``--config paper`` (and ``paper-nokg``, ``--planner steps``) plans with it; the default is the goal
planner (:mod:`conceptbot.pipeline.goal_planner`).
"""
