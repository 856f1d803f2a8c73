"""Peak deceleration: a two-mass drop model with a unilateral floor contact (docs/impact-model.md).

The paper's Kelvin-Voigt model (`impact`) treats the whole aircraft as one mass on one spring
and damper. Its acceleration jumps to c v0 / m at touch-down and decays; through the logger's
500 rad/s low-pass that step comes out at about half the measured peaks (fitted on 50 cm: 48 G
against 90 G). The drop data say what is missing:

- the peaks scale with the impact speed to the power 1.01 (89.7 G at 3.13 m/s, 127.4 G at
  4.43 m/s): the response is linear in v0, which rules out a stiffening spring or a
  Hunt-Crossley contact F ~ x^n (n = 1.5 would scale peaks as v0^1.2);
- the median trace has an early spike one sample after the impact and the main hump 7-8 ms
  later: two time scales, i.e. two masses.

So the model here is linear with two masses -- the exoskeleton (rods + TPU joints, its own mass
m_e; it touches the floor first) and the payload (m - m_e) -- joined by the frame's spring and
damper (k, c, as in the paper), with the exoskeleton on the floor through a contact spring and
damper (k_c, c_c) that can only push (it lets go if the exoskeleton bounces):

    m_p x_p'' = m_p g - k (x_p - x_e) - c (x_p' - x_e')
    m_e x_e'' = m_e g + k (x_p - x_e) + c (x_p' - x_e') - max(0, k_c x_e + c_c x_e')   (x_e > 0)

both starting at x = 0 with x' = sqrt(2 g h). The logger on the payload reads |x_p''| (the
paper's convention) through H(s) = w / (s + w). Piecewise linear: each phase is stepped exactly
with the matrix exponential, so a whole drop costs microseconds, like the closed-form KV model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .impact import G, impact_velocity, lowpass_first_order

MODELS = ("kelvin-voigt", "nonlinear")
SUBSTEPS = 20  # exact steps per logger sample; contact release is located to 1/SUBSTEPS ms

# The crash-test build's exoskeleton (rods + TPU joints), paper table: 62 g of the 241 g.
PAPER_EXO_MASS_KG = 0.062

# Contact law fitted ONCE to the paper's 50 cm drops (`cogniframe fit --model nonlinear` on
# examples/droptests/SoftBottom_50cm, m = 0.241 kg, m_e = 0.062 kg), as ratios to the frame's k
# and c, so that `check` can predict a new design's peaks from its own k, c and masses. The
# 100 cm drops were not used (they validate it: docs/impact-model.md).
CONTACT_K_RATIO = 201.4  # k_c / k: 7.434e5 / 3691 N/m
CONTACT_C_RATIO = 3.1e-5  # c_c / c: 0.0015 / 49.8 N s/m (the fit puts no damping in the contact)


@dataclass(frozen=True)
class TwoMass:
    m_kg: float  # total
    m_exo_kg: float
    k: float  # frame spring, N/m
    c: float  # frame damper, N s/m
    k_c: float  # floor contact spring, N/m
    c_c: float  # floor contact damper, N s/m

    def matrices(self, contact: bool) -> tuple[np.ndarray, np.ndarray]:
        """State y = (x_p, v_p, x_e, v_e): y' = A y + b."""
        mp, me = self.m_kg - self.m_exo_kg, self.m_exo_kg
        kc, cc = (self.k_c, self.c_c) if contact else (0.0, 0.0)
        A = np.array([
            [0, 1, 0, 0],
            [-self.k / mp, -self.c / mp, self.k / mp, self.c / mp],
            [0, 0, 0, 1],
            [self.k / me, self.c / me, -(self.k + kc) / me, -(self.c + cc) / me],
        ], dtype=float)
        b = np.array([0.0, G, 0.0, G])
        return A, b


def _step_operator(A: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact y(t + dt) = Phi y(t) + gamma for y' = A y + b (augmented matrix exponential)."""
    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))
    M[:n, :n] = A
    M[:n, n] = b
    E = _expm(M * dt)
    return E[:n, :n], E[:n, n]


