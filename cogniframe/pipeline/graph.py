"""A small build graph: steps that run only when the hash of what they read changes.

A `Step` names its target, the steps it needs, how to make it and (when it is worth caching)
what it reads. Names hold `{vars}` that expand over rows given by the caller: with rows
`{"material": "tpu_95a", "part": "knee"}, ...`, `part:{material}/{part}` is one task per part and
`plates:{material}` one task per material. `needs` may use the task's own `{vars}` and `*`:
`part:{material}/*` is every part of that task's material.

A step with a `key` is cached. Its key is the sha256 of the step, its vars, what `key(ctx, **vars)`
returns (the inputs it reads: hashes of upstream files, numbers, settings), the source of the
modules in `code` and the `stack` fingerprint (library versions). On a hit its files are copied
from the cache entry, each checked against the sha256 stored with it (cache.get_files), and its
JSON value is read back; on a miss it runs and its files and value are stored atomically
(cache.put_files). A corrupt entry is a miss, never an error. The value a step returns is passed
through JSON even when it ran, so downstream steps see the same thing either way. A step
without a key is cheap and in memory only (a check, a text file): it always runs.

Where a step runs: `where="main"` steps run one at a time on the calling thread, in list order
(Python work: matplotlib, VTK, trimesh); `where="wait"` steps each get a thread, because they
mostly wait for another process (the CAD process pool, PrusaSlicer) or for LAPACK, so they overlap
with the main ones and with each other. A wait step starts the moment its needs are done, from the
thread of the step that finished last, even while a main step is running (a slicer never waits for
a render to end). `after` orders without being an input (not in the key): e.g.
renders start after the plates are laid out, so a long render never delays the slicer.

Why not a library: doit tracks whether targets are up to date *in place* (a dbm of file
checksums per task) while a build here fills a fresh temporary folder from a content-addressed
store; dask runs in-memory task graphs with no persistent keyed cache and would put matplotlib and
VTK on worker threads. What is needed here (content keys, a verified file store, a fan-out over
parts and materials, main thread vs waiting threads) is the ~200 lines below.
"""

from __future__ import annotations

import contextlib
import fnmatch
import json
import string
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from .. import cache


@dataclass(frozen=True)
class Made:
    """What a step made: files (relative to the build folder) and a JSON-able value."""

    files: tuple[str, ...] = ()
    value: Any = None


@dataclass(frozen=True)
class Step:
    name: str  # target, may hold {vars}
    needs: tuple[str, ...]  # step names or patterns, may hold {vars} and *
    run: Callable[..., Made]  # run(ctx, **vars) -> Made (writes its files under ctx.out)
    key: Callable[..., Any] | None = None  # key(ctx, **vars) -> JSON-able inputs; None: always run
    code: tuple[str, ...] = ()  # cogniframe sources (globs) the step's output depends on
    where: str = "main"  # "main" or "wait"
    after: tuple[str, ...] = ()  # order only, not inputs: start after these (patterns like needs)
    reads: str = ""  # what the key reads, in words (the docs' step table)


@dataclass(frozen=True)
class Task:
    name: str
    step: Step
    vars: Mapping[str, str]
    needs: tuple[str, ...]  # task names
    after: tuple[str, ...] = ()  # task names that must finish first (scheduling only, not in the key)


@dataclass
class Context:
    """What steps read: the build folder, the caller's inputs, and the values of finished steps."""

    out: Path
    inputs: Any  # the caller's record of what the steps read (pipeline.context.Inputs for the build)
    stack: str = ""  # fingerprint of library versions, part of every key
    use_cache: bool = True
    values: dict[str, Any] = field(default_factory=dict)

    def __getitem__(self, name: str):
        return self.values[name]

    def each(self, pattern: str) -> dict[str, Any]:
        """Values of the finished tasks matching `pattern`, by task name, in name order."""
        done = dict(self.values)  # a copy: "wait" steps read while the main thread adds values
        return {n: v for n, v in sorted(done.items()) if fnmatch.fnmatchcase(n, pattern)}


@dataclass(frozen=True)
class Record:
    task: str
    status: str  # "ran" | "cached" | "always" (not cached: cheap, in memory, or nothing to store)
    seconds: float


