"""Fitting the drop model's c and k to accelerometer drop tests, and k to a static test.

The default procedure is exactly the paper's (see shared/data/droptests/README.md; steps 1-2,
the logs and the trials of each height, are `analysis/droplogs.py`):

1. per trial, |a| in G; the impact starts one sample before the first sample above 3 G and
   the series is kept from there; trials are cut to the shortest length of their height;
2. trials whose peak is below mean(peaks) - 6 std(peaks) are outliers;
3. the model's |x''| from touch-down (x = 0, x' = sqrt(2 g h)) is passed through
   H(s) = w / (s + w), w = 500 rad/s, on t = n / 1000 s, as ``scipy.signal.lsim`` would;
4. per trial the mean squared error in (m/s^2)^2 from the impact up to (not including) the peak
   of the measured |a|, averaged per height, summed over heights, loss = log(1 + total);
5. Nelder-Mead from (c, k) = (50, 7040).

Why it is fast: every trial of a height shares the same model curve (same h, same start), so
one loss evaluation computes one closed-form response and one exact first-order-hold filter
recurrence per *height*, then the per-trial errors as one masked array operation. Hundreds of
trials fit in milliseconds; reading the files dominates.
"""

from __future__ import annotations

import csv
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
from scipy.optimize import minimize

from cogniframe.analysis.droplogs import SAMPLE_RATE_HZ, HeightData, Skipped
from cogniframe.analysis.impact import G, damping_ratio, impact_velocity, lowpass_first_order, response
from cogniframe.errors import UserError


PAPER_LOWPASS_RAD_PER_S = 500.0
"""The paper's accelerometer/mount low-pass corner (rad/s; its text says "Hz")."""

PAPER_START = (50.0, 7040.0)
"""Nelder-Mead start (c in N s/m, k in N/m), as in the paper."""


# --------------------------------------------------------------------------------------------
# Data


@dataclass(frozen=True, eq=False)
class HeightFit:
    """Per-height outcome of a fit, with the curves of the "measurements vs model" figure.

    ``rmse_g``: sqrt of the height's mean per-trial MSE over the fit window, in G.
    Curves (``t_s`` in s from the impact start; ``mean_g``, ``std_g`` of the measured |a| and
    ``model_g``, the fitted model as the loss sees it, in G) span the trimmed length.
    ``median_window_samples``: median length of the trials' fit windows (impact to peak); a
    few trials peak late on a second bounce, so the longest window is not representative.
    """

    height_cm: float
    trials_used: int
    trials_skipped: int
    rmse_g: float
    peak_median_g: float
    t_s: np.ndarray = field(repr=False)
    mean_g: np.ndarray = field(repr=False)
    std_g: np.ndarray = field(repr=False)
    model_g: np.ndarray = field(repr=False)
    median_window_samples: int = 0

    def to_dict(self) -> dict:
        return {
            "height_cm": self.height_cm,
            "trials_used": self.trials_used,
            "trials_skipped": self.trials_skipped,
            "rmse_g": self.rmse_g,
            "peak_median_g": self.peak_median_g,
        }


@dataclass(frozen=True, eq=False)
class FitResult:
    """Fitted c (N s/m) and k (N/m) for mass ``mass_kg``; ``loss`` is the final objective."""

    c_n_s_per_m: float
    k_n_per_m: float
    damping_ratio: float
    loss: float
    mass_kg: float
    heights: tuple[HeightFit, ...]
    skipped: tuple[Skipped, ...]
    loss_kind: str = "cauchy"
    lowpass_rad_per_s: float | None = PAPER_LOWPASS_RAD_PER_S
    evaluations: int = 0
    converged: bool = True
    elapsed_s: float = 0.0

    def to_dict(self) -> dict:
        """JSON-ready dict (no curves)."""
        return {
            "c_n_s_per_m": self.c_n_s_per_m,
            "k_n_per_m": self.k_n_per_m,
            "damping_ratio": self.damping_ratio,
            "loss": self.loss,
            "loss_kind": self.loss_kind,
            "lowpass_rad_per_s": self.lowpass_rad_per_s,
            "mass_kg": self.mass_kg,
            "evaluations": self.evaluations,
            "converged": self.converged,
            "heights": [h.to_dict() for h in self.heights],
            "skipped": [{"path": str(s.path), "reason": s.reason} for s in self.skipped],
        }


