"""Run a sweep on Dask: designs go out in batches, rows come back and are appended per batch.

    DIR/.cogniframe-sweep.json     marks the folder as cogniframe's (a foreign non-empty folder is refused)
    DIR/results/<code>-<hash>.parquet   one file per finished batch (the resume log)
    DIR/results.parquet            every design of the sweep, in sampling order (rewritten at the end)

Resume: a rerun evaluates only the designs whose `design_id` has no row yet (TIMEOUT rows are
tried again). Rows are only reused when the evaluation code is unchanged (<code> = hash of the
modules `check` runs), so a stale row is never read. A killed sweep loses at most the batches
in flight.

Cluster: `--scheduler ADDRESS` connects to an existing Dask scheduler; without it a LocalCluster
of worker processes (threads_per_worker=1; the FE model is Python-bound, so processes, not
threads). The base params travel inside each task; workers never read the client's disk.

Dask starts its worker processes with multiprocessing's spawn, and a spawned process first runs
the main script again (as `__mp_main__`). A script that calls `cf.sweep(...)` at its top level,
outside `if __name__ == "__main__":`, would start a sweep in every worker while it boots ("Nanny
failed to start"). So when the sweep is called from such a place, the
local cluster is one worker thread in this process instead, and a warning says how to get the
worker processes back (`runtime.mainguard`). Guarded scripts, the CLI, `python -m`, notebooks and REPLs get processes.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator, Sequence

from ..errors import UserError
from . import evaluate as ev
from .sample import designs as sample_designs
from .sweepfile import Sweep

MARKER = ".cogniframe-sweep.json"
RESULTS = "results.parquet"


@dataclass(frozen=True)
class BatchDone:
    rows: tuple[dict, ...]
    worker: str
    done: int
    total: int
    seconds: float
    label: str = "batch"  # optimize reports whole ask/tell rounds


@dataclass(frozen=True)
class SweepResult:
    out_dir: Path
    designs: int
    evaluated: int  # in this run
    skipped: int  # already done by an earlier run
    counts: dict = field(default_factory=dict)
    seconds: float = 0.0
    scheduler: str = ""
    workers: int = 0

    def as_dict(self) -> dict:
        c = self.counts
        return {"designs": self.designs, "pass": c.get("PASS", 0), "fail": c.get("FAIL", 0), "invalid": c.get("INVALID", 0),
                "timeout": c.get("TIMEOUT", 0), "error": c.get("ERROR", 0), "evaluated": self.evaluated,
                "skipped": self.skipped, "seconds": round(self.seconds, 3), "scheduler": self.scheduler,
                "workers": self.workers, "out_dir": str(self.out_dir)}


# -- output folder ---------------------------------------------------------------------------

def default_out(sweep: Sweep) -> Path:
    return Path("out") / "sweeps" / sweep.stem


def claim_folder(out_dir: Path, kind: str, sweep: Sweep, write: bool = True) -> None:
    """Create or re-enter a folder cogniframe made; refuse one it did not (exit 2, nothing written).

    write=False only checks (call it before any slow or failing step, then again with write=True)."""
    marker = out_dir / MARKER
    if out_dir.exists() and not out_dir.is_dir():
        raise UserError(f"{out_dir}: exists and is not a folder. Fix: give -o a folder path.")
    if out_dir.is_dir() and any(out_dir.iterdir()):
        try:
            owner = json.loads(marker.read_text())
        except (OSError, ValueError):
            raise UserError(f"{out_dir}: the folder is not empty and was not made by `cogniframe {kind}` (no {MARKER}); "
                            "cogniframe never writes into or deletes a folder it did not make. "
                            "Fix: give -o a new or empty folder.") from None
        if owner.get("kind") != kind:
            raise UserError(f"{out_dir}: the folder holds a `cogniframe {owner.get('kind')}` run, not a {kind}. "
                            "Fix: give -o another folder.")
    if not write:
        return
    out_dir.mkdir(parents=True, exist_ok=True)
    _write_atomic(marker, json.dumps({"kind": kind, "sweep": sweep.path, "base": sweep.base_path,
                                      "digest": sweep.digest(), "code": code_digest()}, indent=2) + "\n")


def _write_atomic(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def code_digest() -> str:
    """Hash of the modules a design's evaluation runs: rows from other code are not reused."""
    return ev.code_digest()


