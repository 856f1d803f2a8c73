"""Solid finite elements of a printed joint: scikit-fem quadratic (P2) elasticity, condensed.

A joint's tetrahedral mesh (`meshing`: the very CAD `cogniframe build` prints, or a gmsh OCC
primitive in the tests and benchmarks) is assembled as 3D linear elasticity with 10-node
tetrahedra and condensed onto a few rigid *reference bodies*:

- every socket's rod, a rigid body tied to the bore wall and the socket bottom by an elastic
  interface layer (normal stiffness E / h_i and tangential G / h_i per unit area; h_i is the
  fit's radial clearance plus the printed surface roughness, see `model.interface`);
- optionally the joint's support (the foot pad on the floor, the core link's bolted tab), tied
  stiffly.

Static condensation K_c = K_rr - K_ru K_uu^-1 K_ur gives a 6n x 6n stiffness over the n
reference bodies (each referenced at a point of our choice), with the 6 rigid-body modes of the
joint as its null space. The frame model (`stiffness`) takes it as a super-element.

scikit-fem, METIS and CHOLMOD are imported inside the functions: `cogniframe check` never loads
them when the joint results are cached.
"""

from __future__ import annotations

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
    """Quadratic-tetrahedron elasticity of the mesh, condensed onto the tied rigid bodies.

    The DOFs are skfem's for ``ElementVector(ElementTetP2())``: DOF 3 p + c is component c at
    point p (the mesh's vertices, then its edges' midpoints). Everything is assembled as 3 x 3
    blocks of point pairs from the *scalar* P2 basis (a vector basis function is a scalar one
    times a unit vector: 9x fewer basis evaluations, 9x fewer triplets to sort), and the sparse
    matrix's lower triangle is written once, directly in the nested-dissection order the
    factorization uses (`_lower_triplets`). `tests/test_joint_fe_assembly.py` checks it against skfem's own
    BilinearForm / LinearForm assembly (benchmarks/bench_joint_fe.py times it)."""
    return condense_system(assemble(points, tets, e_mpa, nu, ties), ties)


def condense_system(sysm: System, ties: list[Tie]) -> Condensed:
    """`condense` of a system already assembled with these ties."""
    iperm = _nd_order_points(sysm.rows, sysm.cols, sysm.blocks, sysm.n_points)
    lower = _lower_triplets(sysm.rows, sysm.cols, sysm.blocks, iperm)
    perm = (3 * np.argsort(iperm)[:, None] + np.arange(3)[None, :]).ravel()  # new DOF -> old DOF
    Bp = np.ascontiguousarray(sysm.Kur[perm])
    Kc = sysm.Krr - _inverse_form(lower, Bp)
    Kc = 0.5 * (Kc + Kc.T)
    return Condensed(tuple(t.name for t in ties), np.array([t.ref for t in ties], float), Kc,
                     sysm.n_nodes, sysm.n_elements, 3 * sysm.n_points, sysm.tied_area)


@dataclass(frozen=True)
class System:
    """The assembled joint before condensation: K_uu as summed 3 x 3 blocks of point pairs
    (point p holds DOFs 3 p .. 3 p + 2) of its upper triangle (row <= column), sorted by row
    then column; K_ur and K_rr dense."""

    rows: np.ndarray  # (nb,) row point of each block
    cols: np.ndarray  # (nb,) column point, >= row
    blocks: np.ndarray  # (nb, 3, 3)
    n_points: int
    Kur: np.ndarray  # (3 n_points, 6 n_ties)
    Krr: np.ndarray  # (6 n_ties, 6 n_ties)
    n_nodes: int
    n_elements: int
    tied_area: tuple[float, ...]

    def Kuu(self):
        """K_uu as a scipy CSC matrix in skfem's DOF numbering."""
        return _csc_blocks(*_mirror(self.rows, self.cols, self.blocks), np.arange(self.n_points), self.n_points)


