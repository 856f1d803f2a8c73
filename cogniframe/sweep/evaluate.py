"""One design on a worker: base params (a dict) + dotted overrides -> validate -> check -> one row.

Pure with respect to the client: the base params travel as data, nothing is read from the
client's disk. What a worker keeps between tasks is its imports and the FE stiffness cache
(cogniframe.cache, by input hash), so a design seen before costs no FE solve.

A row is a flat dict: `design_id`, every varied key under its dotted name, `verdict`
(PASS, FAIL, INVALID, TIMEOUT or ERROR), `problems`, `error`, the outputs (`mass_g`, `k_n_per_m`,
`max_safe_drop_cm`, `prop_margin_mm`, `joints_outside_box`, ...; plus every scalar of any further section of
`check --json`, e.g. `stiffness.k_lateral_n_per_m` or `flight.hover_time_min`, under its dotted
name), `worker`, `seconds` (wall) and `cpu_seconds` (the evaluating thread's CPU time).
"""

from __future__ import annotations

import copy
import ctypes
import hashlib
import json
import threading
import time
from types import MappingProxyType

# check --json sections read into fixed columns below; every other section's scalars flow through.
_KNOWN = {"name", "verdict", "problems", "mass", "cutlist", "stock", "frame", "parts", "drop", "notes"}
OUTPUTS = ("mass_g", "mass_margin_g", "k_n_per_m", "c_n_s_per_m", "max_safe_drop_cm", "prop_margin_mm", "clearance_mm",
           "stock_rods", "joints_outside_box")


# What a sweep's check leaves out, as `verdict.check`'s options: lists no column records (a row
# keeps only scalars) and no verdict reads; every recorded column keeps check's value.
# `peaks`: the peak deceleration per drop height (computed all the same when
# requirements.max_peak_g makes it part of the verdict). `modes`: the natural frequencies
# (`stiffness.modes_hz`); the recorded `stiffness.mode_near_rotor` is decided by an eigenvalue
# count instead of the eigensolver. `survival_margins`: the survival sweep's per-height margins
# above the first failure (`survival.max_undamaged_drop_cm` and `survival.first_failure.*` are
# the whole sweep's). The thrust case and the rest of the load cases are recorded and run as in check.
CHECK_OPTIONS = MappingProxyType({"peaks": False, "modes": False, "survival_margins": False})


class DesignTimeout(BaseException):
    """Raised inside a design's evaluation when it runs past its time limit (BaseException, so a
    broad `except Exception` in the pipeline cannot swallow it)."""


def apply_overrides(base: dict, overrides: dict) -> dict:
    """A deep copy of `base` with each dotted key set (missing sections are created)."""
    data = copy.deepcopy(base)
    for dotted, v in overrides.items():
        node = data
        parts = dotted.split(".")
        for p in parts[:-1]:
            if not isinstance(node.get(p), dict):
                node[p] = {}
            node = node[p]
        node[parts[-1]] = v
    return data


def design_id(params: dict) -> str:
    """Hash of a design's full params (the base with its overrides applied)."""
    return hashlib.sha256(json.dumps(params, sort_keys=True, default=str).encode()).hexdigest()[:16]


def check_row(params: dict, source: str, text: str | None = None) -> dict:
    """Validate and check one design; INVALID (with the error text) instead of raising.

    `text` is the base file's text: messages then give a key's line in the base file (the varied
    keys sit on the same lines), and never call a key the base sets "not set in the file"."""
    from ..analysis import verdict
    from .. import spec as spec_mod
    from ..errors import UserError

    try:
        spec = spec_mod.from_dict(params, source=source, text=text)
        with spec.blamed():  # a later stage's error gains the key's line, as in `cogniframe check`
            result = verdict.check(spec, **CHECK_OPTIONS)
    except UserError as e:
        return {"verdict": "INVALID", "problems": "", "error": str(e)}
    return outputs(verdict.check_dict(result))


def outputs(d: dict) -> dict:
    """The row's output columns from a `check --json` dict, read by key so new sections flow in."""
    mass = d.get("mass", {})
    drop = d.get("drop") or {}
    frame = d.get("frame", {})
    props = frame.get("prop_margin_mm") or []
    margins = [min(v for k, v in p.items() if k.endswith("_mm")) for p in props]
    row = {
        "verdict": d["verdict"],
        "problems": "; ".join(d.get("problems", [])),
        "error": "",
        "mass_g": mass.get("total_g"),
        "mass_margin_g": mass.get("margin_g"),
        "k_n_per_m": drop.get("k_n_per_m"),
        "c_n_s_per_m": drop.get("c_n_s_per_m"),
        "max_safe_drop_cm": drop.get("max_safe_height_cm"),
        "prop_margin_mm": min(margins) if margins else None,
        "clearance_mm": frame.get("clearance_mm"),
        "stock_rods": (d.get("stock") or {}).get("count"),
        # the joints the surrogate does not cover (solved by FE instead), "" when none: check's notes
        "joints_outside_box": "; ".join(n for n in d.get("notes", []) if n.startswith("joint ")),
    }
    for section, value in d.items():
        if section in _KNOWN or section in row:
            continue
        if isinstance(value, dict):
            row.update(_flatten(value, section))
        elif isinstance(value, (bool, int, float)) and value is not None:  # a top-level scalar, e.g. peak_g
            row[section] = value
    return row


