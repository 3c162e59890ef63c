"""Whether the right reading of a request is among several plain forms sampled from the model.

The goal planner reads a request twice (the rules on its words, and on the model's greedy plain
form, ``pipeline/goal/restate.py``) and can ask which of the two was meant. Where both are wrong no
answer helps: on the 47 that is most of the tasks that fail whatever the person answers
(``docs/asking.md``). This measures, on rounds of the goal set, how often the gold is among the
words' reading, the greedy plain form's and ``--n`` plain forms sampled at ``--temperature``, and
how many distinct readings a question would then have to list (its cost in help). Nothing is tuned
here; the greedy records come from ``bench_restated_reading.py`` (``--greedy``).

Rows go to ``--out`` (JSON lines) as they are read; a second run skips rows already there with the
same prompt, ``n``, temperature and seed (resume). The model's calls go through the answer cache.

    .venv/bin/python benchmarks/bench_sampled_reading.py --rounds 9 10 11 \
        --out results/parts/sampled.jsonl
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from conceptbot.bench.grading import load_dev_scene
from conceptbot.core.config import load_settings
from conceptbot.models.registry import open_llm
from conceptbot.pipeline.goal import Goal, GoalReader, same_goal
from conceptbot.pipeline.goal.aided import choose
from conceptbot.pipeline.goal.aided import votes as counted_votes
from conceptbot.pipeline.goal.restate import PLACEHOLDER, TEMPERATURE, Restater

# The greedy records and the reader are the restated reading benchmark's (a sibling script).
sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_restated_reading as restated

PROMPT: str = restated.PROMPT
graph_reader = restated.graph_reader
GREEDY = Path("results/parts/goal-set.jsonl")


def _key(record: dict[str, Any], n: int, temperature: float, seed: int) -> str:
    return f"{record['key']}|n{n}|t{temperature}|s{seed}"


def _distinct(goals: Sequence[Goal]) -> list[Goal]:
    kept: list[Goal] = []
    for goal in goals:
        if not any(same_goal(goal, k).ok for k in kept):
            kept.append(goal)
    return kept


def read_rows(
    records: Sequence[dict[str, Any]],
    out: Path,
    reader: GoalReader,
    restater: Restater,
    n: int,
    temperature: float,
    seed: int,
) -> None:
    """Sample and read each greedy record not yet in ``out``; append one row per record."""
    done = set()
    if out.exists():
        done = {json.loads(x)["key"] for x in out.read_text(encoding="utf-8").splitlines() if x}
    todo = [r for r in records if _key(r, n, temperature, seed) not in done]
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("a", encoding="utf-8") as sink:
        for i, record in enumerate(todo, 1):
            scene = load_dev_scene(_scene(record))
            gold = Goal.from_dict(record["gold"])
            started = time.perf_counter()
            said = restater.variants(record["request"], n, temperature, seed)
            goals = [reader.read(s.text, scene) for s in said if s.text]
            row = {
                "key": _key(record, n, temperature, seed),
                "task": record["task"],
                "round": record["round"],
                "request": record["request"],
                "samples": [s.text for s in said],
                "sampled_ok": [same_goal(g, gold).ok for g in goals],
                "sampled_goals": [g.to_dict() for g in goals],
                "seconds": round(time.perf_counter() - started, 2),
            }
            sink.write(json.dumps(row) + "\n")
            sink.flush()
            print(f"\r{i}/{len(todo)} sampled", end="", file=sys.stderr, flush=True)
    if todo:
        print(file=sys.stderr)


_SCENES: dict[str, str] = {}


def _scene(record: dict[str, Any]) -> str:
    """The dev scene of a goal-set record (the goal set names it per row)."""
    if not _SCENES:
        for row in json.loads(restated.GOAL_SET.read_text(encoding="utf-8"))["requests"]:
            _SCENES[row["task"]] = row["scene"]
    return _SCENES[record["task"]]


def _checked(row: dict[str, Any]) -> dict[str, Any]:
    """A row as today's restater would have read it: samples that copy a placeholder of the prompt
    (``restate.PLACEHOLDER``, checked since 2026-12-04) give no reading."""
    read = [text for text in row["samples"] if text]  # the samples that were read, in order
    keep = [not PLACEHOLDER.search(text) for text in read]
    return {
        **row,
        "sampled_ok": [ok for ok, k in zip(row["sampled_ok"], keep, strict=True) if k],
        "sampled_goals": [g for g, k in zip(row["sampled_goals"], keep, strict=True) if k],
    }


def report(greedy: dict[str, dict[str, Any]], rows: Sequence[dict[str, Any]]) -> None:
    """Per round: words, greedy plain, either, any sampled, all together; distinct readings."""
    print(f"{'round':>6} {'n':>4} {'words':>7} {'greedy':>7} {'either':>7} {'sampled':>8} {'any':>7} "
          f"{'distinct':>9} {'>2 read':>8}")  # fmt: skip

    def line(label: str, these: list[dict[str, Any]]) -> None:
        if not these:
            return
        total = len(these)
        words = plain = either = sampled = anyone = distinct = many = 0
        for row in these:
            g = greedy[row["key"].split("|n")[0]]
            w, p, s = g["words_ok"], g["plain_ok"], any(row["sampled_ok"])
            words += w
            plain += p
            either += w or p
            sampled += s
            anyone += w or p or s
            goals = [Goal.from_dict(g["words_goal"])]
            goals += [Goal.from_dict(g["plain_goal"])] if g["plain_goal"] else []
            goals += [Goal.from_dict(x) for x in row["sampled_goals"]]
            count = len(_distinct(goals))
            distinct += count
            many += count > 2
        cells = [words, plain, either, sampled, anyone]
        print(f"{label:>6} {total:>4} " + " ".join(f"{100 * c / total:6.1f}%" for c in cells)
              + f" {distinct / total:9.2f} {100 * many / total:7.1f}%")  # fmt: skip

    for number in sorted({r["round"] for r in rows}):
        line(str(number) if number else "orig", [r for r in rows if r["round"] == number])
    line("all", list(rows))


def vote_sets(
    greedy: dict[str, dict[str, Any]], rows: Sequence[dict[str, Any]], votes: int
) -> tuple[int, int, int]:
    """The rule "the reading taken, and every reading that at least ``votes`` of the pool (the words',
    the greedy plain form's and the samples') read alike": per row, whether the set holds the gold,
    and over the rows how many sets hold it, how many hold more than one reading (a question) and
    how many readings they hold in all."""
    covered = asked = size = 0
    for row in rows:
        g = greedy[row["key"].split("|n")[0]]
        words = Goal.from_dict(g["words_goal"])
        plain = Goal.from_dict(g["plain_goal"]) if g["plain_goal"] else None
        taken = choose(words, plain, "grounded", g["request"], g["plain"]).goal
        pool = [words, *([plain] if plain else []), *(Goal.from_dict(x) for x in row["sampled_goals"])]
        kept = [taken, *(goal for goal, n in counted_votes(pool, [taken]) if n >= votes)]
        gold = Goal.from_dict(g["gold"])
        covered += any(same_goal(goal, gold).ok for goal in kept)
        asked += len(kept) > 1
        size += len(kept)
    return covered, asked, size


def report_sets(greedy: dict[str, dict[str, Any]], rows: Sequence[dict[str, Any]]) -> None:
    """Per round: the two readings (asked where they differ) against the vote rule, each as the share
    of rows whose set holds the gold and the share with a question."""
    print(f"\n{'round':>6} {'n':>4} {'pair: holds':>12} {'asked':>6}"
          + "".join(f" {f'>={v} votes: holds':>17} {'asked':>6}" for v in (1, 2, 3)))  # fmt: skip
    for number in sorted({r["round"] for r in rows}):
        these = [r for r in rows if r["round"] == number]
        total = len(these)
        pairs = [greedy[r["key"].split("|n")[0]] for r in these]
        cells = [sum(p["words_ok"] or p["plain_ok"] for p in pairs), sum(not p["agree"] for p in pairs)]
        for votes in (1, 2, 3):
            covered, asked, _ = vote_sets(greedy, these, votes)
            cells += [covered, asked]
        label = str(number) if number else "orig"
        print(f"{label:>6} {total:>4} " + "".join(
            f" {100 * c / total:{17 if i > 1 and i % 2 == 0 else 11 if i == 0 else 5}.1f}%"
            for i, c in enumerate(cells)))  # fmt: skip


def main() -> None:
    """Sample the chosen rounds and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", nargs="+", type=int, required=True, help="0 for the originals")
    parser.add_argument("--out", type=Path, required=True, help="JSON lines, resumed")
    parser.add_argument("--greedy", type=Path, default=GREEDY, help="bench_restated_reading.py's records")
    parser.add_argument("-n", type=int, default=4, help="plain forms sampled per request")
    parser.add_argument("--temperature", type=float, default=TEMPERATURE)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    records = [json.loads(x) for x in args.greedy.read_text(encoding="utf-8").splitlines() if x]
    records = [r for r in records if r["key"].endswith(f"|{PROMPT}") and r["round"] in args.rounds]
    if not records:
        parser.error(f"no greedy records of rounds {args.rounds} in {args.greedy} with today's prompt")
    restater = Restater(open_llm(load_settings(), module="restate"))
    read_rows(records, args.out, graph_reader(), restater, args.n, args.temperature, args.seed)
    wanted = {_key(r, args.n, args.temperature, args.seed) for r in records}
    rows = [_checked(json.loads(x)) for x in args.out.read_text(encoding="utf-8").splitlines() if x]
    chosen = [r for r in rows if r["key"] in wanted]
    report({r["key"]: r for r in records}, chosen)
    report_sets({r["key"]: r for r in records}, chosen)


if __name__ == "__main__":
    main()
