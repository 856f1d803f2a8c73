"""The issue-11 numbers: `cogniframe build` and `check` as a user runs them, each in a fresh process.

    python benchmarks/bench_incremental.py [--params params/carbon.yaml] [--runs 3] [--jobs N] [--analytic]
                                           [--no-server] [--steps]

`--analytic` sets model.stiffness_model: analytic in the copy (closed-form joints instead of their
solid FE): the build's own cost without the joints' finite elements.

`--steps` also prints, for each build of the first run, the steps that ran, as the build's progress
lines say them (how long each took and when it ended, seconds into the build): the build's
timeline, whose last lines are its critical path.

`--no-server` builds with `--no-server` (a process pool per build, as before the CAD server).
By default the builds run as a user's do: the cold build starts the CAD server (its start is
counted in the cold build's CPU), the later builds of the run use it; it is stopped at the end of
each run, and the next run's cold build starts a new one (a fresh cache folder: a new server).

Per run (a fresh cache folder and output folder each time):
  cold       build with an empty cache (parts, assembly, plates, slicing, renders, report)
  no-geom    build after core.battery.mass changes (no part geometry changes)
  one-part   build after motors.bolt_spacing changes (only the motor mount changes)
  check      `check --json` run again with a warm cache
Prints the machine's speed before and after (`_probe`), the median wall and CPU seconds (the process and all its descendants: CAD workers, adopted
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
STEPS: dict[str, list[str]] = {}  # label -> the progress lines of the steps that ran (first run only)


def _subreaper() -> bool:
    """Adopt orphaned descendants (Linux prctl PR_SET_CHILD_SUBREAPER): the CAD pool's forkserver
    and its workers outlive no build, but the build never waits for them, so without this their
    CPU seconds and memory would not reach RUSAGE_CHILDREN."""
    try:
        import ctypes

        return ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _children(of: int) -> list[int]:
    """Live child processes of `of` (zombies included: they wait to be reaped)."""
    kids = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == of:
            kids.append(int(stat.parent.name))
    return kids


def _reap(keep: set[int] = frozenset(), timeout_s: float = 10.0) -> None:
    """Wait for the adopted orphans (they exit once the build has: their pipe to it closes), all
    but `keep` (the CAD server, which outlives builds on purpose)."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout_s:
        try:
            pid, _ = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            if not set(_children(os.getpid())) - set(keep):
                return
            time.sleep(0.02)


def _server_pid(cache: Path) -> int | None:
    for f in sorted((cache / "cad-server").glob("*.pid")):
        try:
            return int(f.read_text())
        except (OSError, ValueError):
            pass
    return None


