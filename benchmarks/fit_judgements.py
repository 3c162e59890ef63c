"""Fit and measure the combination of the model's judgement and the graph's evidence on the judgement
set, and write the weights the planner ships (``src/conceptbot/pipeline/judgement_weights.json``).

Reads the model's readings (``benchmarks/judgement_readings.py``), computes each row's evidence
from the offline graph (and, for the no-graph ablation, from the object's name only), and reports,
on held-out folds (5 folds by object: an object's rows are never both fitted and scored), the
accuracy per kind of:

* ``model``: the default system's question alone (Yes when its calibrated log-odds is above 0; a
  criterion of safety is asked without facts, as the planner asks it, so there it is the plain
  question);
* ``model-fit``: the same with a fitted threshold (a logistic regression on it alone);
* ``model-group``: the model's readings within the objects asked together (as read, standardised
  in the group, its gap below the best), with the criterion's kind;
* ``plain-group``: the same of the question without facts (what the facts do to the model's answer);
* ``graph``: the evidence features alone;
* ``combined``: model + evidence (the default system's combination);
* ``combined+plain``: also the question without facts (one more question per object);
* ``combined+inter``: also the readings without facts, and every reading and statement per kind of
  criterion (measured, not shipped: a point above ``combined`` for one more question per object);
* ``combined+split``: the combination with the materials counted apart, the name's and those only
  the graph adds (measured, not shipped: multi-material 61% -> 67%, a third of a point overall);
* ``nokg``: the question without facts and the name features (the no-graph ablation's combination).

With ``--described FILE`` (``judgement_described.py``) only the rows it read are scored, and two more
variants take the model's answer with its own description of the object in the question:
``combined+described`` and ``nokg+described``.

With ``--conformal`` it also calibrates split conformal prediction on the combination's held-out
probabilities (:mod:`conceptbot.pipeline.goal_planner.conformal`): per coverage, the threshold
fitted on four folds and measured on the fifth (empirical coverage, the share of decisions with one
answer, and how often that one is right), and with ``--write`` the thresholds fitted on every row
(``src/conceptbot/pipeline/conformal.json``).

    .venv/bin/python benchmarks/fit_judgements.py [--readings FILE] [--write] [--conformal]
"""

from __future__ import annotations

import argparse
import json
import zlib
from pathlib import Path

import numpy as np

from conceptbot.core.config import load_settings
from conceptbot.knowledge.registry import open_graph
from conceptbot.pipeline.goal_planner.combine import value
from conceptbot.pipeline.goal_planner.conformal import (
    CALIBRATION_DOC,
    COVERAGES,
    conformal_threshold,
    decision_set,
)
from conceptbot.pipeline.goal_planner.decide import group_readings
from conceptbot.pipeline.goal_planner.evidence import FEATURES, GRAPH_FREE, GraphEvidence

