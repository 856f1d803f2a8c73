"""A small 3D frame finite-element assembler (numpy only): stiffness, mass and geometric stiffness.

Why not PyNite for the frame: the joints are now general 6x6 (or 6n x 6n) condensed stiffness
matrices from the joint models (`joints`), which PyNite cannot take (its springs are
axial only), and the modal and buckling load cases need the assembled K, M and K_G, which PyNite
does not expose. The element here is the textbook 3D Euler-Bernoulli beam (12 DOF: u, v, w,
rx, ry, rz at each end), with the consistent mass matrix and the geometric stiffness of an axial
force (Przemieniecki, "Theory of Matrix Structural Analysis", ch. 5 and 11). tests/test_framefe.py
and tests/test_joint_fe.py check it against closed forms (cantilever deflection and modes, Euler
buckling) and the sparse path against the dense one.

Assembly is vectorized: all beams' element matrices as one (n, 12, 12) stack, rotated by batched
matmul and scattered once (dense: np.bincount; ``sparse=True``: scipy COO -> CSC). A frame has
~800 DOF (1 300 with rods in 4 elements for the modes) and ~15 non-zeros per row, so the load
cases use the sparse matrices and `solve` / `factor` (qdldl's LDL^T); the dense ones remain for
small models and tests.

Units: N, mm, t (tonne = 1000 kg) so that stiffness in N/mm and mass in t give eigenvalues in
(rad/s)^2. Densities in t/mm^3 (g/cm^3 * 1e-9).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


def circle_section(d: float) -> tuple[float, float, float]:
    """(A, I, J) of a solid circle of diameter d (mm^2, mm^4, mm^4)."""
    a = math.pi * d * d / 4
    i = math.pi * d**4 / 64
    return a, i, 2 * i


def _coef(length, *values) -> np.ndarray:
    """Broadcast scalars or per-beam arrays to one float array of the beams' count."""
    return np.broadcast_arrays(np.asarray(length, float), *(np.asarray(v, float) for v in values))


# The element matrices as (row, col, coefficient) tables: the coefficient is a function of L.
# Bending in the x-y plane (v, rz) with Iz; in the x-z plane (w, ry) with Iy, rotation couplings flipped.
_K_XY = ((1, 1, 12, 0), (1, 5, 6, 1), (1, 7, -12, 0), (1, 11, 6, 1), (5, 5, 4, 2), (5, 7, -6, 1),
         (5, 11, 2, 2), (7, 7, 12, 0), (7, 11, -6, 1), (11, 11, 4, 2))
_K_XZ = ((2, 2, 12, 0), (2, 4, -6, 1), (2, 8, -12, 0), (2, 10, -6, 1), (4, 4, 4, 2), (4, 8, 6, 1),
         (4, 10, 2, 2), (8, 8, 12, 0), (8, 10, 6, 1), (10, 10, 4, 2))
_M_XY = ((1, 1, 156, 0), (1, 5, 22, 1), (1, 7, 54, 0), (1, 11, -13, 1), (5, 5, 4, 2), (5, 7, 13, 1),
         (5, 11, -3, 2), (7, 7, 156, 0), (7, 11, -22, 1), (11, 11, 4, 2))
_M_XZ = ((2, 2, 156, 0), (2, 4, -22, 1), (2, 8, 54, 0), (2, 10, 13, 1), (4, 4, 4, 2), (4, 8, -13, 1),
         (4, 10, -3, 2), (8, 8, 156, 0), (8, 10, 22, 1), (10, 10, 4, 2))
_G_XY = ((1, 1, 36, 0), (1, 5, 3, 1), (1, 7, -36, 0), (1, 11, 3, 1), (5, 5, 4, 2), (5, 7, -3, 1),
         (5, 11, -1, 2), (7, 7, 36, 0), (7, 11, -3, 1), (11, 11, 4, 2))
