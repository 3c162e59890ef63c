"""ConceptBot: commonsense-grounded LLM planning for robots.

Layers (imports flow one way): ``core`` -> ``knowledge``, ``models`` -> ``pipeline`` ->
``baselines`` -> ``sim``, ``bench`` -> ``cli``, ``web``.
"""

__version__ = "0.1.0"
