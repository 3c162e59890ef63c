"""Results files, shared by both benchmarks (the paper's tasks and SafeAgentBench).

A run appends one JSON line per graded plan to a results file and is resumable: a job whose key (the
values of a record's key fields, e.g. task, config, backend, model) is already in the file is skipped,
so an interrupted run continues where it stopped. A report reads the file back and writes Markdown,
JSON and a chart beside it.

Reading is strict about what a report needs and lenient about what a crash leaves: a line that is not
JSON is a torn write (a run stopped mid-line) and is skipped, but a line of another shape (another
benchmark's record, ``{"a": 1}``, a binary file) is a :class:`~conceptbot.core.errors.ConfigError`
naming the file and the line, before any work is done (:class:`RecordShape`, :func:`read_records`).

The runners (:mod:`conceptbot.bench.runner`, :mod:`conceptbot.bench.safeagentbench.runner`) supply
only what differs: a job's key and how a job becomes a record. The reports supply the summary, its
Markdown and its chart.
"""

from __future__ import annotations

import json
import threading
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, TypeVar

from conceptbot.core.errors import ConceptBotError, ConfigError
from conceptbot.core.usage import Usage

J = TypeVar("J")
T = TypeVar("T")
Record = dict[str, Any]
OnRecord = Callable[[Record], None]


class Keyed(Protocol):
    """A job with an identity in the results file."""

    def key(self, backend: str, model: str) -> tuple[Any, ...]: ...


K = TypeVar("K", bound=Keyed)


# -- reading -----------------------------------------------------------------------------------------
Types = tuple[type, ...]
NUMBER: Types = (int, float)
TEXT: Types = (str,)
FLAG: Types = (bool,)
NULL = type(None)
USAGE_NUMBERS = ("latency_s", "prompt_tokens", "completion_tokens", "cost_usd", "calls")
"""The per-module usage fields of a record (:func:`usage_fields`); each a number (cost may be null:
an unknown price)."""

_JSON_NAMES = {str: "text", bool: "true/false", int: "a number", float: "a number", NULL: "null"}


def _json_name(value: Any) -> str:
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "a list"
    return _JSON_NAMES.get(type(value), type(value).__name__)


def _expected(types: Types) -> str:
    return " or ".join(dict.fromkeys(_JSON_NAMES.get(t, t.__name__) for t in types))


@dataclass(frozen=True)
class RecordShape:
    """What a report reads from each record of a results file, so a file of another shape is refused
    by line before the report (or a resumed run) trips over it.

    Attributes:
        writer: The command that writes such records (named in the error).
        required: Fields every record has, with their JSON types.
        optional: Fields a record may lack (older versions did not write them), with their types
            when present. ``usage`` is always checked: an object of per-module numbers.
    """

    writer: str
    required: Mapping[str, Types]
    optional: Mapping[str, Types] = field(default_factory=dict)

    def problem(self, record: Any) -> str | None:
        """What is wrong with one parsed line for this shape, or ``None``."""
        if not isinstance(record, dict):
            return f"{_json_name(record)} where a record (a JSON object) belongs"
        missing = [name for name in self.required if name not in record]
        if missing:
            return f"it lacks {', '.join(repr(m) for m in missing)}"
        for name, types in (*self.required.items(), *self.optional.items()):
            if name in record and not isinstance(record[name], types):
                return f"{name!r} is {_json_name(record[name])}, not {_expected(types)}"
        return _usage_problem(record.get("usage"))


def _usage_problem(usage: Any) -> str | None:
    if usage is None:
        return None
    if not isinstance(usage, dict) or not all(isinstance(u, dict) for u in usage.values()):
        return "'usage' is not an object of per-module objects"
    for module, fields in usage.items():
        for name in USAGE_NUMBERS:
            value = fields.get(name, 0)
            if value is None and name == "cost_usd":
                continue
            if isinstance(value, bool) or not isinstance(value, NUMBER):
                return f"usage of {module!r}: {name!r} is {_json_name(value)}, not a number"
    return None


