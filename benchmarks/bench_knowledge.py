"""Knowledge-layer benchmark: look-up latency, ConceptNet 5 import at full size, paper-object coverage.

Run: .venv/bin/python benchmarks/bench_knowledge.py [--lookup] [--import] [--coverage]
     (no flag: all three; the import part generates a full-size dump once, ~10 GB uncompressed,
     in --work-dir, default /tmp/conceptbot-bench)

* look-up: warm latency per concept (median, p95) for 1,000 random concepts of the installed graph
  (each concept is queried once to warm the page cache, then timed), limit 100.
* import: a generated ConceptNet 5.7 assertions dump in the exact format (34M lines, 10% with both
  ends English, like the real one) imported by ``install_conceptnet5`` in a child process:
  wall time, English edges/s, lines/s and the child's peak memory.
* coverage: for every object named in the paper's tables, how the graph matched it (exact/lemma,
  head noun, modifier, none) and with how many edges; the Wikipedia fallback is tried too and its
  availability reported.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import random
import resource
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from conceptbot.core.config import load_settings
from conceptbot.core.errors import KnowledgeUnavailableError
from conceptbot.knowledge.registry import open_graph
from conceptbot.knowledge.sqlite_store import SQLiteGraph

HERE = Path(__file__).parent
RELATIONS = [
    "RelatedTo",
    "IsA",
    "Synonym",
    "PartOf",
    "HasProperty",
    "UsedFor",
    "AtLocation",
    "CapableOf",
    "Antonym",
    "DerivedFrom",
    "FormOf",
    "HasContext",
    "MadeOf",
    "SimilarTo",
    "EtymologicallyRelatedTo",
]
LANGS = ["fr", "de", "ja", "es", "it", "ru", "zh", "pt", "nl", "fi", "la", "ms", "sv", "pl", "ar"]
DATASETS = [
    "/d/wiktionary/en",
    "/d/wiktionary/fr",
    "/d/conceptnet/4/en",
    "/d/wordnet/3.1",
    "/d/verbosity",
    "/d/opencyc",
    "/d/jmdict",
    "/d/umbel",
]


def bench_lookup(graph: SQLiteGraph, n: int = 1000) -> dict[str, float]:
    concepts = graph.random_concepts(n, seed=7)
    for concept in concepts:
        graph.edges(concept)
    times = []
    for concept in concepts:
        started = time.perf_counter()
        graph.edges(concept)
        times.append((time.perf_counter() - started) * 1000)
    times.sort()
    return {
        "lookup_concepts": len(concepts),
        "lookup_median_ms": statistics.median(times),
        "lookup_p95_ms": times[int(0.95 * len(times)) - 1],
        "lookup_max_ms": times[-1],
    }


def _word(rng: random.Random) -> str:
    syllables = ["ka", "to", "re", "mi", "lo", "sa", "ne", "bu", "ti", "po", "va", "qui", "der", "ston", "el"]
    return "".join(rng.choice(syllables) for _ in range(rng.randint(2, 4)))


def _base36(n: int) -> str:
    digits = "0123456789abcdefghijklmnopqrstuvwxyz"
    out = ""
    while True:
        n, rem = divmod(n, 36)
        out = digits[rem] + out
        if n == 0:
            return out


def generate_dump(path: Path, lines: int, english_share: float = 0.1, seed: int = 1) -> None:
    """Write a ConceptNet 5.7 assertions dump in the exact format (gzip, via a `gzip -1` child)."""
    rng = random.Random(seed)
    # 1.5M distinct English concepts (the real dump has about that many): random syllables plus a
    # base-36 serial keep them unique; 30% are two-word phrases like "ice_cream".
    english = [
        _word(rng) + ("_" + _word(rng) if rng.random() < 0.3 else "") + _base36(i) for i in range(1_500_000)
    ]
    foreign = [_word(rng) for _ in range(200_000)]
    tmp = path.with_suffix(".partial")
    with open(tmp, "wb") as out:
        gz = subprocess.Popen(["gzip", "-1"], stdin=subprocess.PIPE, stdout=out)
        assert gz.stdin is not None
        buffer: list[str] = []
        for _i in range(lines):
            rel = rng.choice(RELATIONS)
            if rng.random() < english_share:
                # Heads are Zipf-like (a few concepts have thousands of edges), tails uniform.
                start = f"/c/en/{english[int(len(english) * rng.random() ** 3)]}"
                end = f"/c/en/{english[rng.randrange(len(english))]}"
                if rng.random() < 0.4:
                    start += "/n"
                dataset = rng.choice(DATASETS[:5])
            else:
                lang = rng.choice(LANGS)
                start = f"/c/{lang}/{rng.choice(foreign)}"
                end = f"/c/{rng.choice(['en', lang])}/{rng.choice(foreign)}"
                dataset = rng.choice(DATASETS)
            weight = rng.choice([1.0, 1.0, 2.0, 0.5, 1.5849625007211563, 3.4641016151377544])
            info = (
                f'{{"dataset": "{dataset}", "license": "cc:by-sa/4.0", "sources": [{{"contributor": '
                f'"/s/resource/wiktionary/en", "process": "/s/process/wikiparsec/2"}}], "weight": {weight}}}'
            )
            buffer.append(f"/a/[/r/{rel}/,{start}/,{end}/]\t/r/{rel}\t{start}\t{end}\t{info}\n")
            if len(buffer) >= 100_000:
                gz.stdin.write("".join(buffer).encode())
                buffer.clear()
        gz.stdin.write("".join(buffer).encode())
        gz.stdin.close()
        if gz.wait() != 0:
            raise RuntimeError("gzip failed")
    tmp.rename(path)


def _import_child(dump: str, db: str, queue: multiprocessing.Queue) -> None:
    from conceptbot.knowledge.install import install_conceptnet5

    started = time.perf_counter()
    report = install_conceptnet5(Path(db), Path(db).parent, file=Path(dump))
    queue.put(
        {
            "seconds": time.perf_counter() - started,
            "edges": report.edges,
            "concepts": report.concepts,
            "lines": report.details["conceptnet5"]["lines"],
        }
    )


def bench_import(work: Path, lines: int) -> dict[str, float]:
    work.mkdir(parents=True, exist_ok=True)
    dump = work / f"conceptnet-assertions-synthetic-v2-{lines}.csv.gz"
    if not dump.is_file():
        print(f"generating {lines:,}-line dump at {dump} (once) ...", flush=True)
        started = time.perf_counter()
        generate_dump(dump, lines)
        print(
            f"  generated in {time.perf_counter() - started:.0f} s, {dump.stat().st_size / 1e9:.2f} GB gzip"
        )
    db = work / "cn5-bench.db"
    ctx = multiprocessing.get_context("spawn")
    queue: multiprocessing.Queue = ctx.Queue()
    child = ctx.Process(target=_import_child, args=(str(dump), str(db), queue))
    child.start()
    result = queue.get()
    child.join()
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    db_mb = db.stat().st_size / 1e6
    db.unlink()
    return {
        "import_lines": result["lines"],
        "import_english_edges": result["edges"],
        "import_concepts": result["concepts"],
        "import_seconds": result["seconds"],
        "import_edges_per_s": result["edges"] / result["seconds"],
        "import_lines_per_s": result["lines"] / result["seconds"],
        "import_peak_rss_mb": peak_mb,
        "import_db_mb": db_mb,
    }


def bench_coverage(settings) -> dict[str, object]:
    objects = [
        line.strip()
        for line in (HERE / "data" / "paper_objects.txt").read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    graph = open_graph(settings, fallback=True)
    rows = []
    for name in objects:
        result = graph.edges(name)
        rows.append((name, result.match, result.matched, len(result.edges), "; ".join(result.notes)))
    counts: dict[str, int] = {}
    for _, match, *_ in rows:
        counts[match] = counts.get(match, 0) + 1
    print(f"\ncoverage of the {len(objects)} objects named in the paper's tables:")
    for name, match, matched, n, _notes in rows:
        print(f"  {name:<24} {match:<14} {matched!s:<28} {n:>4} edges")
    notes = sorted({row[4] for row in rows if row[4]})
    return {
        "coverage_objects": len(objects),
        "coverage_by_match": counts,
        "coverage_with_edges": sum(1 for r in rows if r[3] > 0),
        "coverage_direct (exact/lemma)": counts.get("exact", 0) + counts.get("lemma", 0),
        "fallback_notes": notes[:3],
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lookup", action="store_true")
    parser.add_argument("--import", dest="do_import", action="store_true")
    parser.add_argument("--coverage", action="store_true")
    parser.add_argument("--lines", type=int, default=34_000_000, help="dump size for --import")
    parser.add_argument("--work-dir", type=Path, default=Path("/tmp/conceptbot-bench"))
    parser.add_argument("--json", type=Path, help="also write the figures to this JSON file")
    args = parser.parse_args()
    everything = not (args.lookup or args.do_import or args.coverage)
    settings = load_settings()
    results: dict[str, object] = {}
    try:
        graph = SQLiteGraph(settings.kg_path)
    except KnowledgeUnavailableError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    results["graph"] = f"{graph.meta.get('install')}: {graph.meta.get('edges')} edges"
    if everything or args.lookup:
        results.update(bench_lookup(graph))
    if everything or args.coverage:
        results.update(bench_coverage(settings))
    if everything or args.do_import:
        if not shutil.which("gzip"):
            print("gzip is needed to generate the dump", file=sys.stderr)
            return 1
        results.update(bench_import(args.work_dir, args.lines))
    print("\nknowledge-layer benchmark")
    for key, value in results.items():
        shown = f"{value:,.4g}" if isinstance(value, float) else value
        print(f"  {key:<30} {shown}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
