"""Sweep throughput and resume timings on a LocalCluster of worker processes.

Run: python benchmarks/bench_sweep.py [--designs 120] [--workers 2] [--repeat 3]

Prints medians over --repeat runs of:
  1. new designs: every design new, with the example sweeps' closed-form joints (frame model, load
     cases and drop model solved per design), designs/s over the batches;
  2. repeat designs: the same designs into a new folder with the workers' caches filled (k, load
     cases and peaks read from the cache);
  3. resume: a rerun into the finished folder (everything skipped), and after losing half the
     batch files (as a killed sweep would);
  4. the per-design breakdown, serial in this process with single-threaded BLAS as in a worker.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(v, "1")  # as in a Dask worker; also keeps the breakdown comparable


def sweep_text(n: int) -> str:
    return f"""base: {ROOT / 'params' / 'carbon.yaml'}
samples: {n}
sampler: lhs
seed: 11
set:
  model.stiffness_model: analytic  # as the example sweeps: closed-form joints (the solid FE is 30-60 s per new joint)
vary:
  rods.diameter: [2.5, 4.0]
  joints.wall: [1.6, 2.0]
  joints.socket_depth: [8, 14]
  frame.height: [105, 140]
  rods.material: {{choices: [carbon_rod, bamboo]}}
"""


def rate_of(run_sweep, sweep, out, workers):
    """(designs/s wall over the batches, designs/s the workers' CPU time allows, wall of the run)."""
    import pandas as pd

    marks = []
    res = run_sweep(sweep, out, workers=workers, progress=lambda b: marks.append((b.done, b.seconds)), reports=False)
    # designs/s from the first to the last finished batch: excludes cluster start-up and warm-up
    (d0, t0), (d1, t1) = marks[0], marks[-1]
    cpu = pd.read_parquet(out / "results.parquet")["cpu_seconds"]
    return (d1 - d0) / max(t1 - t0, 1e-9), workers / float(cpu.median()), res.seconds


def breakdown(n: int = 12) -> dict[str, float]:
    """Median CPU ms per stage of one new design's check (nothing cached: every design differs),
    and of a whole `check` + row of another new design."""
    import yaml

    from cogniframe import cutlist, frame, partlist
    from cogniframe.analysis import verdict
    from cogniframe import spec as spec_mod
    from cogniframe.analysis import drop, flight, mass
    from cogniframe.sweep import evaluate as ev

    base = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    base["name"] = "carbon"
    base.setdefault("model", {})["stiffness_model"] = "analytic"  # as the sweep above
    names = ("validate", "frame (frame.build)", "parts + cut list + mass", "k: joints + play + secant solve",
             "drop model (impact)", "load cases (wall, thrust, modes, buckling, strain)", "peaks + flight",
             "whole design: check + row")
    t: dict[str, list[float]] = {k: [] for k in names}
    clock = time.thread_time
    for i in range(n + 1):
        marks = [clock()]
        s = spec_mod.from_dict(ev.apply_overrides(base, {"frame.height": 105 + 2.31 * i})); marks.append(clock())
        fr = frame.build(s); marks.append(clock())
        parts = partlist.build(s, fr); cut = cutlist.build(s, fr); budget = mass.budget(s, fr, cut, parts, None)
        marks.append(clock())
        session = drop.Session(s, fr, parts)
        drop.predicted_k_n_per_m(s, fr, budget.total_g, session); marks.append(clock())
        dr = drop.evaluate_design(s, fr, budget.total_g, session); marks.append(clock())
        drop.load_cases(s, fr, budget.total_g, dr, session); marks.append(clock())
        drop.peak_prediction(s, budget.total_g, dr, budget.groups["exoskeleton"]); flight.evaluate(s, budget.total_g)
        marks.append(clock())
        other = ev.apply_overrides(base, {"frame.height": 106 + 2.31 * i})
        ev.outputs(verdict.check_dict(verdict.check(spec_mod.from_dict(other)))); marks.append(clock())
        if i:  # the first pays imports
            for k, a, b in zip(names, marks, marks[1:]):
                t[k].append(b - a)
    return {k: statistics.median(v) * 1000 for k, v in t.items()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--designs", type=int, default=120)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    from cogniframe.sweep import spec
    from cogniframe.sweep.run import run_sweep

    cold, warm, startup, resume_all, resume_half, cold_cpu, warm_cpu = [], [], [], [], [], [], []
    load0 = os.getloadavg()[0]
    for r in range(args.repeat):
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            os.environ["COGNIFRAME_CACHE"] = str(tmp / "cache")  # the workers inherit it: cold FE cache
            (tmp / "s.yaml").write_text(sweep_text(args.designs))
            sweep = spec.load(tmp / "s.yaml")
            rate, cpu_rate, wall = rate_of(run_sweep, sweep, tmp / "cold", args.workers)
            cold.append(rate)
            cold_cpu.append(cpu_rate)
            startup.append(wall - args.designs / rate)
            rate, cpu_rate, _ = rate_of(run_sweep, sweep, tmp / "warm", args.workers)
            warm.append(rate)
            warm_cpu.append(cpu_rate)
            t0 = time.perf_counter()
            run_sweep(sweep, tmp / "cold", workers=args.workers, reports=False)
            resume_all.append(time.perf_counter() - t0)
            files = sorted((tmp / "cold" / "results").glob("*.parquet"))
            for f in files[::2]:
                f.unlink()
            t0 = time.perf_counter()
            res = run_sweep(sweep, tmp / "cold", workers=args.workers, reports=False)
            resume_half.append(time.perf_counter() - t0)
    med = statistics.median
    print(f"{args.designs} designs (examples/sweeps/carbon.yaml box), LocalCluster of {args.workers} worker processes, "
          f"{os.cpu_count()} cores, median of {args.repeat}:")
    print(f"  load average at start {load0:.1f}, at end {os.getloadavg()[0]:.1f} (wall rates fall when the cores are shared)")
    print(f"  new designs (closed-form joints): {med(cold):6.1f} designs/s wall; "
          f"{med(cold_cpu):6.1f} designs/s on {args.workers} dedicated cores (from the median CPU time per design)")
    print(f"  repeat designs (k, cases cached): {med(warm):6.1f} designs/s wall; "
          f"{med(warm_cpu):6.1f} designs/s on {args.workers} dedicated cores")
    print(f"  cluster start + warm-up + reports overhead per run: {med(startup):.1f} s")
    print(f"  resume, everything done:          {med(resume_all):6.2f} s (no cluster started)")
    print(f"  resume, half the batches lost:    {med(resume_half):6.2f} s ({res.evaluated} designs re-run, cached FE)")
    print("per new design, serial, single-threaded BLAS (median CPU ms of this thread):")
    for k, v in breakdown().items():  # CPU time of this thread: independent of other load
        print(f"  {k:28s} {v:7.1f}")


if __name__ == "__main__":
    main()