def boundary_facets(mesh):
    """The skfem mesh's boundary facets: (indices, centroids (3, n), outward unit normals (3, n),
    areas (n,))."""
    bf = mesh.boundary_facets()
    fv = mesh.p[:, mesh.facets[:, bf]]  # (3, 3 vertices, nbf)
    cen = fv.mean(axis=1)
    nrm = np.cross((fv[:, 1] - fv[:, 0]).T, (fv[:, 2] - fv[:, 0]).T).T
    norm = np.linalg.norm(nrm, axis=0)
    nrm /= norm
    # outward: skfem stores a facet's vertices sorted by number, so the cross product's sign is
    # arbitrary (a selection by "facing down" took a mesh-dependent half of the core link's tab
    # underside, and a mirror image of a joint got another half); flip away from the vertex of
    # the facet's tetrahedron that is not on it
    opp = mesh.p[:, mesh.t[:, mesh.f2t[0, bf]]].sum(axis=1) - fv.sum(axis=1)
    nrm *= np.where(np.einsum("ij,ij->j", cen - opp, nrm) < 0, -1.0, 1.0)
    return bf, cen, nrm, 0.5 * norm


def assemble(points: np.ndarray, tets: np.ndarray, e_mpa: float, nu: float, ties: list[Tie]) -> System:
    """K_uu, K_ur, K_rr of the mesh and its ties (see `condense`)."""
    from skfem import ElementTetP2, FacetBasis, MeshTet
    from skfem.models.elasticity import lame_parameters

    mesh = MeshTet(points, tets)
    elem = ElementTetP2()
    npts = mesh.p.shape[1] + mesh.edges.shape[1]  # points (vertices, edge midpoints): 3 DOFs each
    n_dofs = 3 * npts
    blocks = [_elasticity_blocks(mesh, elem, *lame_parameters(e_mpa, nu))]

    bf, cen, nrm, _ = boundary_facets(mesh)

    nr = 6 * len(ties)
    Krr = np.zeros((nr, nr))
    ur_idx, ur_val = [], []  # K_ur as flat (row * nr + column, value) pairs
    areas = []
    for ti, tie in enumerate(ties):
        facets = bf[np.asarray(tie.select(cen, nrm), dtype=bool)]
        if facets.size == 0:
            raise RuntimeError(f"joint FE: no surface found for the tie {tie.name!r}")
        fb = FacetBasis(mesh, elem, facets=facets, intorder=4)
        kn, kt = tie.kn, tie.kt
        phi = np.stack([np.asarray(f[0]) for f in fb.basis])  # (10, nf, nq) scalar P2 values
        n = np.asarray(fb.normals)  # (3, nf, nq), constant on a (flat) facet
        dx = fb.dx  # (nf, nq)
        pts = fb.element_dofs  # (10, nf) point of each local function
        blocks.append(_interface_blocks(pts, phi, n, dx, kn, kt))
        # Coupling with the body's six rigid motions, by quadrature on the same facets.
        x = np.asarray(fb.global_coordinates())  # (3, nf, nq)
        r = _rigid_modes(x, tie.ref)  # (6, 3, nf, nq)
        rn = np.einsum("jinq,inq->jnq", r, n)
        kr = kt * r + (kn - kt) * rn[:, None] * n[None]  # traction of each unit motion, (6, 3, nf, nq)
        Krr[6 * ti:6 * ti + 6, 6 * ti:6 * ti + 6] = np.einsum("aink,bink,nk->ab", r, kr, dx)
        areas.append(float(dx.sum()))
        # K_ur[3 p + c, 6 ti + a] = -int phi_p kr_a[c] dA: each traction field on the basis
        contrib = np.einsum("knq,acnq,nq->kcan", phi, kr, dx)  # (10, 3, 6, nf)
        rows = 3 * pts[:, None, None, :] + np.arange(3)[None, :, None, None]
        cols = 6 * ti + np.arange(6)[None, None, :, None]
        ur_idx.append((rows * nr + cols).ravel())
        ur_val.append(-contrib.ravel())
    Kur = np.bincount(np.concatenate(ur_idx), np.concatenate(ur_val), minlength=n_dofs * nr).reshape(n_dofs, nr)

    bi, bj, bv = _sum_blocks(blocks, npts)
    return System(bi, bj, bv, npts, Kur, Krr, mesh.p.shape[1], mesh.t.shape[1], tuple(areas))


_KU, _LU = np.triu_indices(10)  # the 55 pairs k <= l of a P2 tetrahedron's 10 functions
_T9 = np.arange(9).reshape(3, 3).T.ravel()  # entry (c, d) of a 3 x 3 block -> entry (d, c)


