"""Synthetic drop-logger folders for the fit tests: trials of the Kelvin-Voigt pulse of a 241 g
frame (the paper's mass) with half-normal noise, as CSV in G, optionally with a drop.yaml."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cogniframe.analysis.fit import model_accel_g


def write_drops(folder: Path, height_cm: float, c: float, k: float, manifest: str | None = None,
                n_trials: int = 12, seed: int = 0) -> Path:
    """CSV trials in G. The model curve comes from the library (its agreement with lsim is tested
    in test_fit.py); here it only feeds the commands' plumbing."""
    folder.mkdir(parents=True)
    rng = np.random.default_rng(seed)
    a = model_accel_g(0.241, c, k, height_cm, 200)
    for i in range(n_trials):
        sig = np.concatenate([np.abs(rng.normal(0, 0.2, 30)), a + np.abs(rng.normal(0, 0.3, a.size))])
        sig[30] = 0.1
        t = np.arange(sig.size) / 1000
        rows = "".join(f"{ti:.3f},0,0,{si:.6f}\n" for ti, si in zip(t, sig))
        (folder / f"trial{i}.csv").write_text("t_s,ax_g,ay_g,az_g\n" + rows)
    if manifest is not None:
        (folder / "drop.yaml").write_text(manifest)
    return folder