def _server_cpu(pid: int | None) -> float:
    """CPU seconds of the CAD server with its reaped workers (it reaps each one as its build hangs
    up: wait until it has none left)."""
    if pid is None:
        return 0.0
    t0 = time.perf_counter()
    while _children(pid) and time.perf_counter() - t0 < 10:
        time.sleep(0.02)
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return sum(int(v) for v in fields[11:15]) / os.sysconf("SC_CLK_TCK")  # utime stime cutime cstime


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(args: list[str], env: dict, label: str | None = None) -> float:
    """Wall seconds of one `cogniframe ARGS` in a fresh process; its CPU seconds (with its own
    children: CAD workers, adopted as a subreaper, PrusaSlicer, and the CAD server's share: its
    workers for this build, and its start when this build started it) go to CPU[label]. On a
    shared machine the CPU time is the steadier number."""
    cache = Path(env["COGNIFRAME_CACHE"])
    server = _server_pid(cache)
    c0, s0, t0 = _cpu(), _server_cpu(server), time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "cogniframe", *args], cwd=ROOT, env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    started = _server_pid(cache)
    _reap({started} if started else set())
    if label:
        server_share = _server_cpu(started) - (s0 if started == server else 0.0)
        CPU.setdefault(label, []).append(_cpu() - c0 + server_share)
        STEPS.setdefault(label, [ln.strip() for ln in proc.stderr.splitlines() if re.match(r"\[\s*\d+/\d+\]", ln)
                                 and "cached" not in ln])
    if proc.returncode not in (0, 1):
        sys.exit(f"cogniframe {' '.join(args)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return wall


def _stop_server(env: dict) -> None:
    """End the run's CAD server and reap it (its memory then counts in ru_maxrss)."""
    pid = _server_pid(Path(env["COGNIFRAME_CACHE"]))
    subprocess.run([sys.executable, "-m", "cogniframe", "server", "stop"], cwd=ROOT, env=env,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _reap()
    if pid is not None and pid in _children(os.getpid()):
        os.waitpid(pid, 0)


def _probe() -> float:
    """Seconds of a 3-million-step pure-Python loop in a fresh interpreter: the machine's speed at
    the moment. This 2-core machine takes 0.27-0.50 s by phase, and a build's CPU seconds follow
    it, so a median means little without it."""
    code = "import time; t = time.perf_counter(); s = 0\nfor i in range(3_000_000): s += i * i\nprint(time.perf_counter() - t)"
    return float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)


def _analytic(text: str) -> str:
    return re.sub(r"(\n\s+stiffness_model:\s*)\w+", r"\g<1>analytic", text, count=1)


def one_run(params: Path, jobs: str | None, analytic: bool = False, server: bool = True) -> dict:
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
        extra = (["--jobs", jobs] if jobs else []) + ([] if server else ["--no-server"])
        r = {"cold": _run(["build", str(p), "-o", str(out), *extra], env, "cold")}
        p.write_text(_battery_mass(base, "61"), encoding="utf-8")
        r["no-geom"] = _run(["build", str(p), "-o", str(out), *extra], env, "no-geom")
        p.write_text(_edit(_battery_mass(base, "61"), "motors", "bolt_spacing", "9.5"), encoding="utf-8")
        r["one-part"] = _run(["build", str(p), "-o", str(out), *extra], env, "one-part")
        _run(["check", str(p), "--json"], env)
        r["check"] = statistics.median(_run(["check", str(p), "--json"], env, "check") for _ in range(3))
        _stop_server(env)
        return r


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--params", default="params/carbon.yaml")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--jobs", default=None)
    ap.add_argument("--analytic", action="store_true", help="closed-form joints (no joint FE)")
    ap.add_argument("--no-server", action="store_true", help="builds without the CAD server (a process pool each)")
    ap.add_argument("--steps", action="store_true", help="print each build's steps that ran, with when each ended")
    a = ap.parse_args()
    global LOAD0
    adopted = _subreaper()
    LOAD0 = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    probe0 = _probe()
    runs = [one_run(ROOT / a.params, a.jobs, a.analytic, not a.no_server) for _ in range(a.runs)]
    probe1 = _probe()
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"{a.params}{' (analytic joints)' if a.analytic else ''}, {a.runs} runs, {os.cpu_count()} cores, "
          f"jobs={a.jobs or 'auto'}, {'no CAD server' if a.no_server else 'CAD server (started by the cold build)'}")
    print(f"  load average before: {LOAD0}, after: {', '.join(f'{v:.1f}' for v in os.getloadavg())}")
    print(f"  machine speed: a 3 M-step Python loop took {probe0:.3f} s before, {probe1:.3f} s after "
          "(this machine: 0.27-0.50 s by phase)")
    for k, goal in (("cold", 10.0), ("no-geom", 2.0), ("one-part", 5.0), ("check", 0.3)):
        vals = [r[k] for r in runs]
        print(f"  {k:9s} median {statistics.median(vals):6.2f} s wall, {statistics.median(CPU[k]):6.2f} s CPU  "
              f"(wall runs {', '.join(f'{v:.2f}' for v in vals)}; goal <= {goal:g} s)")
    print(f"  peak RSS of the largest child process: {peak_mb:.0f} MB (goal <= 1024 MB)")
    if a.steps:
        for label in ("cold", "no-geom", "one-part"):
            print(f"  steps of the first {label} build that ran (seconds it took, and when it ended):")
            for line in STEPS.get(label, []):
                print(f"    {line}")
    if not adopted:
        print("  (no subreaper: the CAD workers' CPU seconds are not counted)")


if __name__ == "__main__":
    main()
