"""The CAD server that `cogniframe build` keeps between builds (runtime/cad_server.py).

Each test runs its own server on its own cache folder (so its own key and address) and stops it;
the job functions are standard-library ones, picklable by reference in the server's workers.
"""

from __future__ import annotations

import math
import os
import sys
import time

import pytest

from cogniframe.runtime import cad_server

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the CAD server is Linux-only")


@pytest.fixture
def server_env(tmp_path, monkeypatch):
    """A cache folder of its own; whatever server the test started is stopped afterwards."""
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    yield tmp_path
    cad_server.stop()


def _pid_alive(pid: int) -> bool:
    """Running (not gone, not a zombie waiting for its parent)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.process
def test_workers_are_warm_forks_of_one_server_that_outlives_a_build(server_env):
    assert cad_server.running() is None
    with cad_server.connect(2, idle_s=60) as pool:
        server = cad_server.running()
        assert server is not None and server != os.getpid()
        # two jobs that overlap run in two workers; neither is the server itself
        a, b = pool.submit(time.sleep, 0.5), pool.submit(time.sleep, 0.5)
        pids = {pool.submit(os.getpid).result(), pool.submit(os.getpid).result()}
        a.result(), b.result()
        assert server not in pids
        # CadQuery was imported once, in the server, before the fork
        assert pool.submit(eval, "'cadquery' in __import__('sys').modules").result() is True
        assert pool.submit(eval, "'OCP' in __import__('sys').modules").result() is True
    # the next build (a new pool) gets the same server, and a new worker
    with cad_server.connect(1, idle_s=60) as again:
        assert cad_server.running() == server
        assert again.submit(os.getpid).result() not in pids | {server}


@pytest.mark.process
def test_workers_run_behind_the_build_and_the_server_does_not(server_env):
    """The workers are BACKGROUND_NICE steps nicer than the build (`behind_the_build`): the build's
    main thread goes first. The server itself keeps the build's priority (its start heads the
    critical path of a cold build)."""
    from cogniframe.runtime.pools import BACKGROUND_NICE

    mine = os.getpriority(os.PRIO_PROCESS, 0)
    with cad_server.connect(1, idle_s=60) as pool:
        assert pool.submit(os.getpriority, os.PRIO_PROCESS, 0).result() == min(19, mine + BACKGROUND_NICE)
        assert os.getpriority(os.PRIO_PROCESS, cad_server.running()) == mine
        # and OpenCascade's thread pool is the worker's own thread only (`cad_worker`)
        occ_threads = "__import__('OCP.OSD', fromlist=['OSD_ThreadPool']).OSD_ThreadPool.DefaultPool_s(-1).NbThreads()"
        assert pool.submit(eval, occ_threads).result() == 1


@pytest.mark.process
def test_jobs_run_in_the_builds_folder_and_raise_its_errors(server_env, monkeypatch):
    work = server_env / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    with cad_server.connect(1, idle_s=60) as pool:
        assert pool.submit(os.getcwd).result() == str(work)
        assert pool.submit(math.factorial, 10).result() == 3628800
        with pytest.raises(ValueError, match="math domain error"):
            pool.submit(math.sqrt, -1.0).result()
        # the worker survives a job's exception
        assert pool.submit(math.hypot, 3.0, 4.0).result() == 5.0


@pytest.mark.process
def test_a_worker_that_dies_fails_its_job_and_the_next_job_gets_a_new_worker(server_env):
    with cad_server.connect(1, idle_s=60) as pool:
        first = pool.submit(os.getpid).result()
        with pytest.raises(cad_server.BrokenServer):
            pool.submit(os._exit, 3).result()
        second = pool.submit(os.getpid).result()
        assert second != first and not _pid_alive(first)


@pytest.mark.process
def test_background_jobs_wait_for_the_others(server_env):
    with cad_server.connect(1, idle_s=60) as pool:
        busy = pool.submit(time.sleep, 0.5)  # the one worker is busy while the next two queue
        late = pool.submit(time.monotonic, priority=1)
        soon = pool.submit(time.monotonic)
        busy.result()
        assert soon.result() < late.result()


@pytest.mark.process
def test_stop_ends_the_server_and_removes_its_pid_file(server_env):
    with cad_server.connect(1, idle_s=60) as pool:
        pool.submit(os.getpid).result()
    pid = cad_server.running()
    pidfiles = list((server_env / "cache" / "cad-server").glob("*.pid"))
    assert [int(p.read_text()) for p in pidfiles] == [pid]
    assert cad_server.stop() == pid
    t0 = time.monotonic()
    while _pid_alive(pid) and time.monotonic() - t0 < 10:
        time.sleep(0.05)
    assert not _pid_alive(pid)
    assert cad_server.running() is None
    assert not list((server_env / "cache" / "cad-server").glob("*.pid"))
    assert cad_server.stop() is None


@pytest.mark.process
def test_an_idle_server_exits_by_itself(server_env):
    with cad_server.connect(1, idle_s=1.0) as pool:
        pool.submit(os.getpid).result()
    pid = cad_server.running()
    assert pid is not None
    t0 = time.monotonic()
    while _pid_alive(pid) and time.monotonic() - t0 < 15:
        time.sleep(0.1)
    assert not _pid_alive(pid)


@pytest.mark.process
def test_a_client_without_the_key_gets_nothing(server_env):
    with cad_server.connect(1, idle_s=60) as pool:
        pool.submit(os.getpid).result()
    key = cad_server.server_key()
    auth = server_env / "cache" / "cad-server" / f"{key}.auth"
    assert auth.stat().st_mode & 0o077 == 0  # the key is the user's alone
    assert cad_server._ask(key, b"not the key", ("ping",)) is None
    assert cad_server._ask(key, auth.read_bytes(), ("ping",))[0] == "pong"


def test_the_key_follows_the_code_stack_cache_and_environment(server_env, monkeypatch):
    base = cad_server.server_key("stack-a")
    assert cad_server.server_key("stack-a") == base
    assert cad_server.server_key("stack-b") != base
    monkeypatch.setenv("TMPDIR", str(server_env))
    assert cad_server.server_key("stack-a") != base
    monkeypatch.delenv("TMPDIR")
    monkeypatch.setenv("SOME_TERMINAL_THING", "1")  # not read by a worker
    assert cad_server.server_key("stack-a") == base
    monkeypatch.setenv("COGNIFRAME_CACHE", str(server_env / "other-cache"))
    assert cad_server.server_key("stack-a") != base


def test_wanted_follows_the_flag_then_the_environment(monkeypatch):
    monkeypatch.setenv(cad_server.ENV, "0")
    assert cad_server.wanted() is False
    assert cad_server.wanted(True) is True
    monkeypatch.setenv(cad_server.ENV, "1")
    assert cad_server.wanted() is True
    assert cad_server.wanted(False) is False
    monkeypatch.delenv(cad_server.ENV)
    assert cad_server.wanted() is True


@pytest.mark.process
def test_a_killed_build_leaves_no_worker_running(server_env):
    """The build's workers die with it (`die_with_build`), even by SIGKILL mid-job; the server stays."""
    import signal
    import subprocess

    script = (
        "import os, time\n"
        "from cogniframe.runtime import cad_server\n"
        "pool = cad_server.connect(1, idle_s=60)\n"
        "print(pool.submit(os.getpid).result(), cad_server.running(), flush=True)\n"
        "pool.submit(time.sleep, 60)\n"
        "time.sleep(60)\n"
    )
    build = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True,
                             env={**os.environ, "COGNIFRAME_CACHE": str(server_env / "cache")})
    worker, server = map(int, build.stdout.readline().split())  # (its key is not this process's: its sys.path differs)
    assert _pid_alive(worker)
    time.sleep(0.3)  # the worker is in its 60 s job
    build.send_signal(signal.SIGKILL)
    build.wait()
    t0 = time.monotonic()
    while _pid_alive(worker) and time.monotonic() - t0 < 10:
        time.sleep(0.05)
    assert not _pid_alive(worker)
    assert _pid_alive(server)
    os.kill(server, signal.SIGTERM)


