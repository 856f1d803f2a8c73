"""Time the whole `cogniframe build` command (parts, assembly, plates, slicing, renders, report)
as a user runs it: a fresh process, cold cache, then again with nothing changed.

    python benchmarks/bench_cli_build.py

bench_build.py times the CAD stage alone (the issue's < 10 s cold / < 2 s cached targets);
this one adds the fabrication package on top, which slices (PrusaSlicer) and renders (EGL).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def build(params: str, out: Path, env: dict) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "cogniframe", "build", params, "-o", str(out)], cwd=ROOT, env=env,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    return time.perf_counter() - t0


def main() -> None:
    for preset in ("params/carbon.yaml", "params/bamboo.yaml"):
        with tempfile.TemporaryDirectory() as tmp:
            env = {**os.environ, "COGNIFRAME_CACHE": str(Path(tmp) / "cache")}
            cold = build(preset, Path(tmp) / "out", env)
            warm = build(preset, Path(tmp) / "out", env)
        print(f"cogniframe build {preset}: cold cache {cold:.1f} s; nothing changed {warm:.1f} s")


if __name__ == "__main__":
    main()
