"""The optional parts of the package and what each needs installed (``pip install
'conceptbot[EXTRA]'``): a command that needs one it lacks says which, instead of a traceback.

``pip install conceptbot`` alone plans through an OpenAI-compatible server; the README's install
command installs every extra.
"""

from __future__ import annotations

import importlib.util
import sys

from conceptbot.core.errors import BackendUnavailableError

EXTRAS: dict[str, tuple[str, ...]] = {
    "embedded": ("llama_cpp", "sentence_transformers", "torch"),
    "sim": ("pybullet", "PIL"),
    "web": ("fastapi", "uvicorn", "pydantic"),
    "ros2": ("rclpy",),
}
"""Each extra's import names, as ``pyproject.toml`` declares them."""

_FOR = {
    "embedded": "the embedded model and embedder (llama.cpp, sentence-transformers)",
    "sim": "the PyBullet simulator",
    "web": "the web page",
    "ros2": "the ROS 2 node",
}


def missing(extra: str, modules: tuple[str, ...] | None = None) -> list[str]:
    """The import names of ``extra`` (or just ``modules`` of it) that are not installed."""
    return [m for m in modules or EXTRAS[extra] if not _installed(m)]


def _installed(module: str) -> bool:
    if module in sys.modules:  # imported already (or blocked: None), whatever its spec says
        return sys.modules[module] is not None
    return importlib.util.find_spec(module) is not None


def require(extra: str, modules: tuple[str, ...] | None = None) -> None:
    """Raise unless ``extra`` (or ``modules`` of it) is installed.

    Raises:
        BackendUnavailableError: What is missing, with the install command as the hint.
    """
    absent = missing(extra, modules)
    if absent:
        raise BackendUnavailableError(
            f"{_FOR[extra]} needs {', '.join(absent)}, which {'is' if len(absent) == 1 else 'are'} "
            "not installed",
            hint=f"pip install 'conceptbot[{extra}]' (or run the project's install script: "
            "bash scripts/install.sh)",
        )
