"""What a theme phrase sends: named objects, a remainder, everything, or a criterion, and how many."""

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


#: Words standing in for the noun in a second conjunct ("a tool to measure with and one to cut").
STANDS_IN = frozenset({"one", "another"})


def _lower(token: Token) -> str:
    return token.text.lower()


def objects_in(run: Sequence[int], mentions: Sequence[Mention]) -> tuple[str, ...]:
    """The pickable objects a run names, in text order, each once ("the plum, and only the plum")."""
    inside = set(run)
    named = (
        n
        for m in mentions
        if m.kind in ("object", "both") and set(range(m.start, m.end)) <= inside
        for n in m.names
    )
    return tuple(dict.fromkeys(named))


def _remainder(doc: Doc, run: Sequence[int]) -> bool:
    """Whether the run is a remainder ("the rest", "everything else"), by a marker of the phrase itself."""
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
    """The run without its leading determiners, quantifiers and restrictors ("only the", "all of the")."""
    vocab = vocabulary()
    lead = {
        *vocab["determiners"],
        *vocab["quantifiers"],
        *vocab["restrictors"],
        "one",
        "of",
        "here",
        "there",
        "then",
    }
    lead -= {"something"}
    out = list(run)
    for phrase in vocab["only_phrases"]:  # "nothing but the paper": only the paper
        if [_lower(doc[i]) for i in out[: len(phrase)]] == phrase:
            out = out[len(phrase) :]
            break
    while out and _lower(doc[out[0]]) in lead:
        out = out[1:]
    # "a toy too", "a cuddly toy as well", "a tool for measuring and": not the phrase's words
    trailing = [w.split() for w in vocab["also"]] + [["and"], ["or"]]
    cut = True
    while cut and out:
        cut = False
        for phrase in trailing:
            if len(out) > len(phrase) and [_lower(doc[i]) for i in out[-len(phrase) :]] == phrase:
                out, cut = out[: -len(phrase)], True
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
    """How many objects a criterion phrase asks for: a number; 1 for "a", "something" or a definite
    singular count noun; else all (plurals, "all", "anything", mass nouns)."""
    vocab = vocabulary()
    words = [_lower(doc[i]) for i in run]
    for i in run:
        token = doc[i]
        percent = token.i + 1 < len(doc) and _lower(doc[token.i + 1]) in ("%", "percent", "per")
        number = token.tag_ == "CD" and token.like_num and _lower(token) != "one"
        if number and token.dep_ == "nummod" and not percent:
            try:
                return max(1, int(token.text))
            except ValueError:
                pass
    if words and words[0] in ("whichever", "whatever") and len(run) > 1:
        noun = doc[run[1]]  # "whichever toy is ...": one toy; "whatever food is ...": all of it
        mass = {*vocab["mass"], *MATERIALS}
        if noun.tag_ == "NN" and noun.lemma_.lower() not in mass and _lower(noun) not in mass:
            return 1
    head_at = _head(doc, _stripped(doc, run))
    ahead = [w for i, w in zip(run, words, strict=True) if head_at is None or i <= head_at.i]
    if ahead[:1] == ["both"] and len(ahead) > 1 and ahead[1] in vocab["one"]:
        ahead = ahead[1:]  # "both something to write with and ...": the list's "both", one of each
    if any(w in vocab["quantifiers"] for w in ahead):
        return ALL  # "all the toys"; not "a game we can both play"
    start = next((w for w in words if w not in vocab["restrictors"] and w != "then"), "")  # "then a toy"
    if start in vocab["one"]:
        return 1
    head = _head(doc, _stripped(doc, run))
    if head is None or _plural_noun(head) or _lower(head) == "ones":
        return ALL
    mass = {*vocab["mass"], *MATERIALS}
    if head.lemma_.lower() in mass or _lower(head) in mass:
        return ALL
    if start in ("the", "this", "that", "my", "your", "his", "her", "our", "their"):
        return 1
    # a bare singular count noun, said tersely ("toy for the dog", "drink for my boy"): one of them
    return 1 if start == _lower(head) and head.tag_ == "NN" else ALL


def criterion_text(doc: Doc, run: Sequence[int]) -> str:
    """The criterion's words: the run without leading determiners and quantifiers."""
    kept = _stripped(doc, run)
    # "anything that's poisonous": what the relative clause says
    relative = len(kept) > 2 and _lower(doc[kept[0]]) in ("that", "which", "who")
    if relative and doc[kept[1]].lemma_ in ("be", "'s"):
        kept = kept[2:]
    elif len(kept) > 1 and doc[kept[0]].lemma_ == "be" and doc[kept[0]].pos_ == "AUX":
        kept = kept[1:]  # "anything here that's toxic": "that" went with the determiners
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


