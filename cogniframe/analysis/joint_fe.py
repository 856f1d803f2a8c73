"""Solid finite elements of a printed joint: gmsh tetrahedra, scikit-fem quadratic (P2) elasticity.

A joint is meshed from its solid (the very CAD `cogniframe build` prints, read through a BREP
file, or a gmsh OCC primitive in the benchmarks), assembled as 3D linear elasticity with
10-node tetrahedra, and condensed onto a few rigid *reference bodies*:

- every socket's rod, a rigid body tied to the bore wall and the socket bottom by an elastic
  interface layer (normal stiffness E / h_i and tangential G / h_i per unit area; h_i is the
  fit's radial clearance plus the printed surface roughness, see `joint_stiffness`);
- optionally the joint's support (the foot pad on the floor, the core link's bolted tab), tied
  stiffly.

Static condensation K_c = K_rr - K_ru K_uu^-1 K_ur gives a 6n x 6n stiffness over the n
reference bodies (each referenced at a point of our choice), with the 6 rigid-body modes of the
joint as its null space. The frame model (`stiffness`) takes it as a super-element.

gmsh and scikit-fem are imported inside the functions: `cogniframe check` never loads them when
the joint results are cached.
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Tie:
    """Facets of the mesh tied to a rigid reference body.

    ``select(centroids, normals) -> bool mask`` picks boundary facets (normals outward); ``ref``
    is the body's reference point; ``kn``/``kt`` the interface stiffness per unit area (N/mm^3)
    normal and tangential to the surface.
    """

    name: str
    select: object
    ref: tuple[float, float, float]
    kn: float
    kt: float


@dataclass(frozen=True)
class Condensed:
    names: tuple[str, ...]
    refs: np.ndarray  # (n, 3) reference points
    K: np.ndarray  # (6n, 6n)
    n_nodes: int
    n_elements: int
    n_dofs: int
    tied_area: tuple[float, ...]  # mm^2 per tie (a check that the selection found its surface)


# -- meshing --------------------------------------------------------------------------------

def _gmsh():
    import gmsh

    if not gmsh.isInitialized():
        # interruptible=False: gmsh would otherwise replace the SIGINT handler (Ctrl-C must stay the CLI's)
        gmsh.initialize(["-noenv"], readConfigFiles=False, interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.MaxNumThreads3D", 1)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    return gmsh


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


# -- elasticity and condensation ------------------------------------------------------------

def _rigid_modes(x: np.ndarray, ref) -> np.ndarray:
    """(6, 3, ...) displacement of unit rigid motions of a body referenced at ``ref``, at points x (3, ...)."""
    d = x - np.asarray(ref, float).reshape((3,) + (1,) * (x.ndim - 1))
    z = np.zeros_like(d[0])
    o = np.ones_like(d[0])
    return np.array([
        [o, z, z], [z, o, z], [z, z, o],
        [z, -d[2], d[1]], [d[2], z, -d[0]], [-d[1], d[0], z],
    ])


def condense(points: np.ndarray, tets: np.ndarray, e_mpa: float, nu: float, ties: list[Tie]) -> Condensed:
    """Quadratic-tetrahedron elasticity of the mesh, condensed onto the tied rigid bodies."""
    from skfem import Basis, ElementTetP2, ElementVector, FacetBasis, MeshTet
    from skfem.models.elasticity import lame_parameters

    mesh = MeshTet(points, tets)
    elem = ElementVector(ElementTetP2())
    basis = Basis(mesh, elem, intorder=2)
    coo = [_elasticity(basis, *lame_parameters(e_mpa, nu))]
    n_dofs = int(basis.N)

    bf = mesh.boundary_facets()
    cen = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    a = mesh.p[:, mesh.facets[1, bf]] - mesh.p[:, mesh.facets[0, bf]]
    b = mesh.p[:, mesh.facets[2, bf]] - mesh.p[:, mesh.facets[0, bf]]
    nrm = np.cross(a.T, b.T).T
    nrm /= np.linalg.norm(nrm, axis=0)
    # outward: skfem stores a facet's vertices sorted by number, so the cross product's sign is
    # arbitrary (a selection by "facing down" took a mesh-dependent half of the core link's tab
    # underside, and a mirror image of a joint got another half); flip away from the vertex of
    # the facet's tetrahedron that is not on it
    opp = mesh.p[:, mesh.t[:, mesh.f2t[0, bf]]].sum(axis=1) - mesh.p[:, mesh.facets[:, bf]].sum(axis=1)
    nrm *= np.where(np.einsum("ij,ij->j", cen - opp, nrm) < 0, -1.0, 1.0)

    nr = 6 * len(ties)
    Kur = np.zeros((n_dofs, nr))
    Krr = np.zeros((nr, nr))
    areas = []
    for ti, tie in enumerate(ties):
        facets = bf[np.asarray(tie.select(cen, nrm), dtype=bool)]
        if facets.size == 0:
            raise RuntimeError(f"joint FE: no surface found for the tie {tie.name!r}")
        fb = FacetBasis(mesh, elem, facets=facets, intorder=4)
        kn, kt = tie.kn, tie.kt
        coo.append(_interface(fb, kn, kt))
        # Coupling with the body's six rigid motions, by quadrature on the same facets.
        x = np.asarray(fb.global_coordinates())  # (3, nf, nq)
        n = np.asarray(fb.normals)  # (3, nf, nq)
        dx = fb.dx  # (nf, nq)
        r = _rigid_modes(x, tie.ref)  # (6, 3, nf, nq)
        rn = np.einsum("jinq,inq->jnq", r, n)
        kr = kt * r + (kn - kt) * rn[:, None] * n[None]  # traction of each unit motion, (6, 3, nf, nq)
        Krr[6 * ti:6 * ti + 6, 6 * ti:6 * ti + 6] = np.einsum("aink,bink,nk->ab", r, kr, dx)
        areas.append(float(dx.sum()))
        # K_ur[:, j] = -int N^T kr_j dA: project each traction field on the basis.
        phi = fb.basis  # list over local dofs of DiscreteField tuples
        dofs = fb.element_dofs  # (n_local, nf)
        for ld in range(dofs.shape[0]):
            val = np.asarray(phi[ld][0])  # (3, nf, nq)
            contrib = np.einsum("ink,aink,nk->an", val, kr, dx)  # (6, nf)
            np.add.at(Kur, (dofs[ld][:, None], np.arange(6 * ti, 6 * ti + 6)[None, :]), -contrib.T)
    import scipy.sparse as sp

    Kuu = sp.csc_matrix((np.concatenate([c[2] for c in coo]),
                         (np.concatenate([c[0] for c in coo]), np.concatenate([c[1] for c in coo]))),
                        shape=(n_dofs, n_dofs))
    X = _solve_many(Kuu, Kur, _dof_points(basis))
    Kc = Krr - Kur.T @ X
    Kc = 0.5 * (Kc + Kc.T)
    return Condensed(tuple(t.name for t in ties), np.array([t.ref for t in ties], float), Kc,
                     mesh.p.shape[1], mesh.t.shape[1], n_dofs, tuple(areas))



def _dof_points(basis) -> np.ndarray:
    """The point (vertex or edge node of the P2 mesh) of every DOF of a vector basis."""
    groups = np.empty(basis.N, dtype=np.int64)
    k = 0
    for d in (basis.nodal_dofs, basis.edge_dofs):
        d = np.asarray(d)
        if d.size:
            groups[d] = k + np.arange(d.shape[1])[None, :]
            k += d.shape[1]
    return groups


def _scatter(basis, ke: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """COO triplets (rows, cols, values) of element matrices ke (n_local, n_local, n_elements)."""
    dofs = basis.element_dofs  # (n_local, n_elements)
    rows = np.broadcast_to(dofs[:, None, :], ke.shape).ravel()
    cols = np.broadcast_to(dofs[None, :, :], ke.shape).ravel()
    return rows, cols, ke.ravel()


def _elasticity(basis, lam: float, mu: float):
    """Linear elasticity stiffness, the form of skfem's `linear_elasticity`
    (sigma(u) : eps(v), sigma = 2 mu eps + lam tr(eps) I) evaluated for all pairs of local basis
    functions at once. skfem's BilinearForm calls its kernel once per pair (900 per P2 vector
    tetrahedron, ~1 s per joint); one einsum does the same sums in ~0.1 s."""
    g = np.stack([np.asarray(phi[0].grad) for phi in basis.basis])  # (n_local, 3, 3, ne, nq)
    s2 = math.sqrt(2.0)
    # per quadrature point, rows whose squares sum to the energy density:
    # 2 mu (e11^2 + e22^2 + e33^2 + 2 e12^2 + 2 e13^2 + 2 e23^2) + lam (e11 + e22 + e33)^2
    rows = [g[:, 0, 0], g[:, 1, 1], g[:, 2, 2], (g[:, 0, 1] + g[:, 1, 0]) / s2, (g[:, 0, 2] + g[:, 2, 0]) / s2,
            (g[:, 1, 2] + g[:, 2, 1]) / s2]
    w = np.sqrt(basis.dx)  # (ne, nq)
    a = np.concatenate([math.sqrt(2 * mu) * r * w for r in rows]
                       + [math.sqrt(lam) * (rows[0] + rows[1] + rows[2]) * w], axis=-1)  # (n_local, ne, 7 nq)
    a = a.transpose(1, 2, 0)  # (ne, 7 nq, n_local)
    ke = np.matmul(a.transpose(0, 2, 1), a).transpose(1, 2, 0)  # (n_local, n_local, ne)
    return _scatter(basis, ke)


def _interface(fb, kn: float, kt: float):
    """Elastic interface on the facets of `fb`: traction kn u_n n + kt u_t per unit area, i.e. the
    form kn (u.n)(v.n) + kt (u.v - (u.n)(v.n)), vectorized over all pairs of local functions."""
    v = np.stack([np.asarray(phi[0]) for phi in fb.basis])  # (n_local, 3, nf, nq)
    n = np.asarray(fb.normals)  # (3, nf, nq)
    vn = np.einsum("iafq,afq->ifq", v, n)
    dx = fb.dx
    ke = kt * np.einsum("iafq,jafq,fq->ijf", v, v, dx, optimize=True)
    ke += (kn - kt) * np.einsum("ifq,jfq,fq->ijf", vn, vn, dx, optimize=True)
    return _scatter(fb, ke)


def _solve_many(A, B, groups: np.ndarray | None = None) -> np.ndarray:
    """Solve A X = B for the condensation's right-hand sides with one sparse LU (SuperLU).

    The fill of a 3D solid's factor depends on the elimination order: METIS nested dissection
    (pymetis) of the mesh's point graph gives ~35 % less fill than SuperLU's minimum degree and
    halves the factorization (1.4 s -> 0.7 s CPU on the knee's 28 000 DOF); the three DOFs of a
    point stay together. ``groups`` maps every DOF to its point (None: order the DOF graph).
    A is symmetric positive definite, so the diagonal pivots are kept (no pivoting).
    (Multigrid-preconditioned CG was tried: the stiff interface ties and nu = 0.48 make it
    converge 50x slower than the direct solve.)"""
    from scipy.sparse.linalg import splu

    perm = _nd_order(A, groups)
    P = A[perm][:, perm].tocsc()
    lu = splu(P, permc_spec="NATURAL", options={"SymmetricMode": True, "DiagPivotThresh": 0.0})
    X = np.empty_like(B)
    X[perm] = lu.solve(np.ascontiguousarray(B[perm]))
    return X


def _nd_order(A, groups: np.ndarray | None) -> np.ndarray:
    """Nested-dissection order of A's DOFs (METIS through pymetis, fixed seed: same order every run)."""
    import pymetis
    import scipy.sparse as sp

    n = A.shape[0]
    if groups is None:
        groups = np.arange(n)
    ng = int(groups.max()) + 1
    S = sp.csr_matrix((np.ones(n), (np.arange(n), groups)), shape=(n, ng))
    G = (S.T @ (abs(A) @ S)).tocsr()
    G.setdiag(0)
    G.eliminate_zeros()
    _, iperm = pymetis.nested_dissection(pymetis.CSRAdjacency(G.indptr, G.indices),
                                         options=pymetis.Options(seed=1))
    # iperm[g] = position of point g; DOFs sorted by their point's position, then by DOF number
    return np.lexsort((np.arange(n), np.asarray(iperm)[groups]))