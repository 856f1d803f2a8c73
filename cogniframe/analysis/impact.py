"""The paper's lumped mass-spring-damper drop model (Kelvin-Voigt payload on the exoskeleton).

    m x'' + c x' + k x = m g,   x(0) = 0,   x'(0) = sqrt(2 g h)

x is the payload's displacement towards the ground after the frame touches it (m), m the total
mass (kg), c the damping (N s/m), k the stiffness (N/m), h the drop height (m), g the gravity of analysis/constants.py.
The model holds until x reaches the clearance (16 mm on the carbon build: the battery holder
touches the ground). Units inside are SI; every public result field names its unit.

The response has a closed form in every damping regime (under-, critically and over-damped),
written here in a form that stays accurate across the critical boundary, so nothing needs an
ODE solver: a whole drop evaluates in microseconds, which the fitter (:mod:`.fit`) relies on.
Tests cross-check it against ``scipy.integrate.solve_ivp``.

Pure numpy/scipy; importing this module imports no plotting or CAD library.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np

from .constants import G  # also converts m/s^2 to G

PAPER_CLEARANCE_MM = 16.0
"""Battery-holder underside above the ground plane on the carbon build (mm)."""

# Relative band around zeta = 1 treated as exactly critical. Inside it the under/over-damped
# expressions are still accurate (see _modes), this only avoids dividing by a zero root.
_CRITICAL_EPS = 1e-12


@dataclass(frozen=True)
class HeightResult:
    """The model's answer for one drop height.

    ``x_max_mm`` and ``t_max_s`` are the unconstrained model's maximum compression and its time
    (``inf`` if an over-damped payload only creeps towards m g / k); ``strikes`` says whether
    that maximum reaches the clearance, i.e. the battery holder hits the ground. Energies are
    the paper's split of the touch-down kinetic energy ``energy_j`` (percentages sum to 100).
    ``peak_g`` is the largest |acceleration| in G until x_max, or until the strike.
    """

    height_cm: float
    v_impact_m_per_s: float
    x_max_mm: float
    t_max_s: float
    peak_g: float
    energy_j: float
    energy_spring_pct: float
    energy_damper_pct: float
    energy_rigid_pct: float
    strikes: bool

    def to_dict(self) -> dict:
        """JSON-ready dict (an infinite ``t_max_s`` becomes ``None``)."""
        return {
            "height_cm": self.height_cm,
            "v_impact_m_per_s": self.v_impact_m_per_s,
            "x_max_mm": self.x_max_mm,
            "t_max_s": self.t_max_s if math.isfinite(self.t_max_s) else None,
            "peak_g": self.peak_g,
            "energy_j": self.energy_j,
            "energy_spring_pct": self.energy_spring_pct,
            "energy_damper_pct": self.energy_damper_pct,
            "energy_rigid_pct": self.energy_rigid_pct,
            "strikes": self.strikes,
        }


@dataclass(frozen=True)
class DropResult:
    """The model evaluated at several heights for one (m, c, k, clearance).

    ``k_source`` / ``c_source`` record where each parameter came from: ``"predicted"`` (from the
    frame's geometry), ``"measured"`` (static test or drop-test fit) or ``"given"`` (typed in).
    """

    k_n_per_m: float
    c_n_s_per_m: float
    damping_ratio: float
    mass_kg: float
    clearance_mm: float
    max_safe_height_cm: float
    k_source: str
    c_source: str
    heights: tuple[HeightResult, ...]

    def to_dict(self) -> dict:
        """JSON-ready dict; ``heights`` is a list of :meth:`HeightResult.to_dict`."""
        return {
            "k_n_per_m": self.k_n_per_m,
            "c_n_s_per_m": self.c_n_s_per_m,
            "damping_ratio": self.damping_ratio,
            "mass_kg": self.mass_kg,
            "clearance_mm": self.clearance_mm,
            "max_safe_height_cm": (
                self.max_safe_height_cm if math.isfinite(self.max_safe_height_cm) else None
            ),
            "k_source": self.k_source,
            "c_source": self.c_source,
            "heights": [h.to_dict() for h in self.heights],
        }


# --------------------------------------------------------------------------------------------
# Parameters


def damping_ratio(c_n_s_per_m: float, k_n_per_m: float, mass_kg: float) -> float:
    """zeta = c / (2 sqrt(k m)) (dimensionless)."""
    return c_n_s_per_m / (2.0 * math.sqrt(k_n_per_m * mass_kg))


def damping_from_ratio(zeta: float, k_n_per_m: float, mass_kg: float) -> float:
    """c = 2 zeta sqrt(k m) in N s/m, for a damping ratio ``zeta``, k in N/m, m in kg."""
    return 2.0 * zeta * math.sqrt(k_n_per_m * mass_kg)


def impact_velocity(height_cm: float, g: float = G) -> float:
    """Touch-down speed sqrt(2 g h) in m/s of a drag-free drop from ``height_cm``."""
    return math.sqrt(2.0 * g * height_cm / 100.0)


def _check(mass_kg: float, c: float, k: float) -> None:
    # Library callers get ValueError; the CLI turns bad options into UserError before this.
    if not (mass_kg > 0 and math.isfinite(mass_kg)):
        raise ValueError(f"mass must be a positive number of kg, got {mass_kg!r}")
    if not (k > 0 and math.isfinite(k)):
        raise ValueError(f"stiffness k must be a positive number of N/m, got {k!r}")
    if not (c >= 0 and math.isfinite(c)):
        raise ValueError(f"damping c must be a non-negative number of N s/m, got {c!r}")


# --------------------------------------------------------------------------------------------
# Closed-form response


@dataclass(frozen=True)
class _System:
    """Derived constants of m x'' + c x' + k x = m g (SI)."""

    m: float
    c: float
    k: float
    g: float
    alpha: float  # c / 2m, decay rate (1/s)
    w0sq: float  # k / m (1/s^2)
    wdsq: float  # w0^2 - alpha^2: > 0 under-, < 0 over-damped
    xs: float  # static deflection m g / k (m)

    @staticmethod
    def of(m: float, c: float, k: float, g: float = G) -> "_System":
        alpha = c / (2.0 * m)
        w0sq = k / m
        wdsq = w0sq - alpha * alpha
        if abs(wdsq) <= _CRITICAL_EPS * w0sq:
            wdsq = 0.0
        return _System(m, c, k, g, alpha, w0sq, wdsq, m * g / k)


def _modes(sys: _System, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """exp(-alpha t) C(t) and exp(-alpha t) S(t): the two homogeneous modes.

    C(0) = 1, C'(0) = 0; S(0) = 0, S'(0) = 1; S' = C and C' = -wd^2 S in every regime:
    cos(wd t), sin(wd t)/wd (under-damped); 1, t (critical); cosh(s t), sinh(s t)/s with
    s = sqrt(alpha^2 - w0^2) (over-damped). The over-damped pair is written with
    exp(-(alpha - s) t) and expm1 so it neither overflows for long t nor cancels near
    critical damping.
    """
    t = np.asarray(t, dtype=float)
    a = sys.alpha
    if sys.wdsq > 0.0:
        wd = math.sqrt(sys.wdsq)
        decay = np.exp(-a * t)
        return decay * np.cos(wd * t), decay * np.sin(wd * t) / wd
    if sys.wdsq == 0.0:
        decay = np.exp(-a * t)
        return decay, decay * t
    s = math.sqrt(-sys.wdsq)
    slow = sys.w0sq / (a + s)  # alpha - s without cancellation
    e_slow = np.exp(-slow * t)
    e_2s = np.expm1(-2.0 * s * t)  # exp(-2 s t) - 1
    return e_slow * (1.0 + 0.5 * e_2s), e_slow * (-0.5 * e_2s) / s


def _state(sys: _System, v0: float, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Displacement x (m) and velocity x' (m/s) at times t (s) after touch-down at speed v0."""
    ec, es = _modes(sys, t)
    y0 = -sys.xs  # offset from the static equilibrium at t = 0
    x = sys.xs + y0 * ec + (v0 + sys.alpha * y0) * es
    # y' = v0 C - (alpha v0 + w0^2 y0) S, and w0^2 y0 = -g.
    v = v0 * ec - (sys.alpha * v0 - sys.g) * es
    return x, v


def _state_at(sys: _System, v0: float, t: float) -> tuple[float, float]:
    """`_state` at one time, in plain floats (the scalar root and maximum searches call it
    thousands of times per design; a one-element array costs ten times more)."""
    a = sys.alpha
    if sys.wdsq > 0.0:
        wd = math.sqrt(sys.wdsq)
        decay = math.exp(-a * t)
        ec, es = decay * math.cos(wd * t), decay * math.sin(wd * t) / wd
    elif sys.wdsq == 0.0:
        ec = math.exp(-a * t)
        es = ec * t
    else:
        sq = math.sqrt(-sys.wdsq)
        e_slow = math.exp(-sys.w0sq / (a + sq) * t)
        e_2s = math.expm1(-2.0 * sq * t)
        ec, es = e_slow * (1.0 + 0.5 * e_2s), e_slow * (-0.5 * e_2s) / sq
    y0 = -sys.xs
    return sys.xs + y0 * ec + (v0 + a * y0) * es, v0 * ec - (a * v0 - sys.g) * es


def _accel(sys: _System, x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Payload acceleration x'' = g - (k x + c x') / m in m/s^2 (positive towards the ground)."""
    return sys.g - (sys.k * x + sys.c * v) / sys.m


def response(
    t_s: np.ndarray, mass_kg: float, c_n_s_per_m: float, k_n_per_m: float, v0_m_per_s: float,
    g: float = G,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unconstrained model response at times ``t_s`` (s) after touch-down at ``v0_m_per_s``.

    Returns (x in m, x' in m/s, x'' in m/s^2), positive towards the ground. Exact closed form.
    """
    sys = _System.of(mass_kg, c_n_s_per_m, k_n_per_m, g)
    x, v = _state(sys, v0_m_per_s, np.asarray(t_s, dtype=float))
    return x, v, _accel(sys, x, v)


def _time_of_max(sys: _System, v0: float) -> float:
    """First t > 0 with x'(t) = 0, in s; ``inf`` when the payload never turns back.

    x' = 0  <=>  v0 C(t) = B S(t) with B = alpha v0 - g; solved per regime. The three
    expressions meet continuously at critical damping (all tend to v0 / B).
    """
    b = sys.alpha * v0 - sys.g
    if sys.wdsq > 0.0:
        wd = math.sqrt(sys.wdsq)
        # atan2 picks the root in (0, pi): the first one, since x' > 0 just after touch-down.
        return math.atan2(v0 * wd, b) / wd
    if b <= 0.0:
        return math.inf  # damping alone cannot stop it before gravity's equilibrium
    if sys.wdsq == 0.0:
        return v0 / b
    s = math.sqrt(-sys.wdsq)
    r = s * v0 / b
    return math.atanh(r) / s if r < 1.0 else math.inf


def _x_max(sys: _System, v0: float) -> tuple[float, float]:
    """(x_max in m, its time in s) of the unconstrained model."""
    t_max = _time_of_max(sys, v0)
    if not math.isfinite(t_max):
        return sys.xs, t_max  # supremum, approached as t -> inf
    return _state_at(sys, v0, t_max)[0], t_max


def _settle_time(sys: _System) -> float:
    """A time (s) after which the transient is below 1e-9 of its start: a finite horizon."""
    slowest = sys.alpha if sys.wdsq >= 0.0 else sys.w0sq / (sys.alpha + math.sqrt(-sys.wdsq))
    if slowest <= 0.0:  # undamped: never settles; one period is the longest we ever look at
        return 2.0 * math.pi / math.sqrt(sys.w0sq)
    return 21.0 / slowest  # exp(-21) ~ 1e-9


# Scalar solver. Every root here is bracketed and the function monotone on the bracket:
# bisection is exact enough, and keeps scipy.optimize (~0.4 s to import) out of `cogniframe check`.
def _bisect(f, lo: float, hi: float, xtol: float) -> float:
    """Root of f on [lo, hi] with f(lo) < 0 <= f(hi)."""
    for _ in range(200):
        if hi - lo <= xtol:
            break
        mid = 0.5 * (lo + hi)
        if f(mid) < 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _time_to_reach(sys: _System, v0: float, x_target: float, t_hi: float) -> float:
    """First t in (0, t_hi] where x(t) = x_target; x increases monotonically there."""
    f = lambda t: _state_at(sys, v0, t)[0] - x_target  # noqa: E731
    if f(t_hi) <= 0.0:
        return t_hi
    return _bisect(f, 0.0, t_hi, xtol=1e-14)


def _peak_abs_accel(sys: _System, v0: float, t_end: float) -> float:
    """max |a| over [0, t_end] in m/s^2 (a = x'', the payload's acceleration), in closed form.

    a is a combination of the two homogeneous modes, a = P Ec + Q Es (Ec, Es as in `_modes`;
    P = a(0) = g - c v0 / m), so its extrema are where its derivative (Q - alpha P) Ec -
    (P wd^2 + alpha Q) Es vanishes: R C(t) = W S(t), solved per regime like `_time_of_max`
    (under-damped: every half period from one atan2; critical: one root; over-damped: at most
    one, from atanh). |a| is largest at one of them or at an end of the interval.
    """
    if t_end <= 0.0:
        return abs(_accel(sys, *_state_at(sys, v0, 0.0)))
    al = sys.alpha
    y0 = -sys.xs
    p = -sys.w0sq * y0 - 2.0 * al * v0  # a(0)
    q = -sys.w0sq * (v0 + al * y0) + 2.0 * al * (al * v0 - sys.g)
    r, w = q - al * p, p * sys.wdsq + al * q
    times = [0.0, t_end]
    if sys.wdsq > 0.0:
        wd = math.sqrt(sys.wdsq)
        first = math.atan2(r * wd, w) % math.pi / wd  # tan(wd t) = R wd / W: the first root at or after 0
        times += [t for t in (first + n * math.pi / wd for n in range(int(t_end * wd / math.pi) + 2)) if 0.0 < t < t_end]
    elif sys.wdsq == 0.0:
        if w != 0.0 and 0.0 < r / w < t_end:
            times.append(r / w)
    elif w != 0.0:
        s = math.sqrt(-sys.wdsq)
        z = r * s / w  # tanh(s t) = R s / W
        if 0.0 < z < 1.0 and math.atanh(z) / s < t_end:
            times.append(math.atanh(z) / s)
    return max(abs(_accel(sys, *_state_at(sys, v0, t))) for t in times)


# --------------------------------------------------------------------------------------------
# Public API


def simulate_height(
    mass_kg: float,
    c_n_s_per_m: float,
    k_n_per_m: float,
    height_cm: float,
    clearance_mm: float = PAPER_CLEARANCE_MM,
    g: float = G,
) -> HeightResult:
    """Evaluate one drop from ``height_cm`` (cm) for m (kg), c (N s/m), k (N/m).

    Energy split as in the paper: the touch-down kinetic energy E_k = m v^2 / 2 is 100 %.
    If x_max < clearance: spring = k x_max^2 / 2, damper = the rest, rigid = 0. If the payload
    reaches the clearance x_c: spring = k x_c^2 / 2, rigid = kinetic energy left at x = x_c,
    damper = the rest. Like the paper, the split leaves out the work m g x that gravity does
    during the compression (about 2 % of E_k at 50 cm on the carbon build), so for a barely
    damped frame the damper share can come out slightly negative.
    """
    _check(mass_kg, c_n_s_per_m, k_n_per_m)
    if not (height_cm >= 0 and math.isfinite(height_cm)):
        raise ValueError(f"drop height must be a non-negative number of cm, got {height_cm!r}")
    if not clearance_mm > 0:
        raise ValueError(f"clearance must be a positive number of mm, got {clearance_mm!r}")

    sys = _System.of(mass_kg, c_n_s_per_m, k_n_per_m, g)
    v0 = impact_velocity(height_cm, g)
    x_c = clearance_mm / 1000.0
    x_max, t_max = _x_max(sys, v0)
    strikes = x_max >= x_c

    e_k = 0.5 * mass_kg * v0 * v0
    if strikes:
        t_hit = _time_to_reach(sys, v0, x_c, t_max if math.isfinite(t_max) else _settle_time(sys))
        _, v_hit = _state_at(sys, v0, t_hit)
        e_spring = 0.5 * k_n_per_m * x_c * x_c
        e_rigid = 0.5 * mass_kg * v_hit**2
        t_end = t_hit
    else:
        e_spring = 0.5 * k_n_per_m * x_max * x_max
        e_rigid = 0.0
        t_end = t_max if math.isfinite(t_max) else _settle_time(sys)

    def pct(e: float) -> float:
        return 100.0 * e / e_k if e_k > 0.0 else 0.0

    spring_pct, rigid_pct = pct(e_spring), pct(e_rigid)
    # Damper as the remainder so the three always sum to exactly 100 (0 when nothing moves).
    damper_pct = 100.0 - spring_pct - rigid_pct if e_k > 0.0 else 0.0

    return HeightResult(
        height_cm=float(height_cm),
        v_impact_m_per_s=v0,
        x_max_mm=x_max * 1000.0,
        t_max_s=t_max,
        peak_g=_peak_abs_accel(sys, v0, t_end) / g,
        energy_j=e_k,
        energy_spring_pct=spring_pct,
        energy_damper_pct=damper_pct,
        energy_rigid_pct=rigid_pct,
        strikes=bool(strikes),
    )


def _lowpass_coefficients(dt_s: float, w_rad_per_s: float) -> tuple[float, float, float, float]:
    """(a = w dt, E = exp(-a), b0, b1) of the first-order low-pass recurrence below."""
    a = w_rad_per_s * dt_s
    e = math.exp(-a)
    one_minus_e = -math.expm1(-a)
    return a, e, one_minus_e / a - e, 1.0 - one_minus_e / a


def lowpass_first_order(u: np.ndarray, dt_s: float, w_rad_per_s: float) -> np.ndarray:
    """Filter samples ``u`` (uniform step ``dt_s``) through H(s) = w / (s + w), from rest.

    Exact discretisation for an input interpolated linearly between samples, which is what
    ``scipy.signal.lsim`` does by default, so the result equals
    ``lsim((w, [1, w]), u, t)[1]`` (output 0 at t = 0) at a tiny fraction of its cost:
        y[n+1] = E y[n] + b0 u[n] + b1 u[n+1],  E = exp(-w dt),
        b1 = 1 - (1 - E) / (w dt),  b0 = (1 - E) / (w dt) - E.
    """
    u = np.asarray(u, dtype=float)
    if u.size == 0:
        return u.copy()
    _, e, b0, b1 = _lowpass_coefficients(dt_s, w_rad_per_s)
    from scipy.signal import lfilter  # imported here: scipy.signal costs ~0.6 s, and `check` never filters

    # zi = -b1 u[0] makes y[0] = 0: the filter starts from rest (lfilter is DF-II transposed).
    y, _ = lfilter([b1, b0], [1.0, -e], u, zi=[-b1 * u[0]])
    return y


def lowpass_first_order_np(u: np.ndarray, dt_s: float, w_rad_per_s: float) -> np.ndarray:
    """`lowpass_first_order` in numpy alone (no scipy.signal: its import costs `check` 0.6-1 s).

    The same recurrence y[n+1] = E y[n] + c[n], c[n] = b0 u[n] + b1 u[n+1], solved in closed
    form chunk by chunk: y[s+j] = E^j (y[s] + sum_{k<j} E^-(k+1) c[s+k]), with chunks short enough
    that E^-j stays below 1e150 (no overflow; the rounding is that of the recurrence's, relative
    to the signal's size). tests/test_impact.py checks it against `lowpass_first_order`."""
    u = np.asarray(u, dtype=float)
    if u.size == 0:
        return u.copy()
    a, _, b0, b1 = _lowpass_coefficients(dt_s, w_rad_per_s)
    c = b0 * u[:-1] + b1 * u[1:]
    y = np.zeros(u.size)
    chunk = max(1, int(345.0 / a))  # 345 = ln(1e150)
    for s in range(0, c.size, chunk):
        cc = c[s:s + chunk]
        j = np.arange(1, cc.size + 1)
        y[s + 1:s + 1 + cc.size] = np.exp(-a * j) * (y[s] + np.cumsum(np.exp(a * j) * cc))
    return y


def trajectory(
    mass_kg: float,
    c: float,
    k: float,
    height_cm: float,
    t_end_s: float | None = None,
    n: int = 2000,
    lowpass_rad_per_s: float | None = None,
    g: float = G,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sampled unconstrained response for plots: (t in s, x in m, x' in m/s, |x''| in G).

    The acceleration is the magnitude an accelerometer on the payload would report (what the
    paper compares with). ``lowpass_rad_per_s`` passes it through w / (s + w) as in the fit.
    Default ``t_end_s``: twice the time of x_max (or the settling time if there is none).
    """
    _check(mass_kg, c, k)
    sys = _System.of(mass_kg, c, k, g)
    v0 = impact_velocity(height_cm, g)
    if t_end_s is None:
        t_max = _time_of_max(sys, v0)
        t_end_s = 2.0 * t_max if math.isfinite(t_max) else _settle_time(sys)
    t = np.linspace(0.0, float(t_end_s), int(n))
    x, v = _state(sys, v0, t)
    a_g = np.abs(_accel(sys, x, v)) / g
    if lowpass_rad_per_s is not None and t.size > 1:
        a_g = lowpass_first_order(a_g, t[1] - t[0], lowpass_rad_per_s)
    return t, x, v, a_g


def max_safe_height_cm(
    mass_kg: float, c: float, k: float, clearance_mm: float = PAPER_CLEARANCE_MM, g: float = G
) -> float:
    """Highest drop (cm) whose x_max stays within ``clearance_mm`` (bisection on x_max(h) = x_c).

    x_max grows monotonically with the impact speed, so the root is unique. Returns 0 if the
    payload reaches the clearance even when set down from rest (x_max(0) >= clearance).
    """
    _check(mass_kg, c, k)
    sys = _System.of(mass_kg, c, k, g)
    x_c = clearance_mm / 1000.0

    def excess(h_cm: float) -> float:
        return _x_max(sys, impact_velocity(h_cm, g))[0] - x_c

    if excess(0.0) >= 0.0:
        return 0.0
    hi = 100.0
    while excess(hi) <= 0.0:
        hi *= 2.0
        if hi > 1e9:  # x_max grows ~ sqrt(h); this only trips on absurd inputs
            return math.inf
    return _bisect(excess, 0.0, hi, xtol=1e-9)


def evaluate(
    mass_kg: float,
    c: float,
    k: float,
    heights_cm: Iterable[float],
    clearance_mm: float = PAPER_CLEARANCE_MM,
    k_source: str = "given",
    c_source: str = "given",
    g: float = G,
) -> DropResult:
    """Run :func:`simulate_height` for each height and bundle it with the max safe height."""
    for name, src in (("k_source", k_source), ("c_source", c_source)):
        if src not in ("predicted", "measured", "given"):
            raise ValueError(f"{name} must be 'predicted', 'measured' or 'given', got {src!r}")
    heights = tuple(simulate_height(mass_kg, c, k, h, clearance_mm, g) for h in heights_cm)
    return DropResult(
        k_n_per_m=float(k),
        c_n_s_per_m=float(c),
        damping_ratio=damping_ratio(c, k, mass_kg),
        mass_kg=float(mass_kg),
        clearance_mm=float(clearance_mm),
        max_safe_height_cm=max_safe_height_cm(mass_kg, c, k, clearance_mm, g),
        k_source=k_source,
        c_source=c_source,
        heights=heights,
    )
