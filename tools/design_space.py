#!/usr/bin/env python3
"""Random in-schema params files through `cogniframe check` (and optionally `build`): how many pass,
fail, are refused with a key (exit 2), and how many crash (exit 3, a traceback or a timeout).

    python tools/design_space.py [--n 100] [--seed 1] [--builds 0] [--root DIR] [--keep DIR]

The designs come from tests/design_space.py (the property tests' generator). `--root` runs another
checkout's cogniframe (`python -m cogniframe` from that folder), to compare before and after a
change on the same designs. Each run uses a fresh cache folder.
"""

from __future__ import annotations

import argparse
import os
import random
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE / "tests"))

import design_space  # noqa: E402


def run(root: Path, env: dict, *args: str, timeout: float) -> tuple[object, str]:
    try:
        p = subprocess.run([sys.executable, "-m", "cogniframe", *args], cwd=root, env=env, capture_output=True,
                           text=True, timeout=timeout, errors="replace")
    except subprocess.TimeoutExpired:
        return "timeout", ""
    code = p.returncode if "Traceback" not in p.stderr else 3
    return code, (p.stderr.strip().splitlines() or [""])[-1]


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--builds", type=int, default=0, help="also build the first N accepted designs")
    ap.add_argument("--root", type=Path, default=HERE)
    ap.add_argument("--keep", type=Path, default=None, help="copy the params of every crash here")
    ap.add_argument("--timeout", type=float, default=300)
    a = ap.parse_args()
    rnd = random.Random(a.seed)
    work = Path(tempfile.mkdtemp(prefix="design-space-"))
    env = {**os.environ, "COGNIFRAME_CACHE": str(work / "cache"), "COGNIFRAME_CAD_SERVER": "0"}
    counts: Counter = Counter()
    crashes, accepted = [], []
    for i in range(a.n):
        doc = design_space.random_design(rnd)
        doc["name"] = f"d{i}"
        f = design_space.write(doc, work / f"d{i}.yaml")
        code, last = run(a.root, env, "check", str(f), "--json", timeout=a.timeout)
        counts[code] += 1
        if code in (0, 1):
            accepted.append(f)
        elif code != 2:
            crashes.append(f"check {f.name}: {code} {last[:200]}")
            if a.keep:
                a.keep.mkdir(parents=True, exist_ok=True)
                shutil.copy(f, a.keep)
        print(f"\r{i + 1}/{a.n} {dict(counts)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    built = Counter()
    for f in accepted[: a.builds]:
        code, last = run(a.root, env, "build", str(f), "-o", str(work / "out" / f.stem), timeout=a.timeout * 2)
        built[code] += 1
        if code not in (0, 1, 2):
            crashes.append(f"build {f.name}: {code} {last[:200]}")
            if a.keep:
                a.keep.mkdir(parents=True, exist_ok=True)
                shutil.copy(f, a.keep)
    print(f"seed {a.seed}: {a.n} designs through check: PASS {counts[0]}, FAIL {counts[1]}, refused with a key "
          f"{counts[2]}, crashes {a.n - counts[0] - counts[1] - counts[2]}")
    if a.builds:
        print(f"builds: {sum(built.values())}: built {built[0] + built[1]}, refused {built[2]}, "
              f"crashes {sum(v for k, v in built.items() if k not in (0, 1, 2))}")
    for line in crashes:
        print("  " + line)
    shutil.rmtree(work, ignore_errors=True)
    return 1 if crashes else 0


if __name__ == "__main__":
    sys.exit(main())
