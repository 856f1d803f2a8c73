"""Where a new design's `check` spends its time, in-process, with the surrogate joint model (the
studio's and the sweeps' path), stage by stage.

Run: python benchmarks/bench_check_profile.py [--designs 20] [--seed 5] [--sweep] [--cprofile 30]

Draws --designs random designs (tests/design_space.py, "edit" mode: a box and a few keys changed
as a person does, either preset) with `model.stiffness_model: surrogate`, keeps those that
validate and whose joints lie inside the surrogate's training box (no FE), and checks each as the
studio does: `api.from_text` (YAML, validation, frame, part list, cut list), then
`Design.check()` and its `to_dict()` (the `check --json` object), every cache empty (a new
COGNIFRAME_CACHE folder; the first design, checked before, only warms the imports).

Each stage below is a function wrapped for the run; the time between two events (a stage entered
or left) goes to the innermost stage running, so the stages add up to the whole and a stage
called inside another (the part list inside the fasteners) counts once, where it runs. `calls`
is the stage's calls per design: a figure computed twice shows as 2. Printed: the median per
design of each stage's CPU time (this thread's, which the machine's other load moves least) and
of the whole, and the wall and CPU medians of `check()` alone and with validation.

--sweep checks with the sweep's options (sweep.evaluate.CHECK_OPTIONS: no peak list, no mode
list, survival margins up to the first failure) from `spec.from_dict`, as a sweep worker does.
--cprofile N adds cProfile's N functions of most own time over the same designs (a second pass).
"""

from __future__ import annotations

import argparse
import copy
import functools
import importlib
import os
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))
for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(v, "1")  # as a check computes (one_blas_thread) and as a Dask worker runs

# (module, function, stage): the function is looked up on its module at each call by its callers
# (module attribute or a function-level import), so replacing it there times every call.
STAGES = (
    ("cogniframe.spec", "parse_yaml", "params: YAML"),
    ("cogniframe.spec", "from_dict", "params: validation"),
    ("cogniframe.frame", "frame_of", "frame graph"),
    ("cogniframe.partlist", "part_list", "part list and peg plan"),
    ("cogniframe.families.joint", "core_links", "part list and peg plan"),
    ("cogniframe.cutlist", "cut_list", "cut list"),
    ("cogniframe.analysis.mass", "budget", "mass budget"),
    ("cogniframe.analysis.stiffness", "joint_models", "surrogate (joint models)"),
    ("cogniframe.analysis.stiffness", "model_layout", "frame model layout (once a check)"),
    ("cogniframe.analysis.stiffness", "secant_solution", "frame solve (k, play)"),
    ("cogniframe.analysis.impact", "evaluate", "drop model"),
    ("cogniframe.analysis.load_cases", "load_cases", "load cases"),
    ("cogniframe.analysis.load_cases", "_modes", "load cases: modes"),
    ("cogniframe.analysis.drop", "peak_prediction", "peak G per height"),
    ("cogniframe.analysis.verdict", "_survival", "survival"),
    ("cogniframe.fasteners", "fasteners", "fit check (fasteners)"),
    ("cogniframe.analysis.verdict", "fit_of", "fit check (fasteners)"),
    ("cogniframe.analysis.massprops", "estimate", "mass properties"),
    ("cogniframe.analysis.rotors", "model", "resonance (rotors, flags)"),
    ("cogniframe.analysis.resonance", "assess", "resonance (rotors, flags)"),
    ("cogniframe.analysis.flight", "evaluate", "flight"),
    ("cogniframe.analysis.verdict", "check_dict", "JSON"),
    ("cogniframe.cache", "load_json", "cache files"),
    ("cogniframe.cache", "store_json", "cache files"),
    ("cogniframe.cache", "store_text", "cache files"),
)
OTHER = "other (glue, the surrogate notes, ...)"


class Ledger:
    """Exclusive CPU and wall time per stage: each event charges the time since the last one to the
    innermost stage running."""

    def __init__(self):
        self.stack = [OTHER]
        self.cpu: dict[str, float] = {}
        self.wall: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self.last = (time.thread_time(), time.perf_counter())

    def _charge(self) -> None:
        now = (time.thread_time(), time.perf_counter())
        top = self.stack[-1]
        self.cpu[top] = self.cpu.get(top, 0.0) + now[0] - self.last[0]
        self.wall[top] = self.wall.get(top, 0.0) + now[1] - self.last[1]
        self.last = now

    def enter(self, label: str) -> None:
        self._charge()
        self.stack.append(label)
        self.calls[label] = self.calls.get(label, 0) + 1

    def leave(self) -> None:
        self._charge()
        self.stack.pop()

    def reset(self) -> None:
        self.cpu, self.wall, self.calls = {}, {}, {}
        self.stack = [OTHER]
        self.last = (time.thread_time(), time.perf_counter())


def instrument(ledger: Ledger) -> list:
    saved = []
    for mod_name, name, label in STAGES:
        mod = importlib.import_module(mod_name)
        f = getattr(mod, name, None)
        if f is None:
            print(f"  (no {mod_name}.{name} any more: stage {label!r} not timed there)")
            continue

        def timed(*a, _f=f, _label=label, **k):
            ledger.enter(_label)
            try:
                return _f(*a, **k)
            finally:
                ledger.leave()

        saved.append((mod, name, f))
        setattr(mod, name, functools.wraps(f)(timed))
    return saved


