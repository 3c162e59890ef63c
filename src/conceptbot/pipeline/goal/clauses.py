"""One chunk of a request read as a clause: form, verb, destinations and theme (see :mod:`.parse`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.mentions import OWN_PLACE, Mention
from conceptbot.pipeline.goal.parse import Chunk, Clause, Place, clause_verbs, vocabulary
from conceptbot.pipeline.goal.runs import lower as _lower
from conceptbot.pipeline.goal.runs import nominal
from conceptbot.pipeline.goal.runs import runs as _runs
from conceptbot.pipeline.goal.themes import extend_with_conjuncts
from conceptbot.pipeline.goal.wishes import (
    desire_clause,
    desire_verb,
)

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.tokens import Doc, Token

_NP_START = {"DT", "PDT", "PRP$", "CD", "JJ", "NN", "NNS", "NNP", "NNPS"}


def _phrase_at(doc: Doc, at: int, end: int, phrases: Sequence[Sequence[str]]) -> int:
    """The index after the first of ``phrases`` spelled at ``at`` (by word or lemma), else -1."""
    for phrase in phrases:
        stop = at + len(phrase)
        if stop <= end and all(
            _lower(doc[at + k]) == w or doc[at + k].lemma_.lower() == w for k, w in enumerate(phrase)
        ):
            return stop
    return -1


def assured(doc: Doc, chunk: Chunk) -> int:
    """The index after "make sure (that)" or the like opening the chunk (the state asked for), else -1."""
    vocab = vocabulary()
    i = chunk.start
    while i < chunk.end and (_lower(doc[i]) in vocab["openers"] or doc[i].is_punct):
        i += 1
    after = _phrase_at(doc, i, chunk.end, vocab["assurance"])
    if after < 0:
        return -1
    if after < chunk.end and _lower(doc[after]) == "that":
        after += 1
    return after if after < chunk.end else -1


def _opened(doc: Doc, chunk: Chunk) -> tuple[int, bool, bool]:
    """The index after the chunk's opening words ("please", "could you"), and whether "let's", "make sure"."""
    vocab = vocabulary()
    i, lets, made_sure = chunk.start, False, False
    while i < chunk.end:
        word = _lower(doc[i])
        nxt = _lower(doc[i + 1]) if i + 1 < chunk.end else ""
        topic = _phrase_at(doc, i, chunk.end, vocab["topic"])
        sure = assured(doc, Chunk(i, chunk.end, ""))
        if sure >= 0:
            i, made_sure = sure, True
        elif topic >= 0 and topic < chunk.end:
            i = topic  # "as for the throw pillow": the topic of the next clause
        elif word in vocab["question"] and nxt == "you":
            i += 2
        elif word == "mind" and i + 1 < chunk.end and _lower(doc[i + 1]).endswith("ing"):
            i += 1  # "would you mind grabbing ...", "mind passing ..."
        elif word == "let" and nxt in ("'s", "’s", "us"):
            i, lets = i + 2, True
        elif word in vocab["openers"] or doc[i].is_punct:
            i += 1
        else:
            break
    return i, lets, made_sure


def _closed(doc: Doc, chunk: Chunk) -> int:
    """One past the chunk's last token that is not punctuation or "please"."""
    end = chunk.end
    while end > chunk.start and (doc[end - 1].is_punct or _lower(doc[end - 1]) in ("please", "thanks")):
        end -= 1
    return end


def _mention_at(mentions: Sequence[Mention], index: int) -> Mention | None:
    return next((m for m in mentions if m.covers(index)), None)