def _upper(rows: np.ndarray, cols: np.ndarray, vals: np.ndarray):
    """Blocks of function pairs k <= l as blocks of the upper triangle of K_uu (row point <=
    column point): a pair whose points run the other way is stored as its transpose."""
    rows, cols = rows.ravel(), cols.ravel()
    vals = vals.reshape(9, -1)
    swap = rows > cols
    return np.where(swap, cols, rows), np.where(swap, rows, cols), np.where(swap, vals[_T9], vals)


def _elasticity_blocks(mesh, elem, lam: float, mu: float):
    """Linear elasticity (skfem's `linear_elasticity`: sigma(u) : eps(v), sigma = 2 mu eps +
    lam tr(eps) I) as 3 x 3 blocks of scalar P2 function pairs. With G_kl[i, j] = int d_i phi_k
    d_j phi_l, the block of (phi_k e_c, phi_l e_d) is mu tr(G_kl) delta_cd + mu G_kl[d, c] +
    lam G_kl[c, d]. On an affine tetrahedron grad phi = A^-T grad_ref phi, so G_kl =
    |det A| A^-T Gref_kl A^-1 with Gref_kl = sum_q w_q grad_ref phi_k grad_ref phi_l^T the
    reference element's (skfem's basis and order-2 quadrature, as `Basis(intorder=2)`): the G of
    every pair of every element is one (55 x 9) @ (9 x 9 ne) product. K_uu is symmetric: only
    the pairs k <= l, as upper-triangle blocks (`_upper`), values component-major (9, n)."""
    from skfem.quadrature import get_quadrature

    X, W = get_quadrature(elem.refdom, 2)
    nl = len(elem.doflocs)  # 10: vertices, edges
    gref = np.stack([np.asarray(elem.lbasis(X, k)[1]) for k in range(nl)])  # (10, 3, nq)
    Gref = np.einsum("kaq,lbq,q->klab", gref, gref, W)[_KU, _LU].reshape(-1, 9)  # (pairs, (a, b))
    mp = mesh._mapping()
    inv, det = mp.invA, np.abs(mp.detA)  # (3, 3, ne), (ne,)
    ne = det.size
    T = np.einsum("aie,bje,e->abeij", inv, inv, det).reshape(9, ne * 9)  # ((a, b), (e, i, j))
    G = (Gref @ T).reshape(-1, ne, 3, 3)  # (pair, e, i, j)
    mtr = mu * (G[..., 0, 0] + G[..., 1, 1] + G[..., 2, 2])
    ke = np.empty((3, 3) + G.shape[:2])
    for c in range(3):
        for d in range(3):
            np.multiply(lam, G[..., c, d], out=ke[c, d])
            ke[c, d] += mu * G[..., d, c]
            if c == d:
                ke[c, d] += mtr
    pts = _element_points(mesh, elem)  # (10, ne)
    return _upper(pts[_KU], pts[_LU], ke)


def _element_points(mesh, elem) -> np.ndarray:
    from skfem.assembly import Dofs

    return Dofs(mesh, elem).element_dofs


def _interface_blocks(pts: np.ndarray, phi: np.ndarray, n: np.ndarray, dx: np.ndarray, kn: float, kt: float):
    """Elastic interface on facets: traction kn u_n n + kt u_t per unit area, i.e. the form
    kn (u.n)(v.n) + kt (u.v - (u.n)(v.n)); the block of (phi_k e_c, phi_l e_d) is
    int phi_k phi_l (kt delta_cd + (kn - kt) n_c n_d) dA. Layout as `_elasticity_blocks`."""
    m = np.einsum("kfq,lfq,fq->fkl", phi, phi, dx)[:, _KU, _LU]  # (nf, pair)
    nn = n[:, None, :, 0] * n[None, :, :, 0]  # (3, 3, nf): n n^T of each facet
    t = kt * np.eye(3)[:, :, None] + (kn - kt) * nn
    ke = t.reshape(9, -1, 1) * m[None]  # (9, nf, pair)
    return _upper(pts[_KU].T, pts[_LU].T, ke)


def _mirror(rows: np.ndarray, cols: np.ndarray, blocks: np.ndarray):
    """Upper-triangle blocks -> all blocks (each off-diagonal one also transposed below)."""
    low = rows != cols
    return (np.concatenate([rows, cols[low]]), np.concatenate([cols, rows[low]]),
            np.concatenate([blocks, blocks[low].transpose(0, 2, 1)]))


