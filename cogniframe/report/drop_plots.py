"""Figures for the drop model and the drop-test fit (PNG, deterministic bytes).

Figures are built on matplotlib's object API with the Agg canvas, so nothing touches pyplot's
global state or the user's chosen backend, and matplotlib is only imported when a figure is
drawn. PNGs are written without the "Software" metadata key, so the same input gives the same
bytes (useful for caching and for diffs in CI).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # only for annotations; importing the analysis modules is cheap anyway
    from cogniframe.analysis.fit import FitResult
    from cogniframe.analysis.impact import DropResult

DPI = 100
"""Pixels per inch: a figure of (w, h) inches is (w * DPI, h * DPI) pixels."""


def _figure(width_in: float, height_in: float, nrows: int = 1, ncols: int = 1, fixed: bool = True,
            title_lines: int = 1):
    """A figure of axes. `fixed`: margins set in inches (room for a one-line title above each
    axes, `title_lines` high, numeric tick labels and axis labels), not a layout engine: matplotlib's constrained
    layout draws the figure an extra time to measure it (0.1-0.15 s of each build figure's ~0.25 s).
    Figures with a suptitle or long tick labels pass fixed=False."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), dpi=DPI, layout=None if fixed else "constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False)
    if fixed:
        left, right, bottom, gap_w, gap_h = 0.8, 0.2, 0.6, 0.9, 0.95  # inches
        top = 0.18 + 0.22 * title_lines
        fig.subplots_adjust(left=left / width_in, right=1 - right / width_in, bottom=bottom / height_in,
                            top=1 - top / height_in,
                            wspace=gap_w / ((width_in - left - right - gap_w * (ncols - 1)) / ncols),
                            hspace=gap_h / ((height_in - bottom - top - gap_h * (nrows - 1)) / nrows))
    return fig, axes


def _save(fig, path: Path | str) -> Path:
    from ..outdir import claim_file

    path = Path(path)
    claim_file(path)  # never overwrite a file cogniframe did not write
    path.parent.mkdir(parents=True, exist_ok=True)
    # No bbox_inches="tight": the pixel size must be what the figure size says.
    fig.savefig(path, format="png", dpi=DPI, metadata={"Software": "cogniframe"})
    return path


def plot_drop_response(result: "DropResult", path: Path | str) -> Path:
    """Displacement (mm) and |acceleration| (G) vs time (ms) per height, with the clearance.

    Curves run to 1.2 x the latest time of x_max: past the clearance they are the
    unconstrained model, which the dashed clearance line marks as no longer valid.
    Image: 800 x 700 px.
    """
    from cogniframe import numfmt
    from cogniframe.analysis.impact import trajectory

    fig, axes = _figure(8.0, 7.0, 2, 1, title_lines=2)
    ax_x, ax_a = axes[0, 0], axes[1, 0]
    finite = [h.t_max_s for h in result.heights if np.isfinite(h.t_max_s)]
    t_end = numfmt.sig(1.2 * max(finite)) if finite else None
    # the curves of the model as check.json states it (numfmt): its last bits, which move between
    # machines, moved antialiased pixels too
    m, c, k = (numfmt.sig(v) for v in (result.mass_kg, result.c_n_s_per_m, result.k_n_per_m))
    for h in result.heights:
        t, x, _, a_g = trajectory(m, c, k, h.height_cm, t_end_s=t_end, n=1000)
        label = f"{h.height_cm:g} cm" + (" (strikes)" if h.strikes else "")
        t, x, a_g = (numfmt.plotted(v) for v in (t * 1e3, x * 1e3, a_g))  # ms, mm, G
        (line,) = ax_x.plot(t, x, label=label)
        ax_a.plot(t, a_g, color=line.get_color(), label=label)
    ax_x.axhline(result.clearance_mm, color="k", linestyle="--", linewidth=1,
                 label=f"clearance {result.clearance_mm:g} mm")
    ax_x.set_ylabel("payload displacement x (mm)")
    # Two lines: on one line the title runs past the 800 px figure and is cut off.
    ax_x.set_title(
        f"Drop response: m = {result.mass_kg:.4g} kg, c = {result.c_n_s_per_m:.4g} N s/m, k = {result.k_n_per_m:.4g} N/m\n"
        f"zeta = {result.damping_ratio:.3f}; max safe height {result.max_safe_height_cm:.1f} cm"
    )
    ax_a.set_ylabel("|acceleration| (G)")
    ax_a.set_xlabel("time since touch-down (ms)")
    for ax in (ax_x, ax_a):
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize="small")
    return _save(fig, path)