# --------------------------------------------------------------------------------------------
# Readers


# --------------------------------------------------------------------------------------------
# Event detection, trimming, outliers


# --------------------------------------------------------------------------------------------
# Model vs data


def model_accel_g(
    mass_kg: float,
    c: float,
    k: float,
    height_cm: float,
    n_samples: int,
    lowpass_rad_per_s: float | None = PAPER_LOWPASS_RAD_PER_S,
    sample_rate_hz: float = SAMPLE_RATE_HZ,
    g: float = G,
) -> np.ndarray:
    """The model's |x''| in G on t = n / rate from touch-down, low-passed as the loss sees it."""
    t = np.arange(n_samples) / sample_rate_hz
    _, _, a = response(t, mass_kg, c, k, impact_velocity(height_cm, g), g)
    a = np.abs(a) / g
    if lowpass_rad_per_s is not None:
        a = lowpass_first_order(a, 1.0 / sample_rate_hz, lowpass_rad_per_s)
    return a


class _Objective:
    """The paper's loss over all heights, precomputed so one call costs one model per height."""

    def __init__(
        self,
        heights: Sequence[HeightData],
        mass_kg: float,
        lowpass_rad_per_s: float | None,
        loss: str,
        sample_rate_hz: float,
        g: float,
    ):
        self.mass_kg, self.lowpass, self.loss, self.rate, self.g = (
            mass_kg, lowpass_rad_per_s, loss, sample_rate_hz, g)
        self.parts = []
        for hd in heights:
            n = hd.peak_index.astype(int)  # window: impact start up to (not incl.) the peak
            width = int(n.max())
            meas = hd.a_g[:, :width] * g  # (m/s^2)
            mask = np.arange(width)[None, :] < n[:, None]
            self.parts.append((hd.height_cm, width, meas, mask, n))

    def per_trial_mse(self, c: float, k: float) -> list[np.ndarray]:
        """Per height, each trial's MSE in (m/s^2)^2 over its window."""
        out = []
        for h, width, meas, mask, n in self.parts:
            model = model_accel_g(self.mass_kg, c, k, h, width, self.lowpass, self.rate, self.g)
            err = np.where(mask, meas - model * self.g, 0.0)
            out.append(np.einsum("ij,ij->i", err, err) / n)
        return out

    def total(self, c: float, k: float) -> float:
        """Sum over heights of the mean per-trial MSE, (m/s^2)^2."""
        return float(sum(m.mean() for m in self.per_trial_mse(c, k)))

    def __call__(self, p: np.ndarray) -> float:
        c, k = float(p[0]), float(p[1])
        if not (c >= 0.0 and k > 0.0):
            return math.inf  # outside the physical model; Nelder-Mead only compares values
        tot = self.total(c, k)
        return math.log1p(tot) if self.loss == "cauchy" else tot


LOSSES = ("cauchy", "mse")


def drop_loss(
    heights: Sequence[HeightData],
    mass_kg: float,
    c: float,
    k: float,
    *,
    lowpass_rad_per_s: float | None = PAPER_LOWPASS_RAD_PER_S,
    loss: str = "cauchy",
    sample_rate_hz: float = SAMPLE_RATE_HZ,
    g: float = G,
) -> float:
    """The fit's objective at (c, k): log(1 + total) for "cauchy", the total for "mse"."""
    _check_loss(loss)
    return _Objective(heights, mass_kg, lowpass_rad_per_s, loss, sample_rate_hz, g)(
        np.array([c, k]))


def _check_loss(loss: str) -> None:
    if loss not in LOSSES:
        raise ValueError(f"loss must be one of {', '.join(LOSSES)}, got {loss!r}")


