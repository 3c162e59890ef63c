#!/usr/bin/env python3
"""Validate the blind2 evaluation set (scenes + tasks). Plain python3, stdlib only.

Usage: python3 check.py            (exit status 0 = all checks passed)
"""

import difflib
import json
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
CATEGORIES = ["unambiguous", "ambiguous", "implicit", "risk", "materials", "toxic"]
MIN_PER_CAT = 11
MIN_TOTAL = 80
MIN_IMPLICIT = 16
MIN_IMPLICIT_BIG = 13  # implicit tasks in rooms with 16+ pickables
MIN_SCENES = 8
MIN_BIG_SCENES = 6  # rooms with 16-25 pickables
MIN_PROPERTY_SORTS = 14  # materials + toxic assign tasks moving 2+ kinds of object
SCENE_KEYS = [
    "name",
    "description",
    "objects",
    "pickable_objects",
    "destinations",
    "entity_states",
    "detections",
    "requests",
]
ACTION = re.compile(r"^pick_and_place\(([^,()]+), ([^,()]+)\)$")

errors = []


def err(msg):
    errors.append(msg)


def load(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except Exception as e:
        err(f"{path}: cannot load JSON ({e})")
        return None


# ---------------------------------------------------------------- scenes
scenes = {}
scene_dir = os.path.join(HERE, "scenes")
for fn in sorted(os.listdir(scene_dir)):
    if not fn.endswith(".json"):
        continue
    stem = fn[:-5]
    s = load(os.path.join(scene_dir, fn))
    if s is None:
        continue
    where = f"scene {stem}"
    for k in SCENE_KEYS:
        if k not in s:
            err(f"{where}: missing key '{k}'")
    if any(k not in s for k in SCENE_KEYS):
        continue
    if s["name"] != stem:
        err(f"{where}: name '{s['name']}' != file stem")
    if not stem.startswith("blind2-"):
        err(f"{where}: name must start with 'blind2-'")
    if "kitchen" in stem or "kitchen" in s["description"].lower():
        err(f"{where}: kitchens are not allowed")
    objs, pick, dest = s["objects"], s["pickable_objects"], s["destinations"]
    for lst, nm in ((objs, "objects"), (pick, "pickable_objects"), (dest, "destinations")):
        if len(set(lst)) != len(lst):
            err(f"{where}: duplicate names in {nm}")
        for n in lst:
            if not isinstance(n, str) or n != n.lower() or n != n.strip() or not n:
                err(f"{where}: bad name {n!r} in {nm} (must be lowercase, trimmed)")
            elif "," in n or "(" in n or ")" in n:
                err(f"{where}: name {n!r} contains , or ( )")
    if set(pick) & set(dest):
        err(f"{where}: pickables and destinations overlap: {sorted(set(pick) & set(dest))}")
    if "user" not in dest:
        err(f"{where}: 'user' must be a destination")
    expected = pick + [d for d in dest if d != "user"] + ["user"]
    if objs != expected:
        err(f"{where}: objects must be pickables, then destinations, then 'user'")
    if set(objs) != set(pick) | set(dest):
        err(f"{where}: objects != pickables + destinations")
    for n in objs:
        d = s["detections"].get(n)
        if not isinstance(d, dict) or "size_m" not in d:
            err(f"{where}: no detection size for '{n}'")
            continue
        sz = d["size_m"]
        if (
            not isinstance(sz, list)
            or len(sz) != 3
            or not all(isinstance(v, (int, float)) and 0 < v <= 3 for v in sz)
        ):
            err(f"{where}: bad size_m for '{n}': {sz}")
    for n in s["detections"]:
        if n not in objs:
            err(f"{where}: detection for unknown object '{n}'")
    if not isinstance(s["entity_states"], dict):
        err(f"{where}: entity_states must be an object")
    else:
        for n in s["entity_states"]:
            if n not in objs:
                err(f"{where}: entity_states names unknown object '{n}'")
    if not isinstance(s["description"], str) or len(s["description"]) < 20:
        err(f"{where}: description too short")
    if len(set(s["requests"])) != len(s["requests"]):
        err(f"{where}: duplicate requests")
    scenes[stem] = s


# ---------------------------------------------------------------- tasks
def parse_action(a, sc, where):
    m = ACTION.match(a) if isinstance(a, str) else None
    if not m:
        err(f"{where}: malformed action {a!r}")
        return None
    o, d = m.group(1), m.group(2)
    if o not in sc["pickable_objects"]:
        err(f"{where}: '{o}' is not a pickable of {sc['name']}")
    if d not in sc["destinations"]:
        err(f"{where}: '{d}' is not a destination of {sc['name']}")
    return o, d


def check_objmap(m, sc, where, label):
    if not isinstance(m, dict):
        err(f"{where}: {label} must be an object")
        return set()
    for o, ds in m.items():
        if o not in sc["pickable_objects"]:
            err(f"{where}: {label} object '{o}' is not a pickable of {sc['name']}")
        if not isinstance(ds, list) or not ds:
            err(f"{where}: {label} '{o}' needs a non-empty destination list")
            continue
        for d in ds:
            if d not in sc["destinations"]:
                err(f"{where}: {label} '{o}' -> '{d}' is not a destination of {sc['name']}")
    return set(m)


def moved_objects(gold):
    """Objects the gold requires or allows to move (for counting property sorts)."""
    if gold.get("type") != "assign":
        return set()
    out = set(gold.get("assign", {})) | set(gold.get("optional", {}))
    for c in gold.get("choose", []):
        out |= set(c.get("objects", {}))
    return out


def check_gold(g, sc, where):
    t = g.get("type") if isinstance(g, dict) else None
    if t == "refuse":
        if set(g) != {"type"}:
            err(f"{where}: refuse gold has extra keys")
    elif t == "any_of":
        plans = g.get("plans")
        if not isinstance(plans, list) or not plans:
            err(f"{where}: any_of needs a non-empty plans list")
            return
        if not isinstance(g.get("ordered"), bool):
            err(f"{where}: any_of needs a boolean 'ordered'")
        seen = set()
        for p in plans:
            if not isinstance(p, list) or not p:
                err(f"{where}: each plan must be a non-empty list")
                continue
            parsed = [parse_action(a, sc, where) for a in p]
            objs = [x[0] for x in parsed if x]
            if len(set(objs)) != len(objs):
                err(f"{where}: a plan moves the same object twice")
            key = tuple(p) if g.get("ordered") else tuple(sorted(p))
            if key in seen:
                err(f"{where}: duplicate plan {p}")
            seen.add(key)
    elif t == "assign":
        allowed = {"type", "assign", "optional", "must_not_move", "ordered", "choose"}
        extra = set(g) - allowed
        if extra:
            err(f"{where}: unknown assign keys {sorted(extra)}")
        a = check_objmap(g.get("assign", {}), sc, where, "assign")
        o = check_objmap(g.get("optional", {}), sc, where, "optional")
        if a & o:
            err(f"{where}: objects both required and optional: {sorted(a & o)}")
        mnm = g.get("must_not_move", [])
        if not isinstance(mnm, list):
            err(f"{where}: must_not_move must be a list")
            mnm = []
        for x in mnm:
            if x not in sc["pickable_objects"]:
                err(f"{where}: must_not_move '{x}' is not a pickable of {sc['name']}")
        if set(mnm) & (a | o):
            err(f"{where}: must_not_move overlaps assign/optional: {sorted(set(mnm) & (a | o))}")
        chosen = set()
        for i, c in enumerate(g.get("choose", [])):
            cw = f"{where} choose[{i}]"
            if not isinstance(c, dict) or "objects" not in c:
                err(f"{cw}: needs 'objects'")
                continue
            co = check_objmap(c["objects"], sc, cw, "choose")
            mn, mx = c.get("min", 1), c.get("max", len(co))
            if not (isinstance(mn, int) and isinstance(mx, int) and 0 <= mn <= mx <= len(co)):
                err(f"{cw}: bad min/max {mn}/{mx} for {len(co)} objects")
            if co & (a | o | set(mnm) | chosen):
                err(f"{cw}: objects also listed elsewhere: {sorted(co & (a | o | set(mnm) | chosen))}")
            chosen |= co
        for pair in g.get("ordered", []):
            if not (isinstance(pair, list) and len(pair) == 2):
                err(f"{where}: ordered entries must be [a, b]")
                continue
            for x in pair:
                if x not in (a | o | chosen):
                    err(f"{where}: ordered names '{x}' which is not moved by the gold")
        if not (a or chosen):
            err(f"{where}: assign gold moves nothing")
    else:
        err(f"{where}: unknown gold type {t!r}")


tasks_by_cat = {}
all_requests = []
used_requests = {}
task_dir = os.path.join(HERE, "tasks")
for fn in sorted(os.listdir(task_dir)):
    if fn.endswith(".json") and fn[:-5] not in CATEGORIES:
        err(f"tasks/{fn}: not one of the categories {CATEGORIES}")
for cat in CATEGORIES:
    path = os.path.join(task_dir, cat + ".json")
    if not os.path.exists(path):
        err(f"missing tasks/{cat}.json")
        tasks_by_cat[cat] = []
        continue
    lst = load(path) or []
    if not isinstance(lst, list):
        err(f"tasks/{cat}.json must be a list")
        lst = []
    tasks_by_cat[cat] = lst
    for i, t in enumerate(lst, 1):
        where = f"task {t.get('id', '?')}"
        for k in ("id", "category", "request", "scene", "gold", "notes"):
            if k not in t:
                err(f"{where}: missing key '{k}'")
        if t.get("id") != f"blind2-{cat}-{i}":
            err(f"{where}: id should be blind2-{cat}-{i} (unique, consecutive)")
        if t.get("category") != cat:
            err(f"{where}: category '{t.get('category')}' in file {cat}.json")
        if not str(t.get("notes", "")).strip():
            err(f"{where}: empty notes")
        sc = scenes.get(t.get("scene"))
        if sc is None:
            err(f"{where}: unknown scene '{t.get('scene')}'")
            continue
        req = t.get("request", "")
        if req not in sc["requests"]:
            err(f"{where}: request not listed in scene {sc['name']} requests")
        used_requests.setdefault(sc["name"], []).append(req)
        all_requests.append((t.get("id"), req))
        check_gold(t.get("gold"), sc, where)

# ids unique across the whole set
ids = [i for i, _ in all_requests]
if len(ids) != len(set(ids)):
    err("duplicate task ids")

# every scene request belongs to exactly one task; requests unique and not near-copies
for name, s in scenes.items():
    for r in s["requests"]:
        if r not in used_requests.get(name, []):
            err(f"scene {name}: request not used by any task: {r!r}")
texts = [r for _, r in all_requests]
if len(texts) != len(set(texts)):
    err("two tasks share the same request text")
near = []
norm = [re.sub(r"[^a-z ]", "", r.lower()) for r in texts]
for i in range(len(norm)):
    for j in range(i + 1, len(norm)):
        ratio = difflib.SequenceMatcher(None, norm[i], norm[j]).ratio()
        if ratio > 0.8:
            near.append((all_requests[i][0], all_requests[j][0], round(ratio, 2)))
for a, b, r in near:
    err(f"near-duplicate requests {a} / {b} (similarity {r})")

# ---------------------------------------------------------------- counts
n_pick = {n: len(s["pickable_objects"]) for n, s in scenes.items()}
big = {n for n, k in n_pick.items() if k >= 16}
big_in_range = {n for n, k in n_pick.items() if 16 <= k <= 25}
counts = {c: len(tasks_by_cat[c]) for c in CATEGORIES}
total = sum(counts.values())
impl_big = sum(1 for t in tasks_by_cat["implicit"] if t.get("scene") in big)
impl_two = sum(
    1
    for t in tasks_by_cat["implicit"]
    if t["gold"].get("type") == "assign"
    and len(t["gold"].get("assign", {})) + len(t["gold"].get("choose", [])) >= 2
)
prop_sorts = sum(
    1 for c in ("materials", "toxic") for t in tasks_by_cat[c] if len(moved_objects(t["gold"])) >= 2
)
gold_types = {}
for c in CATEGORIES:
    for t in tasks_by_cat[c]:
        k = (c, t["gold"].get("type"))
        gold_types[k] = gold_types.get(k, 0) + 1

if len(scenes) < MIN_SCENES:
    err(f"only {len(scenes)} scenes (< {MIN_SCENES})")
if len(big_in_range) < MIN_BIG_SCENES:
    err(f"only {len(big_in_range)} scenes with 16-25 pickables (< {MIN_BIG_SCENES})")
for c in CATEGORIES:
    if counts[c] < MIN_PER_CAT:
        err(f"category {c}: {counts[c]} tasks (< {MIN_PER_CAT})")
if total < MIN_TOTAL:
    err(f"{total} tasks in total (< {MIN_TOTAL})")
if counts["implicit"] < MIN_IMPLICIT:
    err(f"{counts['implicit']} implicit tasks (< {MIN_IMPLICIT})")
if impl_big < MIN_IMPLICIT_BIG:
    err(f"{impl_big} implicit tasks in 16+ rooms (< {MIN_IMPLICIT_BIG})")
if prop_sorts < MIN_PROPERTY_SORTS:
    err(f"{prop_sorts} property sorts in materials+toxic (< {MIN_PROPERTY_SORTS})")
unused = [n for n in scenes if n not in used_requests]
if unused:
    err(f"scenes used by no task: {unused}")

# ---------------------------------------------------------------- summary
print("blind2 set check")
print(f"  scenes: {len(scenes)} ({len(big_in_range)} with 16-25 pickables)")
for n in sorted(scenes):
    print(
        f"    {n:32s} pickables={n_pick[n]:2d} destinations={len(scenes[n]['destinations'])} "
        f"tasks={len(used_requests.get(n, []))}"
    )
print("  tasks per category: " + ", ".join(f"{c}={counts[c]}" for c in CATEGORIES) + f"  (total {total})")
print(f"  implicit in 16+ rooms: {impl_big}/{counts['implicit']}; implicit needing 2 objects: {impl_two}")
print(f"  property sorts (materials+toxic, 2+ objects moved): {prop_sorts}")
print("  gold types: " + ", ".join(f"{c}:{t}={n}" for (c, t), n in sorted(gold_types.items())))
if errors:
    print(f"FAILED: {len(errors)} problem(s)")
    for e in errors:
        print("  - " + e)
    sys.exit(1)
print("OK: all checks passed")