# -- the plan and the resume log -------------------------------------------------------------

def plan(sweep: Sweep) -> list[tuple[str, dict]]:
    """(design_id, overrides) for every design; duplicates (a grid of choices, rounding) once."""
    out: dict[str, dict] = {}
    for o in sample_designs(sweep):
        out.setdefault(ev.design_id(ev.apply_overrides(sweep.base_data, o)), o)
    return list(out.items())


def read_log(out_dir: Path, code: str | None = None):
    """Every row written by earlier batches of this code version (a pandas DataFrame, maybe empty)."""
    import pandas as pd

    files = sorted((out_dir / "results").glob(f"{code or code_digest()}-*.parquet"))
    frames = []
    for f in files:
        try:
            frames.append(pd.read_parquet(f))
        except Exception:  # a batch file cut short by a kill: its designs are simply run again
            continue
    frames = [f for f in frames if len(f)]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def write_batch(out_dir: Path, rows: list[dict], code: str) -> Path:
    folder = out_dir / "results"
    folder.mkdir(exist_ok=True)
    ids = hashlib.sha256("".join(r["design_id"] for r in rows).encode()).hexdigest()[:16]
    path = folder / f"{code}-{ids}.parquet"
    tmp = folder / f".{path.name}.{os.getpid()}.tmp"
    _frame(rows).to_parquet(tmp, engine="pyarrow", index=False)
    tmp.replace(path)
    return path


def _frame(rows: list[dict]):
    import pandas as pd

    df = pd.DataFrame(rows) if not isinstance(rows, pd.DataFrame) else rows.copy()

    def missing(v) -> bool:  # None, or the NaN pandas puts where a batch had no such column
        return v is None or (isinstance(v, float) and v != v)

    for col in df.columns:  # parquet needs one type per column: mixed objects become text
        if df[col].dtype == object:  # numpy scalars (a numpy bool from a load case) as Python's
            df[col] = df[col].map(lambda v: v.item() if hasattr(v, "item") and not isinstance(v, (str, bytes)) else v)
        if df[col].dtype == object and not df[col].map(lambda v: missing(v) or isinstance(v, str)).all():
            if df[col].map(lambda v: missing(v) or isinstance(v, bool)).all():
                continue
            if df[col].map(lambda v: missing(v) or (isinstance(v, (int, float)) and not isinstance(v, bool))).all():
                df[col] = df[col].astype(float)
            else:
                df[col] = df[col].map(lambda v: None if missing(v) else str(v))
    return df


# -- Dask ------------------------------------------------------------------------------------

