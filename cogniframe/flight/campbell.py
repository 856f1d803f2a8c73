"""The Campbell diagram of a design's resonance check (`analysis.resonance`): resonance.png
in the flight files."""

from __future__ import annotations

import numpy as np

from ..analysis.resonance import ATTITUDE_BAND_HZ, HARMONICS, Resonance


def plot(res: Resonance, path, title: str = "") -> None:
    """Campbell diagram: frame modes (horizontal lines, flagged ones red, line width by the flight
    controller's share), the rotor's 1x/2x/3x lines over rotor speed with the hover-to-full range
    shaded, and the attitude controller's band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rotor = {b.name: b for b in res.bands}
    hover, full = rotor["rotor 1x"].lo_hz, rotor["rotor 1x"].hi_hz
    fig, ax = plt.subplots(figsize=(8.5, 5.0))
    n = np.linspace(0.0, full * 1.1, 50)
    for h, style in zip(HARMONICS, ("-", "--", ":")):
        ax.plot(n, h * n, style, color="tab:blue", lw=1.4, label=f"rotor {h}x" + (" (blade pass)" if h == 2 else ""))
    ax.axvspan(hover, full, color="tab:blue", alpha=0.08, label="hover to full throttle")
    lo, hi = ATTITUDE_BAND_HZ
    ax.axhspan(lo, hi, color="tab:green", alpha=0.15, label=f"attitude controller ({lo:g}-{hi:g} Hz)")
    flagged = {f.mode for f in res.flags}
    labels = []
    for m in res.modes:
        p = 1.0 if m.fc_participation is None else m.fc_participation
        ax.axhline(m.hz, color="tab:red" if m.number in flagged else "0.4", lw=0.6 + 2.0 * p)
        labels.append(f"{m.number}" + ("" if m.fc_participation is None else f" ({m.fc_participation:.2f})"))
    if res.modes:  # one label per mode, stacked beside the lines: the first modes crowd within a few Hz
        ax.text(1.01, 0.02, "modes (FC share), Hz:\n" + "\n".join(f"{lab}: {m.hz:.1f}" for lab, m in zip(labels, res.modes)),
                transform=ax.transAxes, fontsize=7, va="bottom", ha="left")
    ax.plot([], [], color="tab:red", lw=2, label="frame mode, flagged (width: FC share)")
    ax.set_yscale("log")
    ax.set_ylim(5, 3.3 * full)
    ax.set_xlim(0, full * 1.1)
    ax.set_xlabel("rotor speed (rev/s)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title(f"Campbell diagram{': ' + title if title else ''}")
    ax.legend(loc="upper left", fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.subplots_adjust(left=0.09, right=0.80, top=0.92, bottom=0.11)
    fig.savefig(path, format="png", dpi=100, metadata={"Software": "cogniframe"})
    plt.close(fig)
