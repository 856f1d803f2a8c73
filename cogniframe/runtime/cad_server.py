"""A CAD process that outlives one build, so the next build's parts start warm.

Every build that changes a part used to start its CAD workers from nothing: a forkserver that
imports CadQuery (seconds of the 2-core machine's time, at the head of the critical path of a
one-part change). `cogniframe build` now keeps that process: the first build starts a *CAD
server* (CadQuery, trimesh and the part builders imported, the joint FE's modules too when that
build solves a joint); later builds connect to it and get their workers by `fork` from it, warm,
in milliseconds. The same idea as Gradle's daemon or Bazel's server.

- **What runs where.** The server only accepts connections and forks. Each connection of a build
  is served by its own fork (a *worker*), which runs the build's jobs one after another (part
  CAD, the clash check, the assembly STEP, the joint FE) in the build's working directory and
  sends back each result or exception; a build opens one connection per worker it wants. The
  functions are pickled by reference, exactly as for the process pool they replace.
- **Same code, same environment.** A server serves only builds with the same interpreter, the
  same `sys.path`, the same cogniframe source, the same library versions and the same
  environment variables (`server_key`); any difference gets its own server. So a worker computes
  what a fresh forkserver worker would: the outputs are the same bytes either way (tested).
- **Lifetime.** It exits after `IDLE_S` seconds without a build (10 min; a build in progress
  keeps it), on `cogniframe server stop`, when its key file is gone (the cache folder was
  deleted: no build could reach it, and the next build's server waits for the address), or when
  killed. It holds no file open and its output
  goes to /dev/null: it never keeps a terminal or a pipe of the build waiting.
- **Who may connect.** A Linux abstract socket (no file to leave behind), with the standard
  library's HMAC challenge on a random key kept in the cache folder (mode 0600): only the user
  who owns the cache can submit work.
- **Off switch.** `cogniframe build --no-server`, or `COGNIFRAME_CAD_SERVER=0` (the test suite
  sets it; its own tests start and stop servers explicitly). Elsewhere than Linux, or when the
  server cannot start, the build uses its per-build process pool (`runtime.pools.make_pool`).

Started by `connect` or `prestart` only, as `python -c BOOT SYS_PATH FOLDER KEY IDLE_S STACK [fe]`: BOOT sets
`sys.path` to the build's (a server started from the cache folder would otherwise import, say, an
installed cogniframe where the build imported the checkout it runs in), then `main` checks that
`server_key(STACK)` computed there is KEY before it imports anything heavy, and exits otherwise.
"""

from __future__ import annotations

import itertools
import json
import os
import queue
import sys
import threading
import time
from concurrent.futures import BrokenExecutor, Future
from pathlib import Path

ENV = "COGNIFRAME_CAD_SERVER"  # "0": never use a server
IDLE_S = 600.0
START_TIMEOUT_S = 60.0
KEY_CHECK_S = 1.0  # how often an idle server checks that its key file is still the one it serves
# the environment variables that can change what a worker computes or where it writes (the rest,
# e.g. PATH, a terminal's, or what a library sets for itself while a build runs, cannot)
_ENV_PREFIXES = ("COGNIFRAME_", "PYTHON", "OMP_", "OPENBLAS_", "MKL_", "GOTO", "LD_", "TMP", "TEMP", "XDG_", "LC_",
                 "CSF_", "CASROOT", "MMGT_", "GMSH", "HOME", "LANG")


def wanted(flag: bool | None = None) -> bool:
    """Whether a build should use a server: `flag` (the CLI's --server/--no-server) when given,
    else the environment (`COGNIFRAME_CAD_SERVER`, on unless "0"); never off Linux."""
    if not sys.platform.startswith("linux"):
        return False
    if flag is not None:
        return bool(flag)
    return os.environ.get(ENV, "1").strip() not in ("0", "false", "no", "off")


def folder() -> Path:
    from ..cache import cache_dir

    return cache_dir().resolve() / "cad-server"


def server_key(stack: str = "", root: Path | None = None) -> str:
    """Hash of everything a worker's results could depend on besides its arguments: interpreter,
    import path, cogniframe's source, the library versions (`stack`), the environment variables
    that matter, and the cache folder (which holds the server's key)."""
    from .. import cache

    env = {k: v for k, v in os.environ.items() if k.startswith(_ENV_PREFIXES) and k != ENV}
    return cache.key([sys.executable, sys.path, sorted(env.items()), str(root or folder())], ("**/*.py",), stack)