def _imperative(doc: Doc, at: int, end: int, mentions: Sequence[Mention], opening: bool) -> tuple[int, bool]:
    """The index of the imperative's verb at ``at`` (-1: none), and whether it is negated. A participle
    opens one only after another clause; opening the request it describes the speaker."""
    vocab = vocabulary()
    negated = False
    if at + 2 < end and _lower(doc[at]) == "do" and _lower(doc[at + 1]) in ("n't", "not"):
        at, negated = at + 2, True
    if at >= end or _mention_at(mentions, at) is not None:
        return -1, negated
    token = doc[at]
    word = _lower(token)
    closed = {
        *vocab["determiners"],
        *vocab["quantifiers"],
        *vocab["restrictors"],
        *vocab["personal"],
        *vocab["one"],
    }
    if word in closed or token.dep_ in ("nsubj", "nsubjpass"):
        return -1, negated
    consequence = at > 0 and _lower(doc[at - 1]) in ("so", "then")  # "..., so put it somewhere safe"
    if (
        token.dep_ == "conj"
        and not consequence
        and token.head.dep_ not in ("relcl", "acl")
        and _lower(doc[token.head.left_edge.i]) not in vocab["conditional"]  # "if X would ..., lock it"
        and not (token.tag_ == "VB" and token.head.tag_ in ("VBD", "VBZ", "VBN"))  # "X's been good, so let"
        and any(c.dep_ in ("nsubj", "nsubjpass") and _lower(c) != "you" for c in token.head.children)
    ):
        return -1, negated  # "I fell off my bike | and scraped my knee": the subject is shared
    minded = at > 0 and _lower(doc[at - 1]) == "mind"  # "(would you) mind grabbing a drink?"
    if minded and word.endswith("ing"):
        return at, negated
    if token.tag_ in ("VB", "VBP", "VBD") or (token.tag_ == "VBG" and not opening):
        return at, negated
    if token.tag_ in ("NNS", "NNPS", "VBG"):
        return -1, negated  # a plural noun is no imperative ("Houseplants that are ...")
    nxt = doc[at + 1] if at + 1 < end else None
    opens_phrase = nxt is not None and (
        nxt.tag_ in ("DT", "PDT", "PRP", "PRP$", "WP", "WDT", "CD", "RP")
        or _lower(nxt) in ("away", "up", *vocab["restrictors"])
    )
    tagged_verb = token.pos_ in ("NOUN", "PROPN", "ADV", "ADJ", "VERB") or (
        token.pos_ == "INTJ" and any(c.dep_ == "dobj" for c in token.children)  # "Bin/UH just the ..."
    )
    if tagged_verb and opens_phrase:
        return at, negated  # the tagger's "Sort/RB what I foraged"
    return -1, negated


def _particles(doc: Doc, verb: int, end: int) -> list[int]:
    """The verb's particles and the "of" of "get rid of", "dispose of"."""
    vocab = vocabulary()
    found = []
    i = verb + 1
    if i < end and _lower(doc[i]) == "rid":
        found.append(i)
        i += 1
    if i < end and _lower(doc[i]) == "of":
        found.append(i)
    for token in doc[verb + 1 : end]:
        # Only the verb's own: a particle may belong to a relative clause or a destination.
        own = token.head.i == verb and (token.dep_ in ("prt", "advmod") or token.tag_ == "RP")
        if own and _lower(token) in vocab["particles"]:
            found.append(token.i)
    return found


def _determiners_before(doc: Doc, start: int, floor: int, mentions: Sequence[Mention]) -> int:
    """The first index of the determiners and adjectives before ``start`` ("the", "my", "bored")."""
    vocab = vocabulary()
    j = start
    while j - 1 >= floor and _mention_at(mentions, j - 1) is None:
        before = doc[j - 1]
        if _lower(before) in vocab["determiners"] or before.tag_ in ("PRP$", "JJ", "PDT"):
            j -= 1
        else:
            break
    return j


def _is_for(doc: Doc, at: int, end: int) -> int:
    """After a subject destination: the index of "for" in "is for" or "where" in "is where", else -1."""
    if (
        at < end
        and _lower(doc[at]) == "for"
        and not any(t.tag_.startswith("VB") for t in doc[at:end] if t.dep_ == "ROOT")
    ):
        return at  # a fragment: "toxic tray for the poisonous ones"
    if at < end and doc[at].lemma_ == "be":
        j = at + 1
        while j < end and _lower(doc[j]) in vocabulary()["restrictors"]:
            j += 1
        if j < end and _lower(doc[j]) in ("for", "where"):
            return j
    return -1


