"""The goal reader: a request and a scene in, a :class:`~conceptbot.pipeline.goal.types.Goal` out.

Clauses (:mod:`.parse`) become targets: a clause's theme goes to its destinations (several places
make a sort), or to ``to`` None where it names none. With no target, a dish when the request asks
for one, else a need; the planner chooses where those go. Stacking makes ``stack`` true.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from conceptbot.core.scene import Scene
from conceptbot.pipeline.goal.clauses import analyse
from conceptbot.pipeline.goal.items import clause_items as _items
from conceptbot.pipeline.goal.items import indefinite, item_targets, names_itself
from conceptbot.pipeline.goal.mentions import Mention, scene_mentions
from conceptbot.pipeline.goal.parse import Clause, chunks, vocabulary
from conceptbot.pipeline.goal.themes import (
    Reading,
    conjuncts,
    objects_in,
    read_theme,
    read_themes,
)
from conceptbot.pipeline.goal.types import ALL, Goal, GoalTarget
from conceptbot.pipeline.hazards import is_person as default_is_person

if TYPE_CHECKING:  # spaCy is loaded with the model, on first use (pipeline/goal imports light)
    from spacy.language import Language
    from spacy.tokens import Doc

logger = logging.getLogger(__name__)


class GoalReader:
    """Reads the goal of a request (see the module docstring and :mod:`conceptbot.pipeline.goal`).

    Args:
        nlp: A spaCy pipeline with a parser and lemmatizer (default: the project's, loaded on first use).
        is_dish: Whether a phrase names a dish to prepare (a graph check); None: trust the parse.
        is_person: Whether a destination is a person or an animal (things are handed to it).
    """

    def __init__(
        self,
        nlp: Language | None = None,
        is_dish: Callable[[str], bool] | None = None,
        is_person: Callable[[str], bool] = default_is_person,
    ) -> None:
        self._nlp = nlp
        self.is_dish = is_dish
        self.is_person = is_person
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
            The goal (never raises: a request the rules cannot read is a need).
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
        doc = self.nlp(re.sub(r"(?<=[^\s.!?])([.!?]+)\s*$", r" \1", request))
        spelled = self._spell(scene.names)
        mentions = scene_mentions(
            doc,
            scene,
            spelled,
            vocab["people"],
            vocab["recipient_pronouns"],
            self.is_person,
        )
        clauses = [analyse(doc, c, mentions, self.is_person) for c in chunks(doc, mentions)]
        stack = is_stacking(doc)
        users = [d for d in scene.destinations if d.lower() == "user"]
        items = _items(doc, clauses, mentions, stack, users)
        targets = item_targets(doc, items, mentions)
        dish: str | None = None
        need: str | None = None
        if stack:
            targets = [_stacked(doc, clauses, mentions)]
        if not targets and not stack:
            targets, dish = self._wished(doc, clauses, mentions, scene)
        if not targets and not stack:
            need = request.strip().rstrip(".!?")
            targets = [GoalTarget(None, "need")]
        return Goal(stack, dish, need, tuple(targets))

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
                thing = names_itself(doc, clause.theme, mentions) or _described(doc, clause.theme)
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
                names_itself(doc, p, mentions) or indefinite(doc, p) or _described(doc, p) for p in parts
            )
            if not making and thing:
                return _all_to(users, read_themes(doc, wished, mentions)), None
            dish = dish_words(doc, wished)
            if dish and (self.is_dish is None or self.is_dish(dish)):
                named = objects_in(wished, mentions)
                return [GoalTarget(None, "ingredients", named, "", ALL)], dish
            if not making:
                return [_to(users, reading)], None
        return [], None


def _polite(doc: Doc, clause: Clause) -> bool:
    """Whether a verbless chunk is a request by its politeness ("A drink, please.")."""
    return any(t.text.lower() in ("please", "thanks") for t in doc[clause.chunk.start : clause.chunk.end])


def _described(doc: Doc, run: Sequence[int]) -> bool:
    """Whether a wished-for phrase describes a thing by its use ("a tool for driving nails"), not a dish."""
    inside = set(run)
    for i in run:
        token = doc[i]
        if token.text.lower() == "for" and i + 1 in inside and doc[i + 1].tag_ == "VBG":
            return True
        if token.dep_ == "relcl" and token.head.i in inside and any(c.tag_ == "WDT" for c in token.children):
            return True
    return False


def _to(users: list[str], reading: Reading) -> GoalTarget:
    """A wished-for thing, to the user (None where the scene has no user)."""
    return GoalTarget(
        users[0] if users else None, reading.takes, reading.named, reading.criterion, reading.count
    )


def _all_to(users: list[str], readings: list[Reading]) -> list[GoalTarget]:
    """Wished-for things (a list: "a napkin and something to read"), to the user."""
    return [_to(users, r) for r in readings]


def dish_words(doc: Doc, run: Sequence[int]) -> str:
    """The dish a wished-for phrase names: its words up to the head noun and an "of"/"with" phrase,
    without determiners; "a bowl of guacamole" is guacamole."""
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
    """Whether the request asks for a pile ("stack these", "into one pile"); "sort this pile" is not one."""
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
    """What a stacking clause's theme stacks: "all of these" in "all of these into one pile"."""
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
