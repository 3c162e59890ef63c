"""Model-layer benchmark: embedded LLM speed, response-cache speed-up, embedder throughput.

Run: .venv/bin/python benchmarks/bench_models.py [--model qwen2.5-coder-1.5b] [--runs 3]

Prints medians over --runs repetitions (these machines are noisy; medians and ratios are the figures
to compare). Every LLM request starts with a unique tag so llama.cpp's prefix cache cannot help the
"fresh" numbers.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from conceptbot.core.config import load_settings
from conceptbot.models import weights
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.caching import CachedEmbedder, CachedLLM
from conceptbot.models.llamacpp import LlamaCppLLM
from conceptbot.models.llm import ChatRequest, ScoreRequest
from conceptbot.models.st_embedder import SentenceTransformerEmbedder

LONG_CONTEXT = (
    "You are a kitchen robot. Objects on the table: eggs, butter, lemon, salt, pepper, a whisk, a glass "
    "bowl, a metal pot, a wooden spoon, a knife, a cutting board, a sponge, a bag of chips, an apple, a "
    "banana, a carrot, a can of Coke, a bottle of water, a plate, a mug. Each object has properties such "
    "as fragile, dangerous, deformable or able to hold liquid. "
) * 3


def median(values: list[float]) -> float:
    return statistics.median(values)


def resident_anonymous_mb() -> float:
    """This process's resident anonymous memory (heap, llama.cpp buffers), 0 where /proc is missing."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("RssAnon:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def bench_llm(llm: LlamaCppLLM, runs: int) -> dict[str, float]:
    prompt_rates, gen_rates = [], []
    for run in range(runs):
        tag = f"[run {time.time_ns()}-{run}] "
        started = time.perf_counter()
        out = llm.chat(ChatRequest.of(tag + LONG_CONTEXT + "Say OK.", max_tokens=1))
        prompt_rates.append(out.usage.prompt_tokens / (time.perf_counter() - started))
        # A short prompt and a long answer: the time is dominated by generation.
        gen = llm.chat(ChatRequest.of(tag + "Count from 1 to 60, separated by commas.", max_tokens=96))
        gen_rates.append(gen.usage.completion_tokens / gen.usage.latency_s)
    return {"prompt_tok_s": median(prompt_rates), "generation_tok_s": median(gen_rates)}


def bench_cache(llm: LlamaCppLLM, runs: int) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as tmp:
        cached = CachedLLM(llm, CacheStore(Path(tmp) / "cache.db"), module="bench")
        first, second = [], []
        for run in range(runs):
            request = ChatRequest.of(
                f"[{time.time_ns()}-{run}] In one sentence: what is hollandaise sauce made of?",
                max_tokens=40,
            )
            t0 = time.perf_counter()
            cached.chat(request)
            t1 = time.perf_counter()
            hit = cached.chat(request)
            t2 = time.perf_counter()
            assert hit.cached
            first.append(t1 - t0)
            second.append(t2 - t1)
    return {
        "first_call_s": median(first),
        "cached_call_s": median(second),
        "cache_speedup": median(first) / median(second),
    }


def bench_scoring(llm: LlamaCppLLM, runs: int) -> dict[str, float]:
    objects = ["eggs", "butter", "lemon", "whisk", "glass bowl", "knife", "sponge", "apple"]
    places = ["user", "table", "glass bowl", "metal pot"]
    options = (*tuple(f"pick_and_place({o}, {p})" for o in objects for p in places if o != p), "done()")
    per_option = []
    for run in range(runs):
        prompt = (
            f"[{time.time_ns()}-{run}] "
            + LONG_CONTEXT
            + "Request: I would like a hollandaise sauce.\nNext action: "
        )
        started = time.perf_counter()
        llm.score(ScoreRequest(options=options, prompt=prompt))
        per_option.append((time.perf_counter() - started) / len(options))
    return {"score_options": len(options), "score_s_per_option": median(per_option)}


def bench_embedder(runs: int) -> dict[str, float]:
    embedder = SentenceTransformerEmbedder()
    embedder.embed(["warm up"])
    heads = [
        "knife",
        "glass bowl",
        "sponge",
        "apple",
        "eggs",
        "butter",
        "scissors",
        "bleach",
        "candle",
        "plate",
    ]
    rels = ["IsA", "UsedFor", "HasProperty", "MadeOf", "CapableOf", "AtLocation", "RelatedTo"]
    tails = [f"thing number {i}" for i in range(30)]
    sentences = [f"{h} {r} {t}" for h in heads for r in rels for t in tails]  # 2,100 distinct
    fresh, cached_rates = [], []
    for _ in range(runs):
        t0 = time.perf_counter()
        embedder.embed(sentences)
        fresh.append(len(sentences) / (time.perf_counter() - t0))
    with tempfile.TemporaryDirectory() as tmp:
        cached = CachedEmbedder(embedder, CacheStore(Path(tmp) / "cache.db"))
        cached.embed(sentences)
        for _ in range(runs):
            reader = CachedEmbedder(embedder, cached.store)  # new wrapper: reads SQLite, not memory
            t0 = time.perf_counter()
            reader.embed(sentences)
            cached_rates.append(len(sentences) / (time.perf_counter() - t0))
    return {"embed_sentences_s": median(fresh), "embed_cached_sentences_s": median(cached_rates)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="qwen2.5-coder-1.5b")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--json", type=Path, help="also write the figures to this JSON file")
    args = parser.parse_args()
    settings = load_settings()
    path = weights.verify(settings.models_dir, args.model)
    llm = LlamaCppLLM(path, model=args.model, n_ctx=settings.n_ctx, n_threads=settings.n_threads)
    t0 = time.perf_counter()
    llm.chat(ChatRequest.of("Hi", max_tokens=1))
    results: dict[str, float | str] = {
        "model": args.model,
        "load_and_first_token_s": time.perf_counter() - t0,
    }
    resident = resident_anonymous_mb()
    results.update(bench_llm(llm, args.runs))
    # Chat keeps logits for the last token only; scoring keeps one row per evaluated token.
    results["chat_resident_growth_mb"] = resident_anonymous_mb() - resident
    results.update(bench_cache(llm, args.runs))
    resident = resident_anonymous_mb()
    results.update(bench_scoring(llm, args.runs))
    results["scoring_resident_growth_mb"] = resident_anonymous_mb() - resident
    results.update(bench_embedder(args.runs))
    width = max(len(k) for k in results)
    print(f"model-layer benchmark, median of {args.runs} runs")
    for key, value in results.items():
        print(f"  {key:<{width}}  {value:,.4g}" if isinstance(value, float) else f"  {key:<{width}}  {value}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