@pytest.mark.process
def test_deleting_the_cache_folder_ends_the_server_and_the_next_build_gets_a_new_one(server_env):
    """A cache folder deleted under a running server took its key file with it: the server (same
    address, another key) answered nobody, the next build's new server could not take the
    address, and the build fell back to a process pool of its own (2 s of CadQuery imports)."""
    import shutil

    with cad_server.connect(1, idle_s=60) as pool:
        pool.submit(os.getpid).result()
    old = cad_server.running()
    assert old is not None
    shutil.rmtree(server_env / "cache")
    pool = cad_server.connect(1, idle_s=60)
    assert isinstance(pool, cad_server.ServerPool)  # not None: no fallback
    with pool:
        assert pool.submit(os.getpid).result() > 0
    new = cad_server.running()
    assert new is not None and new != old
    t0 = time.monotonic()
    while _pid_alive(old) and time.monotonic() - t0 < 10:
        time.sleep(0.1)
    assert not _pid_alive(old)


@pytest.mark.process
def test_the_server_runs_the_builds_code_and_refuses_a_key_it_does_not_compute(server_env, tmp_path):
    """The server imports cogniframe through the build's `sys.path` (not its own working
    directory's), and serves only under the key it computes itself: a build that ran a checkout's
    code while the server imported another cogniframe got a TypeError from a job (seen when a
    build from a source folder started a server that imported an installed copy)."""
    import json
    import subprocess

    with cad_server.connect(1, idle_s=60) as pool:
        assert pool.submit(eval, "__import__('sys').path").result() == sys.path
        assert pool.submit(eval, "__import__('cogniframe').__file__").result() == __import__("cogniframe").__file__
    cad_server.stop()
    root = cad_server.folder()
    wrong = "0" * 32
    proc = subprocess.run([sys.executable, "-c", cad_server._BOOT, json.dumps(sys.path), str(root), wrong, "60", "", ""],
                          cwd=str(root), timeout=60, capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == ""
    assert not (root / f"{wrong}.pid").exists()  # it never listened
    assert cad_server.running() is None


def _written(root) -> list[str]:
    """The files in the server folder (key, pid): what a server and its clients wrote."""
    return sorted(p.name for p in root.iterdir()) if root.is_dir() else []


@pytest.mark.process
def test_a_server_started_early_is_the_one_its_build_connects_to_and_stays(server_env):
    """`cogniframe build` starts the server first thing (`prestart`), before it has validated the
    params: nothing is written until the build connects, which then waits for that process
    instead of starting another; once connected it serves like any server (FE modules loaded)."""
    early = cad_server.prestart(idle_s=60)
    assert early is not None and early.proc.poll() is None
    assert _written(early.root) == []  # no key file: the process cannot serve anyone yet
    started = []
    with cad_server.connect(1, idle_s=60, early=early, on_start=lambda: started.append(1)) as pool:
        assert early.adopted and cad_server.running() == early.proc.pid and started == [1]
        assert pool.submit(eval, "'gmsh' in __import__('sys').modules").result() is True
    early.release()  # connected: it stays for the next build
    assert cad_server.running() == early.proc.pid
    assert cad_server.prestart(idle_s=60) is None  # a server answers: no second one


@pytest.mark.process
def test_an_early_server_its_build_did_not_use_ends_having_written_nothing(server_env):
    """Bad params, an up-to-date folder, nothing to build: the CLI releases the early server,
    killed at once; and one whose build died before connecting exits by itself once it has
    imported CadQuery and found no key file (it never listens)."""
    early = cad_server.prestart(idle_s=60)
    time.sleep(0.2)
    early.release()
    assert early.proc.returncode is not None and not _pid_alive(early.proc.pid)
    orphan = cad_server.prestart(idle_s=60)
    assert orphan is not None and orphan.proc.pid != early.proc.pid
    assert orphan.proc.wait(timeout=120) == 0  # no kill: it ended by itself
    assert _written(orphan.root) == [] and cad_server.running() is None


@pytest.mark.process
def test_bad_params_with_the_server_on_leave_no_server_and_no_key(server_env, monkeypatch, tmp_path):
    """The CLI path: exit 2 with the usual message, and the early server is gone."""
    from pathlib import Path

    from cogniframe.cli import main

    monkeypatch.setenv(cad_server.ENV, "1")
    made = []
    real = cad_server.prestart
    monkeypatch.setattr(cad_server, "prestart", lambda *a, **k: made.append(real(*a, **k)) or made[-1])
    good = Path(__file__).resolve().parents[1] / "params" / "bamboo.yaml"
    bad = tmp_path / "bad.yaml"
    bad.write_text(good.read_text().replace("diameter: 3", "diameter: -3", 1))
    assert "diameter: -3" in bad.read_text()
    assert main(["build", str(bad), "-o", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out").exists()
    assert len(made) == 1 and made[0] is not None and made[0].proc.returncode is not None  # started, then ended
    assert _written(cad_server.folder()) == [] and cad_server.running() is None
    assert _processes_naming(str(cad_server.folder())) == []


def _processes_naming(text: str) -> list[int]:
    """Running processes with `text` in their command line (a server has its folder there)."""
    found = []
    for p in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{p}/cmdline", "rb") as fh:
                if text.encode() in fh.read() and _pid_alive(int(p)):
                    found.append(int(p))
        except OSError:  # it ended meanwhile
            pass
    return found
