"""`cogniframe optimize` on a Dask cluster, the joints from the solid FE's surrogate (the default),
every cache empty: the docs' example run (docs/sweeps.md, "Result on the carbon preset").

Run: python benchmarks/bench_optimize.py [--trials 300] [--workers 2] [--repeat 1] [--sweep FILE] [--ab]

Starts `dask scheduler` and N `dask worker --nthreads 1` processes as benchmarks/bench_sweep.py
does (this checkout first on their PYTHONPATH, a new empty COGNIFRAME_CACHE per run), then
minimises mass_g with max_safe_drop_cm >= 120 over --sweep's vary box (default
examples/sweeps/carbon.yaml) and prints, per run and as medians: the wall time (cluster already
up), trials/s, the median CPU seconds per trial on a worker, how many trials had a joint outside
the surrogate's box (solved by FE) and the CPU those took, the best mass found, and the load
average before and after (the machine may be shared: wall times move with it).
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
sys.path.insert(0, str(ROOT / "benchmarks"))
for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(v, "1")  # as in a Dask worker


def one_run(sweep_file: Path, trials: int, workers: int, port: int, as_before: bool = False) -> dict:
    import optuna
    import pandas as pd
    from bench_sweep import Cluster

    from cogniframe.sweep import optimize, sweepfile
    from cogniframe.sweep.optimize import parse_constraint, parse_objectives, run_optimize

    client = {"ask": 0.0, "write": 0.0}  # the client's own time in optuna's ask and in writing trials.parquet
    ask, write = optuna.study.Study.ask, optimize._write_trials

    def timed(key, fn):
        def wrapped(*a, **k):
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                client[key] += time.perf_counter() - t
        return wrapped

    saved = optimize.TRIALS_WRITE_S
    optuna.study.Study.ask, optimize._write_trials = timed("ask", ask), timed("write", write)
    if as_before:  # trials.parquet rewritten every round: the client as it was
        optimize.TRIALS_WRITE_S = 0.0

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        cluster = Cluster(workers, tmp / "cache", port)
        try:
            sweep = sweepfile.load(sweep_file)
            t0 = time.perf_counter()
            result = run_optimize(sweep, parse_objectives(["mass_g"], []), [parse_constraint("max_safe_drop_cm >= 120")],
                                  tmp / "out", trials=trials, scheduler=cluster.address)
            wall = time.perf_counter() - t0
        finally:
            cluster.close()
            optuna.study.Study.ask, optimize._write_trials = ask, write
            optimize.TRIALS_WRITE_S = saved
        table = pd.read_parquet(tmp / "out" / "trials.parquet")
        keys = [c for c in table.columns if c in {k.name for k in sweep.keys}]
        assert len(keys) == len(sweep.keys), (keys, list(table.columns))  # the designs asked, to compare runs
        params = table[["trial", *keys]].to_csv(index=False)
    outside = table["joints_outside_box"].fillna("") != ""
    cpu = table["cpu_seconds"].dropna()
    best = result.best["mass_g"] if result.best else None
    return {"wall": wall, "rate": len(table) / wall, "cpu": float(cpu.median()), "outside": int(outside.sum()),
            "outside_cpu": float(table.loc[outside, "cpu_seconds"].sum()), "all_cpu": float(cpu.sum()), "best": best,
            "trials": len(table), "ask": client["ask"], "write": client["write"], "params": params}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=300)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--port", type=int, default=8899)
    ap.add_argument("--sweep", type=Path, default=ROOT / "examples" / "sweeps" / "carbon.yaml")
    ap.add_argument("--ab", action="store_true", help="alternate runs with the client as it was (trials.parquet "
                    "rewritten every round), and check both asked the same designs")
    args = ap.parse_args()
    load0 = os.getloadavg()
    runs = [one_run(args.sweep, args.trials, args.workers, args.port + r, as_before=args.ab and r % 2 == 0)
            for r in range(args.repeat * (2 if args.ab else 1))]
    load1 = os.getloadavg()
    med = statistics.median
    print(f"optimize {args.sweep.name}: minimise mass_g, max_safe_drop_cm >= 120, {args.trials} trials, surrogate joints, "
          f"empty caches; `dask scheduler` + {args.workers} `dask worker --nthreads 1`; {os.cpu_count()} cores")
    print(f"  load average (1, 5, 15 min) before {load0[0]:.1f} {load0[1]:.1f} {load0[2]:.1f}, "
          f"after {load1[0]:.1f} {load1[1]:.1f} {load1[2]:.1f}")
    for i, r in enumerate(runs):
        tag = ("as before: " if i % 2 == 0 else "now: ") if args.ab else ""
        print(f"  {tag}run: wall {r['wall']:.1f} s (client: ask {r['ask']:.1f} s, trials.parquet {r['write']:.2f} s), "
              f"{r['rate']:.1f} trials/s, CPU per trial (median) {1000 * r['cpu']:.1f} ms, "
              f"{r['outside']} trials with a joint outside the surrogate's box (FE: {r['outside_cpu']:.1f} s of the "
              f"workers' {r['all_cpu']:.1f} s CPU), best mass {r['best']}")
    if args.ab:
        for name, part in (("as before", runs[0::2]), ("now", runs[1::2])):
            print(f"  {name}: median wall {med(r['wall'] for r in part):.1f} s, client ask {med(r['ask'] for r in part):.1f} s, "
                  f"trials.parquet {med(r['write'] for r in part):.2f} s")
        print(f"  every run asked the same designs: {len({r['params'] for r in runs}) == 1}")
    else:
        print(f"  median wall {med(r['wall'] for r in runs):.1f} s")


if __name__ == "__main__":
    main()