def _befalls(preposition: Token) -> bool:
    """Whether "on" before a person says what befalls them ("my phone died on me"), not a place."""
    verb = preposition.head
    if _lower(preposition) != "on" or verb.pos_ != "VERB" or verb.lemma_ in vocabulary()["handing"]:
        return False
    return not any(c.dep_ == "dobj" for c in verb.children)


def place_role(
    doc: Doc,
    mention: Mention,
    chunk: Chunk,
    bounds: tuple[int, int],
    verb: int,
    mentions: Sequence[Mention],
    is_person: Callable[[str], bool],
) -> tuple[int, ...] | None:
    """The frame tokens of a mention in a destination role, or None (see :mod:`.parse`, step 3)."""
    vocab = vocabulary()
    first, end = bounds
    person = mention.kind == "person" or any(is_person(n) for n in mention.names)
    j = _determiners_before(doc, mention.start, first, mentions)
    frame = list(range(j, mention.end))
    rest = [i for i in range(first, end) if i not in frame and not doc[i].is_punct]
    if not rest:
        return tuple(frame)  # "coffee table" alone: a fragment naming a place
    if mention.kind == "person" and _lower(doc[mention.end - 1]) == "way":
        return tuple(frame)  # "send the hairbrush my way"
    if j - 1 > first and doc[j - 1].dep_ == "preconj":
        j -= 1  # "into either the kitchen basket or the disposal bin"
        frame.insert(0, j)
    prev = doc[j - 1] if j - 1 >= first else None
    nxt = doc[mention.end] if mention.end < end else None
    if prev is not None and _lower(prev) in vocab["spatial"]:
        if mention.kind == "person" and _befalls(prev):
            return None  # "my phone is about to die on me": what befalls the person, no place
        frame.append(j - 1)
        k = j - 2
        while k >= first and _lower(doc[k]) in vocab["particles"] + ["next"]:
            frame.append(k)  # "up to", "over to", "next to"
            k -= 1
        return tuple(frame)
    if prev is not None and _lower(prev) == "of" and j - 2 >= first and doc[j - 2].tag_.startswith("NN"):
        # "on the edge of the bathtub": the part's preposition makes the whole a place
        k = _determiners_before(doc, j - 2, first, mentions)
        if k - 1 >= first and _lower(doc[k - 1]) in vocab["spatial"]:
            return (*frame, *range(k - 1, j))
        if k == first and _is_for(doc, mention.end, end) >= 0:
            return (*frame, *range(k, j))  # "the edge of the bathtub is where ..."
    if person and prev is not None and _lower(prev) in ("with", "for"):
        # "share it with the dog"; not "too small for me to read" (the criterion's words)
        if nxt is None or nxt.tag_ != "TO":
            return (*frame, j - 1)
        if verb >= 0:
            return ()
    dative = doc[mention.start].dep_ == "dative"
    before_object = verb >= 0 and j - 1 == verb and nxt is not None and nxt.tag_ in _NP_START | {"PRP"}
    if person and (dative or before_object):
        return tuple(frame)  # "give the dog a treat"
    if j == first and _is_for(doc, mention.end, end) >= 0:
        return tuple(frame)  # "the toxic tray is for ..."
    return None


def _key(doc: Doc, first: int, end: int, mentions: Sequence[Mention]) -> tuple[str, list[int]]:
    """A "by <key>" phrase ("by material", "according to colour") and its tokens."""
    for i in range(first, end):
        word = _lower(doc[i])
        if word == "for" and i + 2 < end and _lower(doc[i + 1]) in ("its", "their") and i > first:
            place = _mention_at(mentions, i - 1)
            if place is not None and place.kind == "place" and doc[i + 2].tag_ in ("NN", "NNS"):
                return "by " + _lower(doc[i + 2]), [i, i + 1, i + 2]  # "into the bin for its material"
        matched, matched_tokens = _matching_key(doc, i, end, mentions)
        if matched:
            return matched, matched_tokens
        size = 2 if word == "according" and i + 1 < end and _lower(doc[i + 1]) == "to" else 1
        if word not in ("by", "according") or (word == "according" and size == 1):
            continue
        j = i + size
        while j < end and _lower(doc[j]) in ("the", "their", "its", "what"):
            j += 1
        k = j
        while k < end and doc[k].tag_ in ("NN", "NNS") and _mention_at(mentions, k) is None:
            k += 1
        if k > j:
            return "by " + " ".join(_lower(t) for t in doc[j:k]), list(range(i, k))
        made = [_lower(t) for t in doc[j : min(end, j + 5)]]
        if ("made" in made and made[-1] == "of") or made[:4] in (
            ["it", "'s", "made", "of"],
            ["they", "'re", "made", "of"],
        ):
            stop = j + made.index("of") + 1
            return "by material", list(range(i, stop))  # "by what they're made of"
    return "", []


