"""One drop's peak |a| as a distribution (analysis/single_drop.py): its analytic pieces against
their closed forms, and the honest validation on the paper's data shipped in examples/ (learn on
one height, predict the other) with the errors docs/impact-model.md reports."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cogniframe.analysis import droplogs as L
from cogniframe.analysis import fit as F
from cogniframe.analysis import impact_nl as N
from cogniframe.analysis import single_drop as S
from cogniframe.analysis.impact import G, impact_velocity

DROPS = Path(__file__).resolve().parents[1] / "examples" / "droptests"
MEASURED = {50: (89.70, 111.90), 100: (127.36, 157.22)}  # median, p90 of the per-trial peaks (G)


# ---- closed forms ----------------------------------------------------------------------------


@pytest.mark.parametrize("zeta", [0.0, 0.1, 0.2743, 0.6])
def test_mount_step_response_peak_matches_closed_form(zeta):
    # unit step of base acceleration: 1 + overshoot, 2 when undamped
    a = S.mount_response(np.ones(40001), 1e-5, 100.0, zeta)
    assert a.max() == pytest.approx(S.mount_step_peak(zeta), rel=1e-5)  # the 10 us grid brackets the peak
    assert S.mount_step_peak(0.0) == 2.0


def test_mount_response_is_the_closed_form_step_response_at_every_instant():
    zeta, f, dt = 0.3, 400.0, 2e-5
    t = np.arange(2001) * dt
    w, wd = 2 * math.pi * f, math.sqrt(1 - zeta ** 2)
    closed = 1 - np.exp(-zeta * w * t) * (np.cos(wd * w * t) - zeta / wd * np.sin(wd * w * t))
    assert S.mount_response(np.ones_like(t), dt, f, zeta) == pytest.approx(closed, abs=1e-9)


def test_mount_passes_a_slow_pulse_unchanged():
    # a 400 Hz mount under a 15 ms pulse: quasi-static, the logger reads the pulse
    t = np.arange(4001) * S.DT_S
    u = np.sin(math.pi * t / 0.015) * (t < 0.015)
    assert S.mount_response(u, S.DT_S, 2000.0, 0.3) == pytest.approx(u, abs=0.015)  # a 1 % lag of the mount


def test_tilted_landing_staggers_the_feet_by_the_closed_form():
    # tilt theta about the diagonal's normal: the far foot lands d sin(theta) / v0 after the first
    feet = S.feet((210.0, 210.0))
    theta, v0 = math.radians(1.0), impact_velocity(50.0)
    tj = S.foot_delays_s(feet, np.array([theta]), np.array([math.pi / 4]), v0)[0]
    diag = math.hypot(0.21, 0.21)
    assert sorted(tj) == pytest.approx([0.0, diag / 2 * math.sin(theta) / v0, diag / 2 * math.sin(theta) / v0,
                                        diag * math.sin(theta) / v0], abs=1e-12)
    assert tj.max() == pytest.approx(1.656e-3, rel=1e-3)  # 1 degree, 50 cm: 1.7 ms between first and last foot


def test_flat_landing_on_a_rigid_mount_samples_the_pulse():
    # no tilt, no mount: each drop's peak is the pulse at its first sample, between f(1 ms) and f(0)
    m, c, k = 0.241, 46.0, 7040.0
    pulse = S.kv_pulse_g(m, c, k, 50.0)
    peaks = S.drop_peaks(pulse, 50.0, S.Scatter(0.0, 0.0, 0.0))
    assert pulse[0] == pytest.approx(c * impact_velocity(50.0) / m / G, rel=1e-9)  # the damper's step, 60.9 G
    assert peaks.max() <= pulse.max() + 1e-9
    assert peaks.min() >= pulse[int(round(1e-3 / S.DT_S))] - 1e-9


def test_seeded_same_params_give_identical_peaks():
    pulse = S.kv_pulse_g(0.241, 70.0, 4500.0, 100.0)
    a = S.drop_peaks(pulse, 100.0, S.PAPER_SCATTER)
    b = S.drop_peaks(pulse, 100.0, S.PAPER_SCATTER)
    assert a.tobytes() == b.tobytes()


def test_single_drop_peaks_are_linear_in_the_pulse_amplitude():
    # the mount and the sampling are linear: a pulse twice as large gives peaks twice as large
    pulse = S.kv_pulse_g(0.241, 70.0, 4500.0, 50.0)
    a = S.drop_peaks(pulse, 50.0, S.PAPER_SCATTER)
    assert S.drop_peaks(2 * pulse, 50.0, S.PAPER_SCATTER) == pytest.approx(2 * a, rel=1e-12)


# ---- validation on the paper's drops -----------------------------------------------------------


@pytest.fixture(scope="module")
def heights():
    return {h: L.load_height([DROPS / f"SoftBottom_{h}cm"], h) for h in (50, 100)}


def _validate(hd_fit, kind):
    """Fit the pulse and the scatter on one height, return {height: (median, p90)} for both."""
    if kind == "kelvin-voigt":
        r = F.fit_drop_tests([hd_fit], 0.241)
        pulse = lambda h: S.kv_pulse_g(0.241, r.c_n_s_per_m, r.k_n_per_m, h)  # noqa: E731
    else:
        r = F.fit_nonlinear([hd_fit], 0.241, N.PAPER_EXO_MASS_KG)
        pulse = lambda h: S.two_mass_pulse_g(r.params(), h)  # noqa: E731
    sf = S.fit_scatter([hd_fit], pulse)
    out = {}
    for h in (50, 100):
        d = S.distribution(S.drop_peaks(pulse(h), h, sf.scatter))
        out[h] = (d["peak_g_drop_median"], d["peak_g_drop_p90"])
    return sf, out


@pytest.fixture(scope="module")
def on50(heights):
    return {kind: _validate(heights[50], kind) for kind in N.MODELS}


def _err(pred, h):
    return tuple(p / m - 1 for p, m in zip(pred[h], MEASURED[h]))


def test_single_drop_median_exceeds_mean_pulse_peak(heights):
    # the measured fact the model is built for: the median of per-trial maxima is ~1.7-1.8x the
    # peak of the mean trace
    for h, hd in heights.items():
        assert np.median(hd.a_g.max(axis=1)) / hd.a_g.mean(axis=0).max() == pytest.approx({50: 1.795, 100: 1.695}[h], abs=0.01)
    # and the model reproduces it: 100 cm single-drop median vs the KV mean pulse (68.2 G)
    kv = F.fit_drop_tests([heights[50]], 0.241)
    pulse = S.kv_pulse_g(0.241, kv.c_n_s_per_m, kv.k_n_per_m, 100.0)
    med = np.median(S.drop_peaks(pulse, 100.0, S.PAPER_SCATTER))
    assert med > 1.8 * N.kv_logger_peak_g(0.241, kv.c_n_s_per_m, kv.k_n_per_m, 100.0)


def test_scatter_learnt_on_50cm_reproduces_its_quantiles(on50):
    sf, pred = on50["kelvin-voigt"]
    for row in sf.heights:
        for q in ("p25", "p50", "p75", "p90"):
            assert row["simulated"][q] == pytest.approx(row["measured"][q], rel=0.02)


def test_fit_on_50_predict_100_single_drop_errors_as_documented(on50):
    # docs/impact-model.md: KV +9.3 % (median) / +3.0 % (p90); two-mass +8.9 % / +10.3 %
    kv = _err(on50["kelvin-voigt"][1], 100)
    nl = _err(on50["nonlinear"][1], 100)
    assert kv == pytest.approx((0.093, 0.030), abs=0.02)
    assert nl == pytest.approx((0.089, 0.103), abs=0.02)


def test_fit_on_100_predict_50_single_drop_errors_as_documented(heights):
    # the reverse: KV -9.9 % / -6.6 %; the model's peaks grow faster with v0 than the data's
    sf, pred = _validate(heights[100], "kelvin-voigt")
    assert _err(pred, 50) == pytest.approx((-0.099, -0.066), abs=0.02)
    # the scatter learnt at 100 cm is close to the one learnt at 50 cm
    assert sf.scatter.mount_zeta == pytest.approx(S.PAPER_SCATTER.mount_zeta, abs=0.03)
    assert sf.scatter.tilt_sigma_deg == pytest.approx(S.PAPER_SCATTER.tilt_sigma_deg, abs=0.1)


def test_paper_scatter_is_the_50cm_kelvin_voigt_fit(on50):
    sf, _ = on50["kelvin-voigt"]
    assert sf.scatter.mount_hz == pytest.approx(S.PAPER_SCATTER.mount_hz, rel=0.01)
    assert sf.scatter.mount_zeta == pytest.approx(S.PAPER_SCATTER.mount_zeta, rel=0.01)
    assert sf.scatter.tilt_sigma_deg == pytest.approx(S.PAPER_SCATTER.tilt_sigma_deg, rel=0.01)


def test_check_model_has_the_smaller_single_drop_errors_at_100cm(on50):
    score = {k: sum(abs(e) for e in _err(v[1], 100)) for k, v in on50.items()}
    assert N.BEST_MODEL == min(score, key=score.get)


def test_design_peaks_carry_the_single_drop_distribution():
    d = N.design_peaks(0.241, 7040.0, 46.0, 0.062, [50, 100], 16.0, footprint_mm=(210.0, 210.0))
    h50, h100 = d["heights"]
    for h in (h50, h100):
        assert h["peak_g"] < h["peak_g_drop_median"] < h["peak_g_drop_p90"]
    assert h100["peak_g_drop_median"] / h50["peak_g_drop_median"] == pytest.approx(1.52, abs=0.05)
    assert d["single_drop"]["mount_hz"] == S.PAPER_SCATTER.mount_hz


def test_tilt_stagger_shrinking_with_speed_is_the_100cm_excess(heights):
    # without the tilt the model is linear in v0 (ratio sqrt 2); the learnt tilt's stagger d / v0
    # shortens at 100 cm and lifts the ratio to 1.54 (measured 1.42): docs/impact-model.md
    kv = F.fit_drop_tests([heights[50]], 0.241)
    pulse = {h: S.kv_pulse_g(0.241, kv.c_n_s_per_m, kv.k_n_per_m, h) for h in (50, 100)}

    def ratio(sc):
        return float(np.median(S.drop_peaks(pulse[100], 100, sc)) / np.median(S.drop_peaks(pulse[50], 50, sc)))

    flat = S.Scatter(S.PAPER_SCATTER.mount_hz, S.PAPER_SCATTER.mount_zeta, 0.0)
    assert ratio(flat) == pytest.approx(math.sqrt(2), rel=0.003)
    assert ratio(S.PAPER_SCATTER) == pytest.approx(1.544, abs=0.01)
    measured = float(np.median(heights[100].a_g.max(axis=1)) / np.median(heights[50].a_g.max(axis=1)))
    assert measured == pytest.approx(1.42, abs=0.005)
