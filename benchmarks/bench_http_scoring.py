"""HTTP scoring against embedded scoring: the same model served by llama_cpp.server and embedded.

``--part saycan``: for the first step of each task (SayCan's prompt and every option: each valid
pick_and_place and done()), both backends score the options; the figures are how often they pick the
same best option, where the HTTP best sits in the embedded ranking (1 = the same), the embedded
log-probability given up by taking it, the rank correlation of all scores (Spearman: the ``search``
method scores only the best exactly and bounds the rest, so expect it low there), and seconds per
step.
``--part yes-no``: the goal planner's kind of question ("to do what the person asked, should the
robot give the X to the user?", Yes/No) for every pickable object of each task; the figures are the
rank correlation of the log-odds per task, how often the two agree on the best object, and seconds
per question. No cache: every call is made.

Run: .venv/bin/python benchmarks/bench_http_scoring.py [--limit N] [--split test] [--json out.json]
     [--url http://127.0.0.1:PORT/v1 --model NAME]   (default: start llama_cpp.server on the
     configured embedded model on a free port, and stop it at the end)
"""

from __future__ import annotations

import argparse
import json
import socket
import statistics
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

from conceptbot.baselines.saycan import SayCan, option_text
from conceptbot.bench.grading import load_tasks, task_scene
from conceptbot.core.config import load_settings
from conceptbot.core.plan import valid_actions
from conceptbot.models.llm import Message, ScoreRequest
from conceptbot.models.openai_backend import OpenAILLM
from conceptbot.models.registry import create_llm
from conceptbot.pipeline import prompts


def _ranks(values: list[float]) -> list[float]:
    order = sorted(range(len(values)), key=lambda i: values[i])
    ranks = [0.0] * len(values)
    for rank, i in enumerate(order):
        ranks[i] = float(rank)
    return ranks


def spearman(a: list[float], b: list[float]) -> float:
    """Spearman's rank correlation (ties broken by position)."""
    ra, rb = _ranks(a), _ranks(b)
    mean_a, mean_b = statistics.fmean(ra), statistics.fmean(rb)
    cov = sum((x - mean_a) * (y - mean_b) for x, y in zip(ra, rb, strict=True))
    var = (sum((x - mean_a) ** 2 for x in ra) * sum((y - mean_b) ** 2 for y in rb)) ** 0.5
    return cov / var if var else 0.0


def start_server(model_path: Path) -> tuple[subprocess.Popen, str]:
    """llama_cpp.server on a free loopback port, ready."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    proc = subprocess.Popen(
        [sys.executable, "-m", "llama_cpp.server", "--model", str(model_path), "--model_alias", "served",
         "--host", "127.0.0.1", "--port", str(port), "--n_ctx", "4096", "--logits_all", "true",
         "--verbose", "false"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )  # fmt: skip
    url = f"http://127.0.0.1:{port}/v1"
    deadline = time.time() + 180
    while True:
        try:
            urllib.request.urlopen(url + "/models", timeout=2).read()
            return proc, url
        except OSError:
            if proc.poll() is not None or time.time() > deadline:
                raise SystemExit("llama_cpp.server did not start") from None
            time.sleep(0.5)


def yes_no_row(task, scene, embedded, served) -> dict:
    """Both backends' log-odds of Yes for "should the robot give the X to the user?" per object."""
    exact, got, methods = [], [], set()
    times = {"embedded": 0.0, "http": 0.0}
    for obj in scene.pickable:
        user = prompts.render(
            "move_user", request=task.request, context="", object=obj, state="", facts="",
            move=f"give the {obj} to the user",
        )  # fmt: skip
        messages = (Message("system", prompts.render("decide_system")), Message("user", user))
        request = ScoreRequest(options=("Yes", "No"), messages=messages)
        for name, llm, out in (("embedded", embedded, exact), ("http", served, got)):
            started = time.perf_counter()
            scored = llm.score(request)
            times[name] += time.perf_counter() - started
            out.append(scored.logprobs[0] - scored.logprobs[1])
            methods.add(scored.method)
    same = max(range(len(exact)), key=exact.__getitem__) == max(range(len(got)), key=got.__getitem__)
    n = len(exact)
    row = {
        "task": task.id,
        "options": n,
        "same_best": same,
        "spearman": spearman(exact, got),
        "embedded_s": times["embedded"] / n,
        "http_s": times["http"] / n,
        "method": "/".join(sorted(methods)),
    }
    line = f"{task.id:16} {n:3} objects  same best: {same!s:5}  spearman {row['spearman']:+.2f}  "
    print(line + f"per question: embedded {row['embedded_s']:.2f} s, http {row['http_s']:.2f} s", flush=True)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--limit", type=int, default=None, help="first N tasks")
    parser.add_argument("--split", default="test")
    parser.add_argument("--url", help="an already running OpenAI-compatible server")
    parser.add_argument("--model", default="served", help="the model name on --url")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--part", choices=("saycan", "yes-no"), default="yes-no")
    args = parser.parse_args()
    settings = load_settings()
    embedded = create_llm(settings.llm, settings)
    proc = None
    url = args.url
    if url is None:
        proc, url = start_server(embedded.model_path)  # type: ignore[attr-defined]
    served = OpenAILLM(args.model, backend="openai-compatible", base_url=url, timeout_s=600, max_retries=1)
    rows = []
    try:
        for task in load_tasks(split=args.split)[: args.limit]:
            scene = task_scene(task)
            if args.part == "yes-no":
                rows.append(yes_no_row(task, scene, embedded, served))
                continue
            request = ScoreRequest(
                options=tuple(option_text(a) for a in valid_actions(scene)),
                prompt=SayCan(embedded).prompt(task.request, scene, []),
            )
            started = time.perf_counter()
            exact = list(embedded.score(request).logprobs)
            embedded_s = time.perf_counter() - started
            started = time.perf_counter()
            over_http = served.score(request)
            http_s = time.perf_counter() - started
            got = list(over_http.logprobs)
            chosen = max(range(len(got)), key=got.__getitem__)
            rank = 1 + sum(e > exact[chosen] for e in exact)
            rows.append(
                {"task": task.id, "options": len(exact), "same_best": rank == 1, "rank": rank,
                 "regret": max(exact) - exact[chosen], "spearman": spearman(exact, got),
                 "embedded_s": embedded_s, "http_s": http_s, "method": over_http.method}
            )  # fmt: skip
            line = f"{task.id:16} {len(exact):4} options  same best: {rank == 1!s:5}  rank {rank:3}  "
            line += f"regret {rows[-1]['regret']:5.2f}  embedded {embedded_s:5.1f} s  "
            print(line + f"http {http_s:5.1f} s ({over_http.method})", flush=True)
    finally:
        if proc is not None:
            proc.terminate()
            proc.wait(30)
    summary = {
        "part": args.part,
        "tasks": len(rows),
        "same_best": sum(r["same_best"] for r in rows),
        "median_spearman": statistics.median(r["spearman"] for r in rows),
        "median_rank": statistics.median(r.get("rank", 1) for r in rows),
        "median_embedded_s": statistics.median(r["embedded_s"] for r in rows),
        "median_http_s": statistics.median(r["http_s"] for r in rows),
        "method": rows[0]["method"] if rows else "",
    }
    print(json.dumps(summary, indent=2))
    if args.json:
        args.json.write_text(json.dumps({"summary": summary, "rows": rows}, indent=2))


if __name__ == "__main__":
    main()
