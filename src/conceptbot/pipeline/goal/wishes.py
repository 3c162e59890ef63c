"""Wishes: "I'd love an omelette", "we should have a fruit salad", "guacamole is what I want to
make", "is there something for my sore throat you could hand me?" (step 2 of
:mod:`conceptbot.pipeline.goal.parse`, the ``desire`` form)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.mentions import Mention
from conceptbot.pipeline.goal.parse import Chunk, Clause, Place, vocabulary
from conceptbot.pipeline.goal.runs import lower as _lower
from conceptbot.pipeline.goal.runs import nominal
from conceptbot.pipeline.goal.runs import runs as _runs

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.tokens import Doc, Token


def desire_verb(doc: Doc, first: int, end: int, lets: bool) -> Token | None:
    """The verb (or "about", or the copula) of a wish: "I'd love X", "we should have X", "how about
    X", "X would be lovely"; None for anything else."""
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
        phrase = _wishing_phrase(doc, token, end)
        wishers = ("i", "we", "who", "anyone", "anybody", "everyone")  # "who's up for pancakes?"
        if phrase is not None and any(_lower(t) in wishers for t in doc[first:end] if t.dep_ == "nsubj"):
            return phrase  # "I'm in the mood for an omelette": the phrase's preposition
        if _lower(token) == "about" and token.i > first and _lower(doc[token.i - 1]) == "how":
            return token
        other = _other_wish(token, subject, speaker)
        if other is not None:
            return other
        conditional = any(_lower(c) in ("would", "could") for c in token.children)
        praised = any(c.dep_ == "acomp" for c in token.children)
        thing = bool(subject) and not any(_lower(c) in vocab["personal"] for c in subject)
        if token.lemma_ == "be" and conditional and praised and thing:
            return token
        if token.lemma_ == "sound" and praised and any(c.pos_ in ("NOUN", "PROPN") for c in subject):
            return token  # "a fruit salad sounds great right now"
    return None


def _other_wish(token: Token, subject: list[Token], speaker: bool) -> Token | None:
    """Wishes said about the meal or by comparison: "breakfast should be an omelette" (the copula),
    "I'm thinking fruit salad" (the verb), "this morning calls for pancakes", "nothing would hit the
    spot like a PB&J" (the preposition before what is wished for); else None."""
    vocab = vocabulary()
    if not token.tag_.startswith("VB"):
        return None
    # the meal is the subject (or, misparsed, a noun phrase before the verb: "Lunch today should be")
    # "dessert tonight is going to be X": the subject is the head's
    said = [*token.children, *(token.head.children if token.dep_ == "xcomp" else ())]
    meal = any(
        c.lemma_.lower() in vocab["meals"] and c.i < token.i and c.dep_ in ("nsubj", "npadvmod") for c in said
    )
    if token.lemma_ == "be" and meal and any(c.dep_ == "attr" for c in token.children):
        return token
    if token.lemma_ == "think" and speaker and any(c.dep_ == "dobj" for c in token.children):
        return token
    if token.lemma_ == "call":
        return next((c for c in token.children if c.dep_ == "prep" and _lower(c) == "for"), None)
    if any(_lower(c) == "nothing" for c in subject):
        # "nothing beats X" is a wish for X, and so is "nothing would hit the spot like X"
        after = [t for t in token.subtree if t.i > token.i]
        compared = next((t for t in after if t.tag_ == "IN" and _lower(t) in vocab["comparing"]), None)
        if compared is not None:
            return compared
        if token.lemma_ == "beat" and any(c.dep_ == "dobj" for c in token.children):
            return token
    return None


def _asks(token: Token) -> bool:
    """Whether the speaker's verb asks to receive: "could/can/may I ...?" (the modal first), or "I'll
    ..." ("I'll take the tape measure")."""
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


def _wishing_phrase(doc: Doc, token: Token, end: int) -> Token | None:
    """The last word of a wishing phrase starting at ``token`` ("in the mood for", "feel like")
    when a noun phrase follows it."""
    for phrase in vocabulary()["wishing_phrases"]:
        last = token.i + len(phrase) - 1
        if last + 1 >= end or [_lower(t) for t in doc[token.i : last + 1]] != phrase:
            continue
        after = doc[last + 1]
        if after.tag_ in ("DT", "NN", "NNS", "JJ", "CD") or _lower(after) in ("some", "something"):
            return doc[last]
    return None


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
    """A wish as a clause: its theme is what is wished for (the subject of "X would be lovely", the
    object otherwise); for "I want to make X" the verb is the wished activity's ("make")."""
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


