"""The precision at which cogniframe writes numbers into its output files: one place, stated.

A float computed from a mesh, a factorization or an ODE carries last bits that move with the CPU
(vector width, fused multiply-add), the BLAS and the releases of numpy/scipy/OCP/trimesh/gmsh that
pyproject.toml allows. Those bits mean nothing, but written out in full they change the file's
bytes, and the golden hashes (tests/test_golden_outputs.py) then fail on every machine but the
one that wrote them. So every output writes its numbers at a stated precision, through here:

- CHECK_FIGURES = 4 significant digits for the model figures of `check --json` and the build's
  check.json: the sections CHECK_MODEL_SECTIONS (drop model, stiffness and load cases, peak
  deceleration, survival sweep). The models behind them are good to a few percent; 4 digits (0.1 %)
  keep every input's effect visible and drop what moves between environments: measured between
  numpy 1.26/scipy 1.11/trimesh 4.0/manifold3d 2.5/scikit-fem 10 and numpy 2.4/scipy 1.17/
  trimesh 5.2/manifold3d 3.5/scikit-fem 12 (OCP 7.9, gmsh 4.15 in both), up to 1e-7 relative on
  forces that vanish by symmetry and 1e-10..1e-8 elsewhere. The
  other sections (mass budget, cut list, stock, frame, parts, flight) are arithmetic on the params
  and CAD volumes, written at their producers' stated decimals (0.01 g, 0.001 g each, 0.01 mm,
  6 significant digits of inertia), which no environment moved.
- GRID_MM = 1e-4 mm for the vertex coordinates of STL, 3MF and GLB meshes: 100 nm, far below any
  printer's resolution and the 0.02 mm tessellation tolerance, far above a float64's noise on a
  200 mm part (~1e-13 mm). Vertices are snapped before welding, so two vertices that the grid
  merges are merged once (and a face they collapse is dropped) before the mesh is checked closed.
- NORMAL_DIGITS = 6 decimals for the unit facet normals an STL carries (slicers recompute them).
- PLACEMENT_DECIMALS = 9 decimals for the entries of the 4x4 placements of the GLB's nodes.
- CAD_DECIMALS = 9 decimals (1e-9 mm; 1e-9 of a unit vector or a rotation entry) for the numbers
  the joints' solids are built from (parts/joint_solid.py, `cad`). They come out of small numpy
  dot and matrix-vector products, which go through the BLAS, whose kernel OpenBLAS picks by CPU:
  with its Haswell and Sandybridge kernels a knee sleeve started at x = 1.7999999999999998 or 1.8,
  and the knee's and core links' STEP (and the bamboo knee's STL) differed between machines of
  one lock file. 1e-9 mm is 1/100 of OpenCascade's confusion tolerance (1e-7 mm), so the
  rounding moves no point that OCC could tell from where it was.
- PLOT_DECIMALS = 6 decimals for the curves a PNG plot draws (ms, mm, G: a millionth of a unit is
  ~1e-5 of a pixel), from the model's stated figures: numpy's exp and sin differ in their last
  bits between releases, and an antialiased pixel followed them.

Rounding to a grid is not a proof of byte identity: a value within its noise of a rounding
boundary can still fall either way. The noise is at most ~1e-3 of the quantum here (1e-7 against
1e-4), so that is rare; the golden test names the file when it happens. What rounding cannot
absorb is a different model: another gmsh release meshes the joints' solids differently (4.12 vs
4.15 moved joint strains by 4e-6 and near-zero rod forces by 5e-3), and OCP 7.7 builds a joint's
solid otherwise than 7.9 (31698 vs 31674 DOF, figures 8e-4 off), manifold3d 2.x computes in
float32 and 3.0.1 triangulates a vitamin's union otherwise than 3.5.4: pyproject.toml asks for
gmsh>=4.15, cadquery>=2.8 (OCP 7.9) and manifold3d>=3.5, and the lock file (constraints.txt)
pins the environment CI and the golden hashes are made in.
"""

from __future__ import annotations

import math

import numpy as np

CHECK_FIGURES = 4
CHECK_MODEL_SECTIONS = ("drop", "stiffness", "peak_g", "survival")
GRID_MM = 1e-4
GRID_DECIMALS = 4  # GRID_MM as decimals for np.round
NORMAL_DIGITS = 6
PLACEMENT_DECIMALS = 9
CAD_DECIMALS = 9
PLOT_DECIMALS = 6