def _flatten(d: dict, prefix: str) -> dict:
    out = {}
    for k, v in d.items():
        name = f"{prefix}.{k}"
        if isinstance(v, dict):
            out.update(_flatten(v, name))
        elif isinstance(v, (bool, int, float, str)) or v is None:
            out[name] = v
    return out


def run_with_timeout(fn, timeout_s: float):
    """fn() in this thread, interrupted with DesignTimeout after timeout_s seconds.

    Dask runs tasks in worker threads, where signals cannot reach; the watchdog raises the
    exception asynchronously in this thread (CPython's PyThreadState_SetAsyncExc). It lands at the
    next Python bytecode, so a long C call (a LAPACK solve) finishes first.
    """
    tid = threading.get_ident()
    lock = threading.Lock()
    state = {"done": False}

    def fire():
        with lock:
            if not state["done"]:
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(tid), ctypes.py_object(DesignTimeout))

    timer = threading.Timer(timeout_s, fire)
    timer.daemon = True
    timer.start()
    try:
        return fn()
    finally:
        with lock:
            state["done"] = True
        timer.cancel()


def evaluate_one(base: dict, overrides: dict, timeout_s: float, worker: str = "", text: str | None = None,
                 base_name: str = "the base") -> dict:
    """The full row of one design (never raises for a bad design). `text`: the base file's text."""
    params = apply_overrides(base, overrides)
    did = design_id(params)
    t0, c0 = time.perf_counter(), time.thread_time()
    try:
        try:
            out = run_with_timeout(lambda: check_row(params, f"design {did} of {base_name}", text), timeout_s)
        except DesignTimeout:
            out = {"verdict": "TIMEOUT", "problems": "", "error": f"cut off after {timeout_s:g} s (sweep timeout_s)"}
        except Exception as e:  # a bug or a numerical failure in one design must not stop the sweep
            out = {"verdict": "ERROR", "problems": "", "error": f"{type(e).__name__}: {e}"}
    except DesignTimeout:  # the watchdog fired just as the design finished
        out = {"verdict": "TIMEOUT", "problems": "", "error": f"cut off after {timeout_s:g} s (sweep timeout_s)"}
    seconds, cpu = time.perf_counter() - t0, time.thread_time() - c0
    if seconds > timeout_s and out["verdict"] != "TIMEOUT":
        # finished before the watchdog got the GIL (it waits up to the interpreter's switch interval,
        # 5 ms): still over the limit, so recorded as what the limit says
        out = {"verdict": "TIMEOUT", "problems": "", "error": f"took {seconds:.3g} s, over the {timeout_s:g} s limit (sweep timeout_s)"}
    row = {"design_id": did, **overrides}
    row.update({k: None for k in OUTPUTS})
    row.update(out)
    # cpu_seconds: this thread's CPU time, what the design costs on a core of its own (seconds is
    # wall time and grows when the machine is shared)
    row.update({"worker": worker, "seconds": round(seconds, 6), "cpu_seconds": round(cpu, 6)})
    return row


def evaluate_batch(base: dict, batch: list[dict], timeout_s: float, text: str | None = None,
                   base_name: str = "the base") -> list[dict]:
    """A Dask task: every design of `batch` in turn on this worker; rows in the same order."""
    worker = _worker_address()
    rows = []
    for overrides in batch:
        try:
            rows.append(evaluate_one(base, overrides, timeout_s, worker, text, base_name))
        except DesignTimeout:  # a watchdog that fired in the last instructions of evaluate_one
            rows.append(_timeout_row(base, overrides, timeout_s, worker))
    return rows


def _timeout_row(base: dict, overrides: dict, timeout_s: float, worker: str) -> dict:
    row = {"design_id": design_id(apply_overrides(base, overrides)), **overrides, **{k: None for k in OUTPUTS},
           "verdict": "TIMEOUT", "problems": "", "error": f"cut off after {timeout_s:g} s (sweep timeout_s)"}
    row.update({"worker": worker, "seconds": timeout_s, "cpu_seconds": None})
    return row


def _worker_address() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return "local"


def code_digest() -> str:
    """Hash of the modules a design's evaluation runs (cogniframe/*.py, analysis/, this file)."""

    from ..cache import code_hash

    return code_hash("*.py", "analysis/*.py", "analysis/joints/*.py", "sweep/evaluate.py")[:12]


def dask_setup(worker=None) -> None:
    """`dask worker ADDRESS --preload cogniframe.sweep.evaluate`: Dask calls this when the worker
    starts, so the pipeline's imports (~1.5 s) are paid then, not at the start of the first sweep."""
    warm_up()


def warm_up() -> str:
    """Run on every worker (client.run) before the clock starts: import the pipeline and what the
    frame model imports on first use (scipy's sparse LU and eigensolver, dense eigh), and return
    the worker's code hash (the client refuses workers running other code)."""
    from ..analysis import verdict  # noqa: F401
    from ..analysis import drop, framefe, impact, stiffness  # noqa: F401

    import scipy.linalg  # noqa: F401
    import scipy.sparse.linalg  # noqa: F401
    return code_digest()
