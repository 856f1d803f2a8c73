"""CPU seconds of the joint FE's condensation (`solid_fe.condense`) per distinct joint, split into
assembly, METIS order, the lower triangle and the CHOLMOD factorization + solve; one BLAS thread, as the build.

    python benchmarks/bench_joint_fe.py [params/carbon.yaml] [--runs 3]

Meshes each joint once (CadQuery + gmsh, not timed), then times `condense` on that mesh `--runs`
times in this process and prints the medians (time.process_time). Mirrored joints are skipped:
the build reflects their original's super-element.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

PHASES = ("assemble", "_nd_order_points", "_lower_triplets", "_inverse_form")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("params", nargs="?", default=str(ROOT / "params" / "carbon.yaml"))
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args(argv)

    from cogniframe import frame, partlist, spec
    from cogniframe.analysis import joints, stiffness
    from cogniframe.analysis.joints import solid_fe
    from cogniframe.analysis.numerics import one_blas_thread

    s = spec.load(args.params)
    f = frame.frame_of(s)
    parts = partlist.part_list(s, f)
    inputs = {}
    real = solid_fe.condense

    def keep(points, tets, e, nu, ties):  # the mesh and ties of the joint being solved
        inputs["args"] = (points, tets, e, nu, ties)
        return real(points, tets, e, nu, ties)

    times: dict[str, float] = {}

    def timed(name, fn):
        def run(*a, **k):
            t0 = time.process_time()
            try:
                return fn(*a, **k)
            finally:
                times[name] = times.get(name, 0.0) + time.process_time() - t0
        return run

    total = 0.0
    print(f"{'joint':<16} {'DOF':>7} {'condense s':>11}  " + "  ".join(f"{p.strip('_'):>14}" for p in PHASES))
    for p in stiffness.joint_parts(parts):
        if joints.is_mirror(p):
            continue
        solid_fe.condense = keep
        try:
            joints.fe_joint(s, p, 1.0)
        finally:
            solid_fe.condense = real
        originals = {n: getattr(solid_fe, n) for n in PHASES}
        for n, fn in originals.items():
            setattr(solid_fe, n, timed(n, fn))
        runs, phases = [], {n: [] for n in PHASES}
        try:
            with one_blas_thread():
                for _ in range(args.runs):
                    times.clear()
                    t0 = time.process_time()
                    c = solid_fe.condense(*inputs["args"])
                    runs.append(time.process_time() - t0)
                    for n in PHASES:
                        phases[n].append(times.get(n, 0.0))
        finally:
            for n, fn in originals.items():
                setattr(solid_fe, n, fn)
        med = statistics.median(runs)
        total += med
        print(f"{p.name:<16} {c.n_dofs:>7} {med:>11.3f}  " + "  ".join(f"{statistics.median(phases[n]):>14.3f}" for n in PHASES))
    print(f"{'all':<16} {'':>7} {total:>11.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