_G_XZ = ((2, 2, 36, 0), (2, 4, -3, 1), (2, 8, -36, 0), (2, 10, -3, 1), (4, 4, 4, 2), (4, 8, 3, 1),
         (4, 10, -1, 2), (8, 8, 36, 0), (8, 10, 3, 1), (10, 10, 4, 2))


def _fill(out: np.ndarray, table, c: np.ndarray, L: np.ndarray, div: np.ndarray | None = None) -> None:
    """out[:, i, j] = out[:, j, i] = c * (val L^p) [/ div] for every (i, j, val, p) of the table
    (the textbook's order of operations: val * L * L)."""
    for i, jj, val, p in table:
        term = val if p == 0 else (val * L if p == 1 else val * L * L)
        v = c * term
        out[:, i, jj] = out[:, jj, i] = v if div is None else v / div


def beam_local_k_batch(length, e, g, a, iy, iz, j) -> np.ndarray:
    """(n, 12, 12) local stiffnesses of 3D Euler-Bernoulli beams (DOF order u1 v1 w1 rx1 ry1 rz1,
    u2 ...); every argument a scalar or an array over the n beams."""
    L, e, g, a, iy, iz, j = (np.atleast_1d(x) for x in _coef(length, e, g, a, iy, iz, j))
    k = np.zeros((L.size, 12, 12))
    ea, gj = e * a / L, g * j / L
    k[:, 0, 0] = k[:, 6, 6] = ea
    k[:, 0, 6] = k[:, 6, 0] = -ea
    k[:, 3, 3] = k[:, 9, 9] = gj
    k[:, 3, 9] = k[:, 9, 3] = -gj
    _fill(k, _K_XY, e * iz, L, L**3)
    _fill(k, _K_XZ, e * iy, L, L**3)
    return k


def beam_local_m_batch(length, rho_a, polar_r2) -> np.ndarray:
    """(n, 12, 12) consistent masses (rho_a = mass per length, polar_r2 = J/A for torsion)."""
    L, rho_a, polar_r2 = (np.atleast_1d(x) for x in _coef(length, rho_a, polar_r2))
    m = np.zeros((L.size, 12, 12))
    c = rho_a * L
    m[:, 0, 0] = m[:, 6, 6] = c / 3
    m[:, 0, 6] = m[:, 6, 0] = c / 6
    m[:, 3, 3] = m[:, 9, 9] = c * polar_r2 / 3
    m[:, 3, 9] = m[:, 9, 3] = c * polar_r2 / 6
    c = rho_a * L / 420
    _fill(m, _M_XY, c, L)
    _fill(m, _M_XZ, c, L)
    return m


def beam_local_kg_batch(length, axial_n) -> np.ndarray:
    """(n, 12, 12) geometric stiffnesses for axial forces (tension positive), bending terms only."""
    L, axial_n = (np.atleast_1d(x) for x in _coef(length, axial_n))
    kg = np.zeros((L.size, 12, 12))
    c = axial_n / (30 * L)
    _fill(kg, _G_XY, c, L)
    _fill(kg, _G_XZ, c, L)
    return kg


@dataclass
class Beam:
    name: str
    n0: str
    n1: str
    e: float
    g: float
    a: float
    i: float
    j: float
    rho: float  # t/mm^3
    group: str = ""