def _expm(M: np.ndarray) -> np.ndarray:
    """Matrix exponential by scaling and squaring with an 18-term Taylor series (exact to
    rounding for these 5x5 matrices; scipy's expm costs 3 ms a call here, this 30 us).
    tests/test_impact_nl.py checks it against scipy.linalg.expm."""
    norm = float(np.abs(M).sum(axis=1).max())
    s = max(0, int(math.ceil(math.log2(norm))) + 1) if norm > 0 else 0
    A = M / 2.0**s
    E = np.eye(M.shape[0])
    term = np.eye(M.shape[0])
    for i in range(1, 19):
        term = term @ A / i
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


def two_mass_response(p: TwoMass, height_cm: float, n_samples: int, rate_hz: float = 1000.0):
    """(t, x_p, payload |a| in G, exo x_e) sampled at `rate_hz` from touch-down."""
    out = two_mass_states(p, height_cm, n_samples, rate_hz)
    xp, vp, xe, ve = out.T
    mp = p.m_kg - p.m_exo_kg
    a = G - (p.k * (xp - xe) + p.c * (vp - ve)) / mp
    t = np.arange(n_samples) / rate_hz
    return t, xp, np.abs(a) / G, xe


def two_mass_states(p: TwoMass, height_cm: float, n_samples: int, rate_hz: float = 1000.0) -> np.ndarray:
    """(n_samples, 4) states (x_p, v_p, x_e, v_e) sampled at `rate_hz` from touch-down.

    Each sample interval is one exact step of the current phase (contact or free); an interval
    in which the contact would change state is redone in SUBSTEPS exact sub-steps."""
    v0 = impact_velocity(height_cm)
    dt = 1.0 / rate_hz
    big = {c: _step_operator(*p.matrices(c), dt) for c in (True, False)}
    small = {c: _step_operator(*p.matrices(c), dt / SUBSTEPS) for c in (True, False)}

    def switch(contact: bool, y: np.ndarray) -> bool:
        if contact:
            return p.k_c * y[2] + p.c_c * y[3] < 0.0 or y[2] < 0.0
        return y[2] >= 0.0 and y[3] > 0.0

    y = np.array([0.0, v0, 0.0, v0])
    contact = True
    out = np.zeros((n_samples, 4))
    out[0] = y
    for i in range(1, n_samples):
        phi, gam = big[contact]
        y1 = phi @ y + gam
        if switch(contact, y1):
            for _ in range(SUBSTEPS):
                phi, gam = small[contact]
                y = phi @ y + gam
                if switch(contact, y):
                    contact = not contact
            y1 = y
        y = y1
        out[i] = y
    return out


def logger_peak_g(p: TwoMass, height_cm: float, lowpass_rad_per_s: float | None = 500.0, n_samples: int = 120) -> float:
    _, _, a, _ = two_mass_response(p, height_cm, n_samples)
    if lowpass_rad_per_s is not None:
        a = lowpass_first_order(a, 1e-3, lowpass_rad_per_s)
    return float(a.max())


def x_max_mm(p: TwoMass, height_cm: float, n_samples: int = 120) -> float:
    _, xp, _, _ = two_mass_response(p, height_cm, n_samples)
    return float(xp.max() * 1000.0)


def kv_logger_peak_g(m: float, c: float, k: float, height_cm: float, lowpass_rad_per_s: float | None = 500.0,
                     n_samples: int = 120, rate_hz: float = 1000.0) -> float:
    """Kelvin-Voigt peak |a| (G) as the logger sees it: the closed-form response sampled at
    `rate_hz` from touch-down, low-passed (what `fit.model_accel_g` computes; not imported from
    there, whose scipy.optimize import would cost `check` ~0.4 s; filtered in numpy alone)."""
    from .impact import lowpass_first_order_np, response

    t = np.arange(n_samples) / rate_hz
    _, _, a = response(t, m, c, k, impact_velocity(height_cm))
    a = np.abs(a) / G
    if lowpass_rad_per_s is not None:
        a = lowpass_first_order_np(a, 1.0 / rate_hz, lowpass_rad_per_s)
    return float(a.max())