def _listed(token: Token) -> list[Token]:
    """The noun phrases coordinated with ``token`` after it (``conj``, or a listed ``appos``/``dep``)."""
    found = []
    for child in token.children:
        nominal = child.tag_.startswith("NN") or child.pos_ in ("NOUN", "PROPN", "PRON")
        nominal = nominal or _lower(child) in STANDS_IN  # "a tool to measure with and one to ..."
        if not nominal or child.i < token.i:
            continue
        listed = child.dep_ == "conj" or (
            child.dep_ in ("appos", "dep")
            and child.left_edge.i > 0
            and child.doc[child.left_edge.i - 1].text in (",", ":")
            and any(c.dep_ == "conj" for c in child.children)
        )
        if listed:
            found += [child, *_listed(child)]
    return found


def _own_span(token: Token, members: set[int]) -> tuple[int, ...]:
    """A conjunct's own words: its subtree without the other conjuncts, their "and" and commas."""
    drop: set[int] = set()
    for child in token.children:
        if child.i in members or (child.dep_ in ("cc", "punct") and child.i > token.i):
            drop |= {t.i for t in child.subtree}
    return tuple(t.i for t in token.subtree if t.i not in drop and not t.is_punct)


def conjuncts(doc: Doc, run: Sequence[int]) -> list[tuple[int, ...]]:
    """The coordinated object phrases of a theme ("the pear and the stapler"), each as its tokens;
    ``[run]`` when it is one phrase (only the head is split: "made of glass and metal" is one)."""
    inside = set(run)
    heads = [doc[i] for i in run if doc[i].head.i not in inside or doc[i].head.i == i]
    head = next((t for t in heads if t.tag_.startswith("NN") or t.pos_ in ("NOUN", "PROPN", "PRON")), None)
    if head is None:
        return [tuple(run)]
    listed = [t for t in _listed(head) if t.i in inside]
    if not listed:
        return [tuple(run)]
    members = {head.i, *(t.i for t in listed)}
    spans = [tuple(i for i in _own_span(t, members) if i in inside) for t in (head, *listed)]
    if any(not s or doc[s[0]].text.lower() in ("nothing", "no", "none", "not") for s in spans):
        return [tuple(run)]
    return spans


def extend_with_conjuncts(doc: Doc, theme: Sequence[int], allowed: set[int]) -> tuple[int, ...]:
    """A theme with the phrases coordinated with its head that the runs split off, within ``allowed``."""
    if not theme:
        return tuple(theme)
    inside = set(theme)
    head = next(
        (
            doc[i]
            for i in theme
            if (doc[i].head.i not in inside or doc[i].head.i == i)
            and (doc[i].tag_.startswith("NN") or doc[i].pos_ in ("NOUN", "PROPN", "PRON"))
        ),
        None,
    )
    if head is None:
        return tuple(theme)
    members = {head.i}
    extra: set[int] = set()
    for token in _listed(head):
        members.add(token.i)
    for token in _listed(head):
        span = [i for i in _own_span(token, members) if i in allowed]
        if not span or doc[span[0]].text.lower() in ("nothing", "no", "none", "not"):
            break
        extra |= set(span)
    return tuple(sorted(inside | extra))


def _standing_in(doc: Doc, part: Sequence[int], first: Sequence[int], reading: Reading) -> Reading:
    """A conjunct led by "one"/"another" with the first conjunct's noun, counted as one."""
    if _lower(doc[part[0]]) not in STANDS_IN or reading.takes != "criterion" or part == first:
        return reading
    head = _head(doc, first)
    if head is None:
        return reading
    rest = "".join(doc[i].text_with_ws for i in part[1:]).strip()
    return Reading("criterion", (), f"{head.text} {rest}".strip(), 1)


def read_themes(doc: Doc, run: Sequence[int], mentions: Sequence[Mention]) -> list[Reading]:
    """What a theme sends: the named objects as one reading, each describing phrase as its own; plural
    or mass criteria ("apples and pears") stay one."""
    parts = conjuncts(doc, run)
    if len(parts) < 2:
        return [read_theme(doc, run, mentions)]
    objects = [m for m in mentions if m.kind in ("object", "both")]
    # a conjunct the run cut inside a name ("the teddy | bear away") takes the whole name
    parts = [
        tuple(
            sorted(
                {*p, *(i for m in objects if m.start in p or m.end - 1 in p for i in range(m.start, m.end))}
            )
        )
        for p in parts
    ]
    readings = [_standing_in(doc, p, parts[0], read_theme(doc, p, mentions)) for p in parts]
    if any(r.takes not in ("named", "criterion") for r in readings):
        return [read_theme(doc, run, mentions)]
    criteria = [r for r in readings if r.takes == "criterion"]
    if criteria and all(r.count == ALL for r in criteria) and len(criteria) == len(readings):
        return [read_theme(doc, run, mentions)]
    named = tuple(dict.fromkeys(n for r in readings for n in r.named))
    out = [Reading("named", named, "", len(named))] if named else []
    return out + criteria
