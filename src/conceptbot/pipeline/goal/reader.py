"""The goal reader: a request and a scene in, a :class:`~conceptbot.pipeline.goal.types.Goal` out.

The request is first said plainly and parsed, and the parse repaired where the small parser
misattaches (:mod:`conceptbot.pipeline.goal.repair`). Clauses
(:mod:`conceptbot.pipeline.goal.parse`) then become targets:

* A clause with destinations sends its theme there; a plural head ("into the recycling bins") or a
  destination-only continuation ("into the paper bin | and the plastic bin") makes a **sort**: each
  place takes the objects that belong in it, by the request's key ("by material") or by its name
  (criterion ""). A place the request also gives a clause of its own leaves the sort ("anything made
  of several materials goes in the mixed bin").
* "TV remote: coffee table" and "Kitchen basket: everything that's safe to eat" pair a theme with a
  place across a colon; "fetch one game ... and set it on the coffee table" gives the first
  clause's theme to the second's place.
* A sorting clause with no place before others that have places only says what is sorted ("Sort the
  potted plants: ..."); "leave X", "don't touch X", "X stays" send nothing.
* An instruction with no place ("throw away just the poisonous mushrooms", "X should be locked
  away") is a target with ``to`` None: the planner chooses where.
* "I need/want something ..." (or a scene object) sends it to the user where the scene has one.
* With no target: a dish when the request asks for one ("I want to make guacamole", "I'd love an
  omelette", "pancakes would be lovely", "a bowl of guacamole" is guacamole); the dish's
  ingredients go to a place the planner chooses. ``is_dish`` (a graph check) can reject a dish, and
  then the thing wished for goes to the user.
* With neither: a need ("my phone battery is almost empty"), met by what the planner chooses; a
  request stating two needs ("I'm chilly and there's nothing to do") has a need target per part,
  with the part's words as its criterion (:mod:`conceptbot.pipeline.goal.needs`).
* Stacking ("stack", "pile ... up", "into one pile", "on top of each other") makes ``stack`` true and
  one target, to None, of what is stacked (every object unless the request says otherwise).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from conceptbot.core.scene import Scene
from conceptbot.pipeline.goal.clauses import analyse
from conceptbot.pipeline.goal.mentions import Mention, scene_mentions
from conceptbot.pipeline.goal.needs import need_parts
from conceptbot.pipeline.goal.parse import Clause, chunks, vocabulary
from conceptbot.pipeline.goal.repair import parsed
from conceptbot.pipeline.goal.themes import (
    EXCEPTED,
    Reading,
    conjuncts,
    criterion_text,
    excepted_mentions,
    exception,
    head_of,
    objects_in,
    read_theme,
    read_themes,
)
from conceptbot.pipeline.goal.types import ALL, Goal, GoalTarget
from conceptbot.pipeline.hazards import is_person as default_is_person

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.language import Language
    from spacy.tokens import Doc, Token

logger = logging.getLogger(__name__)


@dataclass
class _Item:
    """A theme sent to places (None: the planner chooses), before it becomes targets."""

    clause: Clause
    places: list[tuple[str, ...]]  # one entry per mention: a plural head gives several names
    theme: tuple[int, ...]
    key: str = ""
    shared: bool = False  # the theme is shared with the item before ("and the plastic bin")
    condition: bool = False  # an "if" clause's criterion, waiting for the clause that sends "it"
    generic: bool = False  # sends whatever meets a condition: all of them
    remainder: bool = False  # "otherwise it goes in A": what the conditions before leave


class GoalReader:
    """Reads the goal of a request (see the module docstring and :mod:`conceptbot.pipeline.goal`).

    Args:
        nlp: A spaCy pipeline with a parser and a lemmatizer (default: the project's
            ``en_core_web_sm``, loaded on first use).
        is_dish: Whether a phrase names a dish to prepare (a graph check); None: trust the parse.
        is_person: Whether a destination is a person or an animal (things are handed to it).
        find_dish: The graph's dish for a phrase (the phrase and the scene's pickable objects in, the
            dish's concept or None out), for a request the rules read no placed target in ("Could
            we get started on some guacamole?"); None: no such reading.
        same_kind: Whether two nouns name the same kind of thing (a graph check: "basket" and
            "bin"), for places the person calls by a word the scene does not use ("the right
            baskets" where the scene has bins); None: only the scene's own words name places.
    """

    def __init__(
        self,
        nlp: Language | None = None,
        is_dish: Callable[[str], bool] | None = None,
        is_person: Callable[[str], bool] = default_is_person,
        find_dish: Callable[[str, Sequence[str]], str | None] | None = None,
        same_kind: Callable[[str, str], bool] | None = None,
    ) -> None:
        self._nlp = nlp
        self.same_kind = same_kind
        self.is_dish = is_dish
        self.is_person = is_person
        self.find_dish = find_dish
        self._spelled: dict[str, list[str]] = {}

    @property
    def nlp(self) -> Language:
        """The spaCy pipeline (loaded on first use)."""
        if self._nlp is None:
            from conceptbot.knowledge.triples import load_model

            self._nlp = load_model()
        return self._nlp

    def _spell(self, names: Sequence[str]) -> dict[str, list[str]]:
        for name in names:
            if name not in self._spelled:
                self._spelled[name] = [t.text.lower() for t in self.nlp.tokenizer(name)]
        return {n: self._spelled[n] for n in names}

    def read(self, request: str, scene: Scene) -> Goal:
        """The goal of ``request`` in ``scene``.

        Args:
            request: What the person asked.
            scene: What the robot sees (its names are the goal's).

        Returns:
            The goal: targets with scene names, ``to`` None where the planner must choose. It never
            raises on odd input (empty, punctuation only, very long): a request longer than the
            parser takes is read up to its limit, and one the rules cannot read is a need (the
            planner then reads the whole request with the model).
        """
        text = request[: self.nlp.max_length - 1]
        try:
            return self._read(text, scene)
        except Exception:  # a rule tripping on an odd parse must not stop the robot
            logger.exception("goal reader: cannot read %r; taken as a need", request[:200])
            return Goal(False, None, request.strip().rstrip(".!?"), (GoalTarget(None, "need"),))

    def _read(self, request: str, scene: Scene) -> Goal:
        vocab = vocabulary()
        # the tokenizer leaves a final "." on a word with a symbol in it ("a PB&J."): split it off
        doc = parsed(self.nlp, re.sub(r"(?<=[^\s.!?])([.!?]+)\s*$", r" \1", request))
        spelled = self._spell(scene.names)
        mentions = scene_mentions(
            doc,
            scene,
            spelled,
            vocab["people"],
            vocab["recipient_pronouns"],
            self.is_person,
            # "by" also keys a sort ("by material"): no place follows it there
            [w for w in vocab["spatial"] if w not in vocab["key"]],
            [*vocab["generic"], *vocab["whole"], *vocab["remainder"]],
            self.same_kind,
        )
        # Objects an exception names ("a drink other than the juice box", "excluding the
        # highlighter, ...") are no mentions of things to send: each target leaves them out.
        excepted = excepted_mentions(doc, mentions)
        doc.user_data[EXCEPTED] = {i for m in excepted for i in range(m.start, m.end)}
        excluded = tuple(dict.fromkeys(n for m in excepted for n in m.names))
        comma = _fronted_exception(doc, excepted)
        if comma is not None:
            # "Excluding the highlighter, put the writing tools ...": the rest is the request
            return self._read(doc[comma + 1 :].text, scene).leaving_out(excluded)
        mentions = [m for m in mentions if m not in excepted]
        clauses = [analyse(doc, c, mentions, self.is_person) for c in chunks(doc, mentions)]
        stack = is_stacking(doc)
        users = [d for d in scene.destinations if d.lower() == "user"]
        items = _items(doc, clauses, mentions, stack, users)
        targets = _targets(doc, items, mentions)
        dish: str | None = None
        need: str | None = None
        if stack:
            targets = [_stacked(doc, clauses, mentions)]
        if not targets and not stack:
            targets, dish = self._wished(doc, clauses, mentions, scene)
        unplaced = all(t.to is None and t.takes == "criterion" for t in targets)
        if unplaced and not stack and self.find_dish is not None:
            # with no target, or only place-less descriptions ("finish the meal with a fruit
            # salad"), a dish the graph knows is what the request asks for
            found, named_dish = self._dish_named(doc, mentions, scene)
            if found:
                targets, dish = found, named_dish
        if not targets and not stack:
            need = request.strip().rstrip(".!?")
            # "I'm chilly and there's nothing to do": a need per part, each met by its own object
            targets = [GoalTarget(None, "need", (), part) for part in need_parts(doc)] or [
                GoalTarget(None, "need")
            ]
        return Goal(stack, dish, need, tuple(targets)).leaving_out(excluded)

    def _wished(
        self, doc: Doc, clauses: list[Clause], mentions: list[Mention], scene: Scene
    ) -> tuple[list[GoalTarget], str | None]:
        """Targets of a wish: a dish's ingredients, or what is wished for, to the user."""
        vocab = vocabulary()
        users = [d for d in scene.destinations if d.lower() == "user"]
        for clause in clauses:
            personal = all(p.mention.kind == "person" for p in clause.places)
            if clause.form == "imperative" and clause.verb in vocab["making"] and personal:
                wished, making = clause.theme, True  # "make me a PB&J"
            elif clause.form == "fragment" and not clause.places and _polite(doc, clause) and clause.theme:
                dish = dish_words(doc, clause.theme)
                named = objects_in(clause.theme, mentions)
                thing = _names_itself(doc, clause.theme, mentions) or _described(doc, clause.theme)
                thing = thing or doc[clause.theme[0]].text.lower() in vocab["one"]  # "something for ..."
                if dish and not named and not thing and self.is_dish is not None and self.is_dish(dish):
                    return [GoalTarget(None, "ingredients", (), "", ALL)], dish  # "Pancakes, please!"
                return _all_to(users, read_themes(doc, clause.theme, mentions)), None  # "A drink, please."
            elif clause.form == "desire" and (
                clause.verb in vocab["making"] or clause.verb in ("want", "need", "be")
            ):
                wished, making = clause.theme, clause.verb in vocab["making"]
            elif clause.form == "imperative" and clause.verb in vocab["desire"] and not clause.places:
                wished, making = clause.theme, False
            else:
                continue
            if not wished:
                continue
            reading = read_theme(doc, wished, mentions)
            parts = conjuncts(doc, wished)
            thing = any(
                _names_itself(doc, p, mentions) or _indefinite(doc, p) or _described(doc, p) for p in parts
            )
            if not making and thing:
                return _all_to(users, read_themes(doc, wished, mentions)), None
            dish = dish_words(doc, wished)
            if dish and (self.is_dish is None or self.is_dish(dish)):
                named = objects_in(wished, mentions)
                return [GoalTarget(None, "ingredients", named, "", ALL)], dish
            if not making:
                return [_to(users, reading)], None
        made = making_anywhere(doc, mentions)
        if made and (self.is_dish is None or self.is_dish(dish_words(doc, made))):
            return [GoalTarget(None, "ingredients", objects_in(made, mentions), "", ALL)], dish_words(
                doc, made
            )
        return [], None

    def _dish_named(
        self, doc: Doc, mentions: list[Mention], scene: Scene
    ) -> tuple[list[GoalTarget], str | None]:
        """A dish the graph knows, said as the object of a verb or a preposition in a request with no
        other reading ("let's finish the meal with a fruit salad", "I've got a craving for pancakes"):
        its words in the request, its ingredients to a place the planner chooses."""
        assert self.find_dish is not None
        pickable = [o.name for o in scene.objects if o.pickable]
        needs = bool(need_parts(doc))  # once per request, not per noun
        for token in doc:
            if not token.tag_.startswith("NN") or token.dep_ not in ("dobj", "pobj", "attr", "conj", "appos"):
                continue
            if any(m.covers(token.i) for m in mentions) or token.lemma_.lower() in vocabulary()["measure"]:
                continue  # "cut this baguette into slices": a measure, not a dish
            if any(t.tag_ == "TO" for t in token.subtree):
                continue  # "it's time for me to brush my teeth": what follows is an activity
            if _had(token) or not _may_name_dish(token, needs):
                continue  # "I've got a cut on my finger": what the speaker has, not a dish
            phrase = tuple(t.i for t in token.subtree if not t.is_punct)
            words = dish_words(doc, phrase)
            if words and self.find_dish(words, pickable):
                return [GoalTarget(None, "ingredients", objects_in(phrase, mentions), "", ALL)], words
        return [], None


#: Modifiers that make a noun no dish: "at the same time", "my own hands", "whichever tray".
NOT_DISH_MODIFIERS = frozenset({"same", "own", "whichever", "whatever", "next", "last", "right", "other"})
#: Words opening a clause that gives the request's reason or time, not what it asks for.
REASON_MARKS = frozenset({"since", "because", "as", "while", "after", "when", "now", "before", "until"})


def _may_name_dish(token: Token, needs: bool) -> bool:
    """Whether a noun can be the dish a request asks for: not one with a modifier that makes it no
    dish (:data:`NOT_DISH_MODIFIERS`), nor one inside a clause giving the request's reason or time
    ("I picked up a baguette ... to go with the soup", "fresh out of the bath, ...", "since it's
    Sunday, ..."), nor, where the request states how the speaker is, any but what is wished "for"
    ("I'm burning up and shivering at the same time"; "I've got a craving for pancakes"), nor any
    where it states two needs (``needs``: :func:`need_parts` of the request found some)."""
    if any(c.text.lower() in NOT_DISH_MODIFIERS for c in token.children):
        return False
    for ancestor in token.ancestors:
        marks = {c.text.lower() for c in ancestor.children if c.dep_ == "mark"}
        if ancestor.dep_ == "advcl" and (marks & REASON_MARKS or ancestor.tag_ in ("VBG", "VBN", "JJ")):
            return False
        if ancestor.dep_ == "relcl" or (ancestor.dep_ == "xcomp" and ancestor.tag_ == "VB"):
            return False  # "... to go with the soup": what the thing is for
    stated = _speaker_state(token.sent.root) and token.head.text.lower() != "for"
    return not (needs or stated)


def _speaker_state(root: Token) -> bool:
    """Whether a sentence's main clause says how the speaker is ("I'm so dehydrated", "my hair's
    soaked through")."""
    subject = next((c for c in root.children if c.dep_ in ("nsubj", "nsubjpass")), None)
    if subject is None:
        return False
    mine = subject.text.lower() in ("i", "we") or any(
        c.dep_ == "poss" and c.text.lower() in ("my", "our") for c in subject.children
    )
    return mine and root.lemma_ == "be" and any(c.dep_ in ("acomp", "attr") for c in root.children)


def _had(token: Token) -> bool:
    """Whether a noun is what the speaker says they have ("I've got a cut", "I have a cold and a
    cough"): the object of "have"/"get" said of "I"/"we" with no modal ("could I have" asks)."""
    while token.dep_ == "conj" and token.head.i != token.i:
        token = token.head
    verb = token.head
    if token.dep_ != "dobj" or verb.lemma_ not in ("have", "get"):
        return False
    speaker = any(c.dep_ == "nsubj" and c.text.lower() in ("i", "we") for c in verb.children)
    return speaker and not any(c.tag_ == "MD" for c in verb.children)


def _polite(doc: Doc, clause: Clause) -> bool:
    """Whether a verbless chunk is a request by its politeness ("A drink, please.")."""
    return any(t.text.lower() in ("please", "thanks") for t in doc[clause.chunk.start : clause.chunk.end])


def _described(doc: Doc, run: Sequence[int]) -> bool:
    """Whether a wished-for phrase describes a thing by its use ("a tool for driving in nails", "a
    tool that drives in nails"): a thing to hand over, not a dish."""
    inside = set(run)
    for i in run:
        token = doc[i]
        if token.text.lower() == "for" and i + 1 in inside and doc[i + 1].tag_ == "VBG":
            return True
        if token.dep_ == "relcl" and token.head.i in inside and any(c.tag_ == "WDT" for c in token.children):
            return True
    return False


def making_anywhere(doc: Doc, mentions: list[Mention]) -> tuple[int, ...]:
    """The object of a making verb anywhere in the request ("Time to make some guacamole!", "let's
    put together a salad"), for a request with no other target; () if none."""
    vocab = vocabulary()
    for token in doc:
        phrasal = any(
            token.lemma_.lower() == a and any(c.text.lower() == b for c in token.children)
            for a, b in vocab["making_phrases"]
        )
        plain = token.lemma_.lower() in vocab["making"] and not any(c.dep_ == "prt" for c in token.children)
        if not token.tag_.startswith("VB") or not (plain or phrasal):
            continue
        made = next((c for c in token.children if c.dep_ == "dobj"), None)
        if made is not None and made.text.lower() in ("one", "some", "it") and not list(made.children):
            return _indefinite_before(doc, made.i)  # "the pasta needs a green salad; let's make one"
        if made is not None and made.lemma_.lower() not in vocab["stack"]["nouns"]:
            return tuple(t.i for t in made.subtree if not t.is_punct)
    return ()


def _indefinite_before(doc: Doc, at: int) -> tuple[int, ...]:
    """What "one" stands for: the last noun phrase before ``at`` opened by "a", "an" or "some" (its
    words up to the noun); () if none."""
    for token in reversed(doc[:at]):
        if token.tag_ in ("NN", "NNS") and any(
            c.dep_ == "det" and c.text.lower() in ("a", "an", "some") for c in token.children
        ):
            return tuple(range(token.left_edge.i, token.i + 1))
    return ()


def _names_itself(doc: Doc, run: Sequence[int], mentions: list[Mention]) -> bool:
    """Whether a phrase is a scene object ("the watering can"), not a thing made of some ("a tomato
    and cucumber salad")."""
    head = head_of(doc, run)
    return head is not None and any(m.kind in ("object", "both") and m.covers(head.i) for m in mentions)


def _indefinite(doc: Doc, run: Sequence[int]) -> bool:
    """Whether a wished-for phrase is "something ...", "anything ..." (not a dish)."""
    skip = {"a", "an", "the", "some", "really", "just"}
    first = next((i for i in run if doc[i].text.lower() not in skip), run[0])
    return doc[first].text.lower() in ("something", "anything", "someone", "somebody")


def _fronted_exception(doc: Doc, excepted: list[Mention]) -> int | None:
    """The comma that ends an exception opening the request ("Excluding the highlighter, put
    ...", "Apart from the thermos, ..."), or None: the exception's words start the request, and
    every object mention before the comma is excepted."""
    if not excepted or exception(doc, range(min(3, len(doc)))) != 0:
        return None
    end = max(m.end for m in excepted)
    comma = next((t.i for t in doc[end:] if t.text == ","), None)
    if comma is None or comma != end or comma + 1 >= len(doc):
        return None
    return comma


def _to(users: list[str], reading: Reading) -> GoalTarget:
    """A wished-for thing, to the user (None where the scene has no user)."""
    return GoalTarget(
        users[0] if users else None, reading.takes, reading.named, reading.criterion, reading.count
    )


def _all_to(users: list[str], readings: list[Reading]) -> list[GoalTarget]:
    """Wished-for things (a list: "a napkin and something to read"), to the user."""
    return [_to(users, r) for r in readings]


def dish_words(doc: Doc, run: Sequence[int]) -> str:
    """The dish a wished-for phrase names: its words up to the head noun and an "of" or "with" phrase
    ("a salad with tomato and cucumber"), without
    determiners or a following "for breakfast", "to go with ..."; "a bowl of guacamole" is
    guacamole (a measure noun before "of": ``measure`` in ``words.json``)."""
    vocab = vocabulary()
    words = []
    for i in run:
        token = doc[i]
        word = token.text.strip(".,;:!?")
        lower = word.lower()
        if not words and lower in (*vocab["determiners"], *vocab["restrictors"], "really", "some"):
            continue
        joins = token.tag_ == "IN" and lower not in ("of", "with")
        if words and (token.tag_ in ("TO", "WDT", "RB") or joins):
            break
        if words and token.tag_ == "DT":
            break
        words.append(word)
    if len(words) >= 3 and words[1].lower() == "of" and words[0].lower() in vocab["measure"]:
        words = words[2:]
    return " ".join(w for w in words if w)


def is_stacking(doc: Doc) -> bool:
    """Whether the request asks for a pile: "stack"/"pile" as its verb, "into one pile", "make a
    stack", "on top of each other" (``stack`` in ``words.json``); "sort this pile" is not one."""
    words = vocabulary()["stack"]
    text = " ".join(t.text.lower() for t in doc)
    if any(p in text for p in words["phrases"]):
        return True
    for token in doc:
        lemma = token.lemma_.lower()
        if (
            lemma in words["verbs"]
            and token.pos_ == "VERB"
            and token.dep_ in ("ROOT", "conj", "xcomp", "ccomp")
        ):
            return True
        if lemma in words["nouns"] and token.pos_ == "NOUN":
            head = token.head
            made = any(c.text.lower() in ("one", "a", "single") for c in token.children)
            if token.dep_ == "pobj" and (
                head.text.lower() in ("into", "as") or (head.text.lower() == "in" and made)
            ):
                return True  # "into a pile", "in one pile"; not "everything else in this pile"
            if token.dep_ == "dobj" and head.lemma_ in ("make", "build", "form", "create"):
                return True
    return False


def _stacked(doc: Doc, clauses: list[Clause], mentions: list[Mention]) -> GoalTarget:
    """What a pile is made of: every object, unless the stacking clause names or describes some."""
    nouns = vocabulary()["stack"]["nouns"]
    for clause in clauses:
        if clause.form == "imperative" and clause.theme:
            # what is stacked, without "into one pile", "on top of each other"
            run = _stacked_things(doc, list(clause.theme), nouns)
            reading = read_theme(doc, run, mentions) if run else Reading("all")
            if reading.takes in ("named", "criterion") and reading.criterion.lower() not in (
                "",
                "pile",
                "stack",
            ):
                return GoalTarget(None, reading.takes, reading.named, reading.criterion, reading.count)
    return GoalTarget(None, "all")


def _stacked_things(doc: Doc, run: list[int], nouns: Sequence[str]) -> list[int]:
    """What a stacking clause's theme stacks: "all of these" in "all of these into one pile", "a
    single stack out of all of these" or "these on top of each other"."""
    at = next((k for k, i in enumerate(run) if doc[i].lemma_.lower() in nouns), None)
    if (at is not None and doc[run[0]].text.lower() in ("a", "an", "one")) or at == 0:
        # the pile comes first: what it is made of follows "out of", "of", "from", "with"
        after = next(
            (k for k in range(at + 1, len(run)) if doc[run[k]].text.lower() in ("of", "from", "with")), None
        )
        return run[after + 1 :] if after is not None else []
    cut = next(
        (
            k
            for k, i in enumerate(run)
            if doc[i].tag_ == "IN"
            and (doc[i].text.lower() == "on" or any(t.lemma_.lower() in nouns for t in doc[i].subtree))
        ),
        len(run),
    )
    return run[:cut]


def _items(
    doc: Doc, clauses: list[Clause], mentions: list[Mention], stack: bool, users: list[str]
) -> list[_Item]:
    """Each clause's theme and places, with colon pairs, pronoun themes and sort headers resolved."""
    vocab = vocabulary()
    items: list[_Item] = []
    pending = ""  # a key said on its own ("By material, sort ...")
    for n, clause in enumerate(clauses):
        places = [p.mention.names for p in clause.places]
        prev = clauses[n - 1] if n else None
        stay = (clause.verb in vocab["stay"] and not places) or (
            clause.negated and clause.verb in (*vocab["untouched"], *vocab["stay"])
        )
        waiting = items[-1] if items and items[-1].condition else None
        sorting = items and len({n for p in items[-1].places for n in p}) > 1
        if clause.key and not places and not clause.theme and sorting and not items[-1].key:
            items[-1].key = clause.key  # "... go in the recycling bins, | sorted by material"
            continue
        if clause.form == "condition":
            if clause.theme:
                items.append(_Item(clause, [], clause.theme, condition=True))
            continue
        if (
            waiting is not None
            and (stay or clause.verb in vocab["stay"])
            and _pronoun_only(doc, clause.theme)
        ):
            items.pop()  # "if something combines materials, leave it on the desk": it stays
            continue
        if (
            waiting is not None
            and _pronoun_only(doc, clause.theme)
            and clause.form in ("imperative", "subject")
        ):
            # "if it's poisonous, lock it away", "if it's clothing, it belongs in the basket"
            items[-1] = _Item(clause, places, waiting.theme, clause.key or pending, generic=True)
            pending = ""
            continue
        alone = prev is not None and all(  # "otherwise, | it goes ..."
            doc[i].text.lower() in vocab["otherwise"] or doc[i].is_punct
            for i in range(prev.chunk.start, prev.chunk.end)
        )
        if (clause.otherwise or alone) and places and _pronoun_only(doc, clause.theme):
            items.append(_Item(clause, places, clause.theme, clause.key or pending, remainder=True))
            pending = ""
            continue
        if clause.form == "desire" and clause.theme and clause.verb in ("want", "need"):
            # a need is for a thing ("I need a tool that drives in nails"), a wish maybe for a dish
            parts = conjuncts(doc, clause.theme)  # "a bag of crackers and something to drink"
            thing = clause.verb == "need" or any(_indefinite(doc, p) for p in parts)
            if thing or any(_names_itself(doc, p, mentions) for p in parts):
                items.append(_Item(clause, [tuple(users)] if users else [], clause.theme))
            continue
        if stay or clause.form in ("statement", "desire"):
            continue
        if (
            clause.form == "imperative"
            and clause.verb in vocab["making"]
            and not _names_itself(doc, clause.theme, mentions)
        ):
            continue  # "make me a PB&J": a dish, not a thing to hand over
        if clause.form == "imperative" and not places and _says_pronoun(doc, clause):
            # "hand it over", "put those in", "put it somewhere safe": what "it" is, the clause
            # before says; handing it is to the speaker
            handed = clause.verb in vocab["handing"] and users
            if items and items[-1].places and not handed:
                continue  # said twice: "the paper bin is for X; put those in"
            said = tuple(i for r in clause.runs for i in r)
            theme = items[-1].theme if items else ()
            if not theme and n:
                theme = antecedent(doc, clauses[n - 1], mentions, _plural(doc, said))
                if not handed and not objects_in(theme, mentions):
                    continue  # "we'll want a green salad; can you set that up?": a dish, not a thing
            if items and not items[-1].places:
                items.pop()
            if theme:
                items.append(_Item(clause, [tuple(users)] if handed else [], theme, clause.key))
            else:
                pending = pending or clause.key  # "sort these by what they're made of, each one ..."
            continue
        if clause.form == "fragment" and not places and items and items[-1].places and _also(doc, clause):
            # "fetch me the ruler. Oh, and the eraser as well."; "...; the hammer too."
            items.append(_Item(clause, items[-1].places, clause.theme, items[-1].key))
            continue
        if clause.form == "imperative" and not places:
            if clause.verb in (*vocab["making"], *vocab["desire"], *vocab["helping"]):
                continue
            if clause.theme and doc[clause.theme[0]].tag_ == "IN":
                continue  # "look at my fingers": the verb's object is a place it looks, not a thing sent
            if clause.verb in vocab["stack"]["verbs"] or stack:
                continue
            if clause.theme:
                # "could you bring the ruler over?": handed with no one named, to the speaker
                handed = clause.verb in vocab["handing"] and users
                items.append(_Item(clause, [tuple(users)] if handed else [], clause.theme, clause.key))
            continue
        if clause.form == "fragment" and places and not clause.theme:
            if (
                prev is not None
                and clause.chunk.after == "colon"
                and prev.form == "fragment"
                and not prev.places
            ):
                if items and items[-1].clause is prev:
                    items.pop()
                items.append(_Item(clause, places, prev.theme, clause.key))
                continue
            if clause.chunk.after == "soft" and items and items[-1].places:
                items.append(_Item(clause, places, items[-1].theme, items[-1].key, shared=True))
                continue
            nxt = clauses[n + 1] if n + 1 < len(clauses) else None
            if nxt is not None and nxt.chunk.after == "colon" and nxt.form == "fragment" and not nxt.places:
                items.append(_Item(clause, places, nxt.theme, clause.key))
                continue
            continue
        if clause.form == "fragment" and not places and clause.key and not clause.theme:
            pending = clause.key
            continue
        if clause.form == "fragment" and not places:
            paired = prev is not None and clause.chunk.after == "colon" and prev.form == "fragment"
            if clause.theme and paired and prev.places and not prev.theme:
                continue  # paired with the place before (handled there)
            if clause.theme:
                items.append(_Item(clause, [], clause.theme, clause.key))
            continue
        theme = clause.theme
        if places and _pronoun_only(doc, theme) and not items and n:
            # "I'm looking for X; pass it to me"
            said = theme or tuple(i for r in clause.runs for i in r)
            theme = antecedent(doc, clauses[n - 1], mentions, _plural(doc, said)) or theme
        if places and _pronoun_only(doc, theme) and items:
            before = items[-1]
            if before.places == places:
                continue  # "the dog would like a treat; give him one": said twice
            theme = before.theme
            fetched = before.clause.verb in vocab["fetching"] and all(
                p.mention.kind == "person" for p in before.clause.places
            )
            if not before.places or fetched:
                items.pop()  # "fetch one game ... and set it on the coffee table", "grab us a game and ..."
        items.append(_Item(clause, places, theme, clause.key or pending))
        pending = ""
    return _without_headers(items, vocab)


def _says_pronoun(doc: Doc, clause: Clause) -> bool:
    """Whether a clause sends only a pronoun ("hand it over", "put those in")."""
    said = [i for r in clause.runs for i in r]
    return (bool(said) and not clause.theme) or (bool(clause.theme) and _pronoun_only(doc, clause.theme))


def _also(doc: Doc, clause: Clause) -> bool:
    """Whether a place-less fragment adds objects to the clause before: it names objects and says
    "too", "also" or "as well", or opens with "and"."""
    words = [doc[i].text.lower() for i in range(clause.chunk.start, clause.chunk.end)]
    text = " " + " ".join(words) + " "
    added = any(f" {w} " in text for w in vocabulary()["also"]) or "and" in words[:3]
    return added and bool(clause.theme) and any(doc[i].tag_.startswith("NN") for i in clause.theme)


def _plural(doc: Doc, run: Sequence[int]) -> bool | None:
    """Whether a pronoun theme is plural ("them", "they", "these"), singular ("it"), or says not."""
    words = {doc[i].text.lower() for i in run}
    if words & {"them", "they", "these", "those"}:
        return True
    return False if words & {"it", "this", "that"} else None


def antecedent(
    doc: Doc, clause: Clause, mentions: Sequence[Mention] = (), plural: bool | None = None
) -> tuple[int, ...]:
    """What "it" or "them" refers back to in the clause before: the objects it names (all of them
    for "them", the last for "it"), else its last noun phrase that is not a person and agrees in
    number ("I'm looking for something to write with"), as the phrase's tokens."""
    found: tuple[int, ...] = ()
    chunk = clause.chunk
    asked = _asked_which(doc, chunk.start, chunk.end)
    if asked:
        return asked  # "Which things are paper through and through? Those go in the paper bin."
    named = [m for m in mentions if m.kind in ("object", "both") and chunk.start <= m.start < chunk.end]
    if named and plural:
        return tuple(range(named[0].start, named[-1].end))  # "the socks and the towel ...; load them"
    if named and plural is False:
        return tuple(range(named[-1].start, named[-1].end))
    for token in doc[chunk.start : chunk.end]:
        if token.i in found:
            continue  # inside the phrase found: "something with caffeine", not "caffeine"
        role = token.dep_ in ("dobj", "pobj", "nsubj", "attr") and token.tag_.startswith("NN")
        agrees = plural is None or (token.tag_ in ("NNS", "NNPS")) == plural
        if role and agrees and token.text.lower() not in vocabulary()["personal"]:
            found = tuple(t.i for t in token.subtree if chunk.start <= t.i < chunk.end and not t.is_punct)
    return found


def _asked_which(doc: Doc, start: int, end: int) -> tuple[int, ...]:
    """What a "which/what ... is/are X?" question asks about: X ("which things are paper through and
    through?"); () for any other chunk."""
    if start >= end or doc[start].text.lower() not in ("which", "what", "whichever", "whatever"):
        return ()
    be = next((t for t in doc[start:end] if t.lemma_ == "be"), None)
    if be is None:
        return ()
    return tuple(i for i in range(be.i + 1, end) if not doc[i].is_punct)


def _pronoun_only(doc: Doc, run: Sequence[int]) -> bool:
    """Whether a theme is only a pronoun ("it", "them both", "all of them"), or empty."""
    pronouns = ("it", "them", "they", "one", "these", "those")
    words = [doc[i].text.lower() for i in run]
    return not run or (
        all(w in (*pronouns, "both", "all", "of") for w in words) and any(w in pronouns for w in words)
    )


def _without_headers(items: list[_Item], vocab: dict) -> list[_Item]:
    """Drops what says only which objects are sorted ("Sort the potted plants:"), and place-less
    fragments that no place was paired with ("Dinner's ready")."""
    placed = any(i.places for i in items)
    kept = []
    for item in items:
        if not item.places and placed:
            clause = item.clause
            if clause.form == "fragment" or clause.verb in vocab["sort"]:
                continue
        if (not item.places and item.clause.form == "fragment") or item.condition:
            continue  # a condition no clause sent anything by
        kept.append(item)
    return kept


def _targets(doc: Doc, items: list[_Item], mentions: list[Mention]) -> list[GoalTarget]:
    """The items as targets: sorts split into one target per place (see the module docstring)."""
    groups: list[list[_Item]] = []
    for item in items:
        if item.shared and groups:
            groups[-1].append(item)
        else:
            groups.append([item])
    targets: list[GoalTarget] = []
    for group in groups:
        names = list(dict.fromkeys(n for item in group for p in item.places for n in p))
        theme = group[0].theme
        if len(names) > 1:
            # A sort: each place takes what belongs in it, except a place with a clause of its own.
            own = {
                p[0] for other in groups if other is not group for i in other for p in i.places if len(p) == 1
            }
            key = next((i.key for i in group if i.key), "")
            targets += [GoalTarget(n, "criterion", (), key, ALL) for n in names if n not in own]
            continue
        to = names[0] if names else None
        if theme and not group[0].remainder and not group[0].generic:
            # "the pear, the stapler and something to write with": each phrase of a list goes there
            readings = read_themes(doc, theme, mentions)
            if len(readings) > 1:
                targets += [GoalTarget(to, r.takes, r.named, r.criterion, r.count) for r in readings]
                continue
        reading = read_theme(doc, theme, mentions) if theme else Reading("all")
        if group[0].remainder:
            reading = Reading("remainder")
        elif group[0].generic and reading.takes == "criterion":
            reading = Reading("criterion", (), reading.criterion, ALL)  # whatever meets the condition
        criterion = reading.criterion or (criterion_text(doc, theme) if reading.takes == "criterion" else "")
        targets.append(GoalTarget(to, reading.takes, reading.named, criterion, reading.count))
    return _merged_named(targets)


def _merged_named(targets: list[GoalTarget]) -> list[GoalTarget]:
    """Targets naming objects for the same place, as one ("hand me the tape; hand me the glue")."""
    out: list[GoalTarget] = []
    for target in targets:
        same = next(
            (t for t in out if t.to == target.to and t.to and t.takes == target.takes == "named"), None
        )
        if same is None:
            out.append(target)
            continue
        named = tuple(dict.fromkeys((*same.named, *target.named)))
        out[out.index(same)] = GoalTarget(same.to, "named", named, "", len(named))
    return out
