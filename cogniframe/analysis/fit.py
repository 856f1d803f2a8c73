"""Fitting the drop model's c and k to accelerometer drop tests, and k to a static test.

The default procedure is exactly the paper's (see shared/data/droptests/README.md):

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
from typing import Callable, Iterable, Sequence

import numpy as np
from scipy.optimize import minimize

from cogniframe.analysis.impact import G, damping_ratio, impact_velocity, lowpass_first_order, response
from cogniframe.errors import UserError

IMPACT_THRESHOLD_G = 3.0
"""An impact starts one sample before the first sample above this |a| (G)."""

OUTLIER_STD = 6.0
"""Trials with a peak below mean - OUTLIER_STD * std of their height's peaks are dropped."""

PAPER_LOWPASS_RAD_PER_S = 500.0
"""The paper's accelerometer/mount low-pass corner (rad/s; its text says "Hz")."""

PAPER_START = (50.0, 7040.0)
"""Nelder-Mead start (c in N s/m, k in N/m), as in the paper."""

SAMPLE_RATE_HZ = 1000.0
"""The logger's rate; the paper simulates on t = n / 1000 s whatever the timestamps say."""

MIN_RECORDS = 100
"""Fewer samples than this (0.1 s at 1 kHz) cannot hold a drop: the file is skipped."""

MIN_AFTER_IMPACT = 20
"""Samples needed after the impact start; one trial cut short would shorten its whole height."""

TRIAL_SUFFIXES = (".bin", ".csv")
# Files in a data folder that are clearly not trials and not worth a "skipped" line.
_IGNORED_SUFFIXES = {".md", ".txt", ".yaml", ".yml", ".json", ".png", ".pdf", ".svg"}

_RECORD = np.dtype([("t_us", "<u4"), ("x", "<u2"), ("y", "<u2"), ("z", "<u2")])


# --------------------------------------------------------------------------------------------
# Data