def _sum_blocks(blocks, npts: int):
    """Sum the 3 x 3 blocks of equal (row point, column point): (rows, cols, values (nb, 3, 3)),
    sorted by row then column. Each entry of the blocks is one `np.bincount` over the blocks'
    ranks (a sequential sum: the same bits every run)."""
    keys = [b[0].astype(np.int64) * npts + b[1] for b in blocks]
    key = np.concatenate(keys)
    order = np.argsort(key)  # ties in any order: the ranks below do not depend on it
    sk = key[order]
    new = np.empty(sk.size, dtype=bool)
    new[0] = True
    np.not_equal(sk[1:], sk[:-1], out=new[1:])
    rank = np.empty(key.size, dtype=np.int64)
    rank[order] = np.cumsum(new) - 1
    nb = int(rank.max()) + 1 if rank.size else 0
    bv = np.zeros((9, nb))
    start = 0
    for b, k in zip(blocks, keys):
        r = rank[start:start + k.size]
        start += k.size
        vals = b[2]
        for c in range(9):
            bv[c] += np.bincount(r, vals[c], minlength=nb)
    uk = sk[new]
    return uk // npts, uk % npts, np.ascontiguousarray(bv.T).reshape(nb, 3, 3)


def _csc_blocks(bi: np.ndarray, bj: np.ndarray, bv: np.ndarray, iperm: np.ndarray, npts: int):
    """The scalar CSC matrix of the blocks (point bi, point bj) -> values (3 x 3), in the point
    order ``iperm`` (point p moves to iperm[p], its DOF 3 p + c to 3 iperm[p] + c); built
    directly with sorted indices, without COO -> CSC conversion, duplicate sums or re-sorting."""
    import scipy.sparse as sp

    I, J = iperm[bi], iperm[bj]
    order = np.argsort(J * npts + I)
    I, J, bv = I[order], J[order], bv[order]
    bptr = np.zeros(npts + 1, dtype=np.int64)
    np.cumsum(np.bincount(J, minlength=npts), out=bptr[1:])
    nnz = 9 * J.size
    if nnz >= 2**31:
        raise RuntimeError(f"joint FE: {nnz} nonzeros exceed the sparse matrix's 32-bit indices")
    m = (bptr[J + 1] - bptr[J]).astype(np.int32)  # blocks in each block's column
    k = np.arange(J.size, dtype=np.int32) - bptr[J].astype(np.int32)  # rank of the block in its column
    r = np.arange(3, dtype=np.int32)
    # entry (r, c) of block b goes to 9 bptr[J] + 3 c m + 3 k + r (column 3 J + c holds, block by
    # block, the three rows of each)
    pos = ((9 * bptr[J].astype(np.int32) + 3 * k)[:, None, None] + r[:, None] + (3 * m)[:, None, None] * r).ravel()
    data = np.empty(nnz)
    data[pos] = bv.ravel()
    indices = np.empty(nnz, dtype=np.int32)
    indices[pos] = np.broadcast_to((3 * I.astype(np.int32))[:, None, None] + r[:, None], (J.size, 3, 3)).ravel()
    cm = np.diff(bptr)
    indptr = np.empty(3 * npts + 1, dtype=np.int32)
    indptr[:-1] = (9 * bptr[:-1, None] + 3 * cm[:, None] * r[None, :]).ravel()
    indptr[-1] = nnz
    P = sp.csc_matrix((data, indices, indptr), shape=(3 * npts, 3 * npts))
    P.has_sorted_indices = True
    P.has_canonical_format = True
    return P


