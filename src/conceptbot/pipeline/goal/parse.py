"""The request's clauses, read off spaCy's parse (trusted for tags, nearby labels and sentence ends,
as the small model often misparses imperatives): where each one sends things and what it sends.

1. **Chunks**: split at hard (".", ";") and soft (",", "and") boundaries; one phrase is joined back.
2. **Clauses** (:mod:`.clauses`, :mod:`.wishes`): each chunk's form, ``imperative``, ``subject``
   ("X goes in A"), ``for`` ("A is for X"), ``desire`` ("I want X"), ``fragment`` or ``statement``.
3. **Places**: a destination mention only in a destination role (after a spatial preposition...).
4. **Theme**: what is sent, the tokens left once the frame (verb, destinations...) is taken out.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.mentions import Mention

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.tokens import Doc, Token

HARD = {".", "!", "?", ";", ":"}
SOFT = {",", "and", "but", "then", "so", "because", "since", "while", "whereas"}
CLAUSE_DEPS = {"ROOT", "conj", "ccomp", "parataxis", "advcl", "dep", "xcomp"}


@cache
def vocabulary() -> dict:
    """The vocabulary of ``words.json``."""
    text = resources.files("conceptbot.pipeline.goal").joinpath("words.json").read_text(encoding="utf-8")
    return json.loads(text)


@dataclass
class Chunk:
    """A run of tokens read as one clause.

    Attributes:
        start: The first token's index.
        end: One past the last token's index.
        after: The boundary before it: ``""`` (the first), ``hard`` (".", ";"), ``colon`` or ``soft``.
    """

    start: int
    end: int
    after: str


@dataclass
class Place:
    """A destination of a clause: one mention (several names for a plural head)."""

    mention: Mention
    frame: tuple[int, ...]  # the mention's tokens with its preposition and determiners


@dataclass
class Clause:
    """What one chunk says (see the module docstring).

    Attributes:
        chunk: Its tokens.
        form: ``imperative``, ``subject``, ``for``, ``desire``, ``fragment`` or ``statement``.
        verb: The main verb's lemma ("" for a fragment).
        places: Its destinations in a destination role.
        theme: The token indices of what it sends (empty: none).
        key: "by material" when it sorts by a key, else "".
        negated: The verb is negated ("don't touch").
        runs: Every run of non-frame tokens (for the dish and need readings).
        otherwise: It opens with "otherwise": "it" is what the conditions before leave.
    """

    chunk: Chunk
    form: str
    verb: str = ""
    verb_at: int = -1
    places: list[Place] = field(default_factory=list)
    theme: tuple[int, ...] = ()
    key: str = ""
    negated: bool = False
    runs: list[tuple[int, ...]] = field(default_factory=list)
    otherwise: bool = False


def _in_mention(mentions: Sequence[Mention], index: int) -> Mention | None:
    return next((m for m in mentions if m.covers(index)), None)


def clause_verbs(doc: Doc, start: int, end: int, mentions: Sequence[Mention]) -> list[Token]:
    """The verbs heading a clause of their own in ``doc[start:end]`` (not in a relative clause or noun
    phrase, not a "to" infinitive, not part of a scene name)."""
    found = []
    for token in doc[start:end]:
        if not token.tag_.startswith("VB") and token.tag_ != "MD":
            continue
        if _in_mention(mentions, token.i) or token.dep_ in ("aux", "auxpass"):
            continue
        if token.dep_ not in CLAUSE_DEPS and start <= token.head.i < end:
            continue
        if token.dep_ == "xcomp" and start <= token.head.i < end:
            continue
        if token.i > 0 and doc[token.i - 1].tag_ == "TO":
            continue
        if token.tag_ in ("VBN", "VBG") and token.dep_ not in ("ROOT", "conj", "ccomp", "parataxis", "advcl"):
            continue
        found.append(token)
    return found


def chunks(doc: Doc, mentions: Sequence[Mention]) -> list[Chunk]:
    """The request's chunks (step 1 of the module docstring)."""
    pieces: list[Chunk] = []
    start, after = 0, ""
    sentence_starts = {s.start for s in doc.sents}
    for token in doc:
        i = token.i
        word = token.text.lower()
        if i in sentence_starts and i > start:
            pieces.append(Chunk(start, i, after))
            start, after = i, "hard"
        if _in_mention(mentions, i):
            continue
        if word in HARD or _dash(token):
            if i > start:
                pieces.append(Chunk(start, i, after))
            start, after = i + 1, "colon" if word == ":" else "hard"
        elif _soft(token) and i > start and not all(doc[j].text.lower() in SOFT for j in range(start, i)):
            # a run of boundary words (", and then") stays at the head of the next chunk
            pieces.append(Chunk(start, i, after))
            start, after = i, "soft"
    if start < len(doc):
        pieces.append(Chunk(start, len(doc), after))
    pieces = [p for p in pieces if any(not doc[i].is_punct for i in range(p.start, p.end))]
    return _merged(doc, pieces, mentions)


def _dash(token: Token) -> bool:
    """A dash standing apart between words, a boundary like ";" (not the hyphen of "non-toxic")."""
    doc = token.doc
    if token.text not in ("-", "--", "–", "—") or token.i == 0 or token.i + 1 >= len(doc):
        return False
    return bool(token.whitespace_) and bool(doc[token.i - 1].whitespace_)


