"""The goal planner, ConceptBot's default: read where the request sends things, decide which
objects go with one scored yes/no question each, check each move's risk, and plan the moves
(:mod:`.planner`; design and measurements in ``docs/planning.md``).
"""