def designs(n: int, seed: int) -> list[dict]:
    """n params documents that validate with the surrogate model and need no joint FE."""
    import design_space

    import cogniframe.api as api
    from cogniframe import spec as spec_mod

    rnd = random.Random(seed)
    out = []
    while len(out) < n:
        doc = design_space.random_design(rnd, "edit")
        doc.setdefault("model", {})["stiffness_model"] = "surrogate"
        try:
            d = api.Design(spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml"), "", "x.yaml", None).validate()
        except Exception:  # noqa: BLE001 - a design the validation refuses: drawn again
            continue
        if not d.needs_fe():
            out.append(doc)
    return out


def run(docs: list[dict], sweep: bool, ledger: Ledger | None):
    import yaml

    import cogniframe.api as api
    from cogniframe import spec as spec_mod
    from cogniframe.analysis import verdict
    from cogniframe.sweep import evaluate

    texts = [yaml.safe_dump(d, sort_keys=False) for d in docs]
    rows = []
    for doc, text in zip(docs, texts):
        if ledger is not None:
            ledger.reset()
        t0, c0 = time.perf_counter(), time.thread_time()
        if sweep:
            s = spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml")
            t1, c1 = time.perf_counter(), time.thread_time()
            with s.blamed():
                verdict.check_dict(verdict.check(s, **evaluate.CHECK_OPTIONS))
        else:
            d = api.from_text(text, "x.yaml")
            t1, c1 = time.perf_counter(), time.thread_time()
            d.check().to_dict()
        t2, c2 = time.perf_counter(), time.thread_time()
        rows.append({"check_ms": 1000 * (t2 - t1), "all_ms": 1000 * (t2 - t0), "cpu_ms": 1000 * (c2 - c0),
                     "check_cpu_ms": 1000 * (c2 - c1),
                     "stages": dict(ledger.cpu) if ledger else {}, "calls": dict(ledger.calls) if ledger else {}})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--designs", type=int, default=20)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--sweep", action="store_true", help="the sweep's check (evaluate.CHECK_OPTIONS)")
    ap.add_argument("--cprofile", type=int, default=0, metavar="N", help="also print cProfile's top N by own time")
    args = ap.parse_args()
    os.environ["COGNIFRAME_CACHE"] = tempfile.mkdtemp(prefix="bench-check-warm-")
    docs = designs(args.designs + 1, args.seed)
    run(docs[:1], args.sweep, None)  # the imports, once
    os.environ["COGNIFRAME_CACHE"] = tempfile.mkdtemp(prefix="bench-check-")
    load0 = os.getloadavg()
    plain = run(docs[1:], args.sweep, None)
    os.environ["COGNIFRAME_CACHE"] = tempfile.mkdtemp(prefix="bench-check-")
    ledger = Ledger()
    saved = instrument(ledger)
    try:
        timed = run(docs[1:], args.sweep, ledger)
    finally:
        for mod, name, f in saved:
            setattr(mod, name, f)
    med = statistics.median
    print(f"{len(plain)} new designs (random, tests/design_space.py seed {args.seed}), surrogate joints, empty caches, "
          f"{'the sweep' if args.sweep else 'the studio'}'s path; {os.cpu_count()} cores, load average "
          f"{load0[0]:.1f} before, {os.getloadavg()[0]:.1f} after (a shared machine: wall times move with it)")
    print(f"  check() + to_dict():          median wall {med(r['check_ms'] for r in plain):7.1f} ms "
          f"(min {min(r['check_ms'] for r in plain):.1f}, max {max(r['check_ms'] for r in plain):.1f}), "
          f"CPU {med(r['check_cpu_ms'] for r in plain):.1f} ms")
    print(f"  with validation (from_text):  median wall {med(r['all_ms'] for r in plain):7.1f} ms, "
          f"CPU {med(r['cpu_ms'] for r in plain):.1f} ms")
    labels = list(dict.fromkeys([s[2] for s in STAGES] + [OTHER]))
    print("  per stage, median CPU ms per design (instrumented pass; calls per design):")
    total = 0.0
    for label in labels:
        v = med(r["stages"].get(label, 0.0) for r in timed) * 1000
        calls = med(r["calls"].get(label, 0) for r in timed)
        total += v
        print(f"    {label:34s} {v:7.1f}   x{calls:g}")
    print(f"    {'sum of the medians':34s} {total:7.1f}   (the instrumented whole: "
          f"{med(r['cpu_ms'] for r in timed):.1f} ms CPU)")
    if args.cprofile:
        import cProfile
        import pstats

        os.environ["COGNIFRAME_CACHE"] = tempfile.mkdtemp(prefix="bench-check-")
        pr = cProfile.Profile()
        pr.enable()
        run(docs[1:], args.sweep, None)
        pr.disable()
        pstats.Stats(pr).sort_stats("tottime").print_stats(args.cprofile)


if __name__ == "__main__":
    main()