FOLDS = 5
L2 = 1.0  # 0.1 and 3 fitted within a point of it on held-out folds; 10 was worse
WEIGHTS = Path("src/conceptbot/pipeline/judgement_weights.json")
CONFORMAL = Path("src/conceptbot/pipeline/conformal.json")
GROUP = (
    "model", "model_z", "model_gap", "is_dish", "model*is_dish", "model_gap*is_dish", "is_material",
    "is_several", "model*is_several",
)  # fmt: skip
#: What the graph states, by the kind of criterion (a hazard statement means something else for "safe").
STATED = (
    *(
        f"{f}*is_{g}"
        for f in ("own_yes", "own_no", "kind_yes", "kind_no")
        for g in ("safe", "poison", "food")
    ),
    "model*is_safe",
    "model*is_poison",
)
#: The criterion's kind, as the evidence reads it from the criterion's words.
KIND_FLAGS = ("is_poison", "is_food", "is_safe", "is_material", "is_several", "is_dish")
#: Each reading (with facts, and without: ``plain_*``) and each statement, per kind of criterion.
INTERACTIONS = (
    *(f"{m}*{k}" for m in ("model_z", "model_gap", "plain_z", "plain_gap") for k in KIND_FLAGS),
    *(
        f"{f}*{k}"
        for f in ("own_yes", "own_no", "kind_yes", "kind_no", "name_yes", "name_no")
        for k in KIND_FLAGS
    ),
)
#: The materials a row's evidence counts, apart: those its name states, and those only the graph adds.
SPLIT_MATERIALS = ("name_materials", "graph_materials")
VARIANTS = {
    "model": None,
    "model-fit": ("model",),
    "model-group": GROUP,
    "plain-group": tuple(n.replace("model", "plain") for n in GROUP),
    "graph": FEATURES,
    "combined": tuple(dict.fromkeys((*GROUP, *FEATURES))),
    "combined+kinds": tuple(dict.fromkeys((*GROUP, *FEATURES, *STATED))),
    "combined+plain": tuple(dict.fromkeys((*GROUP, "plain", *FEATURES, *STATED))),
    "combined+inter": tuple(
        dict.fromkeys((*GROUP, "plain", "plain_z", "plain_gap", *FEATURES, *INTERACTIONS))
    ),
    "combined+split": tuple(
        dict.fromkeys((*GROUP, *(f for f in FEATURES if f != "materials_named"), *SPLIT_MATERIALS))
    ),
    "nokg": tuple(dict.fromkeys((*GROUP, *GRAPH_FREE))),
}
#: The described reading (``--described``): as read, standardised in its group, and its gap.
DESCRIBED = ("described", "described_z", "described_gap")
#: The described reading per kind of criterion (a description names one material: "several" reads it
#: the other way round).
DESCRIBED_KINDS = ("described*is_several", "described*is_dish", "described*is_poison", "described*is_safe")
DESCRIBED_INTER = tuple(f"{m}*{k}" for m in ("described_z", "described_gap") for k in KIND_FLAGS)
DESCRIBED_VARIANTS = {
    "described": ("described",),
    "combined+described": tuple(dict.fromkeys((*GROUP, *DESCRIBED, *FEATURES))),
    "combined+desc+kinds": tuple(dict.fromkeys((*GROUP, *DESCRIBED, *DESCRIBED_KINDS, *FEATURES))),
    "inter+described": tuple(
        dict.fromkeys((*GROUP, "plain", "plain_z", "plain_gap", *DESCRIBED, *FEATURES, *INTERACTIONS))
    ),
    "inter+desc+inter": tuple(
        dict.fromkeys(
            (*GROUP, "plain", "plain_z", "plain_gap", *DESCRIBED, *FEATURES, *INTERACTIONS, *DESCRIBED_INTER)
        )
    ),
    "nokg+described": tuple(dict.fromkeys((*GROUP, *DESCRIBED, *GRAPH_FREE))),
    # The no-graph twin of inter+desc+inter: its one question has no facts (so no plain reading),
    # and only the interactions of readings and names.
    "nokg+inter+desc": tuple(
        dict.fromkeys(
            (
                *GROUP,
                *DESCRIBED,
                *GRAPH_FREE,
                *(
                    f
                    for f in INTERACTIONS
                    if f.split("*")[0] in ("model_z", "model_gap", "name_yes", "name_no")
                ),
                *DESCRIBED_INTER,
            )
        )
    ),
    "nokg+desc+kinds": tuple(dict.fromkeys((*GROUP, *DESCRIBED, *DESCRIBED_KINDS, *GRAPH_FREE))),
}
#: The combinations shipped: the default system's and the no-graph ablation's.
SHIPPED = (("graph", "combined"), ("nograph", "nokg"))
#: The same with the described reading (``--described`` over every row).
SHIPPED_DESCRIBED = (("graph", "inter+desc+inter"), ("nograph", "nokg+inter+desc"))


def fit(x: np.ndarray, y: np.ndarray, l2: float = L2) -> tuple[np.ndarray, float]:
    """Logistic regression by Newton's method with an L2 penalty on the weights (not the bias)."""
    n, d = x.shape
    a = np.hstack([x, np.ones((n, 1))])
    w = np.zeros(d + 1)
    penalty = np.eye(d + 1) * l2
    penalty[d, d] = 0.0
    for _ in range(50):
        p = 1.0 / (1.0 + np.exp(-(a @ w)))
        grad = a.T @ (p - y) + penalty @ w
        hess = a.T @ (a * (p * (1 - p))[:, None]) + penalty + 1e-9 * np.eye(d + 1)
        step = np.linalg.solve(hess, grad)
        w -= step
        if np.abs(step).max() < 1e-8:
            break
    return w[:d], float(w[d])