@dataclass
class Frame3D:
    """Nodes, beams, general springs (6k x 6k matrices over k nodes), point masses, supports."""

    nodes: dict[str, np.ndarray] = field(default_factory=dict)
    beams: list[Beam] = field(default_factory=list)
    springs: list[tuple[tuple[str, ...], np.ndarray]] = field(default_factory=list)
    masses: dict[str, np.ndarray] = field(default_factory=dict)  # 6x6 mass (t, t mm^2) per node

    def add_node(self, name: str, pos) -> str:
        if name in self.nodes:
            raise ValueError(f"duplicate node {name}")
        self.nodes[name] = np.asarray(pos, dtype=float)
        return name

    def add_beam(self, name, n0, n1, e, g, d=None, *, section=None, rho=0.0, group="") -> None:
        a, i, j = circle_section(d) if section is None else section
        self.beams.append(Beam(name, n0, n1, e, g, a, i, j, rho, group))

    def add_spring(self, nodes: tuple[str, ...], k: np.ndarray) -> None:
        k = np.asarray(k, dtype=float)
        if k.shape != (6 * len(nodes),) * 2:
            raise ValueError("spring matrix must be 6k x 6k for k nodes")
        self.springs.append((tuple(nodes), 0.5 * (k + k.T)))

    def set_spring(self, i: int, k: np.ndarray) -> None:
        """Replace the matrix of spring i (same nodes), symmetrized as `add_spring` does."""
        nodes = self.springs[i][0]
        k = np.asarray(k, dtype=float)
        if k.shape != (6 * len(nodes),) * 2:
            raise ValueError("spring matrix must be 6k x 6k for k nodes")
        self.springs[i] = (nodes, 0.5 * (k + k.T))

    def add_mass(self, node: str, mass_t: float, inertia_t_mm2=(0.0, 0.0, 0.0)) -> None:
        m = self.masses.setdefault(node, np.zeros((6, 6)))
        m[0, 0] += mass_t
        m[1, 1] += mass_t
        m[2, 2] += mass_t
        for a in range(3):
            m[3 + a, 3 + a] += inertia_t_mm2[a]

    def index(self) -> dict[str, int]:
        return {n: i for i, n in enumerate(self.nodes)}

    # -- assembly: every beam at once (stacked element matrices, one scatter) --------------------

    def _beam_arrays(self, idx: dict[str, int], beams: list[Beam] | None = None):
        """(L, T, dofs) of the beams: lengths (n,), 12x12 rotations (n, 12, 12), DOFs (n, 12)."""
        beams = self.beams if beams is None else beams
        i0 = np.fromiter((idx[b.n0] for b in beams), int, len(beams))
        i1 = np.fromiter((idx[b.n1] for b in beams), int, len(beams))
        pos = np.array(list(self.nodes.values()), float).reshape(-1, 3)
        L, R = _frame_axes_batch(pos[i0], pos[i1])
        T = np.zeros((len(beams), 12, 12))
        for blk in range(4):
            T[:, 3 * blk:3 * blk + 3, 3 * blk:3 * blk + 3] = R
        six = np.arange(6)
        dofs = np.concatenate([6 * i0[:, None] + six, 6 * i1[:, None] + six], axis=1)
        return L, T, dofs

    def _beam_props(self, beams: list[Beam]):
        return (np.array([[b.e, b.g, b.a, b.i, b.j, b.rho] for b in beams], float).reshape(-1, 6)).T

    def _spring_coo(self, idx):
        """(rows, cols, values) of the springs, batched by their node count; within a batch in
        the springs' order."""
        six = np.arange(6)
        groups: dict[int, tuple[list, list]] = {}
        for nodes, k in self.springs:
            g = groups.setdefault(len(nodes), ([], []))
            g[0].append([idx[n] for n in nodes])
            g[1].append(k)
        parts = [_block_coo((6 * np.asarray(nodes)[:, :, None] + six).reshape(len(nodes), -1), np.asarray(ks))
                 for nodes, ks in groups.values()]
        if not parts:
            return _EMPTY
        return tuple(np.concatenate(x) for x in zip(*parts))

    def stiffness(self, sparse: bool = False):
        """Assembled K (dense ndarray; ``sparse=True``: scipy CSC), DOFs in node order x 6."""
        idx = self.index()
        parts = []
        if self.beams:
            L, T, dofs = self._beam_arrays(idx)
            e, g, a, i, j, _ = self._beam_props(self.beams)
            parts.append(_block_coo(dofs, _rotate(T, beam_local_k_batch(L, e, g, a, i, i, j))))
        return _assemble(6 * len(idx), parts + [self._spring_coo(idx)], sparse)

    def mass(self, sparse: bool = False):
        """Assembled consistent mass M (beams with rho > 0, point masses); as `stiffness`."""
        idx = self.index()
        heavy = [b for b in self.beams if b.rho > 0]
        parts = []
        if heavy:
            L, T, dofs = self._beam_arrays(idx, heavy)
            e, g, a, i, j, rho = self._beam_props(heavy)
            parts.append(_block_coo(dofs, _rotate(T, beam_local_m_batch(L, rho * a, j / a))))
        if self.masses:
            dofs = np.array([np.arange(6 * idx[n], 6 * idx[n] + 6) for n in self.masses])
            parts.append(_block_coo(dofs, np.array(list(self.masses.values()))))
        return _assemble(6 * len(idx), parts, sparse)

    def axial_forces(self, u: np.ndarray) -> dict[str, float]:
        """Axial force (N, tension positive) in every beam for a displacement vector u."""
        if not self.beams:
            return {}
        idx = self.index()
        L, T, dofs = self._beam_arrays(idx)
        e, _, a, _, _, _ = self._beam_props(self.beams)
        x = T[:, 0, :3]  # the member axis
        ul0 = np.einsum("ij,ij->i", x, u[dofs[:, :3]])
        ul6 = np.einsum("ij,ij->i", x, u[dofs[:, 6:9]])
        n = e * a / L * (ul6 - ul0)
        return {b.name: float(v) for b, v in zip(self.beams, n)}

    def end_forces(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """Every beam's end forces in its local axes (12: N, Vy, Vz, T, My, Mz at each end; N,
        N mm) for a displacement vector u: k_local T u_element."""
        if not self.beams:
            return {}
        idx = self.index()
        L, T, dofs = self._beam_arrays(idx)
        e, g, a, i, j, _ = self._beam_props(self.beams)
        ul = np.einsum("nij,nj->ni", T, u[dofs])
        f = np.einsum("nij,nj->ni", beam_local_k_batch(L, e, g, a, i, i, j), ul)
        return {b.name: f[k] for k, b in enumerate(self.beams)}


_EMPTY = (np.zeros(0, int), np.zeros(0, int), np.zeros(0))


def _rotate(T: np.ndarray, k: np.ndarray) -> np.ndarray:
    """T^T k T for stacks of element matrices (local -> global axes)."""
    return np.matmul(np.matmul(T.transpose(0, 2, 1), k), T)


def _block_coo(dofs: np.ndarray, blocks: np.ndarray):
    """(rows, cols, values) of element blocks (n, m, m) on their DOFs (n, m), row-major."""
    m = dofs.shape[1]
    return np.repeat(dofs, m, axis=1).ravel(), np.tile(dofs, (1, m)).ravel(), blocks.ravel()


def _frame_axes_batch(p0: np.ndarray, p1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lengths (n,) and rotations (n, 3, 3) whose rows are each member's local x, y, z axes
    (the reference is global z, or x for a member near vertical)."""
    x = p1 - p0
    length = np.sqrt(np.einsum("ij,ij->i", x, x))
    x = x / length[:, None]
    ref = np.where((np.abs(x[:, 2]) < 0.9)[:, None], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    y = _cross(ref, x)
    y /= np.sqrt(np.einsum("ij,ij->i", y, y))[:, None]
    z = _cross(x, y)
    return length, np.stack([x, y, z], axis=1)


def member_axes(direction: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations whose rows are local x (along each direction), y, z: the members' axes
    convention (`_frame_axes_batch`) for directions instead of end points."""
    d = np.asarray(direction, float).reshape(-1, 3)
    return _frame_axes_batch(np.zeros_like(d), d)[1]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def _assemble(n: int, parts, sparse: bool):
    """Sum (rows, cols, values) triplets into an n x n matrix (dense: np.bincount, which adds in
    the order given; sparse: scipy COO -> CSC, duplicates summed)."""
    rows = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, int)
    cols = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, int)
    vals = np.concatenate([p[2] for p in parts]) if parts else np.zeros(0)
    if sparse:
        from scipy.sparse import coo_matrix

        return coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsc()
    return np.bincount(rows * n + cols, weights=vals, minlength=n * n).reshape(n, n)