@contextlib.contextmanager
def dask_client(scheduler: str | None, workers: int | None) -> Iterator[tuple[object, str, int]]:
    """(client, scheduler address, worker count): an existing cluster, or a LocalCluster of processes."""
    import logging

    from distributed import Client, LocalCluster

    for name in ("distributed", "distributed.scheduler", "distributed.nanny", "distributed.worker", "distributed.core"):
        logging.getLogger(name).setLevel(logging.ERROR)
    if scheduler:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as e:
            raise UserError(f"--scheduler {scheduler}: cannot reach a Dask scheduler there ({e}). "
                            "Fix: start one (`dask scheduler` and `dask worker ADDRESS`) or leave --scheduler out "
                            "to run on local worker processes.") from None
        try:
            want = workers or 1
            try:
                client.wait_for_workers(want, timeout=60)
            except TimeoutError:
                raise UserError(f"--scheduler {scheduler}: fewer than {want} Dask worker(s) joined within 60 s. "
                                f"Fix: start workers (`dask worker {scheduler} --nthreads 1`)"
                                + (" or lower --workers." if workers else ".")) from None
            yield client, scheduler, len(_worker_addresses(client))
        finally:
            client.close()
        return
    from ..runtime.mainguard import unguarded_main_script

    where = unguarded_main_script()
    if where is not None:
        import warnings

        script, line = where
        warnings.warn_explicit(
            f"cogniframe: {script} starts this sweep at its top level, not under "
            f'`if __name__ == "__main__":`, and every Dask worker process would run the script again; '
            f"the designs are checked one at a time in this process instead. Put the script's code under "
            f"that line to check them on {workers or max(1, os.cpu_count() or 1)} worker processes.",
            UserWarning, script, line)
        # one thread: the FE model is Python-bound (threads would not run it faster) and gmsh is not thread-safe
        cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None,
                               scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                               silence_logs=logging.CRITICAL)
        client = Client(cluster)
        try:
            yield client, cluster.scheduler_address, 1
        finally:
            client.close()
            cluster.close()
        return
    n = workers or max(1, os.cpu_count() or 1)
    # no dashboard; the scheduler's small HTTP server on a free localhost port (not 8787: another
    # cluster may hold it, and not on every interface)
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None,
                           scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                           silence_logs=logging.CRITICAL)  # shutdown chatter of the workers is not the user's business
    client = Client(cluster)
    try:
        # every worker registered before the first batch goes out (evaluate_all spreads the first
        # round over the workers the scheduler knows)
        client.wait_for_workers(n, timeout=60)
        yield client, cluster.scheduler_address, n
    finally:
        client.close()
        cluster.close()


def _worker_addresses(client) -> list[str]:
    """The addresses of every worker the scheduler knows, sorted (newer `distributed` lists only
    the first few unless asked for all)."""
    import inspect

    all_of_them = "n_workers" in inspect.signature(client.scheduler_info).parameters
    info = client.scheduler_info(n_workers=-1) if all_of_them else client.scheduler_info()
    return sorted(info.get("workers", {}))


MIN_BATCH, MAX_BATCH = 4, 64


def batch_sizes(n_designs: int, n_workers: int, requested: int | None) -> list[int]:
    """Designs per task, in submission order: `requested` each when the sweep file sets `batch`;
    otherwise each batch half the designs left per worker (at most 64, at least 4), so
    the batches shrink towards the end. Few large batches keep the scheduling and the client's
    parquet files few; small last ones let the workers finish together (with equal batches the
    last one runs alone while the other workers idle, up to a batch's time)."""
    if requested:
        return [requested] * math.ceil(n_designs / requested)
    out, left = [], n_designs
    while left > 0:
        size = min(left, max(MIN_BATCH, min(MAX_BATCH, math.ceil(left / max(1, 2 * n_workers)))))
        out.append(size)
        left -= size
    return out


def check_workers(client) -> None:
    """Import the pipeline on every worker (`evaluate.warm_up`) and refuse workers whose code hash
    differs from this machine's: their rows would not match."""
    codes = client.run(ev.warm_up)
    mine = ev.code_digest()
    other = {addr: c for addr, c in codes.items() if c != mine}
    if other:
        raise UserError(f"Dask worker(s) {', '.join(sorted(other))} run different cogniframe code than this machine "
                        f"(code hash {', '.join(sorted(set(other.values())))} against {mine}): their rows would not match. "
                        "Fix: install the same cogniframe version on every worker and restart them.")


