"""Time `cogniframe check` as a user runs it: a fresh interpreter, cold and warm stiffness cache.

Run: python benchmarks/bench_check.py
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run(params: str, env: dict) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "cogniframe", "check", params, "--json"], cwd=ROOT, env=env,
                   stdout=subprocess.DEVNULL, check=False)
    return time.perf_counter() - t0


def main() -> None:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "pass"], check=True)
    python = time.perf_counter() - t0
    print(f"python start-up alone: {python:.3f} s")
    for preset in ("params/carbon.yaml", "params/bamboo.yaml"):
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "COGNIFRAME_CACHE": cache}
            cold = run(preset, env)
            warm = min(run(preset, env) for _ in range(3))
        print(f"check {preset}: first run (FE model solved, PyNite imported) {cold:.3f} s; "
              f"repeat (stiffness cached) {warm:.3f} s; minus start-up {warm - python:.3f} s")


if __name__ == "__main__":
    main()