def _lower_triplets(bi: np.ndarray, bj: np.ndarray, bv: np.ndarray, iperm: np.ndarray):
    """The lower triangle of K_uu in the point order ``iperm`` (point p moves to iperm[p]) as
    (values, rows, columns, size), from its upper-triangle blocks (`System`): each block, or its
    transpose, placed where its row point follows its column point; of a diagonal block, the
    entries on and below the diagonal. What CHOLMOD reads (`_inverse_form`), without the full
    symmetric matrix (`_csc_blocks` of `_mirror`), its COO copy and the filter."""
    I, J = iperm[bi], iperm[bj]
    swap = I < J
    R, C = np.where(swap, J, I), np.where(swap, I, J)  # block row >= block column
    V = np.where(swap[:, None, None], bv.transpose(0, 2, 1), bv)
    r = np.broadcast_to(3 * R[:, None, None] + np.arange(3)[None, :, None], V.shape)
    c = np.broadcast_to(3 * C[:, None, None] + np.arange(3)[None, None, :], V.shape)
    keep = r >= c
    n = 3 * (int(iperm.max()) + 1) if iperm.size else 0
    return V[keep], r[keep], c[keep], n


def _nd_order_points(bi: np.ndarray, bj: np.ndarray, bv: np.ndarray, npts: int) -> np.ndarray:
    """Nested-dissection order of the points (METIS through pymetis, fixed seed: same order every
    run) on the graph of point pairs with a nonzero block, given by the upper-triangle blocks
    (bi < bj); iperm[p] = new position of point p. The three DOFs of a point stay together
    (METIS on the DOF graph gives no less fill and takes longer)."""
    import pymetis

    keep = (bi != bj) & np.any(bv != 0, axis=(1, 2))
    rows, cols = np.concatenate([bi[keep], bj[keep]]), np.concatenate([bj[keep], bi[keep]])
    order = np.argsort(rows * npts + cols)  # adjacency lists in ascending order
    rows, cols = rows[order], cols[order]
    xadj = np.zeros(npts + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=npts), out=xadj[1:])
    _, iperm = pymetis.nested_dissection(pymetis.CSRAdjacency(xadj, cols), options=pymetis.Options(seed=1))
    return np.asarray(iperm, dtype=np.int64)


def _inverse_form(lower, B: np.ndarray) -> np.ndarray:
    """B^T P^-1 B from one sparse Cholesky factorisation (CHOLMOD, supernodal, through cvxopt) of
    P, given by its lower triangle (values, rows, columns, size: `_lower_triplets`) and already in
    its fill-reducing order: with P = Q^T L L^T Q (Q: CHOLMOD's own postorder),
    B^T P^-1 B = Y^T Y for Y = L^-1 Q B, one triangular solve instead of the two of P X = B.

    P is symmetric positive definite: LL^T takes half the flops and memory of the LU that SuperLU
    (scipy's splu, SymmetricMode, no pivoting) computed, and the form needs only the forward
    solve (about a quarter of SuperLU's time on the carbon knee: benchmarks/bench_joint_fe.py).
    cvxopt is the wheel that ships CHOLMOD (scikit-sparse has no wheels; pypardiso needs MKL,
    200 MB); its OpenBLAS is built without threads, so the
    sums are in the same order on every machine and every run.

    The fill of a 3D solid's factor depends on the elimination order: METIS nested dissection
    (`_nd_order_points`) of the mesh's point graph gives ~35 % less fill than a minimum degree
    order; it is given to CHOLMOD as is (identity permutation).
    (Multigrid-preconditioned CG was tried: the stiff interface ties and nu = 0.48 make it
    converge 50x slower than the direct solve. Tried on the knee and dropped: METIS options
    (nseps, ufactor, ccorder: +-5 % fill, no steady gain), qdldl's LDL^T (3x slower), cholespy
    (2x slower).)"""
    import cvxopt
    from cvxopt import cholmod

    vals, rows, cols, n = lower
    A = cvxopt.spmatrix(vals, rows.astype(np.int64), cols.astype(np.int64), size=(n, n))
    cholmod.options.clear()  # the library's defaults, whatever another caller set
    cholmod.options["supernodal"] = 2  # LL^T (D = I)
    try:
        F = cholmod.symbolic(A, p=cvxopt.matrix(np.arange(n, dtype=np.int64), tc="i"))
        cholmod.numeric(A, F)
    except ArithmeticError as exc:
        raise RuntimeError(f"joint FE: the stiffness matrix is not positive definite ({exc}): "
                           "a part of the mesh is not held by any tie") from None
    Y = cvxopt.matrix(np.asarray(B, dtype=float))
    cholmod.solve(F, Y, sys=7)  # Y = Q B
    cholmod.solve(F, Y, sys=4)  # Y = L^-1 Q B
    Y = np.array(Y)
    return Y.T @ Y
