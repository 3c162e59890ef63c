"""The package version, in the lowest layer so any layer may read it without importing the package top.

Keep it equal to ``version`` in ``pyproject.toml``. ``conceptbot.__version__`` re-exports it.
"""

from __future__ import annotations

__version__ = "0.1.0"
