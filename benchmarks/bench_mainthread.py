"""Main-thread CPU of the build's output steps (plates, previews, GLB, plots, figures, renders, viewer).

    python benchmarks/bench_mainthread.py [--params params/carbon.yaml] [--runs 3] [--out DIR] [--keep-keys]
        [--profile TASK]

Runs one build in this process with the cache folder of COGNIFRAME_CACHE (the part steps come from
it after the first run), with each output step run `--runs` times in a row, uncached, and prints the
median and the first run's CPU seconds of the thread that ran it (time.thread_time: the main
thread's own CPU, not the CAD workers' or the slicer's). The first run of a step pays what it
shares with later steps (reading a part's STL once per build); the median is the step alone.
With --keep-keys and --runs 1: the main thread's CPU of an incremental build, step by step (build
once, change the params, run again with the same cache folder).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TIMED = ("plates:", "previews:", "glb", "plots", "figures", "render:", "renders", "viewer")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--params", default=str(ROOT / "params" / "carbon.yaml"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--out", default=None)
    ap.add_argument("--keep-keys", action="store_true",
                    help="keep the steps' cache keys (a step from the cache is not timed): time an incremental build once")
    ap.add_argument("--profile", default=None, help="cProfile this step's first run (a task name: glb, previews:abs)")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from rich.console import Console

    from cogniframe.pipeline import steps
    from cogniframe.pipeline import run_build
    from cogniframe.spec import load as load_spec

    times: dict[str, list[float]] = {}
    proc: dict[str, list[float]] = {}  # the whole process's CPU meanwhile (threads of libraries)

    def timed(step):
        def run(ctx, **kw):
            name = step.name.format(**kw)
            made = None
            for _ in range(args.runs):
                prof = None
                if name == args.profile and name not in times:
                    import cProfile

                    prof = cProfile.Profile()
                    prof.enable()
                t0, p0 = time.thread_time(), time.process_time()
                made = step.run(ctx, **kw)
                if prof is not None:
                    prof.disable()
                    import pstats

                    pstats.Stats(prof, stream=sys.stderr).sort_stats("cumulative").print_stats(40)
                times.setdefault(name, []).append(time.thread_time() - t0)
                proc.setdefault(name, []).append(time.process_time() - p0)
            return made
        if args.keep_keys:
            return dataclasses.replace(step, run=run)
        return dataclasses.replace(step, run=run, key=None)  # uncached: it runs every time

    steps.STEPS = tuple(timed(s) if s.name.startswith(TIMED) else s for s in steps.STEPS)
    spec = load_spec(Path(args.params))
    out = Path(args.out or tempfile.mkdtemp(prefix="bench-mainthread-")) / "build"
    run_build(spec, Path(args.params), out, use_cache=True, console=Console(stderr=True, quiet=True))
    total = 0.0
    groups: dict[str, float] = {}
    for name, ts in times.items():
        med = statistics.median(ts)
        total += med
        g = name.split(":")[0]
        groups[g] = groups.get(g, 0.0) + med
        print(f"{name:32s} median {med:6.3f} s CPU   first {ts[0]:6.3f} s   process {statistics.median(proc[name]):6.3f} s ({len(ts)} runs)")
    print("-- by step (sum of medians)")
    for g, v in groups.items():
        print(f"{g:32s} {v:6.3f} s CPU")
    print(f"{'total':32s} {total:6.3f} s CPU")


if __name__ == "__main__":
    main()