def fold(obj: str) -> int:
    """An object's fold (stable across runs and machines)."""
    return zlib.crc32(obj.lower().encode()) % FOLDS


def matrix(rows: list[dict], names: tuple[str, ...], ablation: bool = False) -> np.ndarray:
    """The rows' features; for the no-graph ablation, its own readings and evidence (``nokg_``)."""
    prefix = "nokg_" if ablation else ""
    return np.array(
        [
            [value({k[len(prefix) :]: v for k, v in r.items() if k.startswith(prefix)}, n) for n in names]
            for r in rows
        ],
        dtype=float,
    )


def add_group_readings(rows: list[dict]) -> None:
    """Each row's readings standardised within its group (the objects asked together), as the
    planner computes them (``decide.group_readings``): with facts, and without (the ablation's)."""
    groups: dict[tuple[str, str], list[dict]] = {}
    for row in rows:
        groups.setdefault((row["request"], row["criterion"]), []).append(row)
    for members in groups.values():
        with_facts = group_readings({r["object"]: r["model"] for r in members})
        without = group_readings({r["object"]: r["plain"] for r in members})
        described = (
            group_readings({r["object"]: r["described"] for r in members})
            if all("described" in r for r in members)
            else {}
        )
        for r in members:
            r.update(with_facts[r["object"]])
            r.update({f"nokg_{k}": v for k, v in without[r["object"]].items()})
            r.update({f"plain{k[len('model') :]}": v for k, v in without[r["object"]].items()})
            for k, v in described.get(r["object"], {}).items():
                name = f"described{k[len('model') :]}"
                r[name] = r[f"nokg_{name}"] = v


