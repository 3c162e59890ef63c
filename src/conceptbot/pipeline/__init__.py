"""The ConceptBot pipeline: the stages between a request and a plan.

Shared by both planners: relation retrieval and its cosine filter (:mod:`.retrieval`), OPE
(:mod:`.ope`, its modes and typed answers), URP (:mod:`.urp`), the affordance (:mod:`.affordance`),
the hazard veto (:mod:`.hazards`), the prompts and the words they list, the trace parts
(:mod:`.tracing`) and the composition by configuration (:mod:`.conceptbot`). The planners live in
their own subpackages: :mod:`.goal_planner` (the default, with the request reader :mod:`.goal`) and
:mod:`.steps` (the paper's step-by-step planner).
"""
