"""The pipeline's results as parts of a plan's trace (:mod:`conceptbot.core.trace`).

One home for the conversions, so each part's rounding is written once: similarities to 4 decimals,
targets' and judgements' scores as their own JSON forms round them
(:meth:`~conceptbot.pipeline.goal_planner.targets.Target.to_dict`,
:meth:`~conceptbot.pipeline.goal_planner.decide.Judgement.to_dict`). Each part is built from the typed
result, never read back from a dict.
"""

from __future__ import annotations

from collections.abc import Mapping

from conceptbot.core.trace import (
    EdgeTrace,
    JudgementTrace,
    ObjectTrace,
    OPETrace,
    RetrievalTrace,
    TargetTrace,
    URPTrace,
)
from conceptbot.pipeline.goal_planner.decide import Judgement
from conceptbot.pipeline.goal_planner.targets import ALL, Target
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.retrieval import Retrieval, edge_text
from conceptbot.pipeline.urp import URPResult


def retrieval_trace(retrieval: Retrieval) -> RetrievalTrace:
    """One concept's retrieval, every scored edge with its similarity."""
    return RetrievalTrace(
        matched=retrieval.matched,
        match=retrieval.match,
        notes=tuple(retrieval.notes),
        edges=tuple(
            EdgeTrace(edge_text(s.edge), s.edge.source, round(s.similarity, 4), s.target, s.kept)
            for s in retrieval.edges
        ),
    )


def retrievals_trace(retrievals: Mapping[str, Retrieval]) -> dict[str, RetrievalTrace]:
    """Retrievals by concept."""
    return {name: retrieval_trace(r) for name, r in retrievals.items()}


def ope_trace(
    mode: str,
    why: str,
    properties: Mapping[str, ObjectProperties],
    retrievals: Mapping[str, Retrieval] | None = None,
) -> OPETrace:
    """OPE's part: the mode and why, each object's values, and the retrievals behind them."""
    return OPETrace(
        mode=mode,
        why=why,
        objects={name: ObjectTrace(p.values, p.cached, tuple(p.relations)) for name, p in properties.items()},
        retrieval=retrievals_trace(retrievals or {}),
    )


def urp_trace(urp: URPResult) -> URPTrace:
    """URP's part: keywords, both sets of relations, reasoning, commands and refusal."""
    return URPTrace(
        keywords=tuple(urp.keywords),
        keyword_relations=retrievals_trace(urp.keyword_retrievals),
        object_relations=retrievals_trace(urp.object_retrievals),
        reasoning=urp.reasoning,
        commands=tuple(urp.commands),
        rejected_commands=tuple(urp.rejected_commands),
        refused=urp.refused,
        refusal_reason=urp.refusal_reason,
    )


def target_trace(target: Target) -> TargetTrace:
    """A goal target for the trace (count ``"all"``, score to 3 decimals, as its JSON form)."""
    return TargetTrace(
        to=target.name,
        count="all" if target.count == ALL else target.count,
        how=target.how,
        named=tuple(target.named),
        score=round(target.score, 3),
        criterion=target.criterion,
        dish=target.dish,
        ingredients=target.ingredients,
        rest=target.rest,
        part=target.part,
    )


def judgement_trace(judgement: Judgement, name_score: float | None = None) -> JudgementTrace:
    """A decision for the trace (as its JSON form rounds it), with the name ranking's score (3
    decimals) if any."""
    evidence = judgement.evidence
    return JudgementTrace(
        object=judgement.subject,
        p_yes=round(judgement.p_yes, 4),
        score=round(judgement.score, 3),
        facts=tuple(judgement.facts),
        name_score=None if name_score is None else round(name_score, 3),
        model=None if judgement.model is None else round(judgement.model, 3),
        evidence=None if evidence is None else evidence.to_dict(),
        p_one=None
        if judgement.p_one is None or judgement.p_one != judgement.p_one
        else round(judgement.p_one, 4),
        described=judgement.described,
    )
