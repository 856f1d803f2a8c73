"""The joint FE's block assembly (`solid_fe.assemble`) against scikit-fem's own BilinearForm /
LinearForm assembly of the same forms, and the condensation against a dense reference."""

from __future__ import annotations

import numpy as np
import pytest

import tiers

from cogniframe.analysis.joints import meshing
from cogniframe.analysis.joints import solid_fe as J

E, NU = 26.0, 0.45
L, B, H = 6.0, 4.0, 3.0


def _ties():
    # two faces of the box by facet centroid, with unequal normal / tangential stiffness, and a
    # bottom face picked by its outward normal
    return [J.Tie("x0", lambda c, n: c[0] < 1e-9, (0.0, B / 2, H / 2), 40.0, 7.0),
            J.Tie("xL", lambda c, n: c[0] > L - 1e-9, (L, 1.0, 2.0), 55.0, 11.0),
            J.Tie("z0", lambda c, n: n[2] < -0.99, (L / 2, B / 2, -1.0), 30.0, 30.0)]


@pytest.fixture(scope="module")
@tiers.needs('fe')
def box():
    return meshing.mesh_occ(lambda occ: occ.addBox(0, 0, 0, L, B, H), 1.5)


def _reference(points, tets):
    """K_uu, K_ur, K_rr by skfem's forms on ElementVector(ElementTetP2()) (DOF numbering as ours)."""
    from skfem import Basis, BilinearForm, ElementTetP2, ElementVector, FacetBasis, Functional, LinearForm, MeshTet, asm
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = MeshTet(points, tets)
    elem = ElementVector(ElementTetP2())
    basis = Basis(mesh, elem, intorder=2)
    K = asm(linear_elasticity(*lame_parameters(E, NU)), basis)
    where = {"x0": lambda x: x[0] < 1e-9, "xL": lambda x: x[0] > L - 1e-9, "z0": lambda x: x[2] < 1e-9}
    ties = _ties()
    Kur = np.zeros((basis.N, 6 * len(ties)))
    Krr = np.zeros((6 * len(ties), 6 * len(ties)))
    for ti, tie in enumerate(ties):
        fb = FacetBasis(mesh, elem, facets=mesh.facets_satisfying(where[tie.name], boundaries_only=True), intorder=4)
        kn, kt = tie.kn, tie.kt

        @BilinearForm
        def itf(u, v, w, kn=kn, kt=kt):
            return kt * dot(u, v) + (kn - kt) * dot(u, w.n) * dot(v, w.n)

        Ki = asm(itf, fb)
        K = K + Ki

        def motion(a, x, ref=tie.ref):
            d = x - np.asarray(ref).reshape(3, 1, 1)
            if a < 3:
                return np.eye(3)[a].reshape(3, 1, 1) * np.ones_like(d)
            return np.cross(np.eye(3)[a - 3], d, axis=0)

        for a in range(6):
            @LinearForm
            def rig(v, w, a=a, kn=kn, kt=kt):
                r = motion(a, w.x)
                return -(kt * dot(r, v) + (kn - kt) * dot(r, w.n) * dot(v, w.n))

            Kur[:, 6 * ti + a] = asm(rig, fb)
            for b in range(6):
                @Functional
                def rr(w, a=a, b=b, kn=kn, kt=kt):
                    ra, rb = motion(a, w.x), motion(b, w.x)
                    return kt * dot(ra, rb) + (kn - kt) * dot(ra, w.n) * dot(rb, w.n)

                Krr[6 * ti + a, 6 * ti + b] = asm(rr, fb)
    return K.tocsc(), Kur, Krr


def test_block_assembly_equals_skfem_bilinear_and_linear_forms(box):
    points, tets = box
    sysm = J.assemble(points, tets, E, NU, _ties())
    K, Kur, Krr = _reference(points, tets)
    A = sysm.Kuu()
    assert A.shape == K.shape == (3 * sysm.n_points,) * 2
    assert abs(A - K).max() <= 1e-12 * abs(K).max()
    assert abs(A - A.T).max() <= 1e-14 * abs(K).max()  # symmetric (assembled from one triangle)
    assert np.abs(sysm.Kur - Kur).max() <= 1e-12 * np.abs(Kur).max()
    assert np.abs(sysm.Krr - Krr).max() <= 1e-12 * np.abs(Krr).max()
    # the tied areas: the end faces and the bottom
    assert sysm.tied_area == pytest.approx((B * H, B * H, L * B), rel=1e-12)
    # the sparsity of a scalar scatter of whole tetrahedra: every pair of a tetrahedron's DOFs
    # (zero values kept: the factorization's fill does not depend on an accidental zero)
    from skfem import Basis, ElementTetP2, ElementVector, MeshTet

    d = Basis(MeshTet(points, tets), ElementVector(ElementTetP2())).element_dofs.astype(np.int64)
    pairs = np.unique((d[:, None, :] * A.shape[0] + d[None, :, :]).ravel())
    assert A.nnz == pairs.size
    np.testing.assert_array_equal(np.sort(A.indices.astype(np.int64) * A.shape[0]
                                          + np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))), pairs)


def test_csc_blocks_in_a_point_order_equal_the_permuted_matrix(box):
    points, tets = box
    sysm = J.assemble(points, tets, E, NU, _ties())
    iperm = np.random.default_rng(3).permutation(sysm.n_points)
    assert np.all(sysm.rows <= sysm.cols)  # the upper triangle, mirrored for the CSC
    P = J._csc_blocks(*J._mirror(sysm.rows, sysm.cols, sysm.blocks), iperm, sysm.n_points)
    perm = (3 * np.argsort(iperm)[:, None] + np.arange(3)).ravel()
    ref = sysm.Kuu()[perm][:, perm].tocsc()
    ref.sort_indices()
    assert P.has_sorted_indices
    np.testing.assert_array_equal(P.indptr, ref.indptr)
    np.testing.assert_array_equal(P.indices, ref.indices)
    np.testing.assert_array_equal(P.data, ref.data)


def test_condensation_equals_dense_schur_complement(box):
    # K_c = K_rr - K_ur^T K_uu^-1 K_ur on the skfem reference matrices, by a dense solve
    points, tets = box
    C = J.condense(points, tets, E, NU, _ties())
    K, Kur, Krr = _reference(points, tets)
    ref = Krr - Kur.T @ np.linalg.solve(K.toarray(), Kur)
    ref = 0.5 * (ref + ref.T)
    assert np.linalg.norm(C.K - ref) <= 1e-10 * np.linalg.norm(ref)
    # the six rigid motions of the whole joint (all bodies moving together) cost nothing
    refs = np.array([t.ref for t in _ties()])
    rigid = []
    for a in range(6):
        v = []
        for p in refs:
            # one motion of the whole about the origin, expressed at each body's reference point
            w = np.eye(3)[a - 3] if a >= 3 else np.zeros(3)
            t = np.eye(3)[a] if a < 3 else np.cross(w, p)
            v.append(np.r_[t, w])
        rigid.append(np.concatenate(v))
    rigid = np.array(rigid).T
    assert np.abs(C.K @ rigid).max() <= 1e-9 * np.abs(C.K).max()


def test_condense_same_bits_run_to_run(box):
    points, tets = box
    a = J.condense(points, tets, E, NU, _ties())
    b = J.condense(points, tets, E, NU, _ties())
    assert np.array_equal(a.K, b.K)