def _lines(path: Path) -> Iterator[tuple[int, Any]]:
    """``(line number, parsed value)`` for each line of a results file that is JSON.

    A line that is not JSON is a torn write and is skipped: the last line of a run that was
    stopped, or one that a resumed run of an older version appended to. A line that is not UTF-8
    is not something a run writes (it writes UTF-8 JSON), so it is an error, unless it is the last
    line and only its end is cut inside a character.

    Raises:
        ConfigError: The file cannot be read, or a line is not UTF-8 text.
    """
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"cannot read {path}: {exc.strerror or exc}") from None
    lines = data.split(b"\n")
    for number, raw in enumerate(lines, start=1):
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            if number == len(lines) and exc.reason == "unexpected end of data":
                continue  # a torn last line, cut inside a character
            raise ConfigError(
                f"{path} line {number} is not UTF-8 text (byte {exc.start + 1} of the line): "
                "not a results file",
                hint="give the JSONL file that `conceptbot bench run` or `safebench run` wrote (--out)",
            ) from None
        try:
            value = json.loads(text)
        except (ValueError, RecursionError):  # RecursionError: JSON nested thousands deep
            continue
        yield number, value


def read_records(path: Path, shape: RecordShape | None = None) -> list[Record]:
    """The records of a results file (torn lines skipped); ``[]`` when it does not exist yet.

    Args:
        path: The JSONL results file.
        shape: What each record must hold; None: take every JSON line as it is.

    Raises:
        ConfigError: The file cannot be read, or a line (named by number) is not UTF-8 or not a
            record of ``shape``.
    """
    path = Path(path)
    if not path.exists():
        return []
    records = []
    for number, value in _lines(path):
        if shape is not None and (problem := shape.problem(value)):
            raise ConfigError(
                f"{path} line {number} is not a `{shape.writer}` record: {problem}",
                hint=f"is it the right file? `{shape.writer}` writes one record per line; "
                "give that file, or remove the line",
            )
        records.append(value)
    return records


def load_records(
    path: Path, hint: str = "run `conceptbot bench run` first", shape: RecordShape | None = None
) -> list[Record]:
    """The records of a results file for a report (torn lines skipped).

    Args:
        path: The JSONL results file.
        hint: How to make one, shown when there is none.
        shape: What each record must hold (see :func:`read_records`).

    Raises:
        ConfigError: The file does not exist, holds no records, or has a line of the wrong shape.
    """
    if not Path(path).is_file():
        raise ConfigError(f"no results file {path}", hint=hint)
    records = read_records(Path(path), shape)
    if not records:
        raise ConfigError(f"{path} holds no benchmark records")
    return records


def done_keys(path: Path, fields: tuple[str, ...], commit: str | None = None) -> set[tuple[Any, ...]]:
    """Keys (the values of ``fields``) of the records already in a results file (a torn last line,
    or a record without one of the fields, is ignored); with ``commit``, only the records made by
    that commit of the code (:mod:`conceptbot.bench.provenance`): other code is planned again."""
    if not path.is_file():
        return set()
    keys: set[tuple[Any, ...]] = set()
    for _, r in _lines(path):
        try:
            if commit is None or r.get("commit") == commit:
                keys.add(tuple(r[f] for f in fields))
        except (KeyError, TypeError, AttributeError):
            continue
    return keys


def pending(
    jobs: Iterable[K], out: Path, backend: str, model: str, fields: tuple[str, ...], commit: str | None = None
) -> list[K]:
    """The jobs whose key (``fields`` of a record) is not yet in the results file ``out`` (with
    ``commit``: not yet there from that commit of the code)."""
    seen = done_keys(out, fields, commit)
    return [j for j in jobs if j.key(backend, model) not in seen]


# -- writing -----------------------------------------------------------------------------------------
def append_results(
    todo: Iterable[J],
    make_record: Callable[[J], Record],
    out: Path,
    workers: int = 1,
    on_record: OnRecord | None = None,
) -> list[Record]:
    """Make a record per job and append each to the JSONL file ``out`` as soon as it exists (an
    interrupted run loses at most the job in progress); ``workers`` jobs at once."""
    out.parent.mkdir(parents=True, exist_ok=True)
    _end_torn_line(out)
    lock = threading.Lock()
    records: list[Record] = []

    def work(job: J) -> None:
        record = make_record(job)
        with lock, open(out, "a", encoding="utf-8") as handle:
            handle.write(json.dumps(record, ensure_ascii=False) + "\n")
            records.append(record)
        if on_record:
            on_record(record)

    if workers <= 1:
        for job in todo:
            work(job)
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(work, todo))
    return records


