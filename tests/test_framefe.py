"""The frame FE's fast paths against closed forms and dense references.

`framefe` assembles every beam at once and solves sparse; `framefe.lowest_eigenvalues` finds
the modes by shift-inverted Lanczos with an inertia check; `framefe.euler_loads` solves all
rods' buckling problems in one batch. Each is checked here against theory and against the
plain dense computation on the same matrices.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from scipy.linalg import eigh
from scipy.optimize import brentq

from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe import spec as spec_mod
from cogniframe.analysis import framefe as ff
from cogniframe.analysis import stiffness as st

from conftest import PARAMS

E, G_MOD, D, RHO = 125_000.0, 5_000.0, 3.0, 1.6e-9  # carbon rod: MPa, MPa, mm, t/mm^3


def _rod(direction, length: float, n: int, rho: float = 0.0) -> ff.Frame3D:
    fe = ff.Frame3D()
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    for i in range(n + 1):
        fe.add_node(f"n{i}", (10.0, -4.0, 7.0) + u * length * i / n)
    for i in range(n):
        fe.add_beam(f"b{i}", f"n{i}", f"n{i + 1}", E, G_MOD, D, rho=rho)
    return fe


@pytest.mark.parametrize("direction", [(1, 0, 0), (0, 0, 1), (0.3, -0.8, 0.52), (-0.1, 0.05, 0.99)])
def test_cantilever_in_any_direction_matches_PL3_over_3EI(direction):
    # stacked element matrices and rotations (one of them near vertical: the other reference axis)
    L, P, n = 120.0, 2.0, 6
    fe = _rod(direction, L, n)
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    load = np.cross(u, [0.0, 1.0, 0.0] if abs(u[1]) < 0.9 else [1.0, 0.0, 0.0])
    load /= np.linalg.norm(load)
    f = np.zeros(6 * (n + 1))
    f[6 * n:6 * n + 3] = P * load
    fixed = np.zeros(f.size, dtype=bool)
    fixed[:6] = True
    _, i_, _ = ff.circle_section(D)
    expect = P * L**3 / (3 * E * i_)
    for K in (fe.stiffness(), fe.stiffness(sparse=True)):
        x = ff.solve(K, f, fixed)
        tip = x[6 * n:6 * n + 3]
        assert tip @ load == pytest.approx(expect, rel=1e-9)  # cubic elements are exact for end loads
        assert abs(tip @ u) < 1e-9 * expect
        assert np.linalg.norm(x[6 * n + 3:6 * n + 6]) == pytest.approx(P * L**2 / (2 * E * i_), rel=1e-9)
    # a rigid-body motion of the whole rod stores no energy: translation and a small rotation
    K = fe.stiffness(sparse=True)
    pts = np.array(list(fe.nodes.values()))
    rig = np.zeros(f.size)
    w = np.array([0.2, -0.1, 0.3])
    for i, p in enumerate(pts):
        rig[6 * i:6 * i + 3] = [1.0, 2.0, -1.0] + np.cross(w, p)
        rig[6 * i + 3:6 * i + 6] = w
    assert np.abs(K @ rig).max() < 1e-9 * np.abs(K).max()


def _carbon_model(rod_segments: int = 1, masses: bool = False):
    """The carbon frame with the closed-form joints (the tab link: the pegs have no closed form)."""
    data = yaml.safe_load((PARAMS / "carbon.yaml").read_text(encoding="utf-8"))
    data["core"]["link"] = "tab"
    s = spec_mod.from_dict(data)
    f = frame_mod.frame_of(s)
    p = partlist.part_list(s, f)
    joints = st.joint_models(s, p, "analytic")
    play = st.play_springs(s, f, p, joints, st.PLAY_REFERENCE_N)
    m = st.masses_g(s, f, p, 241.0) if masses else None
    return st.build_model(s, f, p, joints, play=play, rod_segments=rod_segments, masses=m)


def test_sparse_assembly_and_solve_equal_the_dense_ones_on_the_carbon_frame():
    mdl = _carbon_model(rod_segments=4, masses=True)
    fe = mdl.fe
    Kd, Ks = fe.stiffness(), fe.stiffness(sparse=True)
    assert np.abs(Ks.toarray() - Kd).max() <= 1e-12 * np.abs(Kd).max()
    assert np.abs(Kd - Kd.T).max() <= 1e-12 * np.abs(Kd).max()
    Md, Ms = fe.mass(), fe.mass(sparse=True)
    assert np.abs(Ms.toarray() - Md).max() <= 1e-12 * np.abs(Md).max()
    # the consistent mass carries the rods' whole mass in each direction (+ the point masses)
    idx = fe.index()
    ux = np.zeros(Md.shape[0])
    ux[0::6] = 1.0
    rods = sum(b.rho * b.a * np.linalg.norm(fe.nodes[b.n1] - fe.nodes[b.n0]) for b in fe.beams)
    points = sum(m[0, 0] for m in fe.masses.values())
    assert ux @ Md @ ux == pytest.approx(rods + points, rel=1e-12)
    # the payload case: SuperLU against dense LU (the model's condition number is ~1e10)
    Kf, fixed = st._floor_bc(mdl, fe.stiffness(sparse=True), "sliding")
    fixed = st._drop_unconnected(Kf, fixed)
    f = np.zeros(Kd.shape[0])
    f[6 * idx[mdl.payload] + 2] = -10.0
    us = ff.solve(Kf, f, fixed)
    ud = ff.solve(Kf.toarray(), f, fixed)
    assert np.abs(us - ud).max() <= 1e-6 * np.abs(ud).max()
    # backward stable: the residual is round-off of the stiffest terms, not of the load
    assert np.abs(Kf @ us - f)[~fixed].max() <= 1e-12 * abs(Kf).max() * np.abs(us).max()


def _free_free_rod(n: int = 60, length: float = 300.0):
    fe = _rod((1.0, 0.2, 0.1), length, n, rho=RHO)
    return fe.stiffness(sparse=True), fe.mass(sparse=True)


def test_free_free_rod_modes_match_4730_and_7853_both_planes():
    # the round rod's bending modes come in exactly degenerate pairs (the two planes): the case
    # where shift-inverted Lanczos can miss one of a cluster; the inertia count must catch that
    L = 300.0
    K, M = _free_free_rod(length=L)
    assert K.shape[0] > 200  # the sparse path, not the small-problem dense one
    w = ff.lowest_eigenvalues(K, M, 12)
    hz = np.sqrt(np.abs(w)) / (2 * math.pi)
    a, i_, _ = ff.circle_section(D)
    base = math.sqrt(E * i_ / (RHO * a * L**4)) / (2 * math.pi)
    assert np.all(hz[:6] < 1e-3 * base)  # six rigid-body modes
    for pair, beta_l in zip(range(3), (4.7300, 7.8532, 10.9956)):
        expect = beta_l**2 * base
        assert hz[6 + 2 * pair] == pytest.approx(expect, rel=5e-3)
        assert hz[7 + 2 * pair] == pytest.approx(hz[6 + 2 * pair], rel=1e-8)  # the pair, both found


def test_lowest_eigenvalues_equal_the_dense_solver_on_the_carbon_frame(monkeypatch):
    mdl = _carbon_model(rod_segments=4, masses=True)
    K, M = mdl.fe.stiffness(sparse=True), mdl.fe.mass(sparse=True)
    Kd, Md = K.toarray(), M.toarray()
    n = Kd.shape[0]
    # dense reference, shift-inverted so its error is relative to the low modes, not to the
    # stiff links' (eigh(K, M) straight is off by ~1e-4 here: eps x the largest eigenvalue)
    sigma = -1e-7 * np.median(np.diag(Kd) / np.diag(Md))
    nu = eigh(Md, Kd - sigma * Md, eigvals_only=True, subset_by_index=[n - 14, n - 1])
    ref = np.sort(1 / nu + sigma)

    def no_fallback(*a, **k):
        raise AssertionError("the sparse solver fell back to dense on the carbon frame")

    monkeypatch.setattr(ff, "_dense_lowest", no_fallback)
    w = ff.lowest_eigenvalues(K.tocsc(), M.tocsc(), 14)
    assert np.abs(w[6:] - ref[6:]).max() <= 1e-6 * ref[6]
    assert np.abs(w[:6]).max() <= 1e-6 * ref[6]
    # Sylvester's inertia: the count below any point between modes is the modes' count
    for i in (6, 9, 13):
        assert ff._count_below(K, M, 0.5 * (ref[i] + ref[i + 1]) if i < 13 else ref[13] * 1.0001) == i + 1


def test_dense_reference_equals_the_sparse_solver_on_the_carbon_frame():
    mdl = _carbon_model(rod_segments=4, masses=True)
    K, M = mdl.fe.stiffness(sparse=True).tocsc(), mdl.fe.mass(sparse=True).tocsc()
    sparse, dense = ff.lowest_eigenvalues(K, M, 14), ff._dense_lowest(K, M, 14)
    assert np.abs(dense[6:] - sparse[6:]).max() <= 1e-6 * sparse[6]
    assert np.abs(dense[:6]).max() <= 1e-6 * sparse[6]


def test_a_motor_station_next_to_a_division_point_leaves_no_sliver_segment(monkeypatch):
    """This design put the motor station 0.47 um from its arm rods' midpoints: a rod segment of
    ~1e16 N/mm whose round-off (K's eigenvalues down to -7) made the free-flight modes fail
    (LinAlgError, `check` exit 3). The station now replaces the division point."""
    import yaml

    from cogniframe.analysis import load_cases
    from cogniframe.analysis.verdict import check

    data = yaml.safe_load((PARAMS / "carbon.yaml").read_text(encoding="utf-8"))
    data["rods"]["diameter"], data["frame"]["height"] = 3.047, 139.828
    data["joints"].update(wall=1.703, socket_depth=12.598, hinge_thickness=1.54)
    data["joints"]["fit_clearance"]["tpu_95a"] = 0.082
    data["model"]["stiffness_model"] = "surrogate"
    models = []
    real = load_cases.build_model

    def keep(*a, **k):
        models.append(real(*a, **k))
        return models[-1]

    monkeypatch.setattr(load_cases, "build_model", keep)
    result = check(spec_mod.from_dict(data))
    modes = result.stiffness["modes_hz"]
    assert len(modes) >= 6 and all(0 < a <= b for a, b in zip(modes, modes[1:]))
    fe = next(m.fe for m in models if any("#3" in b.name for b in m.fe.beams))  # the modes' 4-segment rods
    for b in fe.beams:
        if b.group.startswith("rod_arm"):
            length = float(np.linalg.norm(np.asarray(fe.nodes[b.n1]) - np.asarray(fe.nodes[b.n0])))
            assert length >= 0.5, b.name  # 1 % of the 76 mm arm rod at least
    K = fe.stiffness(sparse=True)
    assert np.linalg.eigvalsh(K.toarray())[0] > -1e-3  # semi-definite to round-off, not -7


def test_a_missed_mode_is_caught_and_answered_densely(monkeypatch):
    # ARPACK that loses one eigenvalue of a pair: the inertia count disagrees, dense answers
    from scipy.sparse.linalg import eigsh as real

    def lossy(*a, **k):
        w = np.sort(real(*a, **k))
        return np.delete(np.append(w, w[-1] * 1.5), 7)

    import scipy.sparse.linalg

    monkeypatch.setattr(scipy.sparse.linalg, "eigsh", lossy)
    K, M = _free_free_rod()
    w = ff.lowest_eigenvalues(K, M, 12)
    assert w[7] == pytest.approx(w[6], rel=1e-8)  # the pair is whole again


@pytest.mark.parametrize("c", [0.0, 300.0, 3000.0, 3.0e4, 1.0e9])
def test_euler_loads_match_the_elastically_restrained_column(c):
    # pinned ends with rotational springs c at both: symmetric mode, tan(u/2) = -u EI / (c L),
    # P = (u / L)^2 EI; c = 0 gives pi^2 EI / L^2, c -> inf 4 pi^2 EI / L^2
    L, ei = 80.0, E * ff.circle_section(D)[1]
    if c == 0.0:
        u = math.pi
    else:
        u = brentq(lambda x: math.tan(x / 2) + x * ei / (c * L), math.pi + 1e-9, 2 * math.pi - 1e-9)
    expect = (u / L) ** 2 * ei
    assert ff.euler_load(L, ei, c, c) == pytest.approx(expect, rel=2e-3)  # 8 elements
    assert ff.euler_load(L, ei, c, c, n_el=32) == pytest.approx(expect, rel=1e-5)


def test_euler_loads_batch_equals_one_by_one():
    ls, ka, kb = [40.0, 80.0, 61.5, 80.0], [0.0, 3000.0, 1e5, 50.0], [10.0, 3000.0, 0.0, 7e4]
    ei = E * ff.circle_section(D)[1]
    batch = ff.euler_loads(ls, ei, ka, kb)
    for i in range(4):
        assert batch[i] == pytest.approx(ff.euler_load(ls[i], ei, ka[i], kb[i]), rel=1e-12)
    # unequal end springs lie between the pinned-pinned and the fixed-fixed column
    assert all(math.pi**2 * ei / l**2 * 0.999 < p < 4 * math.pi**2 * ei / l**2 * 1.001 for l, p in zip(ls, batch))


def test_negative_pivots_count_the_negative_eigenvalues_sylvester():
    from scipy.sparse import csc_matrix

    rng = np.random.default_rng(3)
    a = rng.standard_normal((40, 40))
    a = a + a.T + np.diag(np.linspace(-30, 30, 40))
    assert ff.negative_pivots(csc_matrix(a)) == int(np.count_nonzero(np.linalg.eigvalsh(a) < 0))


def test_factor_solves_a_matrix_without_an_ldlt_by_lu():
    # a zero leading pivot: no LDL^T without pivoting, SuperLU takes over
    from scipy.sparse import csc_matrix

    a = np.array([[0.0, 2.0, 0.0], [2.0, 1.0, 1.0], [0.0, 1.0, 3.0]])
    b = np.array([1.0, 2.0, 3.0])
    assert ff.negative_pivots(csc_matrix(a)) in (-1, 1)
    assert np.allclose(ff.factor(csc_matrix(a)).solve(b), np.linalg.solve(a, b), rtol=1e-12)
