"""A small 3D frame finite-element assembler (numpy only): stiffness, mass and geometric stiffness.

Why not PyNite for the frame: the joints are now general 6x6 (or 6n x 6n) condensed stiffness
matrices from the joint models (`joint_stiffness`), which PyNite cannot take (its springs are
axial only), and the modal and buckling load cases need the assembled K, M and K_G, which PyNite
does not expose. The element here is the textbook 3D Euler-Bernoulli beam (12 DOF: u, v, w,
rx, ry, rz at each end), with the consistent mass matrix and the geometric stiffness of an axial
force (Przemieniecki, "Theory of Matrix Structural Analysis", ch. 5 and 11). `tests/test_framefe.py`
checks it against closed forms and against PyNite on the same frame.

Units: N, mm, t (tonne = 1000 kg) so that stiffness in N/mm and mass in t give eigenvalues in
(rad/s)^2. Densities in t/mm^3 (g/cm^3 * 1e-9). Dense matrices: a frame has a few hundred DOF.
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


def _frame_axes(p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """3x3 rotation whose rows are the member's local x (along it), y and z axes."""
    x = p1 - p0
    length = float(np.linalg.norm(x))
    x = x / length
    ref = np.array([0.0, 0.0, 1.0]) if abs(x[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    y = np.cross(ref, x)
    y /= np.linalg.norm(y)
    z = np.cross(x, y)
    return np.vstack([x, y, z])


def beam_local_k(length: float, e: float, g: float, a: float, iy: float, iz: float, j: float) -> np.ndarray:
    """12x12 local stiffness of a 3D Euler-Bernoulli beam (DOF order u1 v1 w1 rx1 ry1 rz1, u2 ...)."""
    L = length
    k = np.zeros((12, 12))
    ea, gj = e * a / L, g * j / L
    k[0, 0] = k[6, 6] = ea
    k[0, 6] = k[6, 0] = -ea
    k[3, 3] = k[9, 9] = gj
    k[3, 9] = k[9, 3] = -gj
    # bending in the x-y plane (v, rz) with Iz
    c = e * iz
    for (i, jj, val) in ((1, 1, 12), (1, 5, 6 * L), (1, 7, -12), (1, 11, 6 * L), (5, 5, 4 * L * L), (5, 7, -6 * L),
                         (5, 11, 2 * L * L), (7, 7, 12), (7, 11, -6 * L), (11, 11, 4 * L * L)):
        k[i, jj] = k[jj, i] = c * val / L**3
    # bending in the x-z plane (w, ry) with Iy (signs flip on the rotation coupling)
    c = e * iy
    for (i, jj, val) in ((2, 2, 12), (2, 4, -6 * L), (2, 8, -12), (2, 10, -6 * L), (4, 4, 4 * L * L), (4, 8, 6 * L),
                         (4, 10, 2 * L * L), (8, 8, 12), (8, 10, 6 * L), (10, 10, 4 * L * L)):
        k[i, jj] = k[jj, i] = c * val / L**3
    return k


def beam_local_m(length: float, rho_a: float, polar_r2: float) -> np.ndarray:
    """12x12 consistent mass (rho_a = mass per length, polar_r2 = J/A for the torsional inertia)."""
    L = length
    m = np.zeros((12, 12))
    c = rho_a * L
    m[0, 0] = m[6, 6] = c / 3
    m[0, 6] = m[6, 0] = c / 6
    m[3, 3] = m[9, 9] = c * polar_r2 / 3
    m[3, 9] = m[9, 3] = c * polar_r2 / 6
    c = rho_a * L / 420
    for (i, jj, val) in ((1, 1, 156), (1, 5, 22 * L), (1, 7, 54), (1, 11, -13 * L), (5, 5, 4 * L * L), (5, 7, 13 * L),
                         (5, 11, -3 * L * L), (7, 7, 156), (7, 11, -22 * L), (11, 11, 4 * L * L)):
        m[i, jj] = m[jj, i] = c * val
    for (i, jj, val) in ((2, 2, 156), (2, 4, -22 * L), (2, 8, 54), (2, 10, 13 * L), (4, 4, 4 * L * L), (4, 8, -13 * L),
                         (4, 10, -3 * L * L), (8, 8, 156), (8, 10, 22 * L), (10, 10, 4 * L * L)):
        m[i, jj] = m[jj, i] = c * val
    return m


def beam_local_kg(length: float, axial_n: float) -> np.ndarray:
    """12x12 geometric stiffness for an axial force (tension positive), bending terms only."""
    L = length
    kg = np.zeros((12, 12))
    c = axial_n / (30 * L)
    for (i, jj, val) in ((1, 1, 36), (1, 5, 3 * L), (1, 7, -36), (1, 11, 3 * L), (5, 5, 4 * L * L), (5, 7, -3 * L),
                         (5, 11, -L * L), (7, 7, 36), (7, 11, -3 * L), (11, 11, 4 * L * L)):
        kg[i, jj] = kg[jj, i] = c * val
    for (i, jj, val) in ((2, 2, 36), (2, 4, -3 * L), (2, 8, -36), (2, 10, -3 * L), (4, 4, 4 * L * L), (4, 8, 3 * L),
                         (4, 10, -L * L), (8, 8, 36), (8, 10, 3 * L), (10, 10, 4 * L * L)):
        kg[i, jj] = kg[jj, i] = c * val
    return kg


def _t12(rot: np.ndarray) -> np.ndarray:
    t = np.zeros((12, 12))
    for b in range(4):
        t[3 * b:3 * b + 3, 3 * b:3 * b + 3] = rot
    return t


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

    def add_mass(self, node: str, mass_t: float, inertia_t_mm2=(0.0, 0.0, 0.0)) -> None:
        m = self.masses.setdefault(node, np.zeros((6, 6)))
        m[0, 0] += mass_t
        m[1, 1] += mass_t
        m[2, 2] += mass_t
        for a in range(3):
            m[3 + a, 3 + a] += inertia_t_mm2[a]

    def index(self) -> dict[str, int]:
        return {n: i for i, n in enumerate(self.nodes)}

    def _beam_geom(self, b: Beam):
        p0, p1 = self.nodes[b.n0], self.nodes[b.n1]
        L = float(np.linalg.norm(p1 - p0))
        return L, _t12(_frame_axes(p0, p1))

    def stiffness(self) -> np.ndarray:
        idx = self.index()
        n = 6 * len(idx)
        K = np.zeros((n, n))
        for b in self.beams:
            L, T = self._beam_geom(b)
            kg = T.T @ beam_local_k(L, b.e, b.g, b.a, b.i, b.i, b.j) @ T
            dofs = _dofs(idx, (b.n0, b.n1))
            K[np.ix_(dofs, dofs)] += kg
        for nodes, k in self.springs:
            dofs = _dofs(idx, nodes)
            K[np.ix_(dofs, dofs)] += k
        return K

    def mass(self) -> np.ndarray:
        idx = self.index()
        n = 6 * len(idx)
        M = np.zeros((n, n))
        for b in self.beams:
            if b.rho <= 0:
                continue
            L, T = self._beam_geom(b)
            mg = T.T @ beam_local_m(L, b.rho * b.a, b.j / b.a) @ T
            dofs = _dofs(idx, (b.n0, b.n1))
            M[np.ix_(dofs, dofs)] += mg
        for node, m in self.masses.items():
            i = 6 * idx[node]
            M[i:i + 6, i:i + 6] += m
        return M

    def axial_forces(self, u: np.ndarray) -> dict[str, float]:
        """Axial force (N, tension positive) in every beam for a displacement vector u."""
        idx = self.index()
        out = {}
        for b in self.beams:
            L, T = self._beam_geom(b)
            dofs = _dofs(idx, (b.n0, b.n1))
            ul = T @ u[dofs]
            out[b.name] = b.e * b.a / L * (ul[6] - ul[0])
        return out

    def geometric_stiffness(self, forces: dict[str, float]) -> np.ndarray:
        idx = self.index()
        n = 6 * len(idx)
        KG = np.zeros((n, n))
        for b in self.beams:
            p = forces.get(b.name, 0.0)
            if p == 0.0:
                continue
            L, T = self._beam_geom(b)
            dofs = _dofs(idx, (b.n0, b.n1))
            KG[np.ix_(dofs, dofs)] += T.T @ beam_local_kg(L, p) @ T
        return KG


def _dofs(idx: dict[str, int], nodes) -> np.ndarray:
    return np.concatenate([np.arange(6 * idx[n], 6 * idx[n] + 6) for n in nodes])


def solve(K: np.ndarray, f: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """Solve K u = f with the DOFs in `fixed` (bool mask) held at zero (dense Cholesky/LU)."""
    free = ~fixed
    u = np.zeros(K.shape[0])
    Kff = K[np.ix_(free, free)]
    u[free] = np.linalg.solve(Kff, f[free])
    return u


def rigid_transfer(ref: np.ndarray, point: np.ndarray) -> np.ndarray:
    """6x6 T with [u_point; r_point] = T [u_ref; r_ref] for a rigid body (small rotations)."""
    d = np.asarray(point, float) - np.asarray(ref, float)
    t = np.eye(6)
    t[:3, 3:] = -_skew(d)
    return t


def _skew(v) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
