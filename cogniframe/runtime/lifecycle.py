"""How a worker process of a build lives: what it preloads, that it dies with the build that asked
for it and runs behind it. Both kinds of workers use it: the process pools (`pools`) and the
forks of the CAD server (`server`)."""

from __future__ import annotations

import os
import threading

CAD_PRELOAD = ("cogniframe.runtime.worker",)  # CadQuery (with a lazy vtk), trimesh, the part builders
FE_PRELOAD = ("gmsh", "skfem", "pymetis", "cvxopt.cholmod")  # the joint FE's mesher and solver

BACKGROUND_NICE = 10  # how much nicer than the build its CAD workers and PrusaSlicer run


def start_worker(build_pid: int) -> None:
    """What a CAD worker of the build `build_pid` does first, in a process pool or forked by the CAD
    server: die with the build, and run behind it (`behind_the_build`)."""
    die_with_build(build_pid)
    behind_the_build()


def behind_the_build(pid: int = 0) -> None:
    """Make process `pid` (0: this one) BACKGROUND_NICE steps nicer than it is (at most 19).

    In the second half of a build the CAD workers (the joints' FE, the clash check, the assembly
    STEP) and PrusaSlicer run beside the build's main thread, which draws the previews, renders
    and plots one after the other and is then the critical path; the others' results are awaited
    only at the end. Running them nicer lets the main thread go first (docs/build.md has the
    measurements). Only the build's own helpers give way, and only to it. Linux applies the nice
    value to the thread that sets it and to the threads it starts later."""
    try:
        os.setpriority(os.PRIO_PROCESS, pid, min(19, os.getpriority(os.PRIO_PROCESS, pid) + BACKGROUND_NICE))
    except (AttributeError, OSError):  # no setpriority (Windows), or the process has just ended
        pass


def die_with_build(build_pid: int) -> None:
    """Exit this worker as soon as the build process `build_pid` is gone (even by SIGKILL).

    A worker's parent is the forkserver, not the build, and the forkserver only exits once every
    worker has (they hold its keep-alive pipe), so neither the kernel's parent-death signal nor the
    forkserver would end them, and a worker could still write into the temp folder after the next
    build had cleaned it. A daemon thread waits on the build's pidfd (Linux) or polls it, then ends
    the worker; with the workers gone the forkserver exits too."""
    import select
    import time

    def watch() -> None:
        try:
            fd = os.pidfd_open(build_pid)
        except (AttributeError, OSError):
            fd = None
        if fd is not None:
            select.select([fd], [], [])  # readable when the build has exited
        else:
            while True:
                time.sleep(0.5)
                try:
                    os.kill(build_pid, 0)
                except ProcessLookupError:
                    break
                except PermissionError:
                    pass
        os._exit(1)

    threading.Thread(target=watch, name="die-with-build", daemon=True).start()
