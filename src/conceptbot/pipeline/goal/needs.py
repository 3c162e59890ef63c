"""Needs: a request that names no object and states how the speaker is ("my phone battery is almost
empty"), and where it states two or more such things, each of them ("I'm chilly and there's
nothing to do", "my hair is soaking wet and all tangled"): each part is a need of its own, met by an
object of its own.

A part is a clause joined to the sentence's main clause by "and" (or a sentence of its own) that
states how the speaker is: its subject is the speaker ("I", "we"), something of the speaker's ("my
hair") or an expletive ("there's nothing to do"), or, joined to such a clause, "it"/"they" ("my hair
is all knots and it's still wet", "I'm bored, and it's cold in here"); and it says a state ("I'm
chilly", "I have a headache", "my knee is bleeding", "I've cut my finger": the present perfect says
how things are now), not an event or the speaker's doing ("I'm working under the car"); or a second
state of the same subject ("soaking wet and all tangled", "a cut and a headache" after "I have"). A
clause about someone else ("the neighbours are drilling and I'm trying to take a nap") or an event
("I fell off my bike and scraped my knee") is the need's cause, not a need of its own: such a
request stays one need. So does "I cut my finger and now I have a headache", whose two needs the
syntax cannot tell from a cause and its effect.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.runs import lower as _lower

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.tokens import Doc, Span, Token

SPEAKER = frozenset({"i", "we"})
POSSESSIVE = frozenset({"my", "our"})
SUBJECTS = ("nsubj", "nsubjpass", "expl")
CLAUSE_POS = ("VERB", "AUX")
HAVING = frozenset({"have", "get"})  # "I've got a cut on my finger and a splitting headache"


#: Subjects that, in a clause joined to one of the speaker's, are the speaker's too: the thing just
#: spoken of ("my hair is all knots and it's still wet") or the speaker's surroundings ("I'm bored,
#: and it's cold in here").
REFERRING = frozenset({"it", "they"})


def _speakers(head: Token, joined: bool = False) -> bool:
    """Whether a clause's subject is the speaker, the speaker's, or an expletive (or, for a clause
    ``joined`` to one of the speaker's, "it"/"they": see :data:`REFERRING`)."""
    for child in head.children:
        if child.dep_ not in SUBJECTS:
            continue
        if child.dep_ == "expl" or _lower(child) in SPEAKER or (joined and _lower(child) in REFERRING):
            return True
        if any(c.dep_ == "poss" and _lower(c) in POSSESSIVE for c in child.children):
            return True
    return False


def _clauses(sent: Span) -> list[Token]:
    """The sentence's main clause and the clauses "and" joins to it, each by its verb."""
    root = sent.root
    joined = [c for c in root.conjuncts if c.pos_ in CLAUSE_POS and _subject(c)]
    return [root, *joined]


def _text(tokens: list[Token]) -> str:
    """The tokens as words, without a leading "and"/"but" or trailing punctuation."""
    words = [t for t in tokens if not t.is_punct]
    while words and words[0].dep_ == "cc":
        words = words[1:]
    while words and words[-1].dep_ == "cc":
        words = words[:-1]
    # a word whose punctuation was dropped ("Ugh, my hair") keeps a space before the next
    return "".join(
        t.text + (t.whitespace_ or (" " if n < len(words) - 1 and words[n + 1].i != t.i + 1 else ""))
        for n, t in enumerate(words)
    ).strip()


def _own(head: Token, others: list[Token]) -> list[Token]:
    """A clause's tokens without those of the other clauses (its conjuncts' subtrees)."""
    inside = [o for o in others if o is not head and head.is_ancestor(o)]
    skipped = {t.i for o in inside for t in o.subtree}
    return [t for t in head.subtree if t.i not in skipped]


def _states(head: Token) -> list[str]:
    """A clause listing two states of the speaker's ("my hair is soaking wet and all tangled", "I've
    got a cut and a headache"): each state with the clause's start ("my hair is all tangled"); []
    otherwise. The states are the complement's conjuncts, or (as the small parser often reads "is
    soaking wet and all tangled") the verb's own conjuncts that have no subject of their own."""
    if not _speakers(head):
        return []
    complements = [c for c in head.children if c.dep_ == "acomp"]
    # "is dripping wet and full of knots": the complement the others are joined to
    complement = next((c for c in complements if c.conjuncts), complements[0] if complements else None)
    kinds: tuple[str, ...] = ("ADJ",)
    if complement is None and head.lemma_ in HAVING:
        complement, kinds = next((c for c in head.children if c.dep_ == "dobj"), None), ("NOUN",)
    if complement is not None and complement.conjuncts:
        first = complement
    elif any(c.dep_ == "aux" and c.lemma_ == "be" for c in head.children):
        first, kinds = head, ("ADJ",)  # "is soaking wet and all tangled", "tangled" a participle
    else:
        return []  # "I fell off the ladder and scraped my elbow": events
    states = [
        first,
        *(c for c in first.conjuncts if (c.pos_ in kinds or c.tag_ == "VBN") and not _subject(c)),
    ]
    if len(states) < 2:
        return []
    if first is head:  # the verb's conjuncts: each after the subject and the auxiliaries
        start = [t for c in head.children if c.dep_ in SUBJECTS or c.dep_ == "aux" for t in c.subtree]
        start = sorted(start, key=lambda t: t.i)
        return [_text(_own(head, states)), *(_text(start + _own(s, states)) for s in states[1:])]
    # "is dripping wet and full of knots": "dripping" is the first state's, not every state's
    others = {t.i for c in complements if c.i != complement.i for t in c.subtree}
    start = [t for t in head.subtree if t.i < complement.left_edge.i and t.i not in others]
    first_words = [t for t in head.subtree if t.i in others]
    return [_text(start + (first_words if n == 0 else []) + _own(s, states)) for n, s in enumerate(states)]


def _stative(head: Token) -> bool:
    """Whether a clause states how things are, not what happened: "I'm chilly", "there's nothing
    to do", "I have a headache", "I feel sick" (not "I'm on the sofa", "I've got back from a run",
    "I have to brush my teeth")."""
    children = {c.dep_ for c in head.children}
    auxiliaries = {c.lemma_ for c in head.children if c.dep_ == "aux"}
    if head.lemma_ == "be":
        return bool(children & {"acomp", "attr", "expl"})
    if head.lemma_ in HAVING:
        return "dobj" in children and not children & {"xcomp", "prt"}
    if head.tag_ == "VBN" and "have" in auxiliaries and not children & {"xcomp", "prt"}:
        return True  # "I've cut my finger": what happened, and how things are now
    if head.lemma_ == "feel":
        return "acomp" in children  # "I'm feeling cold"
    if head.tag_ == "VBN" and any(c.dep_ == "auxpass" and c.lemma_ == "be" for c in head.children):
        return True  # "my shirt is torn", "it's covered in mud": a state, not "I got stung"
    if head.tag_ == "VBG" and "be" in auxiliaries and not children & {"xcomp", "ccomp"}:
        # "my knee is bleeding", "it's still sopping wet" (the small parser's verb): how a thing is
        # now; the speaker's own "-ing" is what they are doing ("I'm working under the car")
        subject = [c for c in head.children if c.dep_ in SUBJECTS]
        return bool(subject) and not any(_lower(c) in SPEAKER for c in subject)
    return False


def _subject(token: Token) -> bool:
    """Whether a verb has a subject of its own (a clause, not a second verb of the same one)."""
    return any(c.dep_ in SUBJECTS for c in token.children)


def _referred(head: Token, heads: list[Token]) -> str:
    """A clause's words, with an "it"/"they" subject that refers back to the first clause's subject
    ("my hair is all knots and it's still wet": "my hair's still wet") said as that subject, so each
    part can be read alone; "it" of the surroundings ("it's cold in here") stays."""
    own = _own(head, heads)
    subject = next((c for c in head.children if c.dep_ in SUBJECTS), None)
    first = next((c for c in heads[0].children if c.dep_ in SUBJECTS), None)
    if head is heads[0] or subject is None or first is None or _lower(subject) not in REFERRING:
        return _text(own)
    if not any(c.dep_ == "poss" and _lower(c) in POSSESSIVE for c in first.children):
        return _text(own)
    said = "".join(t.text_with_ws for t in first.subtree).strip()
    rest = _text([t for t in own if t.i != subject.i])
    return f"{said}{'' if rest.startswith(chr(39)) else ' '}{rest}".strip()  # "my hair's"


def need_parts(doc: Doc) -> list[str]:
    """The parts of a need (see the module docstring), in the request's order; [] when it states
    one need (the whole request is the need)."""
    parts: list[str] = []
    for sent in doc.sents:
        heads = _clauses(sent)
        if len(heads) == 1:
            states = _states(heads[0])
            if states:
                parts.extend(states)
            elif _speakers(heads[0]) and _stative(heads[0]):  # not "Can you help?" after a need
                parts.append(_text(list(sent)))
            continue
        if not (
            _speakers(heads[0]) and all(_speakers(h, i > 0) and _stative(h) for i, h in enumerate(heads))
        ):
            # "the neighbours are drilling and I'm trying to nap", "I fell off my bike and scraped my
            # knee": an event or someone else's doing is the need's cause, not a need of its own
            return []
        parts.extend(_referred(h, heads) for h in heads)
    return [p for p in parts if p] if len(parts) >= 2 else []
