"""Peak-deceleration models: the two-mass model's physics, and the honest validation on the
paper's data (fit on 50 cm alone, predict 100 cm) that picks the model `check` uses."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cogniframe.analysis import droplogs as L

from cogniframe.analysis import fit as F
from cogniframe.analysis import impact_nl as N
from cogniframe.analysis import peaks
from cogniframe.analysis.impact import G, impact_velocity

ROOT = Path(__file__).resolve().parents[1]
DROPS = ROOT / "examples" / "droptests"
MEASURED_MEDIAN_PEAK = {50: 89.7, 100: 127.4}  # the paper's medians (and of these files)


def test_expm_matches_scipy():
    from scipy.linalg import expm

    p = N.TwoMass(0.241, 0.062, 4000.0, 50.0, 8e5, 1.0)
    A, b = p.matrices(True)
    M = np.zeros((5, 5))
    M[:4, :4], M[:4, 4] = A, b
    for dt in (1e-3, 5e-5):
        assert np.allclose(N._expm(M * dt), expm(M * dt), rtol=1e-10, atol=1e-12)


def test_two_mass_with_a_rigid_light_exoskeleton_is_the_kelvin_voigt_model():
    # m_e -> 0 and a very stiff contact: the payload sees the paper's closed form
    from cogniframe.analysis.impact import response

    m, c, k = 0.241, 46.0, 7040.0
    p = N.TwoMass(m, 1e-6, k, c, 1e9, 0.0)
    t, xp, a, _ = N.two_mass_response(p, 50.0, 8)  # up to x_max (7.3 ms); after it the feet may lift
    x_kv, _, a_kv = response(t, m - 1e-6, c, k, impact_velocity(50.0))
    assert np.allclose(xp, x_kv, atol=2e-5)  # m, 20 um of a 9.6 mm compression
    assert a[1:] == pytest.approx(np.abs(a_kv[1:]) / G, rel=0.02, abs=0.5)


def test_two_mass_momentum_and_contact_only_pushes():
    p = N.TwoMass(0.241, 0.062, 5000.0, 40.0, 5e5, 5.0)
    t, xp, a, xe = N.two_mass_response(p, 100.0, 80)
    assert xp.max() > xe.max() > 0  # the payload travels further than the frame's feet
    assert np.isfinite(a).all()


@pytest.fixture(scope="module")
def validation():
    h50 = L.load_height([DROPS / "SoftBottom_50cm"], 50)
    kv = F.fit_drop_tests([h50], 0.241)
    nl = F.fit_nonlinear([h50], 0.241, N.PAPER_EXO_MASS_KG)
    pred = {
        "kelvin-voigt": peaks.predict("kelvin-voigt", 0.241, kv.c_n_s_per_m, kv.k_n_per_m, [50, 100], 16.0),
        "nonlinear": peaks.predict("nonlinear", 0.241, nl.c_n_s_per_m, nl.k_n_per_m, [50, 100], 16.0,
                               m_exo=N.PAPER_EXO_MASS_KG, k_c=nl.contact_k_n_per_m, c_c=nl.contact_c_n_s_per_m),
    }
    return kv, nl, pred


def test_fit_on_50_predict_100_errors_as_documented(validation):
    kv, nl, pred = validation
    err = {m: pred[m][1]["peak_g"] / MEASURED_MEDIAN_PEAK[100] - 1 for m in pred}
    # docs/impact-model.md: both under-predict the 100 cm median peak by about half
    assert err["kelvin-voigt"] == pytest.approx(-0.465, abs=0.03)
    assert err["nonlinear"] == pytest.approx(-0.483, abs=0.03)
    # linear in v0 as the data are: peak(100) / peak(50) close to sqrt(2)
    for m in pred:
        assert pred[m][1]["peak_g"] / pred[m][0]["peak_g"] == pytest.approx(math.sqrt(2), rel=0.05)


def test_check_uses_the_model_that_predicts_100_cm_best(validation):
    _, _, pred = validation
    best = min(pred, key=lambda m: abs(pred[m][1]["peak_g"] - MEASURED_MEDIAN_PEAK[100]))
    assert peaks.BEST_MODEL == best


def test_contact_ratios_are_the_50cm_fit(validation):
    _, nl, _ = validation
    assert N.CONTACT_K_RATIO == pytest.approx(nl.contact_k_n_per_m / nl.k_n_per_m, rel=0.05)
