"""Drop-test logs: reading the data logger's files (binary or CSV), finding each impact, and the
trials of one height lined up as the paper's procedure does (steps 1-2 of `analysis/fit.py`):
|a| in G, the impact from one sample before the first sample above 3 G, trials cut to the
shortest of their height, outliers (a peak below mean - 6 std) dropped.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np

from cogniframe.errors import UserError

IMPACT_THRESHOLD_G = 3.0
"""An impact starts one sample before the first sample above this |a| (G)."""


OUTLIER_STD = 6.0
"""Trials with a peak below mean - OUTLIER_STD * std of their height's peaks are dropped."""


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