def expand(steps: Sequence[Step], rows: Iterable[Mapping[str, str]]) -> list[Task]:
    """One task per distinct binding of each step's {vars}; needs resolved to task names."""
    rows = list(rows)
    named: list[tuple[str, Step, dict]] = []
    for step in steps:
        fields = [f for _, f, _, _ in string.Formatter().parse(step.name) if f]
        seen = []
        for row in (rows if fields else [{}]):
            binding = {f: row[f] for f in fields}
            if binding not in seen:
                seen.append(binding)
                named.append((step.name.format(**binding), step, binding))
    names = [n for n, _, _ in named]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate task names: {sorted(n for n in names if names.count(n) > 1)}")
    tasks = []
    for i, (name, step, binding) in enumerate(named):
        resolved = []
        for patterns in (step.needs, step.after):
            found: list[str] = []
            for pat in patterns:
                pat = pat.format(**binding)
                hits = [n for n in names[:i] if fnmatch.fnmatchcase(n, pat)]  # only earlier steps: no cycles
                if not hits and "*" not in pat:
                    raise ValueError(f"{name} needs {pat!r}, which no earlier step makes")
                found += [h for h in hits if h not in found]
            resolved.append(tuple(found))
        tasks.append(Task(name, step, binding, resolved[0], resolved[1]))
    return tasks


def task_key(task: Task, ctx: Context) -> str | None:
    """The task's cache key, or None when it is not cached (no key function, caching off, or the key
    function returned None: nothing worth storing this time, e.g. no slicer installed)."""
    if task.step.key is None or not ctx.use_cache:
        return None
    inputs = task.step.key(ctx, **task.vars)
    if inputs is None:
        return None
    return cache.key([task.step.name, dict(task.vars), inputs], task.step.code, ctx.stack)


def will_run(task: Task, ctx: Context) -> bool:
    """Whether `task` will run rather than come from the cache, as far as can be told before the
    build (a stored entry that proves damaged when read also runs). Only for tasks whose key reads
    no other task's value (e.g. `part:*`, keyed by the params alone)."""
    key = task_key(task, ctx)
    return key is None or not (cache.entry_dir(_kind(task), key) / "meta.json").is_file()


def _kind(task: Task) -> str:
    """Cache folder of a step: steps/<name before ':' or '{'>."""
    return "steps/" + (task.step.name.split(":", 1)[0].split("{", 1)[0].strip("/") or "step")


def _do(task: Task, ctx: Context) -> tuple[Any, str]:
    """Run one task (or take it from the cache); returns (value, status)."""
    key = task_key(task, ctx)
    if key is not None:
        hit = cache.get_files(_kind(task), key, ctx.out)
        if hit is not None:
            return hit["value"], "cached"
    made = task.step.run(ctx, **task.vars)
    if not isinstance(made, Made):
        raise TypeError(f"step {task.name} returned {type(made).__name__}, not Made")
    value = made.value
    if task.step.key is not None:  # the same plain JSON whether it ran or came from the cache
        value = json.loads(json.dumps(value))
    if key is not None:
        cache.put_files(_kind(task), key, ctx.out, made.files, value)
    return value, ("ran" if key is not None or (task.step.key is not None and not ctx.use_cache) else "always")


STOP_POLL_S = 0.1  # how soon a run with a `stop` notices it while its steps run


class Stopped(Exception):
    """`run`'s caller set its `stop`: the steps under way ended, no other started."""


class _Failures:
    """The errors of one run, each with when and in which task it arose. The first (by time) calls
    the caller's `on_error()` once; `raise_first` raises the one that stopped the run."""

    def __init__(self, on_error: Callable[[], None] | None):
        self.on_error = on_error
        self.errors: list[tuple[float, str, BaseException]] = []  # (when, task, error)

    def __bool__(self) -> bool:
        return bool(self.errors)

    def add(self, task: str, e: BaseException) -> None:  # holding the run's lock
        self.errors.append((time.perf_counter(), task, e))
        if len(self.errors) == 1 and self.on_error is not None:
            self.on_error()

    def stopped(self, stop: threading.Event | None) -> bool:  # holding the run's lock
        """Whether the run ends: an error, or the caller's `stop` set (a `Stopped` error then)."""
        if stop is not None and stop.is_set() and not self.errors:
            self.add("", Stopped("the build graph's run was stopped by its caller"))
        return bool(self.errors)

    def raise_first(self) -> None:
        """Raise the first error, an interruption (Ctrl-C, exit) before any other, with a note naming
        its task; nothing when there was none."""
        if not self.errors:
            return
        _, task, first = min(self.errors, key=lambda x: (not isinstance(x[2], (KeyboardInterrupt, SystemExit)), x[0]))
        if task:
            first.add_note(f"first failed step: {task}")
        raise first


