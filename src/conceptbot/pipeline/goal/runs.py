"""Runs of tokens: the pieces of a chunk left once its frame is taken out, and whether one can be a theme."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.parse import vocabulary

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.tokens import Doc, Token

_PRONOUN_THEMES = {"it", "them", "they", "him", "her", "one"}


def lower(token: Token) -> str:
    return token.text.lower()


def runs(indices: Sequence[int], frame: set[int], doc: Doc) -> list[tuple[int, ...]]:
    """Maximal runs of non-frame tokens, without punctuation and joining words at their edges."""
    runs: list[list[int]] = []
    current: list[int] = []
    for i in indices:
        if i in frame or (doc[i].is_punct and lower(doc[i]) not in ("-", "%")):
            if current:
                runs.append(current)
            current = []
        else:
            current.append(i)
    if current:
        runs.append(current)
    trimmed = []
    edge = {"and", "or", "but", "so", "then", "please", "also", "now", ","}
    for run in runs:
        while run and (lower(doc[run[0]]) in edge | {"with"} or doc[run[0]].is_punct):
            run = run[1:]
        while run and (lower(doc[run[-1]]) in edge or doc[run[-1]].is_punct):
            run = run[:-1]
        if run:
            trimmed.append(tuple(run))
    return trimmed


def nominal(doc: Doc, run: Sequence[int]) -> bool:
    """Whether a run can be a theme: a noun, indefinite pronoun or adjective, not only a personal pronoun."""
    vocab = vocabulary()
    words = [lower(doc[i]) for i in run]
    if all(w in _PRONOUN_THEMES for w in words):
        return False
    pronouns = {*vocab["quantifiers"], *vocab["one"], "these", "those", "this", "what", "whatever"}
    return any(doc[i].tag_ in ("NN", "NNS", "NNP", "NNPS") or lower(doc[i]) in pronouns for i in run) or any(
        doc[i].tag_ == "JJ" for i in run
    )