def coverage(rows: list[dict]) -> None:
    """Per kind: how often the graph states something of the object itself (its edges, gloss or
    name) and how often that is right; how often only something of its kind (an IsA parent's)."""
    print(f"\n{'kind':16} {'n':>4} {'own':>5} {'right':>6} {'kind':>5} {'right':>6} {'none':>5}")
    for kind in [*sorted({r["kind"] for r in rows}), "all"]:
        chosen = [r for r in rows if kind in ("all", r["kind"])]
        yes = {id(r): r.get("own_yes", 0) + r.get("name_yes", 0) for r in chosen}
        no = {id(r): r.get("own_no", 0) + r.get("name_no", 0) for r in chosen}
        own = [r for r in chosen if yes[id(r)] or no[id(r)]]
        own_right = sum((yes[id(r)] > no[id(r)]) == bool(r["y"]) for r in own)
        only_kind = [r for r in chosen if r not in own and (r.get("kind_yes") or r.get("kind_no"))]
        kind_right = sum((r.get("kind_yes", 0) > r.get("kind_no", 0)) == bool(r["y"]) for r in only_kind)
        print(
            f"{kind:16} {len(chosen):>4} {len(own):>5} {own_right / max(1, len(own)):>6.0%} "
            f"{len(only_kind):>5} {kind_right / max(1, len(only_kind)):>6.0%} "
            f"{len(chosen) - len(own) - len(only_kind):>5}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--readings", type=Path, default=Path("results/parts/judgements-qwen2.5-coder-1.5b.jsonl")
    )
    parser.add_argument("--write", action="store_true", help=f"write the fitted weights to {WEIGHTS}")
    parser.add_argument("--errors", action="store_true", help="print the combination's held-out errors")
    parser.add_argument("--conformal", action="store_true", help="calibrate conformal prediction too")
    parser.add_argument(
        "--described", type=Path, default=None, help="judgement_described.py's readings: score those rows"
    )
    args = parser.parse_args(argv)
    rows = [json.loads(line) for line in args.readings.read_text(encoding="utf-8").splitlines() if line]
    variants = dict(VARIANTS)
    shipped = SHIPPED
    if args.described is not None:
        found = {}
        for line in args.described.read_text(encoding="utf-8").splitlines():
            if line.strip():
                r = json.loads(line)
                found[(r["object"], r["criterion"], r["request"])] = r["described"]
        every = len(rows)
        rows = [r for r in rows if (r["object"], r["criterion"], r["request"]) in found]
        for r in rows:
            r["described"] = found[(r["object"], r["criterion"], r["request"])]
        variants.update(DESCRIBED_VARIANTS)
        if len(rows) < every and args.write:
            parser.error(f"--described read {len(rows)} of the {every} rows: the weights need every row")
        shipped = SHIPPED_DESCRIBED
    graph = GraphEvidence(open_graph(load_settings(), fallback=False))
    names_only = GraphEvidence(None)
    for row in rows:
        with_graph = graph.read(row["object"], row["criterion"])
        row.update(with_graph.features)
        row["statements"] = list(with_graph.statements)
        row.update(
            {f"nokg_{k}": v for k, v in names_only.read(row["object"], row["criterion"]).features.items()}
        )
        row["y"] = 1.0 if row["answer"] else 0.0
        row["name_materials"] = row["nokg_materials_named"]
        row["graph_materials"] = max(0.0, row["materials_named"] - row["name_materials"])
    add_group_readings(rows)
    y = np.array([r["y"] for r in rows])
    folds = np.array([fold(r["object"]) for r in rows])
    predicted: dict[str, np.ndarray] = {}
    # Each shipped combination's P(yes), each row scored by a fit without it (for --conformal).
    held_out_p = {variant: np.zeros(len(rows)) for _, variant in shipped}
    log_loss: dict[str, float] = {}  # held-out, over every row: how sharp and honest P(yes) is
    for variant, names in variants.items():
        if names is None:
            predicted[variant] = np.array([r["model"] > 0 for r in rows], dtype=float)
            continue
        x = matrix(rows, names, ablation=variant.startswith("nokg"))
        out = np.zeros(len(rows))
        p_out = np.zeros(len(rows))
        for k in range(FOLDS):
            train, test = folds != k, folds == k
            w, b = fit(x[train], y[train])
            out[test] = (x[test] @ w + b) > 0
            p_out[test] = 1.0 / (1.0 + np.exp(-(x[test] @ w + b)))
        held_out_p[variant] = p_out
        p_clipped = np.clip(p_out, 1e-6, 1 - 1e-6)
        log_loss[variant] = float(-np.mean(y * np.log(p_clipped) + (1 - y) * np.log(1 - p_clipped)))
        predicted[variant] = out
    kinds = sorted({r["kind"] for r in rows})
    header = f"{'kind':16} {'n':>4} " + " ".join(f"{v:>15}" for v in variants)
    print(header)
    for kind in [*kinds, "all"]:
        mask = np.array([kind in ("all", r["kind"]) for r in rows])
        cells = " ".join(f"{(predicted[v][mask] == y[mask]).mean():>15.1%}" for v in variants)
        print(f"{kind:16} {int(mask.sum()):>4} {cells}")
    cells = " ".join(f"{log_loss[v]:>15.3f}" if v in log_loss else f"{'-':>15}" for v in variants)
    print(f"{'log-loss':16} {len(rows):>4} {cells}")
    # How sharp: the share of rows whose conformal set at 0.9 holds one answer (threshold from four
    # folds, measured on the fifth).
    cells = " ".join(
        f"{sure_share(held_out_p[v], y, folds, 0.9):>15.1%}" if v in log_loss else f"{'-':>15}"
        for v in variants
    )
    print(f"{'one answer @0.9':16} {len(rows):>4} {cells}")
    stated = np.array([any(r[f] for f in FEATURES if f not in GRAPH_FREE) for r in rows])
    print(f"\nrows where the graph states something: {int(stated.sum())} of {len(rows)}")
    for v in ("model", "graph", "combined"):
        right = (predicted[v][stated] == y[stated]).mean() if stated.any() else 0.0
        print(f"  {v} right on {right:.1%} of them")
    coverage(rows)
    if args.errors:
        for r, p in zip(rows, predicted["combined"], strict=True):
            if p != r["y"]:
                print(
                    f"WRONG {r['kind']:14} {r['object']:24} {r['criterion'][:40]:40} "
                    f"answer={r['answer']!s:5} model={r['model']:+.2f} {'; '.join(r['statements'])[:160]}"
                )
    fitted = {}
    for name, variant in shipped:
        names = variants[variant]
        assert names is not None
        w, b = fit(matrix(rows, names, ablation=variant.startswith("nokg")), y)
        fitted[name] = {
            "features": list(names),
            "weights": [round(float(v), 4) for v in w],
            "bias": round(b, 4),
        }
        print(
            f"{name}: "
            + ", ".join(f"{n} {v:+.2f}" for n, v in zip(names, w, strict=True))
            + f", bias {b:+.2f}"
        )
    qhat = (
        {name: conformal(held_out_p[variant], y, folds, name) for name, variant in shipped}
        if args.conformal
        else {}
    )
    if args.write and qhat:
        # Only the decision-level entries: the plan-level ones are fit_conformal_plans.py's.
        data = json.loads(CONFORMAL.read_text(encoding="utf-8")) if CONFORMAL.exists() else {}
        data.update(
            {
                "_doc": CALIBRATION_DOC,
                "fitted_on": f"{args.readings.name}, {len(rows)} rows",
                "qhat": {
                    name: {str(c): round(q, 4) for c, q in fitted.items()} for name, fitted in qhat.items()
                },
            }
        )
        CONFORMAL.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {CONFORMAL}")
    if args.write:
        doc = {
            "_doc": "Written by benchmarks/fit_judgements.py from the judgement set's readings with "
            f"{args.readings.name}; read by conceptbot.pipeline.goal_planner.combine. "
            "Refit for another model.",
            "readings": args.readings.name,
            **({"described": args.described.name} if args.described is not None else {}),
            "rows": len(rows),
            "combinations": fitted,
        }
        WEIGHTS.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {WEIGHTS}")
    return 0