def _matching_key(doc: Doc, i: int, end: int, mentions: Sequence[Mention]) -> tuple[str, list[int]]:
    """ "the bin that matches its material" at ``i`` (after a place): "by <noun>" and its tokens."""
    place = _mention_at(mentions, i - 1) if i > 0 else None
    if place is None or place.kind != "place" or place.end != i:
        return "", []
    j = i + 1 if _lower(doc[i]) in ("that", "which") else i
    if j >= end or doc[j].lemma_.lower() not in OWN_PLACE:
        return "", []
    k = j + 1
    while k < end and _lower(doc[k]) in ("to", "with", "up"):
        k += 1
    if k + 1 < end and _lower(doc[k]) in ("its", "their") and doc[k + 1].tag_ in ("NN", "NNS"):
        return "by " + _lower(doc[k + 1]), list(range(i, k + 2))
    return "", []


def _chain(doc: Doc, verb: Token, first: int, end: int) -> list[int]:
    """A subject-form verb with its auxiliaries ("should be thrown", "need to go")."""
    chain = {verb.i}
    heads = [verb]
    if verb.dep_ == "xcomp" and first <= verb.head.i < end:
        heads.append(verb.head)
        chain.add(verb.head.i)
    for head in heads:
        chain |= {c.i for c in head.children if c.dep_ in ("aux", "auxpass", "neg") and first <= c.i < end}
    at = verb.i
    if at - 2 >= first and doc[at - 1].tag_ == "TO" and _lower(doc[at - 2]) in vocabulary()["obligation"]:
        chain |= {at - 2, at - 1}  # "needs to go", where the tagger took "needs" for a noun
    return sorted(chain)


def _subject_verb(
    doc: Doc, first: int, end: int, places: list[Place], mentions: Sequence[Mention], state: bool = False
) -> Token | None:
    """The verb of a "X goes in A" / "X should be thrown away" clause, or None; ``state``: "X is in A"."""
    vocab = vocabulary()
    motion = {*vocab["motion"], "be"} if state else set(vocab["motion"])
    place_tokens = {i for p in places for i in p.frame}
    for token in doc[first:end]:
        phrasal = token.lemma_ in motion and token.i + 1 < end and _lower(doc[token.i + 1]) == "up"
        if _mention_at(mentions, token.i) is not None or not (token.tag_.startswith("VB") or phrasal):
            continue
        auxes = [c for c in token.children if c.dep_ in ("aux", "auxpass")]
        if token.dep_ == "xcomp" and token.head.lemma_ in ("need", "have"):
            auxes += [token.head]
        obliged = any(_lower(a) in vocab["obligation"] or a.lemma_ in vocab["obligation"] for a in auxes)
        # a question opened by its modal asks for it: "Could something to read be brought to me?"
        obliged = obliged or any(a.i == first and a.tag_ == "MD" for a in auxes)
        if token.lemma_ in motion:
            after = token.i + 1
            while after < end and _lower(doc[after]) in vocab["particles"]:
                after += 1
            if after in place_tokens or (obliged and token.lemma_ == "go"):
                return token
        placed = any(_lower(c) in ("away", "out") for c in token.children) or any(
            i in place_tokens for i in range(token.i + 1, end)
        )
        # "X should be locked up": shut away, as "locked away"
        placed = placed or (token.lemma_ == "lock" and any(_lower(c) == "up" for c in token.children))
        if token.tag_ == "VBN" and any(a.dep_ == "auxpass" for a in auxes) and obliged and placed:
            return token  # "X should be thrown away"; not "this baguette needs to be sliced" (a need)
        if token.tag_ == "VBG" and token.dep_ == "xcomp" and token.head.lemma_ == "need":
            # "X needs locking away"; not "this baguette needs slicing" (a need: nothing says where)
            away = any(_lower(c) == "away" for c in token.children)
            if away or any(i in place_tokens for i in range(token.i + 1, end)):
                return token
    return None


