"""Drop/fit figures: real PNGs of the documented size, byte-identical for identical input."""

from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cogniframe.analysis.fit import FitResult, HeightFit
from cogniframe.analysis.impact import evaluate
from cogniframe.report.drop_plots import plot_drop_response, plot_energy_split, plot_fit

REPO = Path(__file__).resolve().parents[1]


def png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


@pytest.fixture(scope="module")
def drop_result():
    return evaluate(0.241, 46.0, 7040.0, [50, 100, 150])


def fake_fit(c: float = 69.5) -> FitResult:
    t = np.arange(200) / 1000
    curve = 80 * np.exp(-((t - 0.006) / 0.004) ** 2)
    heights = tuple(
        HeightFit(height_cm=h, trials_used=10, trials_skipped=1, rmse_g=20.0, peak_median_g=90.0,
                  t_s=t, mean_g=curve * h / 50, std_g=0.2 * curve, model_g=0.8 * curve * h / 50,
                  median_window_samples=7)
        for h in (50.0, 100.0)
    )
    return FitResult(c_n_s_per_m=c, k_n_per_m=4323.0, damping_ratio=1.08, loss=11.9,
                     mass_kg=0.241, heights=heights, skipped=())


@pytest.mark.parametrize("plot, size", [(plot_drop_response, (800, 700)),
                                        (plot_energy_split, (700, 450))])
def test_drop_plots_are_pngs_of_expected_size(tmp_path, drop_result, plot, size):
    out = plot(drop_result, tmp_path / "sub" / "x.png")  # creates the folder
    assert out.stat().st_size > 10_000
    assert png_size(out) == size


def test_fit_plot_is_png_500px_per_height(tmp_path):
    out = plot_fit(fake_fit(), tmp_path / "fit.png")
    assert out.stat().st_size > 10_000
    assert png_size(out) == (1000, 450)


@pytest.mark.parametrize("name", ["response", "energy", "fit"])
def test_same_input_same_bytes_different_input_different_bytes(tmp_path, drop_result, name):
    other = evaluate(0.241, 30.0, 7040.0, [50, 100, 150])
    draw = {
        "response": lambda r, p: plot_drop_response(r, p),
        "energy": lambda r, p: plot_energy_split(r, p),
        "fit": lambda r, p: plot_fit(fake_fit(r.c_n_s_per_m), p),
    }[name]
    a = draw(drop_result, tmp_path / "a.png").read_bytes()
    b = draw(drop_result, tmp_path / "b.png").read_bytes()
    c = draw(other, tmp_path / "c.png").read_bytes()
    assert a == b
    assert a != c
    # Software names cogniframe without a version (so outputs stay byte-stable across upgrades, and
    # cogniframe can tell its own PNGs from a user's before overwriting one).
    assert b"Software\x00cogniframe" in a and b"Matplotlib" not in a


@pytest.mark.process
def test_importing_the_physics_modules_does_not_import_matplotlib():
    code = ("import sys; import cogniframe.analysis.impact, cogniframe.analysis.fit, "
            "cogniframe.report.drop_plots, cogniframe.commands.drop_fit; "
            "print('matplotlib' in sys.modules, 'cadquery' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO,
                         check=True)
    assert out.stdout.split() == ["False", "False"]
