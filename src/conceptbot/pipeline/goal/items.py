"""Clauses as targets: :func:`clause_items` resolves each clause's theme and places (pronouns,
remainders, sort headers); :func:`item_targets` makes them the goal's targets (a sort: one per place).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from conceptbot.pipeline.goal.mentions import Mention
from conceptbot.pipeline.goal.parse import Clause, vocabulary
from conceptbot.pipeline.goal.themes import (
    Reading,
    conjuncts,
    criterion_text,
    head_of,
    objects_in,
    read_theme,
    read_themes,
)
from conceptbot.pipeline.goal.types import ALL, GoalTarget

if TYPE_CHECKING:
    from spacy.tokens import Doc


@dataclass
class _Item:
    """A theme sent to places (None: the planner chooses), before it becomes targets."""

    clause: Clause
    places: list[tuple[str, ...]]  # one entry per mention: a plural head gives several names
    theme: tuple[int, ...]
    key: str = ""
    shared: bool = False  # the theme is shared with the item before ("and the plastic bin")
    remainder: bool = False  # "otherwise it goes in A": what the conditions before leave


def names_itself(doc: Doc, run: Sequence[int], mentions: list[Mention]) -> bool:
    """Whether a phrase is a scene object ("the watering can"), not a thing made of some (a salad)."""
    head = head_of(doc, run)
    return head is not None and any(m.kind in ("object", "both") and m.covers(head.i) for m in mentions)


def indefinite(doc: Doc, run: Sequence[int]) -> bool:
    """Whether a wished-for phrase is "something ...", "anything ..." (not a dish)."""
    skip = {"a", "an", "the", "some", "really", "just"}
    first = next((i for i in run if doc[i].text.lower() not in skip), run[0])
    return doc[first].text.lower() in ("something", "anything", "someone", "somebody")


def clause_items(
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
        sorting = items and len({n for p in items[-1].places for n in p}) > 1
        if clause.key and not places and not clause.theme and sorting and not items[-1].key:
            items[-1].key = clause.key  # "... go in the recycling bins, | sorted by material"
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
            thing = clause.verb == "need" or any(indefinite(doc, p) for p in parts)
            if thing or any(names_itself(doc, p, mentions) for p in parts):
                items.append(_Item(clause, [tuple(users)] if users else [], clause.theme))
            continue
        if stay or clause.form in ("statement", "desire"):
            continue
        if (
            clause.form == "imperative"
            and clause.verb in vocab["making"]
            and not names_itself(doc, clause.theme, mentions)
        ):
            continue  # "make me a PB&J": a dish, not a thing to hand over
        if clause.form == "imperative" and not places and _says_pronoun(doc, clause):
            pending = pending or _pronoun_command(doc, clauses, n, mentions, items, users)
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
            _place_only(clauses, n, places, items)
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
        theme = _placed_theme(doc, clauses, n, mentions, items, places)
        if theme is None:
            continue  # "the dog would like a treat; give him one": said twice
        items.append(_Item(clause, places, theme, clause.key or pending))
        pending = ""
    return _without_headers(items, vocab)


def _pronoun_command(
    doc: Doc, clauses: list[Clause], n: int, mentions: list[Mention], items: list[_Item], users: list[str]
) -> str:
    """An instruction that sends only a pronoun ("hand it over"): what the clause before names goes,
    handed to the speaker for a handing verb. Returns the clause's sort key where it sends nothing
    yet ("sort these by what they're made of, each one ..."), else ""."""
    clause = clauses[n]
    handed = clause.verb in vocabulary()["handing"] and users
    if items and items[-1].places and not handed:
        return ""  # said twice: "the paper bin is for X; put those in"
    said = tuple(i for r in clause.runs for i in r)
    theme = items[-1].theme if items else ()
    if not theme and n:
        theme = antecedent(doc, clauses[n - 1], mentions, _plural(doc, said))
        if not handed and not objects_in(theme, mentions):
            return ""  # "we'll want a green salad; can you set that up?": a dish, not a thing
    if items and not items[-1].places:
        items.pop()
    if not theme:
        return clause.key
    items.append(_Item(clause, [tuple(users)] if handed else [], theme, clause.key))
    return ""


def _place_only(clauses: list[Clause], n: int, places: list[tuple[str, ...]], items: list[_Item]) -> None:
    """A fragment that names only places: it takes the theme of a colon pair ("Pears: the bowl",
    "the bowl: pears") or, after a soft boundary, the theme of the item before."""
    clause, prev = clauses[n], clauses[n - 1] if n else None
    if prev is not None and clause.chunk.after == "colon" and prev.form == "fragment" and not prev.places:
        if items and items[-1].clause is prev:
            items.pop()
        items.append(_Item(clause, places, prev.theme, clause.key))
        return
    if clause.chunk.after == "soft" and items and items[-1].places:
        items.append(_Item(clause, places, items[-1].theme, items[-1].key, shared=True))
        return
    nxt = clauses[n + 1] if n + 1 < len(clauses) else None
    if nxt is not None and nxt.chunk.after == "colon" and nxt.form == "fragment" and not nxt.places:
        items.append(_Item(clause, places, nxt.theme, clause.key))


def _placed_theme(
    doc: Doc,
    clauses: list[Clause],
    n: int,
    mentions: list[Mention],
    items: list[_Item],
    places: list[tuple[str, ...]],
) -> tuple[int, ...] | None:
    """What a clause with places sends: its theme, or for a pronoun what the clause or item before
    names ("I'm looking for X; pass it to me"); None where it repeats the item before."""
    clause, theme = clauses[n], clauses[n].theme
    if places and _pronoun_only(doc, theme) and not items and n:
        said = theme or tuple(i for r in clause.runs for i in r)
        theme = antecedent(doc, clauses[n - 1], mentions, _plural(doc, said)) or theme
    if places and _pronoun_only(doc, theme) and items:
        before = items[-1]
        if before.places == places:
            return None
        theme = before.theme
        fetched = before.clause.verb in vocabulary()["fetching"] and all(
            p.mention.kind == "person" for p in before.clause.places
        )
        if not before.places or fetched:
            items.pop()  # "fetch one game ... and set it on the coffee table", "grab us a game and ..."
    return theme


def _says_pronoun(doc: Doc, clause: Clause) -> bool:
    """Whether a clause sends only a pronoun ("hand it over", "put those in")."""
    said = [i for r in clause.runs for i in r]
    return (bool(said) and not clause.theme) or (bool(clause.theme) and _pronoun_only(doc, clause.theme))


def _plural(doc: Doc, run: Sequence[int]) -> bool | None:
    """Whether a pronoun theme is plural ("them", "they", "these"), singular ("it"), or says not."""
    words = {doc[i].text.lower() for i in run}
    if words & {"them", "they", "these", "those"}:
        return True
    return False if words & {"it", "this", "that"} else None


def antecedent(
    doc: Doc, clause: Clause, mentions: Sequence[Mention] = (), plural: bool | None = None
) -> tuple[int, ...]:
    """The tokens "it"/"them" refers back to in the clause before: the objects it names, else its last
    noun phrase that is not a person and agrees in number."""
    found: tuple[int, ...] = ()
    chunk = clause.chunk
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


def _pronoun_only(doc: Doc, run: Sequence[int]) -> bool:
    """Whether a theme is only a pronoun ("it", "them both", "all of them"), or empty."""
    pronouns = ("it", "them", "they", "one", "these", "those")
    words = [doc[i].text.lower() for i in run]
    return not run or (
        all(w in (*pronouns, "both", "all", "of") for w in words) and any(w in pronouns for w in words)
    )


def _without_headers(items: list[_Item], vocab: dict) -> list[_Item]:
    """Drops sort headers ("Sort the potted plants:") and place-less fragments paired with no place."""
    placed = any(i.places for i in items)
    kept = []
    for item in items:
        if not item.places and placed:
            clause = item.clause
            if clause.form == "fragment" or clause.verb in vocab["sort"]:
                continue
        if not item.places and item.clause.form == "fragment":
            continue
        kept.append(item)
    return kept


def item_targets(doc: Doc, items: list[_Item], mentions: list[Mention]) -> list[GoalTarget]:
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
        if theme and not group[0].remainder:
            # "the pear, the stapler and something to write with": each phrase of a list goes there
            readings = read_themes(doc, theme, mentions)
            if len(readings) > 1:
                targets += [GoalTarget(to, r.takes, r.named, r.criterion, r.count) for r in readings]
                continue
        reading = read_theme(doc, theme, mentions) if theme else Reading("all")
        if group[0].remainder:
            reading = Reading("remainder")
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