def address(key: str) -> str:
    return f"\0cogniframe-cad-{os.getuid()}-{key}"


def _authkey(root: Path, key: str, create: bool) -> bytes | None:
    """The server's random key (32 bytes, file mode 0600), created once by the first client."""
    import secrets

    path = root / f"{key}.auth"
    try:
        return path.read_bytes()
    except FileNotFoundError:
        if not create:
            return None
    root.mkdir(parents=True, exist_ok=True, mode=0o700)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:  # another build made it first
        return path.read_bytes()
    with os.fdopen(fd, "wb") as fh:
        fh.write(secrets.token_bytes(32))
    return path.read_bytes()


def _client(key: str, authkey: bytes):
    from multiprocessing.connection import Client

    return Client(address(key), family="AF_UNIX", authkey=authkey)


def _ask(key: str, authkey: bytes, message: tuple, timeout_s: float = 5.0):
    """One request to the server itself (ping, stop); None when no server answers."""
    from multiprocessing import AuthenticationError

    try:
        conn = _client(key, authkey)
    except (OSError, EOFError, AuthenticationError):
        return None
    try:
        conn.send(message)
        return conn.recv() if conn.poll(timeout_s) else None
    except (OSError, EOFError, AuthenticationError):
        return None
    finally:
        conn.close()


def _pid_if(stack: str, message: tuple, answer: str) -> int | None:
    """Send `message` to this environment's server; its pid when it answers `answer`."""
    key = server_key(stack)
    authkey = _authkey(folder(), key, create=False)
    reply = None if authkey is None else _ask(key, authkey, message)
    return reply[1] if reply and reply[0] == answer else None


def running(stack: str = "") -> int | None:
    """The pid of this environment's server, or None."""
    return _pid_if(stack, ("ping",), "pong")


def stop(stack: str = "") -> int | None:
    """Stop this environment's server; returns its pid (None: there was none)."""
    return _pid_if(stack, ("stop",), "stopping")


class Early:
    """A CAD server process that `cogniframe build` starts first thing (`prestart`), while it
    imports its own modules and validates the params, before it knows whether it needs one.

    The process imports CadQuery as any server does, then looks for its key file: only `connect`
    writes that, once the build is under way. So until the build connects, the early process
    has written nothing, and `release` ends it when the build did not connect (bad params, an
    up-to-date folder, every part cached, Ctrl-C)."""

    def __init__(self, key: str, root: Path, proc, idle_s: float):
        self.key, self.root, self.proc, self.idle_s = key, root, proc, idle_s
        self.adopted = False  # a build connected to it: it serves like any server from then on

    def release(self) -> None:
        """End the process unless a build connected to it."""
        if not self.adopted and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


def prestart(stack: str = "", idle_s: float | None = None) -> Early | None:
    """Start this environment's server now, unless one answers; `connect(early=...)` then uses it
    (the joint FE's modules are preloaded: the build does not know yet whether it solves a joint).
    Starting it here instead of once the build knows its parts moves the server's ~2 s of imports,
    the head of a cold build's critical path, earlier, onto the core the CLI leaves idle."""
    key = server_key(stack)
    root = folder()
    authkey = _authkey(root, key, create=False)
    if authkey is not None and _ask(key, authkey, ("ping",)) is not None:
        return None
    idle = IDLE_S if idle_s is None else float(idle_s)
    return Early(key, root, _spawn(root, key, idle, stack, fe=True), idle)


def _spawn(root: Path, key: str, idle_s: float, stack: str, fe: bool):
    import subprocess

    root.mkdir(parents=True, exist_ok=True, mode=0o700)
    proc = subprocess.Popen([sys.executable, "-c", _BOOT, json.dumps(sys.path), str(root), key, repr(idle_s), stack]
                            + (["fe"] if fe else []), cwd=str(root), stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, close_fds=True,
                            start_new_session=True,
                            # a snapshot: the build may set a variable in another thread meanwhile
                            env=os.environ.copy())
    # reaped by this thread whenever it ends while this process lives (a script or a test that
    # builds many times would otherwise keep a zombie); after this process, by init
    threading.Thread(target=proc.wait, name="cad-server-reaper", daemon=True).start()
    return proc