def sig(x: float, digits: int = CHECK_FIGURES) -> float:
    """`x` rounded to `digits` significant digits (correctly rounded through its decimal form);
    non-finite values and 0 unchanged, -0.0 written as 0.0."""
    if not math.isfinite(x) or x == 0:
        return x + 0.0 if x == 0 else x
    return float(f"{x:.{digits}g}") + 0.0


def norm(v: np.ndarray) -> float:
    """`np.linalg.norm` of a 1-D float vector, the same bits (the sqrt of its dot with itself, as
    numpy sums it) without its argument checks: a third of the time, for the check's hundreds of
    short vectors."""
    return math.sqrt(v.dot(v))


def figures(obj, digits: int = CHECK_FIGURES):
    """A copy of a JSON-able tree (dicts, lists, tuples, scalars) with every float rounded to
    `digits` significant digits; ints, bools, strings and None unchanged. numpy floats count as
    floats (and come back as Python floats).

    The plain types (float, dict, list, tuple, str, int, bool, None) go by their exact type, in
    half the time of the isinstance tests (a check's tree has ~1500 floats); every other node
    (subclasses, numpy scalars) by `_figures`, the same rules."""
    def walk(o):
        t = type(o)
        if t is float:
            return sig(o, digits)
        if t is dict:
            return {k: walk(v) for k, v in o.items()}
        if t is list or t is tuple:
            return [walk(v) for v in o]
        if t is str or t is int or t is bool or o is None:
            return o
        return _figures(o, digits)

    return walk(obj)


def _figures(obj, digits: int):
    """`figures` of any node, by isinstance."""
    if isinstance(obj, bool) or obj is None or isinstance(obj, (int, str)):
        return obj
    if isinstance(obj, (float, np.floating)):
        return sig(float(obj), digits)
    if isinstance(obj, dict):
        return {k: figures(v, digits) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [figures(v, digits) for v in obj]
    return obj


def check_figures(check: dict) -> dict:
    """The check JSON with its model sections (CHECK_MODEL_SECTIONS) at CHECK_FIGURES significant
    digits; the other sections as they are."""
    return {k: figures(v) if k in CHECK_MODEL_SECTIONS else v for k, v in check.items()}


def on_grid(vertices) -> np.ndarray:
    """Vertex coordinates (mm) snapped to the GRID_MM grid, float64; -0.0 made 0.0."""
    return np.round(np.asarray(vertices, dtype=np.float64), GRID_DECIMALS) + 0.0


def cad(x):
    """A number, or an array of them, that a part's CAD is built from, rounded to CAD_DECIMALS
    decimals (a float or a float64 array); -0.0 made 0.0."""
    a = np.round(np.asarray(x, dtype=np.float64), CAD_DECIMALS) + 0.0
    return float(a) if a.ndim == 0 else a


def unit_normals(normals) -> np.ndarray:
    """Unit normals rounded to NORMAL_DIGITS decimals, float64; -0.0 made 0.0."""
    return np.round(np.asarray(normals, dtype=np.float64), NORMAL_DIGITS) + 0.0


def placement(matrix) -> np.ndarray:
    """A 4x4 placement (rotation and mm) rounded to PLACEMENT_DECIMALS decimals, float64: a
    rotation entry's 1e-9 moves a point 200 mm out by 2e-7 mm, below GRID_MM."""
    return np.round(np.asarray(matrix, dtype=np.float64), PLACEMENT_DECIMALS) + 0.0


def canonical_faces(faces) -> np.ndarray:
    """Triangles in one stated order: each turned (winding kept) to start at its lowest vertex, then
    sorted. The same set of triangles in any order (trimesh's and scipy's releases order a convex
    hull's or a primitive's faces differently) gives the same array."""
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if not len(f):
        return f
    turn = np.argmin(f, axis=1)
    f = np.stack([f[np.arange(len(f)), (turn + k) % 3] for k in range(3)], axis=1)
    return f[np.lexsort((f[:, 2], f[:, 1], f[:, 0]))]


def plotted(values) -> np.ndarray:
    """A plotted curve's values at PLOT_DECIMALS decimals, float64."""
    return np.round(np.asarray(values, dtype=np.float64), PLOT_DECIMALS) + 0.0