def solve(K, f: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """Solve K u = f with the DOFs in `fixed` (bool mask) held at zero: dense LU for an ndarray K,
    a sparse LDL^T for a scipy sparse K (`factor`)."""
    free = ~fixed
    u = np.zeros(K.shape[0])
    if isinstance(K, np.ndarray):
        u[free] = np.linalg.solve(K[np.ix_(free, free)], f[free])
        return u
    u[free] = factor(K, free).solve(f[free])
    return u


def factor(A, keep: np.ndarray | None = None):
    """Factors of a symmetric positive definite sparse matrix (a stiffness, K - sigma M), or of
    its rows and columns `keep` (bool mask) when given, with a ``solve(b)``: qdldl's LDL^T
    (approximate minimum degree order, no pivoting, which a positive definite matrix never needs;
    2x faster to factor and 4x to solve than SuperLU here), or SuperLU (`sparse_lu`) when qdldl
    meets a zero pivot (a matrix that is not definite)."""
    import qdldl

    A = A.tocsc()
    try:
        return qdldl.Solver(upper_triangle(A, keep), upper=True)
    except RuntimeError:
        return sparse_lu(A if keep is None else A[keep][:, keep])


def upper_triangle(A, keep: np.ndarray | None = None):
    """The upper triangle, diagonal included, of the sparse A (of its rows and columns `keep`, a
    bool mask, when given) in canonical CSC: what qdldl factors (it takes the triangle itself
    from a whole matrix with `scipy.sparse.triu`). The same arrays as
    ``triu(A[keep][:, keep], format="csc")``, in one pass over A's entries instead of three."""
    from scipy.sparse import csc_matrix

    A = A.tocsc()
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
    n = A.shape[0]
    counts = np.diff(A.indptr)
    rows = A.indices
    cols = np.repeat(np.arange(n, dtype=rows.dtype), counts)
    take = rows <= cols
    if keep is not None:
        take &= np.repeat(keep, counts)
        take &= keep[rows]
        new = np.cumsum(keep, dtype=rows.dtype) - 1  # old DOF -> its index among those kept
        rows, cols, n = new[rows[take]], new[cols[take]], int(np.count_nonzero(keep))
    else:
        rows, cols = rows[take], cols[take]
    indptr = np.zeros(n + 1, dtype=A.indptr.dtype)
    np.cumsum(np.bincount(cols, minlength=n), out=indptr[1:])
    return csc_matrix((A.data[take], rows, indptr), shape=(n, n))


def negative_pivots(A) -> int:
    """How many negative pivots an LDL^T of the symmetric sparse A has: by Sylvester's law of
    inertia, how many eigenvalues of A are negative. -1 when no symmetric factorization exists
    (a zero pivot)."""
    import qdldl

    try:
        d = qdldl.Solver(upper_triangle(A), upper=True).factors()[1]
    except RuntimeError:
        return -1
    return int(np.count_nonzero(d < 0))


def sparse_lu(A):
    """SuperLU factors of a symmetric sparse matrix: a symmetric fill-reducing order (minimum
    degree on A^T + A) and pivots on the diagonal while they are not tiny
    (`scipy.sparse.linalg.splu`)."""
    from scipy.sparse.linalg import splu

    return splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1, options={"SymmetricMode": True})


