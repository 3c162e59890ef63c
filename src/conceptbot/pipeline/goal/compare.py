"""Whether two goals are the same (the goal bench's exact match): ``stack``, the dish's words, whether
there is a need, and the targets as a multiset, criteria compared as content words (:func:`words`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

from conceptbot.pipeline.goal.types import Goal, GoalTarget

#: spaCy stop words that carry a criterion's meaning.
MEANINGFUL = frozenset(
    {"not", "no", "n't", "nothing", "none", "never", "without", "neither", "nor", "whole", "several",
     "empty", "full", "more", "most", "less", "least", "few", "many", "much"}
)  # fmt: skip
GENERIC = frozenset({"one", "ones", "thing", "things", "item", "items", "object", "objects", "stuff"})


@dataclass(frozen=True)
class GoalMatch:
    """The comparison's result, with the first difference found.

    Attributes:
        ok: The goals match.
        reason: What differs ("" when they match).
    """

    ok: bool
    reason: str = ""


@lru_cache(maxsize=4096)
def _lemma(word: str) -> str:
    """A word's lemma, taken alone, so that the same word gets the same lemma in any phrase."""
    from conceptbot.knowledge.triples import load_model

    return load_model()(word)[0].lemma_.lower().strip(".,;:!?'\"()-")


@lru_cache(maxsize=4096)
def words(text: str) -> tuple[str, ...]:
    """A criterion's or dish's content words: lemmas less stop words (but :data:`MEANINGFUL`) and generics."""
    from spacy.lang.en.stop_words import STOP_WORDS

    from conceptbot.knowledge.triples import load_model

    kept = []
    for token in load_model().tokenizer(text.lower()):
        word = token.text.strip(".,;:!?'\"()-")
        if not word or token.is_punct or (token.text in STOP_WORDS and token.text not in MEANINGFUL):  # "'s"
            continue
        lemma = _lemma(word)
        if word in GENERIC or lemma in GENERIC:
            continue
        if (word in STOP_WORDS or lemma in STOP_WORDS) and word not in MEANINGFUL and lemma not in MEANINGFUL:
            continue
        kept.append(lemma)
    return tuple(kept)


def _key(target: GoalTarget) -> tuple:
    return (
        target.to or "",
        target.takes,
        tuple(sorted(target.named)),
        () if target.takes == "need" else words(target.criterion),  # a need's words: as the goal's
        str(target.count),
    )


def _show(target: GoalTarget) -> str:
    named = f" {list(target.named)}" if target.named else ""
    criterion = f" {target.criterion!r}" if target.criterion else ""
    return f"{target.takes}{named}{criterion} x{target.count} -> {target.to}"


def same_goal(read: Goal, gold: Goal) -> GoalMatch:
    """Compare a goal read from a request with the gold one (see the module docstring).

    Returns:
        The match, with the first difference as its reason when they differ.
    """
    if read.stack != gold.stack:
        return GoalMatch(False, f"stack: read {read.stack}, gold {gold.stack}")
    read_dish = words(read.dish) if read.dish else None
    gold_dish = words(gold.dish) if gold.dish else None
    if read_dish != gold_dish:
        return GoalMatch(False, f"dish: read {read.dish!r}, gold {gold.dish!r}")
    if (read.need is None) != (gold.need is None):
        return GoalMatch(False, f"need: read {read.need!r}, gold {gold.need!r}")
    left = [_key(t) for t in read.targets]
    right = [_key(t) for t in gold.targets]
    extra = [t for t, k in zip(read.targets, left, strict=True) if left.count(k) > right.count(k)]
    missing = [t for t, k in zip(gold.targets, right, strict=True) if right.count(k) > left.count(k)]
    if extra or missing:
        parts = [f"extra {_show(t)}" for t in extra] + [f"missing {_show(t)}" for t in missing]
        return GoalMatch(False, "; ".join(parts))
    return GoalMatch(True)


def structure(goal: Goal) -> Goal:
    """The goal without its criteria's words (what "structure" compares in the goal bench)."""
    return replace(goal, targets=tuple(replace(t, criterion="") for t in goal.targets))
