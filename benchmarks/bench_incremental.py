"""The issue-11 numbers: `cogniframe build` and `check` as a user runs them, each in a fresh process.

    python benchmarks/bench_incremental.py [--params params/carbon.yaml] [--runs 3] [--jobs N] [--analytic]

`--analytic` sets model.stiffness_model: analytic in the copy (closed-form joints instead of their
solid FE): the build's own cost without the joints' finite elements.

Per run (a fresh cache folder and output folder each time):
  cold       build with an empty cache (parts, assembly, plates, slicing, renders, report)
  no-geom    build after core.battery.mass changes (no part geometry changes)
  one-part   build after motors.bolt_spacing changes (only the motor mount changes)
  check      `check --json` run again with a warm cache
Prints the median wall and CPU seconds (the process and all its descendants: CAD workers, adopted
as a subreaper, and PrusaSlicer) of each over the runs, the load average (the machine may be shared), and the peak resident memory of the biggest child
process (resource.getrusage(RUSAGE_CHILDREN).ru_maxrss, which is per process, not summed).
Targets (2 cores): cold <= 10 s, no-geom <= 2 s, one-part <= 5 s, check <= 0.3 s, peak <= 1 GB.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LOAD0 = ""


def _edit(text: str, section: str, key: str, value: str) -> str:
    """Set `key` inside the top-level `section` of a params YAML (adds it if missing), keeping comments."""
    lines = text.splitlines()
    start = next(i for i, ln in enumerate(lines) if re.match(rf"^{section}:", ln))
    end = next((i for i in range(start + 1, len(lines)) if lines[i] and not lines[i][0].isspace()
                and not lines[i].startswith("#")), len(lines))
    for i in range(start + 1, end):
        m = re.match(rf"^(\s+){key}:", lines[i])
        if m:
            lines[i] = f"{m.group(1)}{key}: {value}"
            return "\n".join(lines) + "\n"
    lines.insert(start + 1, f"  {key}: {value}")
    return "\n".join(lines) + "\n"


def _battery_mass(text: str, grams: str) -> str:
    return re.sub(r"(\n    mass: )\d+(\.\d+)?", rf"\g<1>{grams}", text, count=1)


CPU: dict[str, list[float]] = {}


def _subreaper() -> bool:
    """Adopt orphaned descendants (Linux prctl PR_SET_CHILD_SUBREAPER): the CAD pool's forkserver
    and its workers outlive no build, but the build never waits for them, so without this their
    CPU seconds and memory would not reach RUSAGE_CHILDREN."""
    try:
        import ctypes

        return ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _reap(timeout_s: float = 10.0) -> None:
    """Wait for the adopted orphans (they exit once the build has: their pipe to it closes)."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout_s:
        try:
            pid, _ = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            time.sleep(0.02)


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(args: list[str], env: dict, label: str | None = None) -> float:
    """Wall seconds of one `cogniframe ARGS` in a fresh process; its CPU seconds (with its own
    children: CAD workers, PrusaSlicer) go to CPU[label]. On a shared machine the CPU time is the
    steadier number."""
    c0, t0 = _cpu(), time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "cogniframe", *args], cwd=ROOT, env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    _reap()
    if label:
        CPU.setdefault(label, []).append(_cpu() - c0)
    if proc.returncode not in (0, 1):
        sys.exit(f"cogniframe {' '.join(args)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return wall


def _analytic(text: str) -> str:
    return re.sub(r"(\n\s+stiffness_model:\s*)\w+", r"\g<1>analytic", text, count=1)


def one_run(params: Path, jobs: str | None, analytic: bool = False) -> dict:
    with tempfile.TemporaryDirectory(prefix="bench-incr-") as tmp:
        tmp = Path(tmp)
        env = {**os.environ, "COGNIFRAME_CACHE": str(tmp / "cache")}
        env.pop("PYTHONPROFILEIMPORTTIME", None)
        base = params.read_text(encoding="utf-8")
        if analytic:
            base = _analytic(base)
            assert "stiffness_model: analytic" in base, "no model.stiffness_model key to set in the params"
        p = tmp / params.name
        p.write_text(base, encoding="utf-8")
        out = tmp / "out"
        extra = ["--jobs", jobs] if jobs else []
        r = {"cold": _run(["build", str(p), "-o", str(out), *extra], env, "cold")}
        p.write_text(_battery_mass(base, "61"), encoding="utf-8")
        r["no-geom"] = _run(["build", str(p), "-o", str(out), *extra], env, "no-geom")
        p.write_text(_edit(_battery_mass(base, "61"), "motors", "bolt_spacing", "9.5"), encoding="utf-8")
        r["one-part"] = _run(["build", str(p), "-o", str(out), *extra], env, "one-part")
        _run(["check", str(p), "--json"], env)
        r["check"] = statistics.median(_run(["check", str(p), "--json"], env, "check") for _ in range(3))
        return r


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--params", default="params/carbon.yaml")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--jobs", default=None)
    ap.add_argument("--analytic", action="store_true", help="closed-form joints (no joint FE)")
    a = ap.parse_args()
    global LOAD0
    adopted = _subreaper()
    LOAD0 = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    runs = [one_run(ROOT / a.params, a.jobs, a.analytic) for _ in range(a.runs)]
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"{a.params}{' (analytic joints)' if a.analytic else ''}, {a.runs} runs, {os.cpu_count()} cores, "
          f"jobs={a.jobs or 'auto'}")
    print(f"  load average before: {LOAD0}, after: {', '.join(f'{v:.1f}' for v in os.getloadavg())}")
    for k, goal in (("cold", 10.0), ("no-geom", 2.0), ("one-part", 5.0), ("check", 0.3)):
        vals = [r[k] for r in runs]
        print(f"  {k:9s} median {statistics.median(vals):6.2f} s wall, {statistics.median(CPU[k]):6.2f} s CPU  "
              f"(wall runs {', '.join(f'{v:.2f}' for v in vals)}; goal <= {goal:g} s)")
    print(f"  peak RSS of the largest child process: {peak_mb:.0f} MB (goal <= 1024 MB)")
    if not adopted:
        print("  (no subreaper: the CAD workers' CPU seconds are not counted)")


if __name__ == "__main__":
    main()