def fit_drop_tests(
    heights: Sequence[HeightData],
    mass_kg: float,
    *,
    lowpass_rad_per_s: float | None = PAPER_LOWPASS_RAD_PER_S,
    loss: str = "cauchy",
    start: tuple[float, float] = PAPER_START,
    sample_rate_hz: float = SAMPLE_RATE_HZ,
    g: float = G,
    extra_skipped: Iterable[Skipped] = (),
) -> FitResult:
    """Fit (c in N s/m, k in N/m) to trimmed drop tests of mass ``mass_kg`` (kg), Nelder-Mead.

    ``lowpass_rad_per_s=None`` compares the raw model; ``loss="mse"`` drops the log (it only
    changes Nelder-Mead's stopping test, since the log is monotonic).
    """
    _check_loss(loss)
    if not heights:
        raise ValueError("fit_drop_tests needs at least one height")
    if not mass_kg > 0:
        raise ValueError(f"mass must be positive (kg), got {mass_kg!r}")
    t0 = time.perf_counter()
    obj = _Objective(heights, mass_kg, lowpass_rad_per_s, loss, sample_rate_hz, g)
    res = minimize(obj, np.asarray(start, dtype=float), method="Nelder-Mead")
    c, k = float(res.x[0]), float(res.x[1])
    elapsed = time.perf_counter() - t0

    fits = []
    for hd, mse in zip(heights, obj.per_trial_mse(c, k)):
        length = hd.a_g.shape[1]
        fits.append(HeightFit(
            height_cm=hd.height_cm,
            trials_used=len(hd.paths),
            trials_skipped=len(hd.skipped),
            rmse_g=math.sqrt(float(mse.mean())) / g,
            peak_median_g=float(np.median(hd.a_g.max(axis=1))),
            t_s=np.arange(length) / sample_rate_hz,
            mean_g=hd.a_g.mean(axis=0),
            std_g=hd.a_g.std(axis=0),
            model_g=model_accel_g(mass_kg, c, k, hd.height_cm, length, lowpass_rad_per_s,
                                  sample_rate_hz, g),
            median_window_samples=int(np.median(hd.peak_index)),
        ))
    skipped = tuple(extra_skipped) + tuple(s for hd in heights for s in hd.skipped)
    return FitResult(
        c_n_s_per_m=c,
        k_n_per_m=k,
        damping_ratio=damping_ratio(c, k, mass_kg),
        loss=float(res.fun),
        mass_kg=float(mass_kg),
        heights=tuple(fits),
        skipped=skipped,
        loss_kind=loss,
        lowpass_rad_per_s=lowpass_rad_per_s,
        evaluations=int(res.nfev),
        converged=bool(res.success),
        elapsed_s=elapsed,
    )


# --------------------------------------------------------------------------------------------
# Static stiffness


def fit_static_stiffness(csv_path: Path | str, mass_kg: float, g: float = G) -> float:
    """k in N/m from a static test CSV (columns ``force_n``, ``displacement_mm``; ``#`` lines
    are comments): least squares of F = m g + k x with the intercept fixed at m g, i.e.
    k = sum(x (F - m g)) / sum(x^2), x in metres.
    """
    path = Path(csv_path)
    fix = ("Give a CSV with a header row 'force_n,displacement_mm' (newtons, millimetres) and "
           "at least one non-zero displacement.")
    try:
        with path.open(newline="") as fh:
            rows = [r for r in csv.reader(l for l in fh if not l.lstrip().startswith("#")) if r]
    except OSError as exc:
        raise UserError(f"Cannot read static stiffness file '{path}': {exc.strerror or exc}. "
                        + fix) from None
    header = [h.strip().lower() for h in rows[0]] if rows else []
    if "force_n" not in header or "displacement_mm" not in header:
        raise UserError(f"Static stiffness file '{path}' has columns {header or 'none'}; "
                        "it needs 'force_n' and 'displacement_mm'. " + fix)
    i_f, i_x = header.index("force_n"), header.index("displacement_mm")
    try:
        f = np.array([float(r[i_f]) for r in rows[1:]])
        x = np.array([float(r[i_x]) for r in rows[1:]]) / 1000.0
    except (ValueError, IndexError):
        raise UserError(f"Static stiffness file '{path}' has a non-numeric or missing value "
                        "in 'force_n' or 'displacement_mm'. " + fix) from None
    sxx = float(np.dot(x, x))
    if sxx == 0.0:
        raise UserError(f"Static stiffness file '{path}' has no non-zero displacement. " + fix)
    return float(np.dot(x, f - mass_kg * g)) / sxx


# --------------------------------------------------------------------------------------------
# The two-mass ("nonlinear") model: same data, same loss, same window


