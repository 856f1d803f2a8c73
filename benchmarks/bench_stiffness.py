"""Time the stiffness physics: joint FE (cold), frame solve and load cases (joints cached), and
`cogniframe check` in a fresh process (cold cache vs cached).

    python benchmarks/bench_stiffness.py [params.yaml] [--repeat N] [--skip-cold]

Prints medians. The cold joint FE and the cold check run in a throw-away cache folder.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _median(f, n: int) -> float:
    ts = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def _check_process(params: str, env: dict) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "cogniframe", "check", params, "--json"], cwd=ROOT, env=env,
                   stdout=subprocess.DEVNULL, check=False)
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("params", nargs="?", default=str(ROOT / "params" / "carbon.yaml"))
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--skip-cold", action="store_true", help="skip the cold joint FE and the cold check")
    args = ap.parse_args(argv)

    with tempfile.TemporaryDirectory() as cache:
        os.environ["COGNIFRAME_CACHE"] = cache
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        from cogniframe import frame as frame_mod
        from cogniframe import partlist
        from cogniframe import spec as spec_mod
        from cogniframe.analysis import joints as JS
        from cogniframe.analysis import load_cases as lc
        from cogniframe.analysis import stiffness as st

        s = spec_mod.load(args.params)
        f = frame_mod.frame_of(s)
        parts = partlist.part_list(s, f)
        if not args.skip_cold:
            print(f"cold `check` process (joint FE + load cases):  {_check_process(args.params, env):7.2f} s")
            for p in st.joint_parts(parts):
                js = JS.fe_joint(s, p)
                print(f"  joint FE {p.name:14s} {js.n_dofs:6d} DOF  {js.seconds:6.2f} s")
        joints = st.joint_models(s, parts, "fe")
        an = st.joint_models(s, parts, "analytic")
        print(f"closed-form joints (all five), median:         {_median(lambda: st.joint_models(s, parts, 'analytic'), args.repeat) * 1e3:7.1f} ms")
        print(f"frame k, FE joints cached, median:             {_median(lambda: st.predict_stiffness(s, f, parts, joints=joints), args.repeat) * 1e3:7.1f} ms")
        print(f"frame k, closed-form joints, median:           {_median(lambda: st.predict_stiffness(s, f, parts, joints=an), args.repeat) * 1e3:7.1f} ms")
        print(f"all load cases (joints cached), median:        {_median(lambda: lc.load_cases(s, f, parts, 240.0, joints=joints, design_force_n=95.0), max(1, args.repeat // 2)):7.2f} s")
        if not args.skip_cold:
            _check_process(args.params, env)
        print(f"cached `check` process, median:                {statistics.median(_check_process(args.params, env) for _ in range(args.repeat)):7.2f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