def evaluate_all(client, base: dict, items: list[dict], timeout_s: float, size: int | Sequence[int], n_workers: int,
                 on_batch: Callable[[list[dict]], None] | None = None, text: str | None = None,
                 base_name: str = "the base", checked: bool = False) -> list[dict]:
    """Evaluate `items` (overrides) in batches of `size` designs (or of the sizes listed, in order)
    on the cluster; rows in the order of `items`. `checked`: `check_workers` already ran.

    At most 2 batches per worker are in flight, so a kill loses little and results stream back.
    """
    from distributed import as_completed

    if not checked:
        check_workers(client)
    # the base params and text go with each batch (a few kB), not scattered once: scattered data
    # lives only on the workers, so a worker that dropped out (killed, or its heartbeat missed on a
    # loaded machine) took it along and the batches that needed it were cancelled ("lost
    # dependencies", seen once in the test suite); a batch's own arguments are re-sent with it
    sizes = [size] * math.ceil(len(items) / size) if isinstance(size, int) else list(size)
    starts = [0, *itertools.accumulate(sizes)][:-1]
    batches = [items[a:a + n] for a, n in zip(starts, sizes) if items[a:a + n]]
    index = {}
    rows_by_batch: dict[int, list[dict]] = {}
    todo = iter(enumerate(batches))
    ac = as_completed()
    # the first round goes round-robin over the connected workers: left to itself the scheduler may
    # queue a short sweep's every batch on the first worker that asked; the hint is loose, so a
    # batch whose worker has gone runs on another
    addrs = _worker_addresses(client)
    for n in range(max(1, 2 * n_workers)):
        nxt = next(todo, None)
        if nxt is None:
            break
        where = dict(workers=[addrs[n % len(addrs)]], allow_other_workers=True) if addrs else {}
        fut = client.submit(ev.evaluate_batch, base, nxt[1], timeout_s, text, base_name, pure=False, **where)
        index[fut.key] = nxt[0]
        ac.add(fut)
    for fut in ac:
        rows = fut.result()
        i = index.pop(fut.key)
        rows_by_batch[i] = rows
        fut.release()
        if on_batch:
            on_batch(rows)
        nxt = next(todo, None)
        if nxt is not None:
            f2 = client.submit(ev.evaluate_batch, base, nxt[1], timeout_s, text, base_name, pure=False)
            index[f2.key] = nxt[0]
            ac.add(f2)
    return [r for i in range(len(batches)) for r in rows_by_batch[i]]


# -- the sweep -------------------------------------------------------------------------------

def run_sweep(sweep: Sweep, out_dir: Path | None = None, scheduler: str | None = None, workers: int | None = None,
              progress: Callable[[BatchDone], None] | None = None, reports: bool = True) -> SweepResult:
    """Evaluate the sweep's designs not done yet into `out_dir` (locked: a second sweep into the same
    folder is refused, exit 2, instead of both evaluating the same designs)."""
    from ..outdir import lock

    out_dir = Path(out_dir) if out_dir is not None else default_out(sweep)
    claim_folder(out_dir, "sweep", sweep, write=False)
    with lock(out_dir):
        return _run_sweep(sweep, out_dir, scheduler, workers, progress, reports)


