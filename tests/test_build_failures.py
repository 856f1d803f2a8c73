"""A build that fails: its first cause is reported, the rest of its work cancelled, nothing is
written and no helper process is left behind (runtime/, graph.run)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import pytest

pytestmark = [pytest.mark.cad, pytest.mark.process]  # builds in fresh cogniframe processes


def _processes_with(tag: str) -> list[int]:
    found = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit() or int(d.name) == os.getpid():
            continue
        try:
            if tag.encode() in (d / "environ").read_bytes():
                found.append(int(d.name))
        except OSError:
            pass
    return found


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.process
def test_a_part_that_fails_in_a_worker_is_the_reported_cause_and_nothing_is_left(tmp_path):
    params = tmp_path / "small_bed.yaml"
    params.write_text("name: small_bed\nprinter:\n  bed: [45, 45, 45]\n")
    tag = f"cogniframe-test-{uuid.uuid4().hex}"
    code = textwrap.dedent(f"""
        import sys
        from cogniframe import design as design_mod
        from cogniframe.cli import main
        # let the design through the analytic bed check, so that the CAD workers find it
        design_mod._check_printer_fit = lambda spec, parts: None
        sys.exit(main(["build", {str(params)!r}, "-o", {str(tmp_path / 'out')!r}, "--no-server", "--jobs", "2"]))
    """)
    env = {**os.environ, "COGNIFRAME_TEST_TAG": tag, "COGNIFRAME_CACHE": str(tmp_path / "cache")}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env,
                       cwd=tmp_path)
    assert r.returncode == 2, r.stderr[-3000:]
    message = [ln for ln in r.stderr.splitlines() if str(params) in ln]
    assert len(message) == 1 and "printer.bed (line 3)" in message[0] and "Fix:" in message[0], r.stderr
    assert "Traceback" not in r.stderr and "internal error" not in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache", "small_bed.yaml"]  # no output folder
    deadline = time.monotonic() + 10
    while _processes_with(tag) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _processes_with(tag) == []


@pytest.mark.parametrize("server", [False, True])
@pytest.mark.process
def test_cancel_drops_the_queued_cad_jobs_and_ends_the_running_one(server, tmp_path, monkeypatch):
    """What a failed build does to its CAD work (`CadPool.cancel`): the job under way ends at once
    instead of running to its end, the queued ones never start, and no new job is taken."""
    from cogniframe.runtime import cad_server
    from cogniframe.runtime.pools import CadPool

    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    cad = CadPool(1, fe=False, server=server)
    try:
        cad.run(time.sleep, 0)  # the worker is up
        running = cad.submit(time.sleep, 60)
        queued = [cad.submit(time.sleep, 60) for _ in range(3)]
        t0 = time.monotonic()
        while not running.running() and time.monotonic() - t0 < 10:
            time.sleep(0.01)
        time.sleep(0.3)
        cad.cancel()
        for f in [running, *queued]:
            with pytest.raises(BaseException):
                f.result(timeout=20)
        assert time.monotonic() - t0 < 30  # not the 60 s of the job under way
        if server:
            assert all(f.cancelled() for f in queued)
        with pytest.raises(RuntimeError, match="closed"):
            cad.submit(time.sleep, 0)
    finally:
        cad.close()
        if server:
            cad_server.stop(cad.stack)