def sure_share(p_yes: np.ndarray, y: np.ndarray, folds: np.ndarray, coverage: float) -> float:
    """The share of rows whose held-out conformal set at ``coverage`` holds one answer."""
    scores = np.where(y == 1.0, 1.0 - p_yes, p_yes)
    sure = 0
    for k in range(FOLDS):
        q = conformal_threshold(scores[folds != k].tolist(), coverage)
        sure += sum(decision_set(float(p), q).sure for p in p_yes[folds == k])
    return sure / len(y)


def conformal(p_yes: np.ndarray, y: np.ndarray, folds: np.ndarray, name: str) -> dict[float, float]:
    """Print, per coverage, the conformal sets' held-out figures (threshold from four folds, measured
    on the fifth); return the thresholds fitted on every row."""
    scores = np.where(y == 1.0, 1.0 - p_yes, p_yes)  # 1 - P(the right answer)
    print(f"\nconformal prediction on the {name} combination (threshold from 4 folds, measured on the 5th):")
    print(f"{'coverage':>8} {'empirical':>9} {'one answer':>10} {'right when one':>14} {'qhat':>6}")
    fitted = {}
    for coverage in COVERAGES:
        covered = sure = right = 0
        for k in range(FOLDS):
            q = conformal_threshold(scores[folds != k].tolist(), coverage)
            for p, label in zip(p_yes[folds == k], y[folds == k], strict=True):
                found = decision_set(float(p), q)
                answer = "yes" if label == 1.0 else "no"
                covered += answer in found.answers
                if found.sure:
                    sure += 1
                    right += found.answers[0] == answer
        fitted[coverage] = conformal_threshold(scores.tolist(), coverage)
        print(
            f"{coverage:>8.2f} {covered / len(y):>9.1%} {sure / len(y):>10.1%} "
            f"{(right / sure if sure else 0.0):>14.1%} {fitted[coverage]:>6.3f}"
        )
    return fitted


if __name__ == "__main__":
    raise SystemExit(main())
