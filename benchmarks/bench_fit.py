"""Time the drop-test fit on the shared trials and the drop model over four heights.

    python benchmarks/bench_fit.py [--data DIR] [--repeat N]

Prints: reading + trimming all shared trials (~198 files), the Nelder-Mead fit (median of N),
the same fit with the trials tiled to ~300, one loss evaluation on the fast path vs the
per-trial solve_ivp + lsim reference (and what a whole fit would cost with it), and
`evaluate` over 50/100/150/200 cm.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _median_time(fn, repeat: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def _reference_loss(heights, mass_kg: float, c: float, k: float, w: float = 500.0) -> float:
    """The README's loss one trial at a time with solve_ivp and lsim (what the paper ran)."""
    import numpy as np
    from scipy.integrate import solve_ivp
    from scipy.signal import lsim

    g, total = 9.81, 0.0
    for hd in heights:
        v0 = math.sqrt(2 * g * hd.height_cm / 100)
        errs = []
        for a in hd.a_g:
            n = int(np.argmax(a))
            t = np.arange(n) / 1000
            if n < 2:
                errs.append(np.mean((a[:n] * g) ** 2))
                continue
            s = solve_ivp(lambda _t, y: [y[1], g - (c * y[1] + k * y[0]) / mass_kg], (0, t[-1]),
                          [0, v0], t_eval=t, rtol=1e-9, atol=1e-12)
            acc = np.abs((-k * s.y[0] - c * s.y[1]) / mass_kg + g)
            errs.append(np.mean((a[:n] * g - lsim(([w], [1, w]), acc, t)[1]) ** 2))
        total += np.mean(errs)
    return math.log1p(total)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT / "examples" / "droptests"))
    ap.add_argument("--repeat", type=int, default=10)
    args = ap.parse_args(argv)

    t0 = time.perf_counter()
    import numpy as np

    from cogniframe.analysis import droplogs as L

    from cogniframe.analysis import fit as F
    from cogniframe.analysis.impact import evaluate
    print(f"import numpy/scipy/fit       {time.perf_counter() - t0:8.3f} s")

    data = Path(args.data)
    folders = {50.0: data / "SoftBottom_50cm", 100.0: data / "SoftBottom_100cm"}
    if not all(p.is_dir() for p in folders.values()):
        print(f"no shared drop tests under {data}", file=sys.stderr)
        return 1

    t0 = time.perf_counter()
    heights = [L.load_height([p], h) for h, p in folders.items()]
    n_trials = sum(len(h.paths) for h in heights)
    print(f"read + trim {n_trials} trials       {time.perf_counter() - t0:8.3f} s (cold)")
    dt, _ = _median_time(lambda: [L.load_height([p], h) for h, p in folders.items()], 3)
    print(f"read + trim {n_trials} trials       {dt:8.3f} s (warm, median of 3)")

    dt, res = _median_time(lambda: F.fit_drop_tests(heights, 0.241), args.repeat)
    print(f"fit {n_trials} trials               {dt:8.4f} s (median of {args.repeat}, "
          f"{res.evaluations} evaluations) -> c = {res.c_n_s_per_m:.2f} N s/m, "
          f"k = {res.k_n_per_m:.1f} N/m")

    # Timing only: tile the trials to ~300 (same heights), the size the brief asks about.
    def tile(h):
        half = len(h.paths) // 2
        return L.HeightData(h.height_cm, h.paths + h.paths[:half],
                            np.concatenate([h.a_g, h.a_g[:half]]),
                            np.concatenate([h.peak_index, h.peak_index[:half]]))

    tiled = [tile(h) for h in heights]
    n_tiled = sum(h.a_g.shape[0] for h in tiled)
    dt, _ = _median_time(lambda: F.fit_drop_tests(tiled, 0.241), args.repeat)
    print(f"fit {n_tiled} trials (tiled)       {dt:8.4f} s (median of {args.repeat})")

    dt_fast, _ = _median_time(lambda: F.drop_loss(heights, 0.241, 50.0, 7040.0), 50)
    dt_ref, _ = _median_time(lambda: _reference_loss(heights, 0.241, 50.0, 7040.0), 3)
    print(f"one loss evaluation          {dt_fast * 1e3:8.3f} ms fast path, "
          f"{dt_ref * 1e3:.1f} ms solve_ivp+lsim per trial "
          f"(~{dt_ref * res.evaluations:.1f} s for a whole fit)")

    dt, _ = _median_time(lambda: evaluate(0.241, 46.0, 7040.0, [50, 100, 150, 200]), args.repeat)
    print(f"simulate 4 heights           {dt * 1e3:8.3f} ms (median of {args.repeat}, "
          "incl. max safe height)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