def _run_sweep(sweep: Sweep, out_dir: Path, scheduler: str | None, workers: int | None,
               progress: Callable[[BatchDone], None] | None, reports: bool) -> SweepResult:
    t0 = time.perf_counter()
    code = code_digest()
    designs = plan(sweep)
    log = read_log(out_dir, code)
    done = set()
    if len(log):
        done = set(log.loc[log["verdict"] != "TIMEOUT", "design_id"])
    todo = [(i, o) for i, o in designs if i not in done]
    scheduler_addr, n_workers = scheduler or "", 0
    base_row = None
    if todo:
        with dask_client(scheduler, workers) as (client, scheduler_addr, n_workers):
            claim_folder(out_dir, "sweep", sweep)
            sizes = batch_sizes(len(todo), n_workers, sweep.settings.batch)
            count = {"n": 0}
            tb = time.perf_counter()

            def on_batch(rows: list[dict]) -> None:
                write_batch(out_dir, rows, code)
                count["n"] += len(rows)
                if progress:
                    progress(BatchDone(tuple(rows), rows[0]["worker"], count["n"], len(todo), time.perf_counter() - tb))

            check_workers(client)
            # the summary's base row on a worker, ahead of the batches: the client would have to
            # import and run the pipeline after the sweep for it (the same code: checked above)
            base_fut = client.submit(ev.evaluate_one, sweep.base_data, {}, sweep.settings.timeout_s, "", sweep.base_text,
                                     sweep.base_label, pure=False) if reports else None
            try:
                evaluate_all(client, sweep.base_data, [o for _, o in todo], sweep.settings.timeout_s, sizes, n_workers, on_batch,
                             sweep.base_text, sweep.base_label, checked=True)
            except KeyboardInterrupt:
                consolidate(out_dir, designs, code)  # what finished is in results.parquet; a rerun resumes
                raise
            base_row = _result_or_none(base_fut)
    else:
        claim_folder(out_dir, "sweep", sweep)
    table = consolidate(out_dir, designs, code)
    counts = table["verdict"].value_counts().to_dict() if len(table) else {}
    result = SweepResult(out_dir, len(designs), len(todo), len(designs) - len(todo), {k: int(v) for k, v in counts.items()},
                         time.perf_counter() - t0, scheduler_addr, n_workers)
    if reports:
        from . import report

        report.write_reports(out_dir, sweep, table, result, base_row)
    return result


def _result_or_none(fut):
    """A future's result, or None when its task failed (a worker lost): the caller computes it itself."""
    if fut is None:
        return None
    try:
        return fut.result()
    except Exception:
        return None


def consolidate(out_dir: Path, designs: list[tuple[str, dict]], code: str):
    """DIR/results.parquet: the latest row of every design of this sweep, in sampling order."""
    import pandas as pd

    log = read_log(out_dir, code)
    if not len(log):
        return pd.DataFrame()
    log = log.assign(_timeout=(log["verdict"] == "TIMEOUT"))
    # prefer a finished row over a TIMEOUT one; among equals the last written
    log = log.sort_values("_timeout", kind="stable").drop_duplicates("design_id", keep="first")
    order = {d: i for i, (d, _) in enumerate(designs)}
    log = log[log["design_id"].isin(order)].drop(columns="_timeout")
    log = log.sort_values("design_id", key=lambda s: s.map(order), kind="stable").reset_index(drop=True)
    tmp = out_dir / f".{RESULTS}.{os.getpid()}.tmp"
    log = _frame(log)  # batches may disagree on a column's type (all None in one, text in another)
    log.to_parquet(tmp, engine="pyarrow", index=False)
    tmp.replace(out_dir / RESULTS)
    return log


def progress_printer(stream=None) -> Callable[[BatchDone], None]:
    """A rich progress bar on a terminal; one plain line per batch otherwise."""
    stream = stream or sys.stderr
    if stream.isatty():
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

        bar = Progress(TextColumn("sweep"), BarColumn(), MofNCompleteColumn(), TextColumn("{task.fields[rate]}"),
                       TimeRemainingColumn(), console=Console(file=stream), transient=True)
        state: dict = {}

        def show(b: BatchDone) -> None:
            if "task" not in state:
                bar.start()
                state["task"] = bar.add_task("sweep", total=b.total, rate="")
            bar.update(state["task"], completed=b.done, rate=f"{b.done / max(b.seconds, 1e-9):.1f} designs/s")
            if b.done >= b.total:
                bar.stop()

        return show

    def line(b: BatchDone) -> None:
        verdicts = {}
        for r in b.rows:
            verdicts[r["verdict"]] = verdicts.get(r["verdict"], 0) + 1
        v = ", ".join(f"{n} {k}" for k, n in sorted(verdicts.items()))
        origin = f" from {b.worker}" if b.label == "batch" else ""
        stream.write(f"{b.label} of {len(b.rows)} ({v}){origin}: {b.done}/{b.total} done, "
                     f"{b.done / max(b.seconds, 1e-9):.1f} designs/s\n")
        stream.flush()

    return line