def rigid_transfer(ref: np.ndarray, point: np.ndarray) -> np.ndarray:
    """6x6 T with [u_point; r_point] = T [u_ref; r_ref] for a rigid body (small rotations)."""
    d = np.asarray(point, float) - np.asarray(ref, float)
    t = np.eye(6)
    t[:3, 3:] = -_skew(d)
    return t


def _skew(v) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


# -- solvers: Euler buckling and the lowest modes -------------------------------------------------

def euler_load(length: float, ei: float, k_rot_a: float, k_rot_b: float, n_el: int = 8) -> float:
    """Critical axial load (N) of a rod pinned in translation at both ends with rotational springs
    k_rot_a, k_rot_b (N mm/rad) at its ends (beam FE with geometric stiffness, n_el elements).
    k_rot = 0: pi^2 EI / L^2; k_rot -> inf: 4 pi^2 EI / L^2."""
    return float(euler_loads([length], ei, [k_rot_a], [k_rot_b], n_el)[0])


def euler_loads(lengths, ei, k_rot_a, k_rot_b, n_el: int = 8) -> np.ndarray:
    """`euler_load` of many rods at once (arrays over the rods; ``ei`` may be one number).

    A round rod bends alike in both planes, so one plane is solved: DOFs (v, theta) per node,
    the ends' v held, the rotational springs on the end thetas; the textbook cubic element's K
    and geometric stiffness G for a unit compression (`beam_local_k_batch` / `beam_local_kg_batch`,
    their x-y bending terms). K x = P G x for all rods together: G = C C^T, then the ordinary
    symmetric eigenproblem of C^-1 K C^-T (numpy's batched eigvalsh); the smallest positive P."""
    L = np.atleast_1d(np.asarray(lengths, float))
    nr = L.size
    ei = np.broadcast_to(np.asarray(ei, float), (nr,))
    ka, kb = (np.broadcast_to(np.asarray(k, float), (nr,)) for k in (k_rot_a, k_rot_b))
    le = L / n_el
    # element matrices over (v1, t1, v2, t2): framefe's x-y bending terms (indices 1, 5, 7, 11)
    sel = [1, 5, 7, 11]
    ke = beam_local_k_batch(le, ei, 1.0, 1.0, 1.0, 1.0, 1.0)[:, sel][:, :, sel]  # E I_z = ei
    ge = -beam_local_kg_batch(le, -1.0)[:, sel][:, :, sel]
    nd = 2 * (n_el + 1)
    K = np.zeros((nr, nd, nd))
    Gm = np.zeros((nr, nd, nd))
    for e in range(n_el):
        s_ = slice(2 * e, 2 * e + 4)
        K[:, s_, s_] += ke
        Gm[:, s_, s_] += ge
    K[:, 1, 1] += ka
    K[:, nd - 1, nd - 1] += kb
    free = [i for i in range(nd) if i not in (0, nd - 2)]  # v held at both ends
    K, Gm = K[:, free][:, :, free], Gm[:, free][:, :, free]
    C = np.linalg.cholesky(Gm)
    Ci = np.linalg.inv(C)
    A = Ci @ K @ Ci.transpose(0, 2, 1)
    w = np.linalg.eigvalsh(0.5 * (A + A.transpose(0, 2, 1)))
    return np.array([min(x for x in row if x > 0) for row in w])


