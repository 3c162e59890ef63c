"""Wishes: "I'd love an omelette" (the ``desire`` form of :mod:`.parse`, step 2)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.mentions import Mention
from conceptbot.pipeline.goal.parse import Chunk, Clause, Place, vocabulary
from conceptbot.pipeline.goal.runs import lower as _lower
from conceptbot.pipeline.goal.runs import nominal
from conceptbot.pipeline.goal.runs import runs as _runs

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.tokens import Doc, Token


def desire_verb(doc: Doc, first: int, end: int, lets: bool) -> Token | None:
    """The verb (or "about", or the copula) of a wish ("I'd love X", "how about X"), else None."""
    vocab = vocabulary()
    for token in doc[first:end]:
        subject = [c for c in token.children if c.dep_ == "nsubj"]
        speaker = any(_lower(c) in ("i", "we") for c in subject) or (lets and token.i == first)
        particle = any(c.dep_ == "prt" for c in token.children)  # "make out this tiny print"
        if token.lemma_ in vocab["making"] and token.tag_.startswith("VB") and speaker and not particle:
            return token  # "we're making a green salad"
        wishing = any(c.dep_ == "prep" and _lower(c) == "for" for c in token.children) and any(
            _lower(c) in ("could", "would", "'d") for c in token.children
        )
        if token.lemma_ == "go" and speaker and wishing:
            return token  # "I could really go for a PB&J"
        if token.lemma_ in vocab["desire"] and token.tag_.startswith("VB") and speaker:
            if token.lemma_ == "have" and not (_wishes_to_have(token, subject, lets) or _asks(token)):
                continue  # "I'll have a PB&J" is a wish; "I have a cold" is not
            return token
        if token.lemma_ in vocab["receiving_asked"] and token.tag_ == "VB" and speaker and _asks(token):
            return token  # "could I borrow something to write with?", "I'll take the tape measure"
        if _lower(token) == "about" and token.i > first and _lower(doc[token.i - 1]) == "how":
            return token
        conditional = any(_lower(c) in ("would", "could") for c in token.children)
        praised = any(c.dep_ == "acomp" for c in token.children)
        thing = bool(subject) and not any(_lower(c) in vocab["personal"] for c in subject)
        if token.lemma_ == "be" and conditional and praised and thing:
            return token
        if token.lemma_ == "sound" and praised and any(c.pos_ in ("NOUN", "PROPN") for c in subject):
            return token  # "a fruit salad sounds great right now"
    return None


def _asks(token: Token) -> bool:
    """Whether the speaker's verb asks to receive: "could I ...?" or "I'll ..."."""
    modals = [c for c in token.children if c.tag_ == "MD"]
    subject = next((c for c in token.children if c.dep_ == "nsubj"), None)
    if subject is None:
        return False
    asked = any(_lower(m) in ("could", "can", "may", "might") and m.i < subject.i for m in modals)
    return asked or any(_lower(m) in ("'ll", "will") and m.i > subject.i for m in modals)


def _wishes_to_have(token: Token, subject: list[Token], lets: bool) -> bool:
    """ "have" as a wish: "let's have", "we should/could have", "we're having", "could I have"."""
    modals = {_lower(c) for c in token.children if c.tag_ == "MD"}
    we = any(_lower(c) == "we" for c in subject)
    speaker_i = any(_lower(c) == "i" for c in subject)
    if lets or (we and (modals & {"should", "could", "can", "shall"} or token.tag_ == "VBG")):
        return True
    return speaker_i and bool(modals & {"could", "can", "may"})


def _names_object(doc: Doc, run: Sequence[int], mentions: Sequence[Mention]) -> bool:
    return any(m.kind in ("object", "both") and m.start in run for m in mentions)


def desire_clause(
    doc: Doc,
    chunk: Chunk,
    verb: Token,
    first: int,
    end: int,
    places: list[Place],
    frame: set[int],
    mentions: Sequence[Mention] = (),
) -> Clause:
    """A wish as a clause: its theme is what is wished for; for "I want to make X" the verb is "make"."""
    attr = next((c for c in verb.children if c.dep_ == "attr"), None)
    if verb.lemma_ == "be" and attr is not None:
        # "breakfast should be an omelette": what the meal is to be
        theme = tuple(t.i for t in attr.subtree if t.i not in frame and not t.is_punct)
        return Clause(chunk, "desire", "be", verb.i, [], theme, "", False, [theme])
    subject = next((c for c in verb.children if c.dep_ == "nsubj"), None)
    if verb.lemma_ in ("be", "sound") and subject is not None:  # "X would be lovely", "X sounds great"
        theme = tuple(i for i in range(subject.left_edge.i, subject.right_edge.i + 1) if i not in frame)
        return Clause(chunk, "desire", "be", verb.i, [], theme, "", False, [theme])
    vocab = vocabulary()
    activity = next((c for c in verb.children if c.dep_ in ("xcomp", "ccomp") and c.tag_ == "VB"), None)
    if verb.tag_ == "IN":
        activity = None  # "in the mood for": what follows the preposition
    at = activity if activity is not None else verb
    frame = (
        frame
        | set(range(first, at.i + 1))
        | {c.i for c in at.children if c.dep_ == "prep" and at.lemma_ == "go"}
    )
    if places and activity is None:
        # "I'd like the tweezers put in the first aid kit": a request to move them there
        frame |= {
            t.i
            for t in doc[at.i + 1 : end]
            if t.tag_ in ("VBN", "VBD") and t.dep_ in ("ccomp", "xcomp", "acl")
        }
        runs = _runs(list(range(at.i + 1, end)), frame, doc)
        theme = next((r for r in runs if nominal(doc, r)), ())
        return Clause(chunk, "imperative", "put", at.i, places, theme, "", False, runs)
    runs = _runs(list(range(at.i + 1, end)), frame, doc)
    theme = next((r for r in runs if nominal(doc, r)), ())
    if theme and _names_object(doc, theme, mentions):
        # "could I have the watering can, and the trowel as well?": the objects joined on
        joined = [r for r in runs if r[0] > theme[-1] and _lower(doc[r[0] - 1]) in ("and", ",")]
        theme = (*theme, *(i for r in joined if _names_object(doc, r, mentions) for i in r))
    lemma = "want"
    if activity is not None or at.lemma_ in vocab["making"]:
        lemma = at.lemma_.lower()
    elif verb.lemma_ == "need":
        lemma = "need"
    return Clause(chunk, "desire", lemma, at.i, [], theme, "", False, runs)
