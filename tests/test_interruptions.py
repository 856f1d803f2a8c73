"""Real interrupted builds: a `cogniframe build` subprocess killed with SIGKILL or
interrupted with Ctrl-C (SIGINT to its process group, as a terminal sends it) mid-build, and a
second build started while the first is writing.

The previous output is a finished cogniframe folder; after each interruption it must be exactly as
it was, and the next build must leave nothing beside it. The builds run with an empty cache so
they are slow enough to be caught mid-way (the test waits until part files are being written).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test_outdir import fake_output, snapshot

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ROOT / "params" / "carbon.yaml"

pytestmark = [pytest.mark.cad, pytest.mark.process]  # builds in fresh cogniframe processes


def start_build(final: Path, cache: Path) -> subprocess.Popen:
    env = {**os.environ, "COGNIFRAME_CACHE": str(cache), "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "cogniframe", "build", str(PARAMS), "-o", str(final), "-j", "1"],
                            cwd=final.parent, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)


def wait_mid_build(proc: subprocess.Popen, final: Path, timeout: float = 120.0) -> Path:
    """Wait until the build's temp folder holds its first part file; return the temp folder."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        assert proc.poll() is None, proc.communicate()
        temps = list(final.parent.glob(f".{final.name}.cogniframe-tmp-*"))
        if temps and any(temps[0].glob("stl/*/*.stl")):
            return temps[0]
        time.sleep(0.02)
    proc.kill()
    pytest.fail("the build never started writing parts")


def left_running(tmp_path: Path, timeout: float = 15.0) -> list[str]:
    """Processes of the killed build still alive after `timeout` (its CAD forkserver runs with the
    build's folder on its sys.path, so its command line names tmp_path)."""
    import psutil

    end = time.monotonic() + timeout
    while True:
        alive = []
        for p in psutil.process_iter(["pid", "cmdline"]):
            cmd = " ".join(p.info["cmdline"] or [])
            if str(tmp_path) in cmd and p.pid != os.getpid():
                alive.append(f"{p.pid}: {cmd[:120]}")
        if not alive or time.monotonic() > end:
            return alive
        time.sleep(0.2)


def beside(final: Path) -> list[str]:
    return sorted(p.name for p in final.parent.iterdir())


@pytest.mark.cad
@pytest.mark.fe
@pytest.mark.process
@pytest.mark.slicer
def test_sigkill_mid_build_keeps_previous_output_and_next_build_cleans_up(tmp_path, run_cli, monkeypatch):
    final = fake_output(tmp_path / "carbon", {"report.html": b"<html>the previous build</html>"})
    before = snapshot(final)
    proc = start_build(final, tmp_path / "cache")
    temp = wait_mid_build(proc, final)
    proc.send_signal(signal.SIGKILL)  # the build process alone, as `kill -9 PID` does
    proc.wait(30)
    assert snapshot(final) == before
    assert temp.is_dir()  # what a killed build leaves: a stale temp folder (and its lock file)
    assert left_running(tmp_path) == []  # its CAD server and workers end with it

    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    code, out, err = run_cli("build", PARAMS, "-o", final, "-j", "1", cwd=tmp_path)
    assert code == 0, err
    assert beside(final) == ["cache", "carbon"]  # stale temp and lock gone, nothing else beside
    assert "report.html" in snapshot(final) and snapshot(final)["report.html"] != before["report.html"]


@pytest.mark.process
def test_second_build_is_refused_and_ctrl_c_keeps_previous_output(tmp_path, run_cli):
    final = fake_output(tmp_path / "carbon", {"report.html": b"<html>the previous build</html>"})
    before = snapshot(final)
    proc = start_build(final, tmp_path / "cache")
    wait_mid_build(proc, final)

    code, _, err = run_cli("build", PARAMS, "-o", final, cwd=tmp_path)
    assert code == 2 and "another cogniframe command" in err and f"pid {proc.pid}" in err

    os.killpg(proc.pid, signal.SIGINT)
    _, err_a = proc.communicate(timeout=60)
    assert proc.returncode == 130, err_a
    assert b"interrupted" in err_a and b"Traceback" not in err_a
    assert snapshot(final) == before
    assert beside(final) == ["cache", "carbon"]  # temp folder and lock removed at once
