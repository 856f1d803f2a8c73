"""`check`'s fast paths give the figures of the straightforward ones (issue 44): each fast piece
against a plain reference written here (every point tested, every sample interpolated, the mount
stepped), and the whole `check --json` of the presets and random designs with the references
swapped in against the shipped code. The timings are benchmarks/bench_check_profile.py's, never
asserted here."""

from __future__ import annotations

import copy
import functools
import math
import random
from pathlib import Path

import numpy as np
import pytest

import design_space
from cogniframe import frame as frame_mod
from cogniframe import numfmt
from cogniframe.errors import UserError
from cogniframe import spec as spec_mod
from cogniframe.analysis import drop as drop_mod
from cogniframe.analysis import framefe as ff
from cogniframe.analysis import impact as I
from cogniframe.analysis import single_drop as S
from cogniframe.analysis import stiffness as st
from cogniframe.analysis.joints import mirror
from cogniframe.families import core_plate, joint
from cogniframe.parts import peg_plan


# -- the references: the plain computations the fast paths replace ------------------------------

def sleeve_in_arch_every_point(p0, d, t0, t1, r, box, opening, block, n=96) -> float:
    """The midpoint rule over every point: n steps along the sleeve, n / 3 across its radius, n round."""
    d = np.asarray(d, float)
    a, b = peg_plan._frame_of(d)
    nr = max(4, n // 3)
    t = t0 + (np.arange(n) + 0.5) * (t1 - t0) / n
    rho = (np.arange(nr) + 0.5) * r / nr
    phi = (np.arange(n) + 0.5) * 2 * math.pi / n
    T, P, F = np.meshgrid(t, rho, phi, indexing="ij")
    pts = (np.asarray(p0, float)[:, None] + d[:, None] * T.ravel() + a[:, None] * (P * np.cos(F)).ravel()
           + b[:, None] * (P * np.sin(F)).ravel())
    lo, hi = (np.asarray(v, float)[:, None] for v in box)
    inside = np.all((pts >= lo) & (pts <= hi), axis=0)
    if block is not None:
        blo, bhi = (np.asarray(v, float)[:, None] for v in block)
        inside |= np.all((pts >= blo) & (pts <= bhi), axis=0)
    if opening is not None:
        inside &= ~opening.contains(pts[0], pts[2])
    w = P.ravel() * (r / nr) * (2 * math.pi / n) * ((t1 - t0) / n)
    return float(w[inside].sum())


def mount_response_stepped(u, dt, mount_hz, zeta):
    """The mount's exact first-order-hold steps, one after another."""
    from cogniframe.analysis.impact_nl import _expm

    w = 2.0 * math.pi * mount_hz
    M = np.zeros((4, 4))
    M[0, 1] = 1.0
    M[1, 0], M[1, 1], M[1, 2] = -w * w, -2.0 * zeta * w, -1.0
    M[2, 3] = 1.0
    E = _expm(M * dt)
    z = zd = 0.0
    uu = list(map(float, u))
    out = [0.0]
    for i in range(len(uu) - 1):
        du = (uu[i + 1] - uu[i]) / dt
        z, zd = (E[0, 0] * z + E[0, 1] * zd + E[0, 2] * uu[i] + E[0, 3] * du,
                 E[1, 0] * z + E[1, 1] * zd + E[1, 2] * uu[i] + E[1, 3] * du)
        out.append(-(w * w * z + 2.0 * zeta * w * zd))
    return np.asarray(out)


def drop_peaks_every_sample(pulse_g, height_cm, scatter, footprint_mm=S.PAPER_FOOTPRINT_MM, d=None, dt=S.DT_S,
                            rate_hz=S.RATE_HZ, n_samples=S.N_SAMPLES, mount=mount_response_stepped):
    """Every drop's peak over all its samples, each foot's reading by np.interp."""
    d = d if d is not None else S.draws()
    logger = mount(pulse_g, dt, scatter.mount_hz, scatter.mount_zeta) if scatter.mount_hz > 0 else pulse_g
    tj = S.foot_delays_s(S.feet(footprint_mm), math.radians(scatter.tilt_scale_deg(height_cm)) * d.tilt_unit, d.azimuth,
                         S.impact_velocity(height_cm))
    ts = (np.arange(n_samples)[None, :] + d.phase[:, None]) / rate_hz
    t = ts[:, None, :] - tj[:, :, None]
    a = np.interp(t, np.arange(len(logger)) * dt, logger, left=0.0, right=0.0).mean(axis=1)
    return np.abs(a).max(axis=1)


def figures_by_isinstance(obj, digits=numfmt.CHECK_FIGURES):
    """Every node by isinstance: floats (numpy's too) to `digits` significant digits."""
    if isinstance(obj, bool) or obj is None or isinstance(obj, (int, str)):
        return obj
    if isinstance(obj, (float, np.floating)):
        return numfmt.sig(float(obj), digits)
    if isinstance(obj, dict):
        return {k: figures_by_isinstance(v, digits) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [figures_by_isinstance(v, digits) for v in obj]
    return obj


def triu_of_the_kept(A, keep=None):
    """scipy's own: the rows, then the columns kept, then `triu`."""
    from scipy.sparse import triu

    A = A.tocsc()
    return triu(A if keep is None else A[keep][:, keep], format="csc")


def linear_operator(apply, n):
    """scipy's LinearOperator round a function of vectors."""
    from scipy.sparse.linalg import LinearOperator

    return LinearOperator((n, n), matvec=lambda x: apply(np.ravel(x)), dtype=float)


def placements_per_socket(frame, parts, joints):
    """Each joint placement's bodies: (instance, label, world reference point, (rod, end) or None),
    each socket's rod found by testing every rod of the node for the socket's port and direction."""
    out = []
    for part in (p for p in parts if p.family == "joint"):
        js = joints[part.name]
        for pl in part.placements:
            R = st._rz(pl.rotation_deg)
            for li, lab in enumerate(js.labels):
                ref = R @ np.asarray(js.refs[li]) + np.asarray(pl.origin, float)
                rod = None
                if lab != "body":
                    sock = next(x for x in part.sockets if x.rod == lab)
                    port, d = R @ np.asarray(sock.port) + np.asarray(pl.origin, float), R @ np.asarray(sock.direction)
                    for rn in frame.nodes[pl.instance].rods:
                        r = frame.rods[rn]
                        if (np.linalg.norm(np.asarray(r.end_at(pl.instance).port) - port) < 1e-6
                                and np.linalg.norm(np.asarray(r.socket_direction(pl.instance)) - d) < 1e-6):
                            rod = (rn, "a" if r.a.node == pl.instance else "b")
                    assert rod is not None
                out.append((pl.instance, lab, tuple(ref), rod))
    return out


# -- the designs ---------------------------------------------------------------------------------

def peak_abs_accel_searched(sys, v0, t_end):
    """max |a| over [0, t_end]: a 2001-point grid, then a golden-section search (to 1e-13 s) round its best point."""
    if t_end <= 0.0:
        return abs(I._accel(sys, *I._state_at(sys, v0, 0.0)))
    t = np.linspace(0.0, t_end, 2001)
    a = np.abs(I._accel(sys, *I._state(sys, v0, t)))
    i = int(np.argmax(a))
    best = float(a[i])
    lo, hi = t[max(i - 1, 0)], t[min(i + 1, t.size - 1)]
    f = lambda s: abs(I._accel(sys, *I._state_at(sys, v0, s)))  # noqa: E731
    inv = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = hi - inv * (hi - lo), lo + inv * (hi - lo)
    fc, fd = f(c), f(d)
    while hi - lo > 1e-13:
        if fc > fd:
            hi, d, fd = d, c, fc
            c = hi - inv * (hi - lo)
            fc = f(c)
        else:
            lo, c, fc = c, d, fd
            d = lo + inv * (hi - lo)
            fd = f(d)
    return max(best, fc, fd)


def parse_yaml_pure(text, path):
    """The params file read by the pure-Python loader alone."""
    with pytest.MonkeyPatch.context() as m:
        m.setattr(spec_mod, "_FastUniqueKeyLoader", None)
        return spec_mod.parse_yaml(text, path)



def prop_clearances_one_by_one(frame, spec):
    """Each propeller disc against each cage rod (sampled every 0.5 mm) and each core box (a 1 mm
    polar grid of the disc, every box), one at a time."""
    radius = spec.motors.prop_diameter / 2

    def to_disc(pts, centre):
        dxy = np.hypot(pts[:, 0] - centre[0], pts[:, 1] - centre[1])
        return np.hypot(np.maximum(dxy - radius, 0.0), np.abs(pts[:, 2] - centre[2]))

    def rod_to_disc(rod, centre):
        n = max(2, int(rod.length / 0.5))
        return float(to_disc(rod.start + np.outer(np.linspace(0, 1, n), rod.end - rod.start), centre).min() - rod.diameter / 2)

    def box_to_disc(box, centre):
        rr = np.linspace(0, radius, max(2, int(radius) + 1))
        th = np.linspace(0, 2 * math.pi, max(16, int(2 * math.pi * radius)), endpoint=False)
        R, T = np.meshgrid(rr, th)
        pts = np.column_stack([centre[0] + (R * np.cos(T)).ravel(), centre[1] + (R * np.sin(T)).ravel(),
                               np.full(R.size, centre[2])])
        gap = np.maximum(np.abs(pts - np.asarray(box.centre)) - np.asarray(box.size) / 2, 0.0)
        return float(np.linalg.norm(gap, axis=1).min())

    out = []
    for m in frame.motors:
        centre = np.array([m.axis[0], m.axis[1], m.prop_z])
        cage = min(rod_to_disc(r, centre) for r in frame.rods.values() if r.role != "arm")
        core = min(box_to_disc(b, centre) for b in frame.core.boxes)
        others = [np.hypot(o.axis[0] - m.axis[0], o.axis[1] - m.axis[1]) - 2 * radius for o in frame.motors if o is not m]
        out.append(frame_mod.PropClearance(m.name, round(cage, 2), round(core, 2), round(float(min(others)), 2)))
    return tuple(out)


@functools.lru_cache(maxsize=None)
def _random_docs(n: int, seed: int) -> tuple[dict, ...]:
    """n random designs ("edit" mode) that validate, their joints inside the surrogate's box."""
    import cogniframe.api as api
    from cogniframe.analysis.joints.surrogate import outside_reasons

    rnd = random.Random(seed)
    out = []
    while len(out) < n:
        doc = design_space.random_design(rnd, "edit")
        doc["model"]["stiffness_model"] = "surrogate"
        try:
            d = api.Design(spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml"), "", "x.yaml", None).validate()
        except UserError:  # a design the validation refuses: drawn again
            continue
        if not outside_reasons(d.spec, [p for p in d.derived.parts if p.family == "joint"]):  # no FE to solve
            out.append(doc)
    return tuple(out)


def _presets() -> list[dict]:
    out = []
    for name in design_space.PRESETS:
        doc = design_space.preset(name)
        doc["model"]["stiffness_model"] = "surrogate"
        out.append(doc)
    return out


# -- the pieces ----------------------------------------------------------------------------------

def test_the_sleeve_in_the_arch_is_the_midpoint_rule_over_every_point():
    """The presets' and twelve random designs' pegged links (both hands): the runs along lines sum
    the same points as testing each."""
    rnd = random.Random(7)
    docs = _presets() + [design_space.random_design(rnd, "edit") for _ in range(12)]
    compared = 0
    for doc in docs:
        try:
            s = spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml")
            links = joint.core_links(s, frame_mod.frame_of(s))
        except Exception:  # noqa: BLE001 - a design the validation refuses: not a link to compare
            continue
        for link in links:
            pl = peg_plan.pegged_plan(link.sockets, dict(link.params))
            for st in pl.struts:
                back, mouth = np.asarray(st.back), np.asarray(st.mouth)
                d = (mouth - back) / np.linalg.norm(mouth - back)
                box = ((pl.arch_x[0], pl.arch_n[0], pl.arch_lo), (pl.arch_x[1], pl.arch_n[1], pl.arch_hi))
                want = sleeve_in_arch_every_point(back - d * st.start, d, st.start, st.end, pl.col_r, box, pl.opening, pl.block)
                assert want > 0
                assert peg_plan.sleeve_in_arch(pl, st) == pytest.approx(want, rel=1e-12)
                compared += 1
    assert compared >= 10


def test_the_runs_count_a_box_a_block_and_an_opening_crossed_at_any_angle():
    """A sleeve through a box with a block on it and an opening under it, at slants where a line
    crosses every face, and along an axis (lines parallel to faces)."""
    box = ((-10.0, -3.0, 0.0), (10.0, 3.0, 8.0))
    block = ((-2.0, -3.0, 8.0), (2.0, 3.0, 11.0))
    opening = peg_plan.ArchOpening(0.0, 6.0, 2.0, 0.0, 4.0)
    for d in ([0.0, 0.0, 1.0], [0.3, 0.1, 0.95], [-0.6, 0.2, 0.77], [1.0, 0.0, 0.0]):
        d = np.asarray(d) / np.linalg.norm(d)
        p0 = np.array([0.5, 0.2, 1.0]) - 3.0 * d
        want = sleeve_in_arch_every_point(p0, d, 0.0, 14.0, 2.5, box, opening, block, n=48)
        got = peg_plan._sleeve_in_arch(p0, d, 0.0, 14.0, 2.5, box, opening, block, n=48)
        assert want > 0 and got == pytest.approx(want, rel=1e-12)


def test_the_mount_by_convolution_is_the_mount_stepped():
    """Check's pulses and a unit step, at the paper's mount and another: equal to 1e-12 of the peak."""
    m, c = 0.245, 40.0
    cases = [(S.kv_pulse_g(m, c, k, h), S.DT_S, S.PAPER_SCATTER.mount_hz, S.PAPER_SCATTER.mount_zeta)
             for k, h in ((3000.0, 25.0), (7040.0, 100.0), (20000.0, 300.0))]
    cases.append((np.ones(5001), 1e-5, 100.0, 0.2))
    for u, dt, f, z in cases:
        want = mount_response_stepped(u, dt, f, z)
        got = S.mount_response(u, dt, f, z)
        assert got.shape == want.shape and got[0] == 0.0
        assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()


def test_interp_on_the_equal_steps_is_np_interp_to_the_bit():
    rng = np.random.default_rng(3)
    for n, dt in ((2, 0.5), (4001, S.DT_S), (1000, 1e-3)):
        v = rng.normal(size=n) * 50
        grid = np.arange(n) * dt
        t = np.concatenate([rng.uniform(-2 * dt, (n + 1) * dt, 5000), grid, np.nextafter(grid, -1.0), np.nextafter(grid, 1.0)])
        want = np.interp(t, grid, v, left=0.0, right=0.0)
        assert np.array_equal(S.interp_uniform(t, dt, v), want)


@pytest.mark.parametrize("k,height", [(3000.0, 25.0), (7040.0, 100.0), (20000.0, 150.0), (7040.0, 400.0)])
def test_the_peaks_skipping_samples_are_the_peaks_of_every_sample(k, height):
    """The same mount output in both, so the skipped samples must change no drop's peak at all."""
    pulse = S.kv_pulse_g(0.245, 40.0, k, height)
    want = drop_peaks_every_sample(pulse, height, S.PAPER_SCATTER, (230.0, 190.0), mount=S.mount_response)
    assert np.array_equal(S.drop_peaks(pulse, height, S.PAPER_SCATTER, (230.0, 190.0)), want)


@pytest.mark.parametrize("zeta", [0.0, 0.2, 0.558, 0.95, 1.0, 1.05, 2.5])
def test_the_peak_acceleration_in_closed_form_is_the_searched_one(zeta):
    """Every regime (undamped to over-damped, critical exactly), touch-down speeds of a sweep, to the
    contact and beyond: the closed form is the grid-and-golden-section maximum to 1e-12 and never
    below it (the search only approaches the maximum from below)."""
    rnd = random.Random(int(zeta * 1000))
    for _ in range(60):
        m, k = rnd.uniform(0.15, 0.6), 10 ** rnd.uniform(3.0, 4.6)
        sys = I._System.of(m, 2 * zeta * math.sqrt(k * m), k)
        v0 = rnd.uniform(0.0, 11.0)
        t_max = I._time_of_max(sys, v0)
        for t_end in (t_max if math.isfinite(t_max) else I._settle_time(sys), rnd.uniform(0.0, 0.03), 0.0):
            got, want = I._peak_abs_accel(sys, v0, t_end), peak_abs_accel_searched(sys, v0, t_end)
            assert got == pytest.approx(want, rel=1e-12)
            assert got >= want * (1 - 1e-14)


def test_the_libyaml_loader_reads_what_the_pure_loader_reads():
    """The presets and random designs as YAML: the same data, key order and types; a key written
    twice and a syntax error still get the pure loader's words."""
    import yaml

    docs = _presets() + list(_random_docs(2, seed=44))
    for doc in docs:
        text = yaml.safe_dump(doc, sort_keys=False)
        fast, pure = spec_mod.parse_yaml(text, "x.yaml"), parse_yaml_pure(text, "x.yaml")
        assert fast == pure and repr(fast) == repr(pure)
    for path in sorted((Path(__file__).resolve().parents[1] / "params").glob("*.yaml")):  # with their comments
        text = path.read_text()
        assert repr(spec_mod.parse_yaml(text, path)) == repr(parse_yaml_pure(text, path))
    for bad in ("a: 1\nb:\n  c: 2\n  c: 3\n", "a: [1, 2\nb: 3\n", "a:\n\t- 1\n"):
        with pytest.raises(UserError) as fast:
            spec_mod.parse_yaml(bad, "x.yaml")
        with pytest.raises(UserError) as pure:
            parse_yaml_pure(bad, "x.yaml")
        assert str(fast.value) == str(pure.value)
    assert "written twice" in str(pytest.raises(UserError, spec_mod.parse_yaml, "a: 1\na: 2\n", "x.yaml").value)



def test_the_propeller_clearances_from_one_array_are_the_one_by_one_distances():
    """Both presets and random designs: every disc's gap to the cage, the core and its neighbours,
    equal to the bit; and a box's distance from its two gap columns is the norm of every point's gap."""
    for doc in _presets() + list(_random_docs(6, seed=45)):
        s = spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml")
        f = frame_mod.frame_of(s)
        assert frame_mod.prop_clearances(f, s) == prop_clearances_one_by_one(f, s)
    rnd = random.Random(3)
    box = type("Box", (), {})
    for _ in range(500):
        b = box()
        b.centre, b.size = tuple(rnd.uniform(-80, 80) for _ in range(3)), tuple(rnd.uniform(1, 60) for _ in range(3))
        centre, radius = np.array([rnd.uniform(-120, 120) for _ in range(3)]), rnd.uniform(20, 60)
        dx, dy = frame_mod._disc_grid(radius)
        pts = np.column_stack([centre[0] + dx, centre[1] + dy, np.full(dx.size, centre[2])])
        gap = np.maximum(np.abs(pts - np.asarray(b.centre)) - np.asarray(b.size) / 2, 0.0)
        assert frame_mod._box_to_disc(b, centre, radius) == float(np.linalg.norm(gap, axis=1).min())


def test_a_kept_reflection_is_the_reflection_worked_out_again():
    """The mirrored joints of both presets and random designs: the kept (P, order) equal to the
    bit to a fresh `_reflection`, and a caller's change to P does not reach the next caller."""
    from cogniframe.design import design

    seen = 0
    for doc in _presets() + list(_random_docs(6, seed=45)):
        parts = design(spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml")).parts
        for p in parts:
            if p.family == "joint" and mirror.is_mirror(p):
                o, P, order = mirror.mirror_original(p, parts)
                P0, order0 = mirror._reflection(o, p)
                assert order == order0 and np.array_equal(P, P0) and P.dtype == P0.dtype
                P[:] = 0.0
                assert np.array_equal(mirror.reflection(o, p)[0], P0)
                seen += 1
    assert seen >= 8


def test_key_lines_from_libyaml_are_the_pure_composers():
    """Every key path of the presets, the bad inputs and the examples: the same line in libyaml's
    node tree as in the pure composer's; and `_line_no` (whole and partial, paths that are there
    and paths that are not) the same with libyaml as with the pure composer alone."""
    import yaml

    def lines(node, prefix=()):
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                yield prefix + (str(k.value),), k.start_mark.line
                yield from lines(v, prefix + (str(k.value),))
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                yield prefix + (str(i),), v.start_mark.line
                yield from lines(v, prefix + (str(i),))

    root = Path(__file__).resolve().parents[1]
    files = [*sorted((root / "params").glob("*.yaml")), *sorted((root / "tests" / "bad_inputs").glob("*.yaml")),
             *sorted((root / "examples").rglob("*.yaml"))]
    compared = 0
    for path in files:
        try:
            text = path.read_text(encoding="utf-8")
            pure = list(lines(yaml.compose(text, Loader=yaml.SafeLoader)))
        except (UnicodeDecodeError, yaml.YAMLError):
            continue
        assert list(lines(yaml.compose(text, Loader=yaml.CSafeLoader))) == pure, path.name
        compared += len(pure)
        sample = [loc for loc, _ in pure[::max(1, len(pure) // 8)]] + [("nope",), ("frame", "nope"), ("frame", "height", "x")]
        for loc in sample:
            for partial in (False, True):
                fast = spec_mod._line_no(text, loc, partial)
                with pytest.MonkeyPatch.context() as m:
                    m.setattr(spec_mod, "_FastUniqueKeyLoader", None)
                    assert fast == spec_mod._line_no(text, loc, partial), (path.name, loc)
    assert compared > 400
    assert spec_mod._line_no("a: [1\n", ("a",)) is None  # not YAML for either composer

def _frame_session(doc):
    import cogniframe.api as api

    d = api.Design(spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml"), "", "x.yaml", None)
    return d.spec, d.derived, drop_mod.Session(d.spec, d.derived.frame, d.derived.parts)


def test_the_check_json_by_exact_type_is_the_isinstance_rules():
    from collections import OrderedDict

    tree = {"a": [1.23456789, -0.0, 0.0, float("nan"), float("inf"), -float("inf"), 1e-300, 123456789.0],
            "b": (np.float64(2.718281828), np.float32(0.1), np.int64(3), True, False, None, "x", 7),
            "c": OrderedDict(d=[(0.333333333, {"e": -1.0000049})]), "f": {"g": [], "h": {}}}
    for digits in (4, 6):
        got, want = numfmt.figures(tree, digits), figures_by_isinstance(tree, digits)
        assert repr(got) == repr(want)  # the same types and the same bits (repr tells -0.0, nan and np.float64 apart)
        assert got["a"][:3] == [1.235 if digits == 4 else 1.23457, -0.0, 0.0] and str(got["a"][1]) == "0.0"


def test_the_upper_triangle_of_the_kept_dofs_is_scipys_and_factors_to_the_same_bits():
    """A design's payload stiffness with its supports: the same arrays as triu of the rows and columns
    kept, and qdldl's solution from it bit for bit the one from the whole matrix."""
    import qdldl

    spec, d, session = _frame_session(_presets()[0])
    sol = session.solve()
    K, fixed = st._floor_bc(sol.model, sol.K, "sliding")
    keep = ~st._drop_unconnected(K, fixed)
    assert 0 < np.count_nonzero(~keep) < len(keep)
    for A, mask in ((K, keep), (K, None)):
        got, want = ff.upper_triangle(A, mask), triu_of_the_kept(A, mask)
        for field in ("indptr", "indices", "data"):
            assert np.array_equal(getattr(got, field), getattr(want, field))
    b = np.random.default_rng(1).normal(size=int(keep.sum()))
    assert np.array_equal(ff.factor(K, keep).solve(b), qdldl.Solver(K.tocsc()[keep][:, keep]).solve(b))


def test_the_modes_without_the_operators_shape_handling_are_the_same_bits(monkeypatch):
    from cogniframe.analysis import load_cases as lc

    spec, d, session = _frame_session(_presets()[1])
    masses = st.masses_g(spec, d.frame, d.parts, 240.0)
    K, M = lc._modal_matrices(spec, d.frame, d.parts, session.joints, masses, layout=session.layout)
    got = ff.lowest_eigenvalues(K, M, 14)
    monkeypatch.setattr(ff, "_vector_operator", linear_operator)
    want = ff.lowest_eigenvalues(K, M, 14)
    assert len(got) == 14 and got[6] > 1.0 and np.array_equal(got, want)


def test_the_layout_matches_each_socket_to_its_rod_and_any_joint_models_build_the_same_model():
    """The layout's placements are the rods found by testing every rod of the node; a layout made
    with the check's joints and turned to the datasheet's builds the model a fresh layout builds."""
    from dataclasses import replace

    spec, d, session = _frame_session(_random_docs(2, seed=44)[0])
    layout = session.layout
    got = [(pl.instance, lab, tuple(ref), rod) for pl in layout.placements
           for lab, ref, rod in zip(pl.labels, pl.refs, pl.rods)]
    assert got == placements_per_socket(d.frame, d.parts, session.joints)
    stiff = {n: replace(js, K=tuple(map(tuple, (js.matrix * 3.0).tolist()))) for n, js in session.joints.items()}
    for joints, kw in ((session.joints, {"rod_segments": 4}), (stiff, {"only_roles": ("arm",)})):
        shared = st.build_model(spec, d.frame, d.parts, joints, layout=layout, **kw).fe
        fresh = st.build_model(spec, d.frame, d.parts, joints, **kw).fe
        assert list(shared.nodes) == list(fresh.nodes)
        assert all(np.array_equal(shared.nodes[n], fresh.nodes[n]) for n in shared.nodes)
        assert [(n, k.tobytes()) for n, k in shared.springs] == [(n, k.tobytes()) for n, k in fresh.springs]
        assert (shared.stiffness(sparse=True) != fresh.stiffness(sparse=True)).nnz == 0


def test_the_window_maxima_at_once_are_each_windows_max():
    rng = np.random.default_rng(5)
    v = np.abs(rng.normal(size=300))
    first = rng.integers(0, 300, 200)
    last = np.minimum(first + rng.integers(-3, 60, 200), 299)  # some empty windows (last < first)
    want = np.array([v[a:b + 1].max(initial=0.0) for a, b in zip(first, last)])
    assert np.array_equal(S._window_max(v, first, last), want)


def test_the_row_means_column_by_column_are_numpys_mean():
    rng = np.random.default_rng(9)
    for cols in (1, 2, 4, 5):
        a = rng.normal(size=(3000, cols)) * 10 ** rng.uniform(-3, 3, size=(3000, cols))
        assert np.array_equal(S._row_means(a), a.mean(axis=1))


def test_the_feet_delays_from_the_lowest_foot_column_by_column_are_numpys_row_min():
    d = S.draws()
    for footprint, tilt_deg, v0 in (((210.0, 210.0), 2.0, 3.13), ((230.0, 190.0), 7.5, 4.43)):
        xy = S.feet(footprint) / 1000.0
        tilt = math.radians(tilt_deg) * d.tilt_unit
        h = np.sin(tilt)[:, None] * (np.cos(d.azimuth)[:, None] * xy[None, :, 0] + np.sin(d.azimuth)[:, None] * xy[None, :, 1])
        want = (h - h.min(axis=1, keepdims=True)) / v0
        got = S.foot_delays_s(S.feet(footprint), tilt, d.azimuth, v0)
        assert np.array_equal(got, want) and (got.min(axis=1) == 0.0).all() and got.max() > 1e-4


def test_the_core_plate_from_the_joint_familys_links_is_the_one_planned_alone():
    from cogniframe import partlist

    for doc in _presets() + list(_random_docs(2, seed=44)):
        s = spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml")
        f = frame_mod.frame_of(s)
        plate = next(p for p in partlist.part_list(s, f) if p.family == "core_plate")
        alone = core_plate.plan(s, f)[0]
        assert dict(plate.params)["tubes"] and plate == partlist._with_digest(alone)


def test_the_mass_properties_with_the_fit_checks_fasteners_are_those_without():
    from cogniframe.analysis import mass, massprops
    from cogniframe.fasteners import fasteners

    spec, d, _ = _frame_session(_presets()[0])
    budget = mass.budget(spec, d.frame, d.cut, d.parts, None)
    got = massprops.estimate(spec, d, budget, fasteners(spec, d.frame, d.parts))
    assert got == massprops.estimate(spec, d, budget) and 0.2 < got.mass_kg < 0.3


def test_a_cylinders_inertia_is_numpys_norms_and_identity():
    from cogniframe.analysis import massprops

    rng = np.random.default_rng(11)
    for _ in range(50):
        base, axis = rng.normal(size=3) * 50, rng.normal(size=3)
        m, r, length = rng.uniform(0.1, 20), rng.uniform(0.5, 10), rng.uniform(1, 200)
        a = axis / np.linalg.norm(axis)
        a = a / np.linalg.norm(a)
        want = (m * r * r / 2 - m * (3 * r * r + length * length) / 12) * np.outer(a, a) + m * (3 * r * r + length * length) / 12 * np.eye(3)
        got = massprops.cylinder("c", m, base, axis, r, length)
        assert np.array_equal(np.asarray(got.inertia), want)
        assert got.centroid == tuple(map(float, np.asarray(base) + axis / np.linalg.norm(axis) * length / 2))


# -- the whole check -------------------------------------------------------------------------------

def _check_json(doc: dict) -> dict:
    import cogniframe.api as api

    d = api.Design(spec_mod.from_dict(copy.deepcopy(doc), source="x.yaml"), "", "x.yaml", None)
    return d.check().to_dict()


def _same_check_as_the_references(doc, tmp_path, monkeypatch):
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "fast"))
    fast = _check_json(doc)
    with monkeypatch.context() as m:  # every cache empty again: the references compute everything
        m.setenv("COGNIFRAME_CACHE", str(tmp_path / "reference"))
        m.setattr(peg_plan, "_sleeve_in_arch", sleeve_in_arch_every_point)
        m.setattr(S, "mount_response", mount_response_stepped)
        m.setattr(S, "drop_peaks", drop_peaks_every_sample)
        m.setattr(I, "_peak_abs_accel", peak_abs_accel_searched)
        m.setattr(frame_mod, "prop_clearances", prop_clearances_one_by_one)
        m.setattr(mirror, "reflection", mirror._reflection)
        m.setattr(spec_mod, "_FastUniqueKeyLoader", None)
        m.setattr(numfmt, "figures", figures_by_isinstance)
        m.setattr(ff, "upper_triangle", triu_of_the_kept)
        m.setattr(ff, "_vector_operator", linear_operator)
        m.setattr(drop_mod.Session, "layout", property(lambda self: None))  # a layout per solve and per load cases
        m.setattr(core_plate, "PLANS_FROM_EARLIER", False)  # the core links planned again for the peg tubes
        reference = _check_json(doc)
    assert fast == reference


@pytest.mark.parametrize("i", range(4))
def test_check_figures_are_the_reference_paths(i, tmp_path, monkeypatch):
    """Both presets (with the surrogate) and two random designs: the whole `check --json`, equal."""
    doc = _presets()[i] if i < 2 else _random_docs(2, seed=44)[i - 2]
    _same_check_as_the_references(doc, tmp_path, monkeypatch)


@pytest.mark.long
@pytest.mark.parametrize("i", range(20))
def test_check_figures_of_twenty_random_designs_are_the_reference_paths(i, tmp_path, monkeypatch):
    _same_check_as_the_references(_random_docs(20, seed=4400)[i], tmp_path, monkeypatch)