MODES_EXTRA = 8  # eigsh asks for this many modes beyond those wanted (a degenerate pair at the edge)


def lowest_eigenvalues(K, M, count: int) -> np.ndarray:
    """The `count` smallest eigenvalues of K x = lambda M x (K symmetric positive semi-definite,
    M positive definite; scipy sparse), ascending.

    Sparse shift-invert Lanczos (ARPACK `eigsh`, shift below zero so that K - sigma M is positive
    definite even with the rigid-body modes) for count + MODES_EXTRA eigenvalues, then checked
    by Sylvester's law of inertia: the LDL^T factors of K - s M (s in the first gap above the
    count-th eigenvalue) have exactly as many negative pivots as there are eigenvalues below s.
    A missed mode (Lanczos can skip one of a near-degenerate cluster) fails that count, and the
    dense generalized solver (`scipy.linalg.eigh`) answers instead. Small problems go dense."""
    n = K.shape[0]
    want = count + MODES_EXTRA
    if n <= max(200, 3 * want):
        return _dense_lowest(K, M, count)
    from scipy.sparse.linalg import ArpackNoConvergence, eigsh

    sigma = _shift(K, M)
    lu = factor(K - sigma * M)
    v0 = np.random.default_rng(0).standard_normal(n)  # deterministic, and no symmetry of the frame
    try:
        # tol: Ritz values to 1e-10 relative (the modes are reported to 0.01 Hz; 0 = machine
        # precision costs ~15 % more iterations for nothing the conditioning (~1e-8) keeps)
        w = eigsh(K, k=want, M=_vector_operator(M.__matmul__, n), sigma=sigma, OPinv=_vector_operator(lu.solve, n),
                  which="LM", v0=v0, tol=1e-10, return_eigenvectors=False)
    except ArpackNoConvergence:
        return _dense_lowest(K, M, count)
    w = np.sort(w)
    # the first gap above the count-th eigenvalue (a pair straddling the edge moves it up)
    tol = 1e-9 * max(abs(w[-1]), 1.0)
    j = next((i for i in range(count, want) if w[i] - w[i - 1] > tol), None)
    if j is None or _count_below(K, M, 0.5 * (w[j - 1] + w[j])) != j:
        return _dense_lowest(K, M, count)
    return w[:count]