def _soft(token: Token) -> bool:
    """Whether a token is a soft boundary: a comma, a coordinating "and"/"but", "then", or a subordinator."""
    word = token.text.lower()
    if word == ",":
        return True
    if word in ("and", "but"):
        return token.tag_ == "CC"
    if word == "then":
        return token.tag_ in ("RB", "CC")
    return word in SOFT and token.tag_ in ("IN", "CC") and token.dep_ in ("mark", "cc", "prep", "advmod")


def _has_place(chunk: Chunk, mentions: Sequence[Mention]) -> bool:
    return any(chunk.start <= m.start < chunk.end and m.kind in ("place", "both", "person") for m in mentions)


def _merged(doc: Doc, pieces: list[Chunk], mentions: Sequence[Mention]) -> list[Chunk]:
    """Soft chunks joined back where they are one phrase (step 1 of the module docstring)."""
    out: list[Chunk] = []
    for piece in pieces:
        verbs = clause_verbs(doc, piece.start, piece.end, mentions)
        place = _has_place(piece, mentions)
        prev = out[-1] if out else None
        if prev is not None and piece.after == "soft":
            prev_place = _has_place(prev, mentions)
            if not verbs and not place and not opens_with_verb(doc, piece, mentions):
                prev.end = piece.end  # "and the eraser", "please"
                continue
            wants = _statement_like(doc, prev, mentions) and not _wants(doc, prev)
            if not verbs and place and not prev_place and not wants:
                prev.end = piece.end  # "put the hammer | and the screwdriver in the toolbox"
                continue
            subjects = [c for v in verbs for c in v.children if c.dep_ in ("nsubj", "nsubjpass")]
            if (
                subjects
                and all(prev.start <= c.i < prev.end for c in subjects)
                and not opens_with_verb(doc, piece, mentions)
            ):
                prev.end = piece.end  # "I'd like the tweezers | and the thermometer put in the kit"
                continue
        out.append(piece)
    # A first chunk that is a bare noun phrase is the subject of the next ("The socks | and the towel go").
    while (
        len(out) > 1
        and out[1].after == "soft"
        and doc[out[1].start].text.lower() in ("and", "or", ",")
        and _bare_phrase(doc, out[0], mentions)
        and not opens_with_verb(doc, out[1], mentions)  # "Any herbs we can cook with, | put them ..."
    ):
        out[1] = Chunk(out[0].start, out[1].end, out[0].after)
        out.pop(0)
    # A bare noun phrase before a verb with no subject of its own is that verb's subject.
    n = 0
    while n + 1 < len(out):
        if (
            out[n + 1].after == "soft"
            and _bare_phrase(doc, out[n], mentions)
            and _finite_first(doc, out[n + 1])
        ):
            out[n] = Chunk(out[n].start, out[n + 1].end, out[n].after)
            out.pop(n + 1)
        else:
            n += 1
    return out


def opens_with_verb(doc: Doc, chunk: Chunk, mentions: Sequence[Mention]) -> bool:
    """Whether a chunk opens with a base-form verb before its object (a clause of its own), also where
    the tagger took the verb for an adjective ("so empty the bleach")."""
    vocab = vocabulary()
    closed = {*SOFT, *vocab["openers"], *vocab["determiners"], *vocab["quantifiers"], *vocab["restrictors"]}
    i = chunk.start
    while i < chunk.end and (doc[i].text.lower() in SOFT or doc[i].is_punct):
        i += 1
    if i + 1 >= chunk.end or _in_mention(mentions, i) or doc[i].text.lower() in closed:
        return False
    token, nxt = doc[i], doc[i + 1]
    if any(c.dep_ in ("nsubj", "nsubjpass") and c.i >= chunk.start for c in token.children):
        return False  # a subject before the comma is set apart: "Any herbs we can cook with, put them"
    if token.tag_ == "VB":
        return True
    return token.pos_ in ("ADJ", "VERB") and nxt.tag_ in ("DT", "PRP$", "PDT", "PRP")


def _finite_first(doc: Doc, chunk: Chunk) -> bool:
    """Whether a chunk's first word after its boundary words is a finite verb without a subject."""
    i = chunk.start
    while i < chunk.end and (doc[i].text.lower() in SOFT or doc[i].is_punct):
        i += 1
    if i >= chunk.end or doc[i].tag_ not in ("VBZ", "VBP", "VBD", "MD"):
        return False
    return not any(c.dep_ in ("nsubj", "nsubjpass") for c in doc[i].children)


def _statement_like(doc: Doc, chunk: Chunk, mentions: Sequence[Mention]) -> bool:
    """Whether a chunk has a personal pronoun as the subject of its own verb ("I need ...")."""
    personal = set(vocabulary()["personal"])
    for token in doc[chunk.start : chunk.end]:
        subject = token.dep_ in ("nsubj", "nsubjpass") and token.text.lower() in personal - {"you"}
        if subject and token.head.dep_ not in ("relcl", "acl"):
            return True
    return False


def _wants(doc: Doc, chunk: Chunk) -> bool:
    """Whether a chunk is the speaker's "I want/I'd like X" (joined with what follows as one phrase)."""
    for token in doc[chunk.start : chunk.end]:
        if token.lemma_ in ("want", "like") and any(
            c.dep_ == "nsubj" and c.text.lower() in ("i", "we") for c in token.children
        ):
            return True
    return False


def _bare_phrase(doc: Doc, chunk: Chunk, mentions: Sequence[Mention]) -> bool:
    """A chunk of a noun phrase alone (no verb, no destination, not opened by a preposition)."""
    first = doc[chunk.start]
    if first.tag_ in ("IN", "TO", "WRB") or _has_place(chunk, mentions):
        return False
    return not clause_verbs(doc, chunk.start, chunk.end, mentions)
