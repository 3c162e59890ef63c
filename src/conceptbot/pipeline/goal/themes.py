"""What a theme phrase sends: named objects, a remainder, everything, or the objects a criterion
describes, and how many."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.mentions import Mention
from conceptbot.pipeline.goal.parse import vocabulary
from conceptbot.pipeline.goal.types import ALL, Count
from conceptbot.pipeline.vocabulary import MATERIALS

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.tokens import Doc, Token

_STOP_HEAD = {"IN", "TO", "WDT", "WP", "VBN", "VBG", "VBZ", "VBD", "VBP", "VB", "MD", "RB", ",", "PRP"}


@dataclass(frozen=True)
class Reading:
    """A theme phrase read (see :class:`conceptbot.pipeline.goal.types.GoalTarget`)."""

    takes: str
    named: tuple[str, ...] = ()
    criterion: str = ""
    count: Count = ALL


def _lower(token: Token) -> str:
    return token.text.lower()


def objects_in(run: Sequence[int], mentions: Sequence[Mention]) -> tuple[str, ...]:
    """The pickable objects a run names, in text order."""
    inside = set(run)
    return tuple(
        n
        for m in mentions
        if m.kind in ("object", "both") and set(range(m.start, m.end)) <= inside
        for n in m.names
    )


def _remainder(doc: Doc, run: Sequence[int]) -> bool:
    """ "the rest", "everything else", "the other ones", "whatever is left": the marker belongs to the
    phrase itself, not to a clause inside it."""
    markers = set(vocabulary()["remainder"])
    for i in run:
        token = doc[i]
        if _lower(token) not in markers:
            continue
        if _lower(token) == "left":
            if token.i > 0 and doc[token.i - 1].lemma_ == "be":
                return True
            continue
        if token.head.dep_ in ("relcl", "acl") and token.head.i in run and token.head.i < token.i:
            continue
        if token.i > 0 and _lower(doc[token.i - 1]) in ("nothing", "no", "none"):
            continue  # "the fabric items, and nothing else": only they go
        return True
    return False


def _whole(doc: Doc, run: Sequence[int]) -> bool:
    """A run that is only "all of these", "everything", "this pile": every object."""
    whole = set(vocabulary()["whole"])
    return all(_lower(doc[i]) in whole for i in run)


def _stripped(doc: Doc, run: Sequence[int]) -> list[int]:
    """The run without its leading determiners, quantifiers and restrictors ("only the", "all of
    the", "everything"), nor a "here" after them."""
    vocab = vocabulary()
    lead = {*vocab["determiners"], *vocab["quantifiers"], *vocab["restrictors"], "one", "of", "here", "there"}
    lead -= {"something"}
    out = list(run)
    for phrase in vocab["only_phrases"]:  # "nothing but the paper": only the paper
        if [_lower(doc[i]) for i in out[: len(phrase)]] == phrase:
            out = out[len(phrase) :]
            break
    while out and _lower(doc[out[0]]) in lead:
        out = out[1:]
    return out


def _head(doc: Doc, run: Sequence[int]) -> Token | None:
    """The phrase's head noun: the last noun before a preposition, a relative pronoun or a verb."""
    head = None
    for i in run:
        token = doc[i]
        if head is not None and (token.tag_ in _STOP_HEAD and not _plural_noun(token)):
            break
        if token.tag_.startswith("NN") or _plural_noun(token) or _lower(token) in ("ones", "one"):
            head = token
    return head


def head_of(doc: Doc, run: Sequence[int]) -> Token | None:
    """The head noun of a phrase, after its determiners and quantifiers."""
    return _head(doc, _stripped(doc, run))


def _plural_noun(token: Token) -> bool:
    """A plural noun, also where the tagger took it for a verb ("the glass objects")."""
    if token.tag_ in ("NNS", "NNPS"):
        return True
    word = _lower(token)
    return (
        token.tag_ == "VBZ"
        and word.endswith("s")
        and token.i > 0
        and token.doc[token.i - 1].tag_.startswith("NN")
    )


def count_of(doc: Doc, run: Sequence[int]) -> Count:
    """How many objects a criterion phrase asks for: a number; 1 for "a", "one", "something" or a
    definite singular count noun ("the toy made of metal"); else all (plurals, "all", "every",
    "anything", mass nouns: "the food", "the paper")."""
    vocab = vocabulary()
    words = [_lower(doc[i]) for i in run]
    for i in run:
        token = doc[i]
        if token.tag_ == "CD" and token.like_num and _lower(token) != "one" and token.dep_ == "nummod":
            try:
                return max(1, int(token.text))
            except ValueError:
                pass
    if words and words[0] in ("whichever", "whatever") and len(run) > 1:
        noun = doc[run[1]]  # "whichever toy is ...": one toy; "whatever food is ...": all of it
        mass = {*vocab["mass"], *MATERIALS}
        if noun.tag_ == "NN" and noun.lemma_.lower() not in mass and _lower(noun) not in mass:
            return 1
    if any(w in vocab["quantifiers"] for w in words):
        return ALL
    start = next((w for w in words if w not in vocab["restrictors"]), "")
    if start in vocab["one"]:
        return 1
    head = _head(doc, _stripped(doc, run))
    if head is None or _plural_noun(head) or _lower(head) == "ones":
        return ALL
    mass = {*vocab["mass"], *MATERIALS}
    if head.lemma_.lower() in mass or _lower(head) in mass:
        return ALL
    return 1 if start in ("the", "this", "that", "my", "your", "his", "her", "our", "their") else ALL


def criterion_text(doc: Doc, run: Sequence[int]) -> str:
    """The criterion's words: the run without leading determiners and quantifiers."""
    kept = _stripped(doc, run)
    if not kept:
        return ""
    text = doc[kept[0] : kept[-1] + 1].text
    return text.strip(" ,;:.!?")


def read_theme(doc: Doc, run: Sequence[int], mentions: Sequence[Mention]) -> Reading:
    """What a theme phrase sends (named objects, a remainder, everything, or a criterion)."""
    named = objects_in(run, mentions)
    if named:
        return Reading("named", named, "", len(named))
    if _remainder(doc, run):
        return Reading("remainder")
    if _whole(doc, run):
        return Reading("all")
    return Reading("criterion", (), criterion_text(doc, run), count_of(doc, run))
