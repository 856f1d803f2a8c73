"""The drop model against the paper's numbers, closed forms and an ODE solver."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.signal import lsim

from cogniframe.analysis.impact import (
    damping_from_ratio,
    damping_ratio,
    evaluate,
    lowpass_first_order,
    max_safe_height_cm,
    response,
    simulate_height,
    trajectory,
)

M, C, K = 0.241, 46.0, 7040.0  # the paper's carbon build
from cogniframe.analysis.constants import G  # noqa: E402


def rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


# ---- the paper ---------------------------------------------------------------------------


@pytest.mark.parametrize("height_cm, x_max_mm", [(50, 9.63), (100, 13.56), (150, 16.57)])
def test_paper_xmax_50_100_150cm(height_cm, x_max_mm):
    r = simulate_height(M, C, K, height_cm)
    assert rel(r.x_max_mm, x_max_mm) < 0.01


def test_paper_max_safe_height_139_7cm():
    h = max_safe_height_cm(M, C, K, 16.0)
    assert rel(h, 139.7) < 0.01
    # and it is where x_max meets the clearance: just below stays clear, just above strikes
    assert not simulate_height(M, C, K, h - 0.05).strikes
    assert simulate_height(M, C, K, h + 0.05).strikes


def test_paper_150cm_strikes_100cm_does_not():
    res = evaluate(M, C, K, [100, 150], 16.0)
    assert [h.strikes for h in res.heights] == [False, True]
    # 150 cm reports the unconstrained maximum (beyond the clearance), not the clearance
    assert res.heights[1].x_max_mm > 16.0


def test_paper_damping_ratio_0_558():
    assert rel(damping_ratio(C, K, M), 0.558) < 0.01
    assert rel(evaluate(M, C, K, [50]).damping_ratio, 0.558) < 0.01


def test_damping_from_ratio_inverts_damping_ratio():
    for zeta in (0.1, 0.558, 1.0, 3.0):
        c = damping_from_ratio(zeta, K, M)
        assert math.isclose(c, 2 * zeta * math.sqrt(K * M))
        assert math.isclose(damping_ratio(c, K, M), zeta)


# ---- energy split -------------------------------------------------------------------------


@pytest.mark.parametrize("c, k, h", [(46, 7040, 50), (46, 7040, 150), (10, 3000, 80),
                                     (200, 7040, 300), (69.5, 4323, 100)])
def test_energy_percentages_sum_to_100(c, k, h):
    r = simulate_height(M, c, k, h)
    total = r.energy_spring_pct + r.energy_damper_pct + r.energy_rigid_pct
    assert total == pytest.approx(100.0, abs=1e-9)
    assert r.energy_j == pytest.approx(0.5 * M * 2 * G * h / 100)


def test_energy_split_no_strike_is_spring_and_damper_only():
    r = simulate_height(M, C, K, 50)
    spring = 0.5 * K * (r.x_max_mm / 1000) ** 2 / (0.5 * M * 2 * G * 0.5) * 100
    assert r.energy_rigid_pct == 0.0
    assert r.energy_spring_pct == pytest.approx(spring, rel=1e-9)


def _ivp(m, c, k, h_cm, t_end, **kw):
    v0 = math.sqrt(2 * G * h_cm / 100)
    return solve_ivp(lambda t, s: [s[1], G - (c * s[1] + k * s[0]) / m], (0, t_end), [0.0, v0],
                     rtol=1e-11, atol=1e-14, dense_output=True, **kw)


def test_energy_rigid_is_kinetic_energy_left_at_clearance():
    # Reference: integrate until x = 16 mm with an event, then m v^2 / 2 there.
    h, xc = 200.0, 0.016
    hit = lambda t, s: s[0] - xc  # noqa: E731
    hit.terminal = True
    sol = _ivp(M, C, K, h, 0.1, events=hit)
    v_c = sol.y_events[0][0][1]
    e_k = 0.5 * M * 2 * G * h / 100
    r = simulate_height(M, C, K, h, 16.0)
    assert r.strikes
    assert r.energy_rigid_pct == pytest.approx(100 * 0.5 * M * v_c**2 / e_k, rel=1e-6)
    assert r.energy_spring_pct == pytest.approx(100 * 0.5 * K * xc**2 / e_k, rel=1e-9)


# ---- monotonicity -------------------------------------------------------------------------


def test_max_safe_height_monotonic_in_k_and_clearance():
    ks = [3000, 5000, 7040, 10000, 20000]
    hs = [max_safe_height_cm(M, C, k, 16.0) for k in ks]
    assert all(a < b for a, b in zip(hs, hs[1:])), hs
    clear = [8, 12, 16, 24, 40]
    hc = [max_safe_height_cm(M, C, K, x) for x in clear]
    assert all(a < b for a, b in zip(hc, hc[1:])), hc


def test_max_safe_height_zero_when_resting_payload_reaches_clearance():
    # m g / k = 0.241 * 9.81 / 100 = 23.6 mm > 16 mm: it sinks to the floor even set down gently
    assert max_safe_height_cm(M, 5.0, 100.0, 16.0) == 0.0


# ---- closed forms and the ODE solver -------------------------------------------------------


@pytest.mark.parametrize("h", [0.0, 30.0, 100.0, 262.0])
def test_undamped_matches_closed_form(h):
    # Energy balance with c = 0: m v0^2/2 + m g x = k x^2/2, so
    # x_max = mg/k + sqrt((mg/k)^2 + 2 m g h / k) and the peak |a| is there: k x_max/m - g.
    r = simulate_height(M, 0.0, K, h, clearance_mm=100.0)
    xs = M * G / K
    x_max = xs + math.sqrt(xs**2 + 2 * M * G * (h / 100) / K)
    assert r.x_max_mm == pytest.approx(x_max * 1000, rel=1e-9)
    assert r.peak_g == pytest.approx((K * x_max / M - G) / G, rel=1e-6)
    # time of x_max: x = xs + A sin(w t - phi) reaches xs + A at w t = pi/2 + phi, phi = asin(xs/A)
    w = math.sqrt(K / M)
    assert r.t_max_s == pytest.approx((math.pi / 2 + math.asin(xs / (x_max - xs))) / w, rel=1e-9)


CASES = {
    "underdamped (paper)": (M, 46.0, 7040.0),
    "lightly damped": (M, 5.0, 7040.0),
    "just under critical": (M, 2 * math.sqrt(4323 * M) * (1 - 1e-7), 4323.0),
    "critical": (M, 2 * math.sqrt(4323 * M), 4323.0),
    "just over critical": (M, 2 * math.sqrt(4323 * M) * (1 + 1e-7), 4323.0),
    "overdamped (two-height fit)": (M, 69.5, 4323.0),
    "heavily overdamped": (M, 400.0, 4323.0),
}


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("h", [10.0, 100.0])
def test_closed_form_agrees_with_solve_ivp(name, h):
    m, c, k = CASES[name]
    stop = lambda t, s: s[1]  # noqa: E731  first x' = 0
    stop.terminal, stop.direction = True, -1
    sol = _ivp(m, c, k, h, 1.0, events=stop)
    assert sol.t_events[0].size == 1, "reference found no maximum"
    t_ref, x_ref = sol.t_events[0][0], sol.y_events[0][0][0]
    r = simulate_height(m, c, k, h, clearance_mm=1000.0)
    assert r.t_max_s == pytest.approx(t_ref, rel=1e-6)
    assert r.x_max_mm == pytest.approx(x_ref * 1000, rel=1e-7)
    # peak |a| up to x_max, from a fine sampling of the reference
    tt = np.linspace(0, t_ref, 200001)
    x, v = sol.sol(tt)
    peak_ref = np.max(np.abs(G - (c * v + k * x) / m)) / G
    assert r.peak_g == pytest.approx(peak_ref, rel=1e-6)
    # the whole response, not just the maximum
    x_cf, v_cf, _ = response(tt[::1000], m, c, k, math.sqrt(2 * G * h / 100))
    np.testing.assert_allclose(x_cf, x[::1000], rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(v_cf, v[::1000], rtol=1e-7, atol=1e-10)


def test_overdamped_creep_has_no_maximum():
    # c so large the payload only creeps to m g / k: no finite time of maximum
    k = 4323.0
    r = simulate_height(M, 2000.0, k, 50)
    assert math.isinf(r.t_max_s)
    assert r.x_max_mm == pytest.approx(M * G / k * 1000)
    sol = _ivp(M, 2000.0, k, 50, 0.2)
    assert np.all(np.diff(sol.y[0]) >= 0) and sol.y[0][-1] <= M * G / k  # never turns back
    d = evaluate(M, 2000.0, k, [50]).to_dict()
    assert d["heights"][0]["t_max_s"] is None
    json.dumps(d)


# ---- filter, trajectory, API shape ----------------------------------------------------------


def test_lowpass_matches_lsim():
    rng = np.random.default_rng(1)
    u = np.abs(rng.normal(0, 50, 300))
    t = np.arange(300) / 1000
    _, y_ref, _ = lsim(([500.0], [1.0, 500.0]), u, t)
    np.testing.assert_allclose(lowpass_first_order(u, 1e-3, 500.0), y_ref, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("w, n", [(500.0, 300), (500.0, 2500), (40000.0, 700)])
def test_numpy_lowpass_matches_lsim_over_many_chunks(w, n):
    # the check's filter (no scipy.signal import): chunked closed form of the same recurrence;
    # 2500 samples at w dt = 0.5 and 700 at w dt = 40 span several chunks
    from cogniframe.analysis.impact import lowpass_first_order_np

    rng = np.random.default_rng(2)
    u = np.abs(rng.normal(0, 50, n))
    t = np.arange(n) / 1000
    _, y_ref, _ = lsim(([w], [1.0, w]), u, t)
    np.testing.assert_allclose(lowpass_first_order_np(u, 1e-3, w), y_ref, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(lowpass_first_order_np(u, 1e-3, w), lowpass_first_order(u, 1e-3, w), rtol=1e-12, atol=1e-12)


def test_trajectory_samples_the_model_and_filters_on_request():
    t, x, v, a = trajectory(M, C, K, 100, n=500)
    r = simulate_height(M, C, K, 100)
    assert t[-1] == pytest.approx(2 * r.t_max_s)
    assert x.max() * 1000 == pytest.approx(r.x_max_mm, rel=1e-4)
    assert a[0] == pytest.approx(abs(G - C * math.sqrt(2 * G) / M) / G)
    _, _, _, af = trajectory(M, C, K, 100, n=500, lowpass_rad_per_s=500.0)
    _, y_ref, _ = lsim(([500.0], [1.0, 500.0]), a, t)
    np.testing.assert_allclose(af, y_ref, rtol=1e-8, atol=1e-9)
    assert af[0] == 0.0


def test_to_dict_is_json_ready_with_required_keys():
    d = evaluate(M, C, K, [50, 150], k_source="measured", c_source="measured").to_dict()
    s = json.loads(json.dumps(d))
    for key in ("k_n_per_m", "c_n_s_per_m", "damping_ratio", "mass_kg", "clearance_mm",
                "max_safe_height_cm", "k_source", "c_source", "heights"):
        assert key in s
    for key in ("height_cm", "x_max_mm", "peak_g", "energy_spring_pct", "energy_damper_pct",
                "energy_rigid_pct", "strikes"):
        assert key in s["heights"][0]
    assert [h["strikes"] for h in s["heights"]] == [False, True]
    assert s["k_source"] == "measured"


@pytest.mark.parametrize("args", [(-0.2, C, K, 50), (M, -1.0, K, 50), (M, C, 0.0, 50),
                                  (M, C, K, -10)])
def test_rejects_unphysical_inputs(args):
    with pytest.raises(ValueError):
        simulate_height(*args)


def test_rejects_unknown_source():
    with pytest.raises(ValueError):
        evaluate(M, C, K, [50], k_source="guessed")
