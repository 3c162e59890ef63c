"""Repairs of the small parser's commonest misattachments, made on the parsed request before any
rule reads it, so that every rule sees the same, corrected tree.

``en_core_web_sm`` attaches a second object after a comma to the verb, not to the first object
("give the toddler something to draw with, | and a cuddly toy as well": "toy" a ``conj`` of
"give"), and a stand-in's modifier to the verb ("pass me a tool for measuring and another | for
tightening screws": "for" a ``prep`` of "pass"). Read as parsed, the second object is lost, or the
stand-in describes nothing. Each repair is a general shape of the tree, never a word of a
particular request; a shape that does not match leaves the tree as it is.
"""

from __future__ import annotations

import re
from itertools import pairwise
from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.parse import vocabulary
from conceptbot.pipeline.goal.themes import STANDS_IN

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.language import Language
    from spacy.tokens import Doc, Token

SUBJECTS = frozenset({"nsubj", "nsubjpass", "expl", "csubj"})
OBJECTS = ("dobj", "attr")


def _nominal(token: Token) -> bool:
    return (
        token.pos_ in ("NOUN", "PROPN", "PRON")
        or token.tag_.startswith("NN")
        or token.text.lower() in STANDS_IN
    )


def _places(token: Token) -> bool:
    """Whether a phrase has a preposition of place of its own: a "conjunct" with one is a second
    clause with the verb left out ("put the cup in the sink, and the plate in the drawer")."""
    return any(c.dep_ == "prep" and c.text.lower() in vocabulary()["spatial"] for c in token.children)


def _verb_conjunct_objects(doc: Doc) -> None:
    """A noun phrase the parser made a conjunct of the verb ("give X, and a toy too") becomes a
    conjunct of the verb's object, with its "and" and comma. Not where it has a subject or a place
    of its own (a clause, or a gapped one), nor where the verb has no object before it."""
    for token in doc:
        verb = token.head
        if token.dep_ != "conj" or not _nominal(token) or verb.pos_ not in ("VERB", "AUX"):
            continue
        if any(c.dep_ in SUBJECTS for c in token.children) or _places(token):
            continue
        if token.left_edge.text.lower() in vocabulary()["restrictors"]:
            continue  # "the paper, and only the paper": the first object again, restricted
        objects = [c for c in verb.children if c.dep_ in OBJECTS and c.i < token.i and _nominal(c)]
        if not objects:
            continue
        first = objects[-1]
        # the joining words between the object and the conjunct go with the conjunct's new head
        joining = [
            c
            for c in verb.children
            if first.right_edge.i < c.i < token.left_edge.i and c.dep_ in ("cc", "punct")
        ]
        for word in joining:
            word.head = first
        token.head = first


def _second_objects(doc: Doc) -> None:
    """A verb's second object after its "and" ("give the toddler something to draw with, and a
    soft cuddly toy as well", both read as objects of "give") becomes the first's conjunct."""
    for verb in doc:
        objects = [c for c in verb.children if c.dep_ == "dobj" and _nominal(c)]
        for first, second in pairwise(objects):
            joining = [c for c in verb.children if first.right_edge.i < c.i < second.left_edge.i]
            if not any(c.dep_ == "cc" for c in joining) or _places(second):
                continue
            for word in joining:
                if word.dep_ in ("cc", "punct"):
                    word.head = first
            second.dep_ = "conj"
            second.head = first


def _stand_in_heads(doc: Doc) -> None:
    """A stand-in the parser joined to a noun inside the first phrase's clause ("a tool to drive in
    nails and another": "another" a conjunct of "nails") is joined to that phrase's head ("tool"),
    which is what it stands in for."""
    for token in doc:
        if token.text.lower() not in STANDS_IN or token.dep_ != "conj":
            continue
        inner, head = token.head, token.head
        while head.dep_ not in ("relcl", "acl") and head.head.i != head.i:
            head = head.head
        if head.i == inner.i or head.dep_ not in ("relcl", "acl") or not _nominal(head.head):
            continue
        phrase = head.head
        for word in [c for c in inner.children if c.dep_ in ("cc", "punct") and inner.i < c.i < token.i]:
            word.head = phrase
        token.head = phrase


def _stand_in_modifiers(doc: Doc) -> None:
    """A bare stand-in ("and another") followed by a preposition the parser gave to the verb
    ("... for tightening screws") takes the preposition: a stand-in says nothing without it."""
    for token in doc:
        if token.text.lower() not in STANDS_IN or token.dep_ not in ("conj", "appos", "dobj"):
            continue
        if any(c.i > token.i for c in token.children):
            continue  # it has its own modifier ("one to tighten screws")
        after = token.i + 1
        if after >= len(doc):
            continue
        nxt = doc[after]
        if nxt.dep_ == "prep" and nxt.head.pos_ in ("VERB", "AUX") and nxt.head.i < token.i:
            if nxt.text.lower() in vocabulary()["spatial"]:
                continue  # "and another on the shelf": where it goes
            nxt.head = token


def plain(text: str) -> str:
    """``text`` with its politeness frames and joining phrases said the plain way (``polite_frames``
    and ``joining_phrases`` in ``words.json``: "any chance you could pass me a drink?" is "could you
    pass me a drink?", "the trowel, as well as the watering can" is "the trowel, and the watering
    can"), which every rule reads; the small parser makes "chance" the request's object."""
    vocab = vocabulary()
    frames = sorted(vocab["polite_frames"] + vocab["joining_phrases"], key=lambda f: -len(f[0]))
    for frame, said in frames:  # the longest first: "is there any chance you could" before its tail
        text = re.sub(rf"(?i)\b{re.escape(frame)}\b", said, text)
    return text


def parsed(nlp: Language, text: str) -> Doc:
    """``text`` parsed and repaired. An "'s" the parser read as a possessive where it is the verb
    ("my hair's dripping wet and full of knots", with no verb left; "my phone's about to die", its
    "possessor" the subject) is replaced by "is" and the text parsed again: no rule reads a
    sentence without its verb."""
    text = plain(text)
    doc = nlp(text)
    verbless = not any(t.pos_ in ("VERB", "AUX") for t in doc)
    verbs = [
        t
        for t in doc
        if t.tag_ == "POS" and t.text.lower() == "'s" and (verbless or t.head.dep_ in ("nsubj", "nsubjpass"))
    ]
    for token in reversed(verbs):
        text = text[: token.idx] + " is" + text[token.idx + len(token.text) :]
    return repair(nlp(text) if verbs else doc)


def repair(doc: Doc) -> Doc:
    """``doc`` with the repairs of the module docstring made in place (returned for chaining)."""
    _verb_conjunct_objects(doc)
    _second_objects(doc)
    _stand_in_heads(doc)
    _stand_in_modifiers(doc)
    return doc