def _vector_operator(apply, n: int):
    """A square LinearOperator of ``apply(x)`` for ARPACK's vectors (1-D, float) whose ``matvec``
    calls ``apply`` directly: LinearOperator's own shape handling round it costs as much as a
    solve with the factors here, and ARPACK calls the two operators ~250 times a solve."""
    from scipy.sparse.linalg import LinearOperator

    class VectorOperator(LinearOperator):
        def _matvec(self, x):
            return apply(np.ravel(x))

        matvec = _matvec

    return VectorOperator(np.dtype(float), (n, n))


def _shift(K, M) -> float:
    """The shift-invert shift: below the rigid-body modes (0), so that K - sigma M is positive
    definite, by 1e-7 of the median diagonal ratio K_ii / M_ii (a single element's frequency
    squared; the frame's first modes sit some 1e-7 below it). Much closer to 0 (sigma = -1
    (rad/s)^2) the factors are near-singular (condition ~1e15 with the rigid links) and modes go
    missing; much further, Lanczos needs more restarts."""
    return -1e-7 * float(np.median(K.diagonal() / M.diagonal()))


def _count_below(K, M, s: float) -> int:
    """How many eigenvalues of (K, M) lie below s: the negative pivots of an LDL^T of K - s M
    (Sylvester's law of inertia; M positive definite); -1 if it has no such factors."""
    return negative_pivots(K - s * M)


def _dense_lowest(K, M, count: int) -> np.ndarray:
    """Dense reference: the largest eigenvalues nu = 1 / (lambda - sigma) of M x = nu (K - sigma M) x,
    as those of the symmetric L^T (K - sigma M)^-1 L with M = L L^T.

    eigh(K, M) directly loses ~1e-4 of the low modes to the stiff rigid links: its absolute error
    is eps x the largest eigenvalue; shift-inverted, the wanted end is the large one. K - sigma M
    is not handed to a Cholesky factorization: K is semi-definite only to round-off (eps |K|, and
    a very short element makes |K| large), which a small shift need not cover and a Cholesky
    refuses; the symmetric indefinite solve (LDL^T) does not need it to be definite."""
    from scipy.linalg import cholesky, eigh, solve

    K = K.toarray() if hasattr(K, "toarray") else np.asarray(K)
    M = M.toarray() if hasattr(M, "toarray") else np.asarray(M)
    n = K.shape[0]
    sigma = _shift(K, M)
    L = cholesky(M, lower=True)
    Z = L.T @ solve(K - sigma * M, L, assume_a="sym")
    nu = eigh(0.5 * (Z + Z.T), eigvals_only=True, subset_by_index=[n - count, n - 1])
    return np.sort(1.0 / nu + sigma)