def connect(workers: int, stack: str = "", fe: bool = False, idle_s: float | None = None, log=None,
            on_start=None, early: Early | None = None) -> "ServerPool | None":
    """A pool of `workers` forks of this environment's CAD server, starting the server when none
    runs (and waiting for it: as long as a process pool's first worker would). None when it
    cannot start: the caller falls back to a process pool. `on_start()` is called when this call
    starts a server (before the ~2 s wait). `early`: the server `prestart` started for this build,
    used (and waited for) instead of starting another while it runs."""
    key = early.key if early is not None else server_key(stack)
    root = early.root if early is not None else folder()
    authkey = _authkey(root, key, create=True)
    reply = _ask(key, authkey, ("ping",))
    if reply is None:
        if early is not None and early.proc.poll() is None:
            proc, idle = early.proc, early.idle_s
        else:
            idle = IDLE_S if idle_s is None else float(idle_s)
            proc = _spawn(root, key, idle, stack, fe)
        if on_start is not None:
            on_start()
        t0 = time.monotonic()
        while reply is None:
            if proc.returncode is not None:
                # it could not start (an import failed), or another process holds the address and
                # does not answer to this key: no server this time
                return None
            if time.monotonic() - t0 > START_TIMEOUT_S:
                return None
            time.sleep(0.02)
            reply = _ask(key, authkey, ("ping",))
        if early is not None and reply[1] == early.proc.pid:
            early.adopted = True
        if log is not None:
            log(f"started a CAD server (pid {reply[1]}) so that the next build starts warm: it exits after "
                f"{idle / 60:g} min without a build, or now with `cogniframe server stop`; "
                f"`cogniframe build --no-server` (or {ENV}=0) builds without one")
    return ServerPool(key, authkey, workers)


class BrokenServer(BrokenExecutor):
    """A worker of the CAD server ended while it ran a job (it crashed or was killed)."""


class ServerPool:
    """`concurrent.futures`-style pool over the server: `workers` threads, each with its own
    connection (its own worker process), take jobs by priority (lower first, then in order)."""

    def __init__(self, key: str, authkey: bytes, workers: int):
        self.key, self.authkey, self.workers = key, authkey, max(1, int(workers))
        self._jobs: queue.PriorityQueue = queue.PriorityQueue()
        self._order = itertools.count()
        self._threads: list[threading.Thread] = []
        self._lock = threading.Lock()
        self._worker_pids: set[int] = set()  # the forks serving this pool's connections

    def submit(self, fn, *args, priority: int = 0) -> Future:
        fut: Future = Future()
        self._jobs.put((priority, next(self._order), fut, fn, args))
        with self._lock:
            while len(self._threads) < self.workers:
                t = threading.Thread(target=self._work, name=f"cad-server-{len(self._threads)}", daemon=True)
                t.start()
                self._threads.append(t)
        return fut

    def _work(self) -> None:
        conn = None
        while True:
            _, _, fut, fn, args = self._jobs.get()
            if fut is None:
                break
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                if conn is None:
                    conn = _client(self.key, self.authkey)
                    conn.send(("hello", os.getpid(), os.getcwd()))
                    _, pid = conn.recv()  # ("ready", the worker's pid)
                    with self._lock:
                        self._worker_pids.add(pid)
                conn.send((fn, args))
                status, value = conn.recv()
            except (OSError, EOFError) as exc:
                conn = None
                fut.set_exception(BrokenServer(f"a CAD server worker ended while running {getattr(fn, '__name__', fn)}: {exc!r}"))
                continue
            except BaseException as exc:  # the job could not be pickled, or its result not unpickled
                fut.set_exception(exc)
                continue
            if status == "ok":
                fut.set_result(value)
            else:
                fut.set_exception(value)
        if conn is not None:
            conn.close()

    def cancel_pending(self) -> None:
        """Cancel every job no worker has taken yet (a job under way ends on its own)."""
        while True:
            try:
                item = self._jobs.get_nowait()
            except queue.Empty:
                break
            if item[2] is not None:
                item[2].cancel()
            else:  # a worker's stop mark: keep it
                self._jobs.put(item)
                break

    def kill_workers(self) -> None:
        """End this pool's workers now (the jobs they run fail with BrokenServer); the server,
        which forked them, stays and reaps them."""
        import signal

        with self._lock:
            pids, self._worker_pids = set(self._worker_pids), set()
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        if cancel_futures:
            self.cancel_pending()
        with self._lock:
            threads = list(self._threads)
        for _ in threads:
            self._jobs.put((float("inf"), next(self._order), None, None, None))
        if wait:
            for t in threads:
                t.join()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.shutdown(wait=True)


# -- the server process ------------------------------------------------------------------------