def cleft(doc: Doc, first: int, end: int) -> tuple[str, tuple[int, ...]] | None:
    """ "Guacamole is what I want to make", "What I'd love for breakfast is an omelette": the wished
    activity's verb ("make", or "want") and what is wished for; None for anything else."""
    vocab = vocabulary()
    wishes = {*vocab["desire"], *vocab["making"]}
    for be in doc[first:end]:
        if be.lemma_ != "be":
            continue
        for clause in be.children:
            inside = {t.i for t in clause.subtree}
            if not clause.tag_.startswith("VB") or not any(_lower(doc[i]) == "what" for i in inside):
                continue
            verbs = [
                doc[i] for i in sorted(inside) if doc[i].lemma_ in wishes and doc[i].tag_.startswith("VB")
            ]
            if not verbs or not any(_lower(doc[i]) in ("i", "we") for i in inside):
                continue
            other = next((c for c in be.children if c.dep_ in ("nsubj", "attr") and c.i not in inside), None)
            if other is None:
                continue
            theme = tuple(t.i for t in other.subtree if first <= t.i < end and not t.is_punct)
            making = next((v.lemma_ for v in verbs if v.lemma_ in vocab["making"]), "want")
            return making, theme
    return None


def existential(
    doc: Doc, first: int, end: int, mentions: Sequence[Mention]
) -> tuple[tuple[int, ...], Place] | None:
    """ "Is there something for my sore throat you could hand me?": the thing asked for and the
    person a relative clause asks "you" to hand it to; else None."""
    if first + 1 >= end or doc[first].lemma_ != "be" or _lower(doc[first + 1]) != "there":
        return None
    for asking in doc[first + 2 : end]:
        you = next((c for c in asking.children if _lower(c) == "you" and c.dep_ == "nsubj"), None)
        if asking.dep_ != "relcl" or you is None:
            continue
        for child in asking.children:
            person = next((m for m in mentions if m.kind == "person" and m.covers(child.i)), None)
            if person is not None and child.dep_ in ("dobj", "dative"):
                theme = tuple(i for i in range(first + 2, you.i) if not doc[i].is_punct)
                return (theme, Place(person, tuple(range(you.i, end)))) if theme else None
    return None


def offered(doc: Doc, first: int, end: int) -> tuple[int, ...] | None:
    """ "Have you got something for it?", "do you have any plasters?", "got a pen?": what the speaker
    asks to be given; else None."""
    words = [_lower(t) for t in doc[first : min(end, first + 3)]]
    at = -1
    if words[:3] in (["have", "you", "got"], ["do", "you", "have"], ["you", "got", "any"]):
        at = first + (3 if words[:3] != ["you", "got", "any"] else 2)
    elif words[:2] == ["you", "got"]:
        at = first + 2
    elif (
        words[:1] == ["got"]
        and len(words) > 1
        and words[1] in ("a", "an", "any", "some", "anything", "something")
    ):
        at = first + 1
    if at < 0 or at >= end:
        return None
    theme = tuple(i for i in range(at, end) if not doc[i].is_punct)
    thing = any(doc[i].tag_.startswith("NN") or _lower(doc[i]) in ("something", "anything") for i in theme)
    return theme if thing else None


def recipient_question(
    doc: Doc, first: int, end: int, mentions: Sequence[Mention], is_person: Callable[[str], bool]
) -> tuple[tuple[int, ...], Place] | None:
    """ "Could the dog have a treat?", "can she get something to play with?": a question whose
    subject is a person or an animal of the scene asks for something to be given to them; the thing
    and the person, else None."""
    vocab = vocabulary()
    modal = first < end and doc[first].tag_ == "MD"
    if not modal or _lower(doc[first]) not in [*vocab["question"], "may"]:
        return None
    verb = next((t for t in doc[first + 1 : end] if t.tag_ == "VB"), None)
    if verb is None or verb.lemma_ not in ("have", "get", "keep"):
        return None
    person = next(
        (
            m
            for m in mentions
            if first < m.start < verb.i
            and m.kind != "object"
            and (m.kind == "person" or any(is_person(n) for n in m.names))
        ),
        None,
    )
    if person is None:
        return None
    theme = tuple(i for i in range(verb.i + 1, end) if not doc[i].is_punct)
    return (theme, Place(person, tuple(range(first, verb.i + 1)))) if theme else None
