#!/usr/bin/env python3
"""The outputs a restructuring must leave byte-identical: the sha256 of `check --json` for the
presets and the example designs, and of every file a build of each preset writes (from its
manifest.json), written to tests/data/golden_outputs.json. tests/test_golden_outputs.py
recomputes them and fails on the first byte that moved.

    python tools/golden_outputs.py [--only-check]

Run it on a tree whose outputs are known good (it records what it sees). Files whose bytes carry
PrusaSlicer's time and grams estimates are left out (EXCLUDED): they are the same on every run on
one machine (tests/test_same_bytes.py), but they are PrusaSlicer's, whose release constraints.txt
does not pin (a system package), so their bytes are not a function of the params and the pinned
stack alone.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "data" / "golden_outputs.json"
CHECKED = ("params/carbon.yaml", "params/bamboo.yaml", "examples/rect-240x180.yaml")
BUILT = ("params/carbon.yaml", "params/bamboo.yaml")
EXCLUDED = {
    "bom.csv": "the slicer's grams and print time per printed part (sliced_g, print_time_min)",
    "bom.md": "the slicer's grams and print time per printed part",
    "report.md": "the slicer check's grams and print time per plate and in the printability line",
    "report.html": "the slicer check's grams and print time per plate and in the printability line",
}


def _env(root: Path) -> dict:
    return {**os.environ, "PYTHONPATH": str(root)}


def check_sha256(root: Path, params: str) -> str:
    """sha256 of `cogniframe check PARAMS --json`'s stdout (exit 0 PASS or 1 FAIL both count)."""
    r = subprocess.run([sys.executable, "-m", "cogniframe", "check", params, "--json"], cwd=root, env=_env(root),
                       capture_output=True, timeout=600)
    if r.returncode not in (0, 1):
        raise RuntimeError(f"check {params} exited {r.returncode}: {r.stderr.decode()[-2000:]}")
    return hashlib.sha256(r.stdout).hexdigest()


def build_sha256(root: Path, params: str, out: Path) -> dict[str, str]:
    """sha256 of every file `cogniframe build PARAMS -o OUT` lists in its manifest, by path,
    except EXCLUDED."""
    r = subprocess.run([sys.executable, "-m", "cogniframe", "build", params, "-o", str(out)], cwd=root,
                       env=_env(root), capture_output=True, timeout=1800)
    if r.returncode not in (0, 1):
        raise RuntimeError(f"build {params} exited {r.returncode}: {r.stderr.decode()[-2000:]}")
    return manifest_sha256(out)


def manifest_sha256(out: Path) -> dict[str, str]:
    """sha256 of every file the build in `out` lists in its manifest, by path, except EXCLUDED."""
    manifest = json.loads((out / "manifest.json").read_text())
    return {f["path"]: hashlib.sha256((out / f["path"]).read_bytes()).hexdigest()
            for f in manifest["files"] if f["path"] not in EXCLUDED}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", type=Path, default=ROOT)
    ap.add_argument("--only-check", action="store_true", help="rewrite only the check --json hashes")
    a = ap.parse_args()
    old = json.loads(GOLDEN.read_text()) if GOLDEN.is_file() else {}
    golden = {"check_json": {p: check_sha256(a.root, p) for p in CHECKED},
              "excluded": EXCLUDED,
              "build": old.get("build", {})}
    if not a.only_check:
        with tempfile.TemporaryDirectory(prefix="cogniframe-golden-") as tmp:
            golden["build"] = {p: build_sha256(a.root, p, Path(tmp) / Path(p).stem) for p in BUILT}
    GOLDEN.write_text(json.dumps(golden, indent=2, sort_keys=True) + "\n")
    print(f"wrote {GOLDEN.relative_to(ROOT)}: {len(golden['check_json'])} check outputs, "
          + ", ".join(f"{p}: {len(h)} files" for p, h in golden["build"].items()))


if __name__ == "__main__":
    main()