def _end_torn_line(out: Path) -> None:
    """End a torn last line (a run stopped mid-write) before appending: otherwise the first new
    record would join it and be lost with it."""
    if not out.is_file() or out.stat().st_size == 0:
        return
    with open(out, "rb+") as handle:
        handle.seek(-1, 2)
        if handle.read(1) != b"\n":
            handle.write(b"\n")


def run_pending(
    jobs: Iterable[K],
    make_record: Callable[[K], Record],
    out: Path,
    backend: str,
    model: str,
    fields: tuple[str, ...],
    workers: int = 1,
    on_record: OnRecord | None = None,
    stamp: Record | None = None,
) -> list[Record]:
    """Run the jobs whose key is not yet in ``out`` and append their records to it.

    Args:
        jobs: What to run.
        make_record: Plans and grades one job (it must not raise: see :func:`timed_record`).
        out: The JSONL results file.
        backend, model: Part of the resume key (and recorded by ``make_record``).
        fields: The record fields that make the resume key, in the order of ``Job.key``.
        workers: Jobs at once (1 for in-process backends).
        on_record: Called after each record is written (progress bars).
        stamp: Fields every record carries (:func:`conceptbot.bench.provenance.stamp`); its
            ``commit`` is part of the resume key: records of other code are planned again.

    Returns:
        The new records, in the order they were written.
    """
    extra = dict(stamp or {})

    def stamped(job: K) -> Record:
        return {**make_record(job), **extra}

    todo = pending(jobs, out, backend, model, fields, extra.get("commit"))
    return append_results(todo, stamped, out, workers, on_record)


def built_once(build: Callable[[str], T]) -> Callable[[str], T]:
    """``build(config)`` memoised per configuration (a system loads its model once per run), safe to
    call from several workers at once."""
    built: dict[str, T] = {}
    lock = threading.Lock()

    def get(config: str) -> T:
        with lock:
            if config not in built:
                built[config] = build(config)
            return built[config]

    return get


# -- record fields -----------------------------------------------------------------------------------
def usage_fields(usage: dict[str, Usage]) -> dict[str, dict[str, Any]]:
    """Per-module usage as stored in a results record."""
    return {
        m: {
            "latency_s": round(u.latency_s, 3),
            "prompt_tokens": u.prompt_tokens,
            "completion_tokens": u.completion_tokens,
            "cost_usd": u.cost_usd,
            "calls": u.calls,
        }
        for m, u in usage.items()
    }


def failure_fields(exc: Exception) -> dict[str, str]:
    """``reason`` and ``error`` of a record whose planning raised: a user-facing error by its
    message, anything else (a bug) with its traceback."""
    if isinstance(exc, ConceptBotError):
        return {"reason": f"error: {exc.message}", "error": str(exc)}
    return {"reason": f"crash: {type(exc).__name__}: {exc}", "error": traceback.format_exc(limit=5)}


def timed_record(head: Record, attempt: Callable[[], Record], on_failure: Record) -> Record:
    """A results record: ``head``, then the fields ``attempt()`` returns (plan and verdict), or
    ``on_failure`` and the error when it raises, then the seconds it took and when it finished."""
    record = dict(head)
    started = time.perf_counter()
    try:
        record.update(attempt())
    except Exception as exc:  # a bug must not lose the rest of a long run; it is recorded and reported
        record.update(on_failure, **failure_fields(exc))
    record["seconds"] = round(time.perf_counter() - started, 3)
    record["finished_at"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    return record


# -- reports -----------------------------------------------------------------------------------------
def write_report_files(
    summary: dict[str, Any],
    out_dir: Path,
    names: tuple[str, str, str],
    markdown: Callable[[dict[str, Any]], str],
    chart: Callable[[dict[str, Any], Path], None],
) -> dict[str, Path]:
    """Write a summary's Markdown, JSON and chart into ``out_dir``.

    Args:
        summary: The report's data (JSON-able; sets are written as lists).
        out_dir: Where the files go (created if needed).
        names: File names of the Markdown, the JSON and the chart.
        markdown: Renders the summary as Markdown.
        chart: Draws the summary into a PNG at the given path.

    Returns:
        The paths written, by kind: ``markdown``, ``json``, ``chart``.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = dict(zip(("markdown", "json", "chart"), (out_dir / name for name in names), strict=True))
    paths["markdown"].write_text(markdown(summary), encoding="utf-8")
    paths["json"].write_text(json.dumps(summary, indent=2, default=list), encoding="utf-8")
    chart(summary, paths["chart"])
    return paths
