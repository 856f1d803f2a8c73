"""Time a full stiffness evaluation (frame graph -> PyNite model -> k) for the carbon preset.

    python benchmarks/bench_stiffness.py [params.yaml] [--repeat N]

Prints the import costs, the first (cold) evaluation, and the median / best of N warm ones,
split into frame-graph build, FE model build and solve + read-out.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("params", nargs="?", default=str(ROOT / "params" / "carbon.yaml"))
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args(argv)

    t0 = time.perf_counter()
    from cogniframe import frame as frame_mod
    from cogniframe import spec as spec_mod
    from cogniframe.analysis import stiffness as st
    t1 = time.perf_counter()
    import Pynite  # noqa: F401  (imported lazily by the stiffness module; timed on its own here)
    t2 = time.perf_counter()

    path = Path(args.params)
    spec = spec_mod.load(path) if path.is_file() else spec_mod.from_dict({})
    label = path.name if path.is_file() else "default spec (no params file)"

    t3 = time.perf_counter()
    first = st.predict_stiffness(spec, frame_mod.build(spec))
    cold = time.perf_counter() - t3

    total, graph, model, solve = [], [], [], []
    for _ in range(args.repeat):
        a = time.perf_counter()
        f = frame_mod.build(spec)
        b = time.perf_counter()
        mdl = st.build_model(spec, f)
        c = time.perf_counter()
        mdl.fe.analyze_linear(check_stability=False, sparse=False)
        st.payload_deflection(mdl)
        d = time.perf_counter()
        st.predict_stiffness(spec, f)
        e = time.perf_counter()
        graph.append(b - a)
        model.append(c - b)
        solve.append(d - c)
        total.append((b - a) + (e - d))  # a full evaluation: frame graph + predict_stiffness

    ms = lambda xs: f"median {1000 * statistics.median(xs):7.1f} ms   best {1000 * min(xs):7.1f} ms"  # noqa: E731
    print(f"stiffness benchmark: {label}")
    print(f"  k = {first.k_n_per_m:.0f} N/m (k_top {first.k_top_n_per_m:.0f} N/m), calibration {first.calibration:g}, "
          f"{first.n_nodes} nodes, {first.n_members} members")
    print(f"  import cogniframe (spec, frame, stiffness)   {1000 * (t1 - t0):7.1f} ms")
    print(f"  import Pynite                                 {1000 * (t2 - t1):7.1f} ms")
    print(f"  first evaluation (cold)                       {1000 * cold:7.1f} ms")
    print(f"  full evaluation, {args.repeat} warm runs:  {ms(total)}")
    print(f"    frame graph                          {ms(graph)}")
    print(f"    FE model build                       {ms(model)}")
    print(f"    solve + read-out                     {ms(solve)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
