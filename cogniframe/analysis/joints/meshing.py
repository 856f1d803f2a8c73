"""The joint FE's mesher: a solid (OCC BREP text, or a gmsh OCC primitive in the tests and
benchmarks) to linear tetrahedra with gmsh, single-threaded and seeded so that a solid always
gets the same mesh.

gmsh is imported inside the functions: `cogniframe check` never loads it when the joint results
are cached.
"""

from __future__ import annotations

import contextlib
import os
import tempfile

import numpy as np


def _gmsh():
    import gmsh

    if not gmsh.isInitialized():
        # interruptible=False: gmsh would otherwise replace the SIGINT handler (Ctrl-C must stay the CLI's)
        with _sigpipe_kept():
            gmsh.initialize(["-noenv"], readConfigFiles=False, interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.MaxNumThreads3D", 1)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    return gmsh


@contextlib.contextmanager
def _sigpipe_kept():
    """Put SIGPIPE's action back as it was after the block (from any thread).

    gmsh's initialize sets SIGPIPE to its default action, which ends the process (the one signal it
    changes: /proc/self/status, SigIgn). Python ignores SIGPIPE, so that a write to a pipe or
    socket whose reader has gone raises BrokenPipeError; after gmsh, the same write ended the whole
    process at once, with no traceback: a studio that had solved a joint, writing to a page that
    had closed, or to the queue of a process-pool worker it had just stopped (a pytest-xdist
    worker died so: "node down: Not properly terminated"). `signal.signal` works on the main
    thread only, and joints are solved on others (the studio's), hence libc's `signal()`."""
    import ctypes
    import signal

    if not hasattr(signal, "SIGPIPE"):  # Windows: no such signal
        yield
        return
    libc_signal = ctypes.CDLL(None).signal
    libc_signal.restype = ctypes.c_void_p
    libc_signal.argtypes = (ctypes.c_int, ctypes.c_void_p)
    before = libc_signal(signal.SIGPIPE, ctypes.c_void_p(int(signal.SIG_IGN)))  # reads the action it replaces
    try:
        yield
    finally:
        libc_signal(signal.SIGPIPE, before)


def mesh_occ(build, h: float, name: str = "part", curvature: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Mesh the volume that ``build(gmsh.model.occ)`` creates; returns (points (3, N), tets (4, M))."""
    gmsh = _gmsh()
    gmsh.model.add(name)
    try:
        build(gmsh.model.occ)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeMin", h / 3)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", curvature)
        gmsh.option.setNumber("Mesh.Algorithm3D", 1)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        try:
            gmsh.model.mesh.generate(3)
        except Exception as exc:  # gmsh raises bare Exception
            raise RuntimeError(f"gmsh could not mesh {name}: {exc}") from None
        tags, coords, _ = gmsh.model.mesh.getNodes()
        etypes, _, enodes = gmsh.model.mesh.getElements(3)
        tet = [enodes[i] for i, t in enumerate(etypes) if t == 4]
        if not tet:
            raise RuntimeError(f"gmsh produced no tetrahedra for {name}")
        conn = np.concatenate(tet).astype(np.int64).reshape(-1, 4)
    finally:
        gmsh.model.remove()
    pos = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    pos[tags.astype(np.int64)] = np.arange(tags.size)
    pts = coords.reshape(-1, 3).T
    t = pos[conn].T
    used = np.unique(t)
    remap = np.full(pts.shape[1], -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    return np.ascontiguousarray(pts[:, used]), np.ascontiguousarray(remap[t])


def mesh_brep_text(brep: str, h: float, curvature: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Mesh a solid given as OCC BREP text (what CadQuery's ``exportBrep`` writes)."""
    fd, path = tempfile.mkstemp(suffix=".brep")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(brep)
        return mesh_occ(lambda occ: occ.importShapes(path), h, "joint", curvature)
    finally:
        os.unlink(path)