def run(tasks: Sequence[Task], ctx: Context, threads: int = 16,
        on_start: Callable[[str], None] | None = None,
        on_done: Callable[[Record], None] | None = None,
        on_error: Callable[[], None] | None = None,
        main_lock=None, stop: threading.Event | None = None) -> list[Record]:
    """Run every task once its needs are done. Main-thread tasks run in list order, one at a time;
    "wait" tasks run in threads and are started the moment their needs are done, also while a
    main-thread task is running (a finished wait task starts the ones that needed it from its own
    thread: the slicer never waits for a render to end). Returns one Record per task, in the order
    they finished.

    The first error (by time) stops new tasks and calls `on_error()` once (the caller cancels
    the work it has queued elsewhere, e.g. CAD jobs); the tasks under way end, and that first
    error is raised, with a note naming its task. Errors that follow it (a job cancelled, a
    step that read what the failed one did not make) are consequences and are not reported.
    `main_lock`: held around each main-thread task (a lock that other threads take to work only
    while the main thread has nothing to do). `stop`: once set, the run ends as at a first error
    (`Stopped`): the caller no longer wants its result (a studio that closes)."""
    pending = list(tasks)
    done: set[str] = set()
    records: list[Record] = []
    errors = _Failures(on_error)
    running = [0]
    lock = threading.Condition()

    def ready(t: Task) -> bool:
        return all(n in done for n in t.needs) and all(n in done for n in t.after)

    def finish(task: Task, value, status: str, t0: float) -> None:  # holding the lock
        ctx.values[task.name] = value
        done.add(task.name)
        rec = Record(task.name, status, time.perf_counter() - t0)
        records.append(rec)
        if on_done:
            on_done(rec)

    def in_thread(t: Task, t0: float) -> None:
        try:
            value, status = _do(t, ctx)
        except BaseException as e:  # noqa: BLE001 - handed to the caller
            with lock:
                errors.add(t.name, e)
                running[0] -= 1
                lock.notify_all()
            return
        with lock:
            finish(t, value, status, t0)
            running[0] -= 1
            start_waits()
            lock.notify_all()

    def start_waits() -> None:  # holding the lock
        if errors.stopped(stop):
            return
        for t in [t for t in pending if t.step.where == "wait" and ready(t)]:
            pending.remove(t)
            if on_start:
                on_start(t.name)
            running[0] += 1
            pool.submit(in_thread, t, time.perf_counter())

    def main_loop() -> None:  # the calling thread: start ready wait tasks, run ready main tasks in list order
        while True:
            with lock:
                start_waits()
                main = None if errors.stopped(stop) else next((t for t in pending if t.step.where == "main" and ready(t)), None)
                if main is None:
                    if running[0]:
                        lock.wait(None if stop is None else STOP_POLL_S)  # a stop is not a notify: look again soon
                        continue
                    if errors or not pending:
                        return
                    raise RuntimeError(f"build graph stuck: {[t.name for t in pending]} wait for steps that never run")
                pending.remove(main)
                if on_start:
                    on_start(main.name)
            t0 = time.perf_counter()
            try:
                with (main_lock if main_lock is not None else contextlib.nullcontext()):
                    value, status = _do(main, ctx)
            except Exception as e:  # noqa: BLE001 - handed to the caller, after the running tasks end
                with lock:
                    errors.add(main.name, e)
                continue
            with lock:
                finish(main, value, status, t0)

    with ThreadPoolExecutor(max_workers=threads, thread_name_prefix="step") as pool:
        try:
            main_loop()
        except BaseException as e:  # noqa: BLE001 - Ctrl-C (or the graph stuck): start nothing new,
            with lock:              # let the running tasks end (the executor waits for them), then raise
                errors.add("", e)
                while running[0]:
                    lock.wait()
    errors.raise_first()
    return records
