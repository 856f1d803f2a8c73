#!/usr/bin/env python3
"""Random in-schema params files through `cogniframe check` (and optionally `build`): how many pass,
fail, are refused with a key (exit 2), and how many crash (exit 3, a traceback or a timeout); of
the designs `check` accepts, how many fail the fit check (`fit` in check --json: screws, holes,
motor patterns), and of the refused, how many name each key.

    python tools/design_space.py [--n 100] [--seed 1] [--builds 0] [--root DIR] [--keep DIR]
    python tools/design_space.py --fit-only [--n 2000] [--seed 1]

`--fit-only` takes the designs in process through what the fit check needs and nothing more
(validation, the frame, the part list, the fasteners, analysis/fit_check.py): milliseconds a
design instead of a `check`'s seconds, so thousands of designs.

The designs come from tests/design_space.py (the property tests' generator). `--root` runs another
checkout's cogniframe (`python -m cogniframe` from that folder), to compare before and after a
change on the same designs. Each run uses a fresh cache folder.
"""

from __future__ import annotations

import argparse
import json
import os
import re
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


def run(root: Path, env: dict, *args: str, timeout: float) -> tuple[object, str, str]:
    """(exit code or "timeout", the last line of stderr, stdout)."""
    try:
        p = subprocess.run([sys.executable, "-m", "cogniframe", *args], cwd=root, env=env, capture_output=True,
                           text=True, timeout=timeout, errors="replace")
    except subprocess.TimeoutExpired:
        return "timeout", "", ""
    code = p.returncode if "Traceback" not in p.stderr else 3
    return code, (p.stderr.strip().splitlines() or [""])[-1], p.stdout


def refused_key(message: str) -> str:
    """The params key a refusal names (`file.yaml: motors.model (line 3): ...`), or "?"."""
    m = re.search(r"\.ya?ml: ([A-Za-z_][\w.]*)", message)
    return m.group(1) if m else "?"


def fit_problems(stdout: str) -> list[str] | None:
    """The fit check's problems in check --json's output; None when there is no fit section."""
    try:
        fit = json.loads(stdout).get("fit")
    except ValueError:
        return None
    return None if fit is None else [p["message"] for p in fit["problems"]]


def fit_only(n: int, seed: int) -> int:
    """The fit check alone on `n` random designs: refused (by key), passed, failed, crashed."""
    import traceback

    from cogniframe import spec as spec_mod
    from cogniframe.analysis.verdict import fit_of
    from cogniframe.design import design
    from cogniframe.errors import UserError

    rnd = random.Random(seed)
    keys: Counter = Counter()
    models: Counter = Counter()
    passed, failed, crashes = 0, [], []
    for i in range(n):
        doc = design_space.random_design(rnd)
        doc["name"] = f"d{i}"
        try:
            spec = spec_mod.from_dict(doc, f"d{i}.yaml")
            d = design(spec)
        except UserError as e:
            keys[e.key or refused_key(str(e))] += 1
            continue
        except Exception:  # a crash: the validation should have refused it
            crashes.append(f"d{i}: {traceback.format_exc().strip().splitlines()[-1][:200]}")
            continue
        models[spec.motors.model] += 1
        fit = fit_of(spec, d)
        if fit.ok:
            passed += 1
        else:
            failed.append(f"d{i}: {fit.messages()[0][:200]}")
    print(f"seed {seed}: {n} designs: refused with a key {sum(keys.values())}, fit check passed {passed}, "
          f"failed {len(failed)}, crashes {len(crashes)}")
    print(f"designs that build, by motor: {dict(sorted(models.items()))}")
    print(f"refusals by key: {dict(keys.most_common())}")
    for line in failed + crashes:
        print("  " + line)
    return 1 if failed or crashes else 0


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--builds", type=int, default=0, help="also build the first N accepted designs")
    ap.add_argument("--root", type=Path, default=HERE)
    ap.add_argument("--keep", type=Path, default=None, help="copy the params of every crash here")
    ap.add_argument("--timeout", type=float, default=300)
    ap.add_argument("--fit-only", action="store_true", help="only the fit check, in process (fast)")
    a = ap.parse_args()
    if a.fit_only:
        return fit_only(a.n, a.seed)
    rnd = random.Random(a.seed)
    work = Path(tempfile.mkdtemp(prefix="design-space-"))
    env = {**os.environ, "COGNIFRAME_CACHE": str(work / "cache"), "COGNIFRAME_CAD_SERVER": "0"}
    counts: Counter = Counter()
    keys: Counter = Counter()
    models: Counter = Counter()
    fit_checked, fit_failed = 0, []
    crashes, accepted = [], []
    for i in range(a.n):
        doc = design_space.random_design(rnd)
        doc["name"] = f"d{i}"
        f = design_space.write(doc, work / f"d{i}.yaml")
        code, last, out = run(a.root, env, "check", str(f), "--json", timeout=a.timeout)
        counts[code] += 1
        if code == 2:
            keys[refused_key(last)] += 1
        if code in (0, 1):
            accepted.append(f)
            models[str(doc.get("motors", {}).get("model", "?"))] += 1
            problems = fit_problems(out)
            if problems is not None:
                fit_checked += 1
                if problems:
                    fit_failed.append(f"{f.name}: {problems[0][:200]}")
        elif code != 2:
            crashes.append(f"check {f.name}: {code} {last[:200]}")
            if a.keep:
                a.keep.mkdir(parents=True, exist_ok=True)
                shutil.copy(f, a.keep)
        print(f"\r{i + 1}/{a.n} {dict(counts)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    built = Counter()
    for f in accepted[: a.builds]:
        code, last, _ = run(a.root, env, "build", str(f), "-o", str(work / "out" / f.stem), timeout=a.timeout * 2)
        built[code] += 1
        if code not in (0, 1, 2):
            crashes.append(f"build {f.name}: {code} {last[:200]}")
            if a.keep:
                a.keep.mkdir(parents=True, exist_ok=True)
                shutil.copy(f, a.keep)
    print(f"seed {a.seed}: {a.n} designs through check: PASS {counts[0]}, FAIL {counts[1]}, refused with a key "
          f"{counts[2]}, crashes {a.n - counts[0] - counts[1] - counts[2]}")
    print(f"fit check: {fit_checked} of the {len(accepted)} accepted designs checked, {len(fit_failed)} failed; "
          f"motors {dict(sorted(models.items()))}")
    print(f"refusals by key: {dict(keys.most_common())}")
    for line in fit_failed:
        print("  fit " + line)
    if a.builds:
        print(f"builds: {sum(built.values())}: built {built[0] + built[1]}, refused {built[2]}, "
              f"crashes {sum(v for k, v in built.items() if k not in (0, 1, 2))}")
    for line in crashes:
        print("  " + line)
    shutil.rmtree(work, ignore_errors=True)
    return 1 if crashes or fit_failed else 0


if __name__ == "__main__":
    sys.exit(main())