def _personal_subject(doc: Doc, first: int, end: int) -> Token | None:
    """A personal pronoun that is the subject of the chunk's own verb ("I'm freezing")."""
    personal = set(vocabulary()["personal"]) - {"you"}
    for token in doc[first:end]:
        if token.dep_ in ("nsubj", "nsubjpass", "expl") and _lower(token) in personal | {"there"}:
            after_verb = token.i > 0 and doc[token.i - 1].tag_.startswith("VB") and _lower(token) == "it"
            if token.head.dep_ not in ("relcl", "acl") and not after_verb:  # "swallowed it": an object
                return token
    return None


def analyse(doc: Doc, chunk: Chunk, mentions: Sequence[Mention], is_person: Callable[[str], bool]) -> Clause:
    """Read one chunk (see :mod:`.parse`); ``otherwise`` set where it opens with "otherwise"."""
    clause = _analysed(doc, chunk, mentions, is_person)
    first, _, _ = _opened(doc, chunk)
    if clause.theme:
        # "bring me the pear, | the stapler and the juice box": the rest of the list is the theme's
        framed = {i for p in clause.places for i in p.frame} | {clause.verb_at}
        allowed = {i for i in range(first, chunk.end) if i not in framed and not doc[i].is_punct}
        clause.theme = extend_with_conjuncts(doc, clause.theme, allowed)
    clause.otherwise = any(_lower(t) in vocabulary()["otherwise"] for t in doc[chunk.start : first])
    return clause


