"""Where a request names the scene's objects, destinations and people, as noun phrases.

A name matches only where its tokens end a noun phrase ("dog" not in "the dog biscuit"), longest
first; a plural head names several destinations; "me" is ``user``, "her"/"him" the last person named.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from conceptbot.core.scene import Scene

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.tokens import Doc, Token


@dataclass(frozen=True)
class Mention:
    """Scene names a run of tokens speaks of.

    Attributes:
        names: The scene names (several for a plural head: "the paper and plastic bins").
        start: The first token's index.
        end: One past the last token's index.
        kind: ``place``, ``object`` (pickable), ``both`` (the role decides) or ``person``.
    """

    names: tuple[str, ...]
    start: int
    end: int
    kind: str

    def covers(self, index: int) -> bool:
        """Whether the token at ``index`` is part of the mention."""
        return self.start <= index < self.end


def _forms(word: str) -> set[str]:
    """A name's last word and its plurals."""
    return {word, word + "s", word + "es", word[:-1] + "ies" if word.endswith("y") else word}


def _ends_phrase(doc: Doc, end: int) -> bool:
    """Whether the noun phrase ends at token ``end - 1`` (no noun it modifies or possessive follows)."""
    if end >= len(doc):
        return True
    after = doc[end]
    if after.tag_ == "POS" or (after.text.lower() in ("'s", "’s") and after.dep_ == "case"):
        # a possessor, unless "'s" is "has"/"is" before a participle or adverb ("the dog's been good")
        verb = end + 1 < len(doc) and doc[end + 1].tag_ in ("VBN", "VBD", "VBG", "RB", "JJ")
        # "my boy's thirsty.": a word ending the sentence after "'s" is what the person is
        last = end + 1 < len(doc) and (end + 2 >= len(doc) or doc[end + 2].is_punct)
        return verb or (last and doc[end + 1].tag_ not in ("NNS", "NNPS"))
    return not (after.pos_ in ("NOUN", "PROPN") and doc[end - 1].head.i >= end)


def _names(doc: Doc, scene: Scene, spelled: dict[str, list[str]], used: list[bool]) -> list[Mention]:
    """Mentions of the scene's own names, longest first, each token used once."""
    kinds = {}
    for obj in scene.objects:
        kinds[obj.name] = (
            "both" if obj.pickable and obj.destination else "place" if obj.destination else "object"
        )
    lower = [t.text.lower() for t in doc]
    found: list[Mention] = []
    for name in sorted(kinds, key=lambda n: (-len(spelled[n]), n)):
        key = spelled[name]
        if not key or kinds[name] not in ("place", "object", "both"):
            continue
        for start in range(len(doc) - len(key) + 1):
            end = start + len(key)
            if any(used[start:end]) or lower[start : end - 1] != key[:-1]:
                continue
            head_ok = lower[end - 1] in _forms(key[-1]) or doc[end - 1].lemma_.lower() == key[-1]
            if head_ok and _ends_phrase(doc, end):
                found.append(Mention((name,), start, end, kinds[name]))
                used[start:end] = [True] * len(key)
    return found


def _groups(doc: Doc, scene: Scene, spelled: dict[str, list[str]], used: list[bool]) -> list[Mention]:
    """Plural heads naming several destinations ("the wood, metal and fabric bins", "the bins")."""
    heads: dict[str, list[str]] = {}
    for name in scene.destinations:
        if spelled[name]:
            heads.setdefault(spelled[name][-1], []).append(name)
    found = []
    for token in doc:
        group = heads.get(token.lemma_.lower())
        singular = token.text.lower() == token.lemma_.lower()
        if used[token.i] or not group or token.tag_ == "VBG":
            continue
        if singular:
            continue
        if not _ends_phrase(doc, token.i + 1):
            continue
        start, modifiers, described = _described(doc, token, used, group, spelled)
        if not described and modifiers & {w for n in group for w in spelled[n][:-1]}:
            continue  # "the red bins" where no bin is red: not these bins
        found.append(Mention(tuple(described or group), start, token.i + 1, "place"))
        used[start : token.i + 1] = [True] * (token.i + 1 - start)
    return found