@dataclass(frozen=True, eq=False)
class NonlinearFit:
    """Fitted two-mass model (`impact_nl.TwoMass`): frame c, k and floor contact k_c, c_c."""

    c_n_s_per_m: float
    k_n_per_m: float
    contact_k_n_per_m: float
    contact_c_n_s_per_m: float
    mass_kg: float
    exo_mass_kg: float
    loss: float
    evaluations: int
    converged: bool
    heights: tuple[dict, ...]

    def to_dict(self) -> dict:
        return {"model": "nonlinear", "c_n_s_per_m": self.c_n_s_per_m, "k_n_per_m": self.k_n_per_m,
                "contact_k_n_per_m": self.contact_k_n_per_m, "contact_c_n_s_per_m": self.contact_c_n_s_per_m,
                "mass_kg": self.mass_kg, "exo_mass_kg": self.exo_mass_kg, "loss": self.loss,
                "evaluations": self.evaluations, "converged": self.converged, "heights": list(self.heights)}

    def params(self):
        from cogniframe.analysis.impact_nl import TwoMass

        return TwoMass(self.mass_kg, self.exo_mass_kg, self.k_n_per_m, self.c_n_s_per_m, self.contact_k_n_per_m,
                       self.contact_c_n_s_per_m)


NONLINEAR_START = (50.0, 7040.0, 30.0 * 7040.0, 25.0)
"""Nelder-Mead start (c, k, k_c, c_c): the paper's frame values, a contact 30x stiffer."""


def fit_nonlinear(heights: Sequence[HeightData], mass_kg: float, exo_mass_kg: float, *,
                  lowpass_rad_per_s: float | None = PAPER_LOWPASS_RAD_PER_S, loss: str = "cauchy",
                  start: tuple[float, float, float, float] = NONLINEAR_START, g: float = G,
                  window_samples: int | None = None) -> NonlinearFit:
    """Fit the two-mass model with the paper's loss and window (Nelder-Mead on log parameters).

    ``window_samples``: fit over that many samples from the impact start instead of the paper's
    impact-to-peak window (tried: the whole 40 ms pulse predicts the 100 cm peaks worse)."""
    from cogniframe.analysis.impact_nl import TwoMass, two_mass_response

    _check_loss(loss)
    if not 0 < exo_mass_kg < mass_kg:
        raise ValueError(f"exoskeleton mass must be between 0 and the total mass, got {exo_mass_kg!r}")
    parts = []
    for hd in heights:
        n = hd.peak_index.astype(int) if window_samples is None else np.full(len(hd.paths), min(window_samples, hd.a_g.shape[1]))
        width = max(int(n.max()), 2)
        mask = np.arange(width)[None, :] < n[:, None]
        parts.append((hd, width, hd.a_g[:, :width] * g, mask, np.maximum(n, 1)))

    def curve(p: TwoMass, h: float, width: int) -> np.ndarray:
        _, _, a, _ = two_mass_response(p, h, width)
        return lowpass_first_order(a, 1.0 / SAMPLE_RATE_HZ, lowpass_rad_per_s) if lowpass_rad_per_s else a

    def total(q: np.ndarray) -> float:
        c, k, kc, cc = np.exp(q)
        p = TwoMass(mass_kg, exo_mass_kg, k, c, kc, cc)
        tot = 0.0
        for hd, width, meas, mask, n in parts:
            err = np.where(mask, meas - curve(p, hd.height_cm, width) * g, 0.0)
            tot += float((np.einsum("ij,ij->i", err, err) / n).mean())
        return math.log1p(tot) if loss == "cauchy" else tot

    res = minimize(total, np.log(np.asarray(start, float)), method="Nelder-Mead",
                   options={"maxfev": 1500, "xatol": 1e-4, "fatol": 1e-7})
    c, k, kc, cc = (float(v) for v in np.exp(res.x))
    p = TwoMass(mass_kg, exo_mass_kg, k, c, kc, cc)
    hs = []
    for hd, width, meas, mask, n in parts:
        err = np.where(mask, meas - curve(p, hd.height_cm, width) * g, 0.0)
        hs.append({"height_cm": hd.height_cm, "trials_used": len(hd.paths),
                   "rmse_g": math.sqrt(float((np.einsum("ij,ij->i", err, err) / n).mean())) / g,
                   "peak_median_g": float(np.median(hd.a_g.max(axis=1)))})
    return NonlinearFit(c, k, kc, cc, float(mass_kg), float(exo_mass_kg), float(res.fun), int(res.nfev),
                        bool(res.success), tuple(hs))