def _analysed(
    doc: Doc, chunk: Chunk, mentions: Sequence[Mention], is_person: Callable[[str], bool]
) -> Clause:
    vocab = vocabulary()
    first, lets, made_sure = _opened(doc, chunk)
    end = _closed(doc, chunk)
    mine = [m for m in mentions if first <= m.start < end]
    verb, negated = _imperative(doc, first, end, mine, chunk.after == "")
    frame: set[int] = set(range(chunk.start, first))
    if negated:
        frame |= {verb - 2, verb - 1}  # "do n't"
    places: list[Place] = []
    if verb >= 0 and doc[verb].lemma_ in vocab["helping"]:
        # "help me make a salad": the verb is the one helped
        inner = next((t.i for t in doc[verb + 1 : end] if t.tag_ == "VB"), -1)
        if inner >= 0:
            frame |= set(range(verb, inner))
            verb = inner
    for mention in mine:
        if mention.kind == "object":
            continue
        role = place_role(doc, mention, chunk, (first, end), verb, mine, is_person)
        if role is not None:
            places.append(Place(mention, role))
    if any(p.frame for p in places):
        # "set out a game for us to play on the coffee table": "for us to play" is the criterion's
        places = [p for p in places if p.frame]
    favour = [
        p for p in places if p.mention.kind == "person" and p.frame and _lower(doc[min(p.frame)]) == "for"
    ]
    if favour and len(favour) < len(places):
        # "set the hair dryer on the side of the tub for me": done for the person, put in the place
        frame |= {i for p in favour for i in p.frame}
        places = [p for p in places if p not in favour]
    key, key_tokens = _key(doc, first, end, mine)
    frame |= {i for p in places for i in p.frame} | set(key_tokens)
    indices = list(range(first, end))
    if verb >= 0:
        return imperative_clause(doc, chunk, verb, (first, end), places, frame, key, mine)
    if places and places[0].frame and min(places[0].frame) == first:
        at_for = _is_for(doc, places[0].mention.end, end)
        if at_for >= 0:
            frame |= set(range(places[0].mention.end, at_for + 1))
            runs = _runs(indices, frame, doc)
            theme = next((r for r in runs if r[0] > at_for and nominal(doc, r)), ())
            return Clause(chunk, "for", "be", at_for, places, theme, key, False, runs)
    moving = _subject_verb(doc, first, end, places, mine, made_sure)
    if moving is not None:
        chain = _chain(doc, moving, first, end)
        frame |= set(chain) | set(_particles(doc, moving.i, end))
        # before the verb, less its auxiliaries: "Could something to read be brought over to me?"
        ahead = _runs([i for i in indices if i < moving.i], frame, doc)
        before = [r for r in ahead if nominal(doc, r)]
        runs = _runs(indices, frame, doc)
        if before and _personal_subject(doc, first, chain[0]) is None:
            # the phrase naming objects, else the first: "The fabric items, and nothing else, go ..."
            named = [r for r in before if any(m.kind in ("object", "both") and m.start in r for m in mine)]
            theme = (named or before)[0]
            return Clause(chunk, "subject", moving.lemma_.lower(), moving.i, places, theme, key, False, runs)
        pronoun = [r for r in ahead if all(_lower(doc[i]) in vocab["anaphors"] for i in r)]
        if not before and pronoun and places:
            # "it goes on the sofa": what "it" is, the clause before says
            return Clause(
                chunk, "subject", moving.lemma_.lower(), moving.i, places, pronoun[0], key, False, runs
            )
    desire = desire_verb(doc, first, end, lets)
    if desire is not None:
        return desire_clause(doc, chunk, desire, first, end, places, frame, mine)
    runs = _runs(indices, frame, doc)
    if _personal_subject(doc, first, end) is not None:
        return Clause(chunk, "statement", "", -1, [], (), key, False, runs)
    verbs = clause_verbs(doc, first, end, mine)
    if places or not verbs:
        theme = next((r for r in runs if nominal(doc, r)), ())
        return Clause(chunk, "fragment", "", -1, places, theme, key, False, runs)
    return Clause(chunk, "statement", "", -1, [], (), key, False, runs)


def imperative_clause(
    doc: Doc,
    chunk: Chunk,
    verb: int,
    bounds: tuple[int, int],
    places: list[Place],
    frame: set[int],
    key: str,
    mentions: Sequence[Mention],
) -> Clause:
    """An imperative's clause: its theme is the first noun phrase after the verb, plus objects after "and"."""
    end = bounds[1]
    negated = verb - 2 in frame and _lower(doc[verb - 1]) in ("n't", "not")
    frame |= {verb, *_particles(doc, verb, end)}
    if doc[verb].lemma_ in ("get", "have"):
        # "get the groceries packed in the tote bag": the participle says what to do with them
        frame |= {c.i for c in doc[verb].children if c.tag_ == "VBN" and c.dep_ in ("ccomp", "xcomp", "oprd")}
    runs = _runs(list(range(verb + 1, end)), frame, doc)
    theme = next((r for r in runs if nominal(doc, r)), ())
    if theme and _lower(doc[theme[0]]) in ("it", "them"):
        theme = (theme[0],)  # "put it somewhere safe": an object pronoun takes no modifier
    if places and theme and theme[0] < min(places[0].frame or (end,)):
        joined = [r for r in runs if r[0] > theme[-1] and _lower(doc[r[0] - 1]) in ("and", ",")]
        theme = (*theme, *(i for r in joined for i in r if _names_object(r, mentions)))
    lemma = doc[verb].lemma_.lower()
    children = {_lower(c) for c in doc[verb].children}
    if any(lemma == a and b in children for a, b in vocabulary()["making_phrases"]):
        lemma = "make"  # "put together a salad"
    return Clause(chunk, "imperative", lemma, verb, places, tuple(theme), key, negated, runs)


def _names_object(run: Sequence[int], mentions: Sequence[Mention]) -> bool:
    return any(m.kind in ("object", "both") and m.start in run for m in mentions)