def _described(
    doc: Doc, token: Token, used: list[bool], group: list[str], spelled: dict[str, list[str]]
) -> tuple[int, set[str], list[str]]:
    """Where a head noun's phrase starts, its modifier words, and the places of ``group`` they describe."""
    start = token.i
    while start > 0 and not used[start - 1] and _modifies(doc[start - 1]):
        start -= 1
    modifiers = {t.text.lower() for t in doc[start : token.i]}
    described = [n for n in group if len(spelled[n]) > 1 and set(spelled[n][:-1]) <= modifiers]
    return start, modifiers, described


#: Verbs that make a singular head each object's own place ("the tray where it belongs").
OWN_PLACE = frozenset({"belong", "match", "go", "fit", "suit", "correspond"})


def _modifies(token: Token) -> bool:
    """Whether a token before a plural head is one of its modifiers ("wood", ",", "and")."""
    if token.tag_ in ("DT", "PDT", "PRP$", "IN", "TO", "VB", "MD", "PRP"):
        return False
    return token.pos_ in ("NOUN", "PROPN", "ADJ", "CCONJ") or token.text == "," or token.tag_ == "VBG"


def _people(doc: Doc, scene: Scene, people: dict[str, list[str]], used: list[bool]) -> list[Mention]:
    """People words ("me", "my son") naming the scene's person destinations."""
    found = []
    for name in scene.destinations:
        person_words = people.get(name.lower(), [])
        for token in doc:
            if used[token.i] or token.text.lower() not in person_words or token.tag_ == "PRP$":
                continue
            if token.pos_ != "PRON" and not _ends_phrase(doc, token.i + 1):
                continue
            found.append(Mention((name,), token.i, token.i + 1, "person"))
            used[token.i] = True
    if "user" in [d.lower() for d in scene.destinations]:
        user = next(d for d in scene.destinations if d.lower() == "user")
        for token in doc[1:]:
            if token.text.lower() == "way" and doc[token.i - 1].text.lower() == "my" and not used[token.i]:
                found.append(Mention((user,), token.i - 1, token.i + 1, "person"))  # "send it my way"
                used[token.i - 1 : token.i + 1] = [True, True]
    return found


def _pronouns(
    doc: Doc, known: list[Mention], pronouns: Sequence[str], is_person: Callable[[str], bool]
) -> list[Mention]:
    """ "her", "him" as the person the request spoke of last (or, with none before, first after)."""
    people = [m for m in known if m.kind == "person" or any(is_person(n) for n in m.names)]
    found = []
    for token in doc:
        if token.text.lower() not in pronouns or not people:
            continue
        if token.tag_ != "PRP":
            continue
        before = [m for m in people if m.end <= token.i]
        who = before[-1] if before else people[0]
        found.append(Mention(who.names, token.i, token.i + 1, "person"))
    return found


def scene_mentions(
    doc: Doc,
    scene: Scene,
    spelled: dict[str, list[str]],
    people: dict[str, list[str]],
    pronouns: Sequence[str],
    is_person: Callable[[str], bool],
) -> list[Mention]:
    """Every mention of the scene in the parsed request, in text order (see the module docstring).

    Args:
        doc: The parsed request.
        scene: The scene.
        spelled: Each scene name's tokens, lower case.
        people: Person destination name -> the words that name such a person.
        pronouns: The pronouns that refer back to a person ("her", "him").
        is_person: Whether a destination is a person or an animal.
    """
    used = [False] * len(doc)
    found = _groups(doc, scene, spelled, used)  # before single names: "the paper and plastic bins"
    found += _names(doc, scene, spelled, used)
    found += _people(doc, scene, people, used)
    found = sorted(found, key=lambda m: m.start)
    found += _pronouns(doc, found, pronouns, is_person)
    return sorted(found, key=lambda m: m.start)