def plot_energy_split(result: "DropResult", path: Path | str) -> Path:
    """Stacked bars per height: share of the touch-down energy in spring, damper and rigid
    collision (%), as in the paper. Image: 700 x 450 px."""
    fig, axes = _figure(7.0, 4.5)
    ax = axes[0, 0]
    labels = [f"{h.height_cm:g} cm" for h in result.heights]
    pos = np.arange(len(labels))
    bottom = np.zeros(len(labels))
    for name, key, color in (
        ("spring", "energy_spring_pct", "tab:blue"),
        ("damper", "energy_damper_pct", "tab:orange"),
        ("rigid collision", "energy_rigid_pct", "tab:red"),
    ):
        vals = np.array([getattr(h, key) for h in result.heights])
        ax.bar(pos, vals, 0.6, bottom=bottom, label=name, color=color)
        bottom += vals
    ax.set_xticks(pos, labels)
    ax.set_ylabel("share of impact energy (%)")
    ax.set_ylim(0, 118)  # headroom for the legend above the 100 % bars
    ax.set_title(f"Energy split (c = {result.c_n_s_per_m:.4g} N s/m, "
                 f"k = {result.k_n_per_m:.4g} N/m)")
    ax.legend(loc="upper center", ncol=3, fontsize="small")
    ax.grid(True, axis="y", alpha=0.3)
    return _save(fig, path)


def plot_fit(fit_result: "FitResult", path: Path | str) -> Path:
    """The paper's "raw measurements vs our model" figure: per height, measured mean +- std of
    |a| (G) from the impact start, and the fitted model as the loss sees it (low-passed).
    The shaded span is the median trial's fit window (impact to measured peak); the plot
    shows five times that, at least 40 samples. Image: 500 px wide per height, 450 px tall.
    """
    n = len(fit_result.heights)
    fig, axes = _figure(5.0 * n, 4.5, 1, n, fixed=False)  # a suptitle
    for ax, h in zip(axes[0], fit_result.heights):
        span = min(h.t_s.size, max(5 * h.median_window_samples, 40))
        t_ms = h.t_s[:span] * 1e3
        mean, std = h.mean_g[:span], h.std_g[:span]
        ax.fill_between(t_ms, mean - std, mean + std, alpha=0.3, color="tab:blue",
                        label="measured mean ± std")
        ax.plot(t_ms, mean, color="tab:blue")
        ax.plot(t_ms, h.model_g[:span], color="tab:red", label="model")
        if h.median_window_samples:
            ax.axvspan(0, h.t_s[h.median_window_samples - 1] * 1e3, color="0.9", zorder=0,
                       label="median fit window")
        ax.set_title(f"{h.height_cm:g} cm: {h.trials_used} trials, RMSE {h.rmse_g:.1f} G")
        ax.set_xlabel("time since impact (ms)")
        ax.set_ylabel("|a| (G)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize="small")
    fig.suptitle(
        f"c = {fit_result.c_n_s_per_m:.4g} N s/m, k = {fit_result.k_n_per_m:.4g} N/m, "
        f"zeta = {fit_result.damping_ratio:.3f}, m = {fit_result.mass_kg:g} kg"
    )
    return _save(fig, path)
