"""Error types.

Every error a user can cause or fix is a :class:`ConceptBotError` with a message that says what went
wrong and, where there is one, a ``hint`` that says how to fix it (usually a command to run). The CLI
prints both and exits non-zero; it never shows a stack trace for these.
"""

from __future__ import annotations


class ConceptBotError(Exception):
    """Base class for errors meant to be shown to a user.

    Args:
        message: What went wrong, in one sentence.
        hint: How to fix it (a command to run, a setting to change), or ``None``.
    """

    exit_code: int = 1

    def __init__(self, message: str, *, hint: str | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.hint = hint

    def __str__(self) -> str:
        return self.message if not self.hint else f"{self.message}\nHint: {self.hint}"


class ConfigError(ConceptBotError):
    """Bad configuration: unknown backend name, malformed URL, missing key, bad option."""

    exit_code = 2


class ModelNotInstalledError(ConceptBotError):
    """A local model file is not in the model store."""


class ModelCorruptError(ConceptBotError):
    """A local model file exists but its checksum (or format) is wrong."""


class BackendUnavailableError(ConceptBotError):
    """A backend could not be reached or loaded (server down, time-out, import failure)."""


class BackendRequestError(ConceptBotError):
    """A backend answered, but refused the request (bad model name, bad parameters, auth)."""


class ModelOutputError(ConceptBotError):
    """A model's reply could not be used (e.g. malformed JSON even after a constrained retry)."""


class NotSupportedError(ConceptBotError):
    """The chosen backend cannot do what was asked (e.g. log-probability scoring)."""


class FakeExhaustedError(ConceptBotError):
    """A fake backend was asked for more replies than were scripted (tests only)."""


class KnowledgeUnavailableError(ConceptBotError):
    """The knowledge graph is missing, corrupt or unreachable."""


class ImportDataError(ConceptBotError):
    """An importer could not read its input (missing file, wrong format)."""