def _serve_worker(conn, hello) -> None:
    """A forked worker: run the build's jobs until it hangs up (or dies: `die_with_build`), behind
    the build (`behind_the_build`)."""
    from .lifecycle import start_worker

    _, build_pid, cwd = hello
    os.chdir(cwd)
    start_worker(int(build_pid))
    conn.send(("ready", os.getpid()))
    while True:
        try:
            fn, args = conn.recv()
        except (EOFError, OSError):
            break
        try:
            reply = ("ok", fn(*args))
        except BaseException as exc:  # sent back to the build, which raises it
            reply = ("err", exc)
        try:
            conn.send(reply)
        except (OSError, EOFError):
            break
        except Exception as exc:  # an unpicklable result or exception
            conn.send(("err", RuntimeError(f"{getattr(fn, '__name__', fn)}: {exc!r}")))


def serve(root: Path, key: str, idle_s: float, fe: bool) -> None:
    """The server's loop: answer pings and stops, fork a worker per build connection, reap
    workers, exit after `idle_s` seconds with no worker and no connection."""
    import importlib
    import select
    from multiprocessing.connection import Listener

    importlib.import_module("cogniframe.runtime.worker")  # CadQuery, trimesh, the part builders (frozen there)
    if fe:
        from .heap import imports_frozen
        from .lifecycle import FE_PRELOAD

        with imports_frozen():
            for mod in FE_PRELOAD:
                importlib.import_module(mod)
    authkey = _authkey(root, key, create=False)
    if authkey is None:
        return
    t0 = time.monotonic()
    while True:
        try:
            listener = Listener(address(key), family="AF_UNIX", authkey=authkey)
            break
        except OSError:
            # another server holds the address: it serves, unless it is one whose key file was
            # deleted with the cache folder, which leaves within a second (below): wait for that
            if time.monotonic() - t0 > KEY_CHECK_S + 2.0:
                return
            time.sleep(0.1)
    pidfile = root / f"{key}.pid"
    pidfile.write_text(f"{os.getpid()}\n")
    sock = listener._listener._socket
    workers: set[int] = set()
    last = checked = time.monotonic()
    try:
        while True:
            for pid in list(workers):  # reap (their CPU time then counts as this process's children)
                try:
                    done, _ = os.waitpid(pid, os.WNOHANG)
                except ChildProcessError:
                    done = pid
                if done:
                    workers.discard(pid)
                    last = time.monotonic()
            if not workers and time.monotonic() - checked > KEY_CHECK_S:
                # (also while clients knock: a build with the new key pings every 20 ms)
                checked = time.monotonic()
                if _authkey(root, key, create=False) != authkey:
                    # the cache folder was deleted (or its key replaced): no build can reach this
                    # server any more, and the next one starts its own at this address
                    break
            ready, _, _ = select.select([sock], [], [], 0.2)
            if not ready:
                if not workers and time.monotonic() - last > idle_s:
                    break
                continue
            try:
                conn = listener.accept()
            except Exception:  # a failed handshake (wrong key) or a client that went away
                continue
            last = time.monotonic()
            try:
                msg = conn.recv() if conn.poll(5.0) else None
            except (OSError, EOFError):
                msg = None
            if not msg:
                conn.close()
                continue
            if msg[0] == "ping":
                conn.send(("pong", os.getpid()))
            elif msg[0] == "stop":
                conn.send(("stopping", os.getpid()))
                conn.close()
                break
            elif msg[0] == "hello":
                pid = os.fork()
                if pid == 0:
                    listener.close()
                    try:
                        _serve_worker(conn, msg)
                    finally:
                        os._exit(0)
                workers.add(pid)
            conn.close()
    finally:
        listener.close()
        try:
            if pidfile.read_text().strip() == str(os.getpid()):
                pidfile.unlink()
        except OSError:
            pass


_BOOT = ("import json, sys; sys.path[:] = json.loads(sys.argv[1]); "
         "from cogniframe.runtime.cad_server import main; main(sys.argv[2:])")


def main(argv: list[str]) -> None:
    """The server process (`connect` starts it with `_BOOT`): serve only if this process, with the
    build's `sys.path` and environment, computes the key the build asked for, i.e. it runs the same
    interpreter, cogniframe source and environment; else end, and the build uses a pool of its own."""
    root, key, idle_s, stack = Path(argv[0]), argv[1], float(argv[2]), argv[3]
    if server_key(stack, root) != key:  # (root: the build's cache folder, resolved in its working directory)
        return
    serve(root, key, idle_s, len(argv) > 4 and argv[4] == "fe")