@dataclass(frozen=True)
class LoggerCalibration:
    """ADXL377 logger calibration: zero offsets (counts) and gains (counts per G).

    Defaults are the paper's logger; a_axis = (count - zero) / gain.
    """

    x0: float = 2019.93872
    y0: float = 2020.0
    z0: float = 2020.77284438
    gz: float = 8.87700438
    gx: float = 0.9577 * 8.87700438
    gy: float = 0.9577 * 8.87700438

    def magnitude_g(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """|a| in G from raw counts."""
        ax = (np.asarray(x, dtype=float) - self.x0) / self.gx
        ay = (np.asarray(y, dtype=float) - self.y0) / self.gy
        az = (np.asarray(z, dtype=float) - self.z0) / self.gz
        return np.sqrt(ax * ax + ay * ay + az * az)


@dataclass(frozen=True, eq=False)
class Trial:
    """One drop recording: timestamps (s) and acceleration magnitude |a| (G)."""

    path: Path
    t_s: np.ndarray = field(repr=False)
    a_g: np.ndarray = field(repr=False)


@dataclass(frozen=True)
class Skipped:
    """A file (or trial) left out of a fit, and why."""

    path: Path
    reason: str

    def __str__(self) -> str:
        return f"{self.path}: {self.reason}"


class UnusableTrial(ValueError):
    """A trial file that cannot be used; the message is the reason (one line)."""


@dataclass(frozen=True, eq=False)
class HeightData:
    """The trials of one drop height, trimmed as the paper does, ready to fit.

    ``a_g`` is (n_trials, n_samples) |a| in G starting one sample before the impact, all cut to
    the shortest; ``peak_index`` is each trial's index of max |a| (the fit window's length).
    """

    height_cm: float
    paths: tuple[Path, ...]
    a_g: np.ndarray = field(repr=False)
    peak_index: np.ndarray = field(repr=False)
    skipped: tuple[Skipped, ...] = ()


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


def read_logger_bin(
    path: Path | str, calib: LoggerCalibration = LoggerCalibration(), min_records: int = MIN_RECORDS
) -> Trial:
    """Read the logger's binary format: 10-byte little-endian records (uint32 t_us, uint16 x,
    y, z raw counts). A trailing partial record is ignored. Raises :class:`UnusableTrial` when
    the file is empty or holds fewer than ``min_records`` records.
    """
    path = Path(path)
    raw = path.read_bytes()
    n = len(raw) // _RECORD.itemsize
    if n == 0:
        raise UnusableTrial("empty file" if not raw else f"truncated: {len(raw)} bytes, no full record")
    if n < min_records:
        raise UnusableTrial(f"truncated: {n} records, need at least {min_records}")
    rec = np.frombuffer(raw, dtype=_RECORD, count=n)
    return Trial(path, rec["t_us"] * 1e-6, calib.magnitude_g(rec["x"], rec["y"], rec["z"]))


def read_csv_trial(
    path: Path | str, calib: LoggerCalibration = LoggerCalibration(), min_records: int = MIN_RECORDS
) -> Trial:
    """Read a CSV trial with a header row: ``t_s,ax_g,ay_g,az_g`` (G) or ``t_s,x,y,z`` (raw
    counts, converted with ``calib``). Lines starting with ``#`` are comments; a last row cut
    short is ignored like a partial binary record.
    """
    path = Path(path)
    with path.open(newline="") as fh:
        rows = [r for r in csv.reader(line for line in fh if not line.lstrip().startswith("#")) if r]
    if not rows:
        raise UnusableTrial("empty file")
    header = [h.strip().lower() for h in rows[0]]
    if {"t_s", "ax_g", "ay_g", "az_g"} <= set(header):
        cols, in_g = ("t_s", "ax_g", "ay_g", "az_g"), True
    elif {"t_s", "x", "y", "z"} <= set(header):
        cols, in_g = ("t_s", "x", "y", "z"), False
    else:
        raise UnusableTrial(
            f"unknown columns {','.join(header)}; expected t_s,ax_g,ay_g,az_g or t_s,x,y,z"
        )
    idx = [header.index(c) for c in cols]
    body = rows[1:]
    if body and len(body[-1]) < len(header):
        body = body[:-1]
    try:
        data = np.array([[float(r[i]) for i in idx] for r in body], dtype=float).reshape(-1, 4)
    except (ValueError, IndexError) as exc:
        raise UnusableTrial(f"non-numeric or missing value ({exc})") from None
    if len(data) < min_records:
        raise UnusableTrial(
            "empty file" if len(data) == 0 else f"truncated: {len(data)} rows, need at least {min_records}"
        )
    t, a, b, c = data.T
    mag = np.sqrt(a * a + b * b + c * c) if in_g else calib.magnitude_g(a, b, c)
    return Trial(path, t, mag)


def read_trial(
    path: Path | str, calib: LoggerCalibration = LoggerCalibration(), min_records: int = MIN_RECORDS
) -> Trial:
    """Read a trial file: ``.csv`` as CSV, anything else as the logger's binary format."""
    path = Path(path)
    reader = read_csv_trial if path.suffix.lower() == ".csv" else read_logger_bin
    return reader(path, calib, min_records)


def collect_files(paths: Iterable[Path | str]) -> tuple[list[Path], list[Skipped]]:
    """Expand folders into their ``.bin``/``.csv`` trial files (sorted by name).

    Other files in a folder are reported as skipped (a mis-named trial such as ``acc_a-91.bhn``
    should be noticed, not silently lost), except documentation and manifests (``drop.yaml``).
    A file given explicitly is always read. A missing path raises :class:`UserError`.
    """
    files: list[Path] = []
    skipped: list[Skipped] = []
    for p in map(Path, paths):
        if p.is_dir():
            for f in sorted(p.iterdir()):
                if f.name.startswith(".") or not f.is_file():
                    continue
                suffix = f.suffix.lower()
                if suffix in TRIAL_SUFFIXES:
                    files.append(f)
                elif suffix not in _IGNORED_SUFFIXES:
                    skipped.append(Skipped(f, "not a .bin or .csv trial; rename it if it is one"))
        elif p.is_file():
            files.append(p)
        else:
            raise UserError(
                f"Drop-test data '{p}' does not exist. Give folders of trial files (.bin from the "
                "logger, or .csv) or the files themselves as DATA arguments."
            )
    return files, skipped


def load_trials(
    files: Iterable[Path],
    calib: LoggerCalibration = LoggerCalibration(),
    min_records: int = MIN_RECORDS,
    on_file: Callable[[Path], None] | None = None,
) -> tuple[list[Trial], list[Skipped]]:
    """Read each file; unreadable ones become :class:`Skipped`. ``on_file`` ticks a progress bar."""
    trials: list[Trial] = []
    skipped: list[Skipped] = []
    for f in files:
        try:
            trials.append(read_trial(f, calib, min_records))
        except UnusableTrial as exc:
            skipped.append(Skipped(f, str(exc)))
        except OSError as exc:
            skipped.append(Skipped(f, f"cannot read: {exc.strerror or exc}"))
        if on_file is not None:
            on_file(f)
    return trials, skipped


# --------------------------------------------------------------------------------------------
# Event detection, trimming, outliers


def impact_start(a_g: np.ndarray, threshold_g: float = IMPACT_THRESHOLD_G) -> int | None:
    """Index one sample before the first |a| above ``threshold_g``; None if there is none."""
    above = np.flatnonzero(np.asarray(a_g) > threshold_g)
    if above.size == 0:
        return None
    return int(above[0]) - 1


def prepare_height(
    trials: Sequence[Trial],
    height_cm: float,
    *,
    threshold_g: float = IMPACT_THRESHOLD_G,
    outlier_std: float = OUTLIER_STD,
    min_after_impact: int = MIN_AFTER_IMPACT,
    skipped: Iterable[Skipped] = (),
    source: str = "",
) -> HeightData:
    """Trim the trials of one height as the paper does (steps 1-2 of the module docstring).

    Impact-free trials, recordings that start mid-impact, impacts too near the end and
    outliers join ``skipped``. Raises :class:`UserError` if no trial is left.
    """
    skipped = list(skipped)
    cut: list[tuple[Path, np.ndarray]] = []
    for tr in trials:
        i0 = impact_start(tr.a_g, threshold_g)
        if i0 is None:
            skipped.append(Skipped(tr.path, f"no impact: |a| never above {threshold_g:g} G "
                                   f"(max {float(np.max(tr.a_g)):.1f} G)"))
        elif i0 < 0:
            skipped.append(Skipped(tr.path, f"starts mid-impact: first sample already "
                                   f"{float(tr.a_g[0]):.1f} G > {threshold_g:g} G"))
        elif tr.a_g.size - i0 < min_after_impact:
            skipped.append(Skipped(tr.path, f"impact at sample {i0} leaves {tr.a_g.size - i0} "
                                   f"samples, need {min_after_impact}"))
        else:
            cut.append((tr.path, tr.a_g[i0:]))

    if cut:
        length = min(a.size for _, a in cut)
        a = np.stack([x[:length] for _, x in cut])
        peaks = a.max(axis=1)
        keep = peaks >= peaks.mean() - outlier_std * peaks.std()
        for (p, _), pk, k in zip(cut, peaks, keep):
            if not k:
                skipped.append(Skipped(p, f"outlier: peak {pk:.1f} G below mean - "
                                       f"{outlier_std:g} std of its height"))
        paths = tuple(p for (p, _), k in zip(cut, keep) if k)
        a = a[keep]
    else:
        paths, a = (), np.empty((0, 0))

    if not paths:
        reasons = "; ".join(str(s) for s in skipped[:3]) or "no trial files found"
        more = f" (and {len(skipped) - 3} more)" if len(skipped) > 3 else ""
        raise UserError(
            f"No usable drop trial for {height_cm:g} cm{f' in {source}' if source else ''}: "
            f"{reasons}{more}. Point DATA at folders of logger .bin files or CSV files "
            "(t_s,ax_g,ay_g,az_g or t_s,x,y,z) that contain an impact above "
            f"{threshold_g:g} G."
        )
    return HeightData(
        height_cm=float(height_cm),
        paths=paths,
        a_g=a,
        peak_index=np.argmax(a, axis=1),
        skipped=tuple(skipped),
    )


def load_height(
    paths: Iterable[Path | str],
    height_cm: float,
    calib: LoggerCalibration = LoggerCalibration(),
    **prepare_kw,
) -> HeightData:
    """Collect, read and trim everything under ``paths`` as one height."""
    paths = list(paths)
    files, skipped = collect_files(paths)
    trials, bad = load_trials(files, calib)
    return prepare_height(
        trials, height_cm, skipped=skipped + bad, source=", ".join(map(str, paths)), **prepare_kw
    )


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
