"""Where a request sends things and how many, read from the request by its words and by scored
questions, never by free generation.

A 1.5B model asked to write the goal as JSON listed the scene's destinations and objects instead of
the request's (docs/notes/2026-11-30-planner-redesign.md); asked "how many objects?" as a scored choice
it answered "three" to nearly everything. So:

* **Targets** are the destinations the request names (longest names first, each word used once;
  "me" names the user, "my son" a child destination, from ``request_words.json``; a plural head
  noun, "the recycling bins", names every destination with that head). When it names none, the
  speaker's words ("I", "my") make the user the target, unless the request is about preparing
  food (a dish the graph knows: "I would like a hollandaise sauce", "hollandaise" IsA "sauce"; or
  "cook", "bake"): then, as with neither, the destinations are scored ("should the robot put
  things in the X?" against a content-free request) and the best one (for food: the only one)
  and those well above the content-free request are the targets.
* **Named objects** go to the target named in their own clause (clauses split at "and", "then":
  "hand me the tape and put the gloves on the shelf"), else to the nearest target ("put the hammer
  and the screwdriver in the toolbox").
* **Count** per target: every fitting object when the request says "all", "every", "sort", ...
  or is about cooking ("I want to cook pancakes"); a need of the speaker's ("I'm cold") is one
  thing; otherwise as many as its clauses have named objects or indefinite phrases ("a fruit",
  "something to drink"), and with neither, all that fit ("put the clothes in the basket").
* **Stacking** from the request's words ("stack", "pile", "on top of each other").
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Protocol

from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline import prompts

ALL = 0  # count meaning "every object that fits"
CONTENT_FREE_REQUEST = "Do the task."
CONTENT_FREE_DISH = "the food"  # the dish a preparation question is calibrated against


@cache
def words() -> dict:
    """The vocabulary of ``request_words.json``."""
    text = resources.files("conceptbot.pipeline").joinpath("request_words.json").read_text(encoding="utf-8")
    return json.loads(text)


def tokens(text: str) -> list[str]:
    """Lower-case word tokens, and the punctuation that ends a clause as tokens of its own."""
    return re.findall(r"[a-z0-9][a-z0-9'&-]*|[,;:.!?]", text.lower())


def _find(seq: list[str], key: list[str], used: list[bool]) -> int:
    for start in range(len(seq) - len(key) + 1):
        if key and seq[start : start + len(key)] == key and not any(used[start : start + len(key)]):
            return start
    return -1


def mentions(
    text: str,
    names: Sequence[str],
    people: dict[str, list[str]] | None = None,
    taken: Sequence[int] = (),
) -> list[tuple[int, str]]:
    """``(token position, name)`` for each name the text mentions, in text order.

    Names match as whole words, longest first, each word used once ("non-toxic container" before
    "toxic container"); a name's plural head noun counts ("bins" for "glass bin"); people match by
    their words (``people``: name -> words). Token positions in ``taken`` are not used (the words of
    a destination already found: "pencil cup" does not name a pencil).
    """
    seq = tokens(text)
    used = [i in set(taken) for i in range(len(seq))]
    found: dict[str, int] = {}
    for name in sorted(names, key=lambda n: -len(tokens(n))):
        key = tokens(name)
        at = _find(seq, key, used)
        if at >= 0:
            used[at : at + len(key)] = [True] * len(key)
            found[name] = at
    plurals: dict[str, list[str]] = {}
    for name in names:
        key = tokens(name)
        if name not in found and len(key) >= 2:
            plural = key[-1] + ("es" if key[-1].endswith(("s", "x", "ch", "sh")) else "s")
            if plural in seq:
                plurals.setdefault(plural, []).append(name)
    for plural, group in plurals.items():
        # "the wood, metal and fabric bins": the bins whose other words the text has; "the bins"
        # alone: all of them.
        described = [n for n in group if set(tokens(n)[:-1]) <= set(seq)]
        for name in described or group:
            found[name] = seq.index(plural)
    for name, person_words in (people or {}).items():
        if name in names and name not in found:
            hits = [i for i, w in enumerate(seq) if w in person_words and not used[i]]
            if hits:
                found[name] = hits[0]
    return sorted((at, name) for name, at in found.items())


def _plural(part: Sequence[str]) -> bool:
    """Whether the words speak of several things: a plural noun within two words after "the",
    "these", "those" ("the clothes", "the poisonous ones")."""
    for i, word in enumerate(part):
        noun = len(word) > 3 and word.endswith("s") and not word.endswith(("ss", "'s", "us", "is"))
        if noun and any(part[j] in ("the", "these", "those") for j in range(max(0, i - 2), i)):
            return True
    return False


def _criterion(words_: Sequence[str], drop: Sequence[str]) -> str:
    """The words of a clause that say which objects go ("the poisonous ones go on the toxic tray"
    -> "poisonous"), without the verbs, articles and the destination."""
    kept = [w for w in words_ if w not in drop]
    while kept and kept[-1] in ("by", "at", "as", "for", "than", "like"):
        kept.pop()
    return " ".join(kept)


def is_stacking(request: str) -> bool:
    """Whether the request asks for a pile."""
    text = " ".join(tokens(request))
    return any(re.search(rf"\b{re.escape(w)}\b", text) for w in words()["stack"])


class FoodKnowledge(Protocol):
    """What the planner asks the graph about food (implemented by ``FactFinder``)."""

    def dish(self, request: str, pickable: Sequence[str]) -> str | None:
        """The dish the request asks to be made, or None."""
        ...

    def prep_places(self, destinations: Sequence[str]) -> list[str]:
        """The destinations food can be prepared in or on."""
        ...


@dataclass
class Target:
    """A destination the request sends things to.

    Attributes:
        name: The destination.
        count: How many objects (``ALL``: every one that fits).
        how: ``named``, ``speaker`` or ``scored``.
        named: Objects the request names for it.
        score: The calibrated log-odds when scored.
        criterion: What decides which objects go there, in the request's words ("poisonous",
            "made entirely of glass"), when the request sorts by a property; "" otherwise.
        dish: The dish the request asks to be made ("hollandaise"), when the graph says it is one:
            the graph's concept, which its facts and evidence are read for.
        ingredients: The objects that go are the ingredients of food to prepare.
        rest: It takes whatever no other target takes ("the rest", "everything else").
        part: Where the request asks for several things of different kinds ("something to eat and
            something to drink", "I'm chilly and there's nothing to do"), what this one is for, as
            the questions say it ("as something to eat", 'for "I'm chilly"'); "" otherwise.
        dish_said: The dish in the request's own words ("tomato and cucumber salad", where the
            graph's concept is "salad"), which the model is asked about; "": as ``dish``.
        need: Where the request states two or more needs ("I'm chilly and there's nothing to
            do"), this one's own words ("I'm chilly"): its objects are decided as if it were the
            whole request; "" otherwise.
        helps: It takes what helps with a need the request states ("I can't make out this tiny
            print"): each object is asked "would the X help with what the person said?", and
            ranked with what the graph states it is for.
        excluded: Objects the request leaves out of it ("a drink that isn't the juice box"): never
            its candidates.
    """

    name: str
    count: int
    how: str
    named: list[str] = field(default_factory=list)
    score: float = 0.0
    criterion: str = ""
    dish: str = ""
    ingredients: bool = False
    rest: bool = False
    part: str = ""
    dish_said: str = ""
    need: str = ""
    helps: bool = False
    excluded: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        """JSON form for the trace."""
        return {
            "to": self.name,
            "count": "all" if self.count == ALL else self.count,
            "how": self.how,
            "named": list(self.named),
            "score": round(self.score, 3),
            "criterion": self.criterion,
            "dish": self.dish,
            "ingredients": self.ingredients,
            "rest": self.rest,
            **({"part": self.part} if self.part else {}),
        }


@dataclass(frozen=True)
class ReadingDoubt:
    """Where the request reads two ways: both readings in words, how likely each is the one meant,
    and the other reading's targets, made when asked for (scoring an open place is a model call).

    Attributes:
        taken: The reading the targets are, in words.
        other: The reading not taken, in words.
        p_taken: P(the reading taken is the one meant), from the step of the choice that kept it
            (and the model's preference, where it was asked).
        p_other: P(the reading not taken is).
        step: The step of the choice (:data:`conceptbot.pipeline.goal.aided.STEPS`).
        alternative: Reads the request as the other reading.
        preference: The model's log-odds for the reading taken over the other, which moved the
            step's odds (:mod:`conceptbot.pipeline.goal.judge`); None where it was not asked.
    """

    taken: str
    other: str
    p_taken: float
    p_other: float
    step: str
    alternative: Callable[[], TargetsRead]
    preference: float | None = None


@dataclass(frozen=True)
class TargetsRead:
    """A request's goal as the goal planner takes it (what a ``TargetReader`` returns).

    Attributes:
        stack: The request asks for a pile (no targets then).
        targets: Where things go, in the request's order.
        usage: The model calls made to read it.
        plain: The model's plain form of the request, where it was said plainly (else "").
        reading: Which reading the targets are: ``words`` (the rules on the request's words),
            ``plain`` (on the plain form), ``both`` (the two agree), or "" (only the words read).
        other: The reading not taken where the two differ, as goal-set JSON (else None).
        doubt: Where the two differ: what the planner needs to ask which was meant (else None).
    """

    stack: bool
    targets: list[Target]
    usage: Usage
    plain: str = ""
    reading: str = ""
    other: dict | None = None
    doubt: ReadingDoubt | None = None


class TargetFinder:
    """Targets, counts and named objects for a request (see the module docstring).

    Args:
        llm: An LLM that can score options (labelled ``goal``), for requests naming no destination.
        is_person: Whether a destination is a person.
        threshold: A scored destination other than the best is a target above this.
        food: What the graph knows about food (:class:`conceptbot.pipeline.goal_planner.decide.FactFinder`):
            which dish a request asks to be made, and which destinations food is made in; None:
            only the ``making`` words ("cook", "bake") say that a request is about preparing food,
            and every destination is a candidate for it.
    """

    def __init__(
        self,
        llm: LLM,
        is_person: Callable[[str], bool],
        threshold: float = 1.0,
        food: FoodKnowledge | None = None,
    ) -> None:
        self.llm = llm
        self.is_person = is_person
        self.threshold = threshold
        self.food = food

    def log_odds(self, request: str, dest: str) -> tuple[float, Usage]:
        """The log-odds of Yes to "should the robot put things in the X?" for ``request``."""
        action = f"give things to the {dest}" if self.is_person(dest) else f"put things in or on the {dest}"
        return self._yes_no(prompts.render("target_user", request=request, action=action))

    def prep_log_odds(self, dish: str, place: str) -> tuple[float, Usage]:
        """The log-odds of Yes to "to make the hollandaise, should the robot put the ingredients in
        or on the ceramic bowl?" (asked about the dish, not the request: for the request, the plate
        beat the bowl for a sauce)."""
        return self._yes_no(prompts.render("prep_user", dish=dish, place=place))

    def _yes_no(self, question: str) -> tuple[float, Usage]:
        """The log-odds of Yes against No for one question, scored in one pass."""
        messages = (Message("system", prompts.render("decide_system")), Message("user", question))
        scored = self.llm.score(ScoreRequest(options=("Yes", "No"), messages=messages))
        yes, no = scored.logprobs
        return yes - no, scored.usage

    def read(self, request: str, scene: Scene) -> TargetsRead:
        """Whether the request asks for a pile, and (unless it does) its targets (:meth:`find`)."""
        if is_stacking(request):
            return TargetsRead(True, [], Usage(calls=0))
        targets, usage = self.find(request, scene)
        return TargetsRead(False, targets, usage)

    def find(self, request: str, scene: Scene) -> tuple[list[Target], Usage]:
        """The targets, in the order the request names them (scored ones best first)."""
        started = time.perf_counter()
        usage = Usage(calls=0)
        vocab = words()
        people = {d: vocab["people"].get(d.lower(), []) for d in scene.destinations if self.is_person(d)}
        found = mentions(request, scene.destinations, people)
        seq = tokens(request)
        # Whether the request is about preparing food matters only where it names no destination.
        dish = (self.food.dish(request, scene.pickable) if self.food and not found else None) or ""
        making = bool(dish) or any(w in vocab["making"] for w in seq)
        how = "named"
        if not found and not making:
            speaker = [i for i, w in enumerate(seq) if w in vocab["speaker"]]
            users = [d for d in scene.destinations if d.lower() == "user"]
            if speaker and users:
                found, how = [(speaker[0], users[0])], "speaker"
        scores: dict[str, float] = {}
        if not found:
            how = "scored"
            candidates = list(scene.destinations)
            if making and self.food is not None:
                # Food is made in cookware where the scene has some: asked "should the robot put
                # things in the X?", the model preferred the fridge or the counter to the bowl.
                candidates = self.food.prep_places(candidates) or candidates
            for dest in candidates:
                odds, used = self.log_odds(request, dest)
                prior, used_prior = self.log_odds(CONTENT_FREE_REQUEST, dest)
                usage = usage + used + used_prior
                scores[dest] = odds - prior
            ranked = sorted(scores, key=lambda d: -scores[d])
            # Food is prepared in one place: the best-scored destination only.
            found = [
                (0, d) for i, d in enumerate(ranked) if i == 0 or (scores[d] > self.threshold and not making)
            ]
        targets = self._with_objects(request, scene, found, how, scores, making, dish)
        return targets, usage.with_latency(time.perf_counter() - started)

    def _with_objects(
        self,
        request: str,
        scene: Scene,
        found: list[tuple[int, str]],
        how: str,
        scores: dict[str, float],
        making: bool,
        dish: str,
    ) -> list[Target]:
        vocab = words()
        seq = tokens(request)
        taken = [i for at, name in found if how == "named" for i in range(at, at + len(tokens(name)))]
        objects = mentions(
            request, [o for o in scene.pickable if o not in {n for _, n in found}], taken=taken
        )
        clause = _clause_numbers(seq, vocab["clause_breaks"])
        named = _owners(found, objects, clause, how)
        says_all = any(w in vocab["all"] for w in seq)
        named_at = {i for at, obj in objects for i in range(at, at + len(tokens(obj)))}
        at_of = {name: at for at, name in found}
        targets = []
        for _, name in found:
            mine = set(clause)  # the whole request, unless the request names this target
            if how == "named":
                mine = self._own_clauses(name, found, objects, named[name], clause, at_of[name])
            part = [w for w, c in zip(seq, clause, strict=True) if c in mine]
            indefinite = sum(w in vocab["indefinite"] for w in part)
            free = [w for i, w in enumerate(seq) if clause[i] in mine and i not in named_at]
            if says_all or (making and how != "named"):
                count = ALL
            elif how == "speaker" and not named[name]:
                count = max(1, indefinite)  # "I'm cold": one thing for the speaker unless they say more
            elif _plural(free):
                count = ALL
            elif named[name] or indefinite:
                count = max(len(named[name]), indefinite)
            else:
                count = ALL
            criterion = ""
            if how == "named" and count == ALL and not named[name]:
                criterion = _place_criterion(name, found, seq, clause, mine, at_of[name], vocab)
            ingredients = making and how != "named" and not named[name]
            if ingredients:
                # Which objects go is a question about each one: "is the lime an ingredient of
                # guacamole?" ranked the ingredients above the rest better than "should the robot
                # put the lime in the mixing bowl?" on the dev split.
                criterion = f"an ingredient of {dish or 'the food the person asked for'}"
            targets.append(
                Target(
                    name,
                    count,
                    how,
                    named[name],
                    scores.get(name, 0.0),
                    criterion,
                    dish if ingredients else "",  # "a cake with flowers on the cake plate": no dish
                    ingredients,
                )
            )
        return targets

    def _own_clauses(
        self,
        name: str,
        found: list[tuple[int, str]],
        objects: list[tuple[int, str]],
        owned: list[str],
        clause: list[int],
        at: int,
    ) -> set[int]:
        """The clauses that speak about the target ``name`` named at token ``at``.

        A person's clauses run on to the next target ("the toddler is bored; give her something to
        play with"); a container's is the one that names it. Clauses of objects it owns count too.
        """
        start = clause[at]
        later = [clause[t_at] for t_at, _ in found if clause[t_at] > start]
        end = start + 1
        if self.is_person(name):
            end = min(later) if later else clause[-1] + 1
        return set(range(start, end)) | {clause[o_at] for o_at, obj in objects if obj in owned}


def _clause_numbers(seq: list[str], breaks: list[str]) -> list[int]:
    """For each token, the number of its clause (clauses split at "and", "then", ...)."""
    clause, number = [], 0
    for word in seq:
        number += word in breaks
        clause.append(number)
    return clause


def _owners(
    found: list[tuple[int, str]], objects: list[tuple[int, str]], clause: list[int], how: str
) -> dict[str, list[str]]:
    """The objects the request names, by the target they go to.

    A named object goes to the target of its own clause ("hand me the tape and put the gloves on
    the shelf"), else to the nearest target ("put the hammer and the screwdriver in the toolbox").
    """
    named: dict[str, list[str]] = {name: [] for _, name in found}
    for at, obj in objects:
        same = [name for t_at, name in found if clause[t_at] == clause[at]] if how == "named" else []
        nearest = min(found, key=lambda f: abs(f[0] - at))[1] if found else None
        owner = same[0] if same else nearest
        if owner is not None:
            named[owner].append(obj)
    return named


def _place_criterion(
    name: str,
    found: list[tuple[int, str]],
    seq: list[str],
    clause: list[int],
    mine: set[int],
    at: int,
    vocab: dict[str, list[str]],
) -> str:
    """What fits a named place that takes every fitting object: its clause's own words."""
    shared = sum(1 for t_at, _ in found if t_at == at) > 1
    if shared:  # "the wood, metal and fabric bins": each bin by its own name
        return f"belongs in the {name}"
    places = {i for t_at, other in found for i in range(t_at, t_at + len(tokens(other)))}
    kept = [w for i, w in enumerate(seq) if clause[i] in mine and i not in places]
    return _criterion(kept, [*vocab["not_criteria"], *vocab["clause_breaks"]])
