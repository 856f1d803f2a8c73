"""Designs of a sweep as dotted overrides: grid, Latin hypercube, Sobol (Saltelli) or random.

Pure and seeded: the same sweep file gives the same designs in the same order. Unit-cube
samplers come from scipy.stats.qmc (lhs), numpy (random) and SALib (sobol: Saltelli's design,
so SALib can compute Sobol indices from the results). A range key maps u in [0, 1) to
lo + u (hi - lo), rounded to DECIMALS (an integer key: each integer in the range an equal share); a choice key
picks choices[floor(u n)].
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from .sweepfile import Sweep, VaryKey

DECIMALS = 3  # 1 um / 0.001 of a unit: far below what a printer or a saw holds


def value(key: VaryKey, u: float):
    """The key's value at unit coordinate u (0 <= u <= 1)."""
    if key.is_choice:
        n = len(key.choices)
        return key.choices[min(int(u * n), n - 1)]
    if key.integer:  # every integer in [lo, hi] gets an equal share of the unit interval
        lo, hi = math.ceil(key.lo), math.floor(key.hi)
        return min(hi, lo + int(float(u) * (hi - lo + 1)))
    return round(key.lo + float(u) * (key.hi - key.lo), DECIMALS)


def unit_samples(sweep: Sweep) -> np.ndarray:
    """(designs, keys) unit-cube coordinates for lhs / random / sobol (not grid)."""
    s = sweep.settings
    d = len(sweep.keys)
    if s.sampler == "lhs":
        from scipy.stats import qmc

        return qmc.LatinHypercube(d=d, seed=s.seed).random(s.samples)
    if s.sampler == "random":
        return np.random.default_rng(s.seed).random((s.samples, d))
    if s.sampler == "sobol":
        from SALib.sample import sobol as saltelli

        return saltelli.sample(salib_problem(sweep, unit=True), s.samples, calc_second_order=False, seed=s.seed,
                               scramble=True)
    raise ValueError(f"no unit samples for sampler {s.sampler!r}")


def salib_problem(sweep: Sweep, unit: bool = False) -> dict:
    return {"num_vars": len(sweep.keys), "names": [k.name for k in sweep.keys],
            "bounds": [[0.0, 1.0] for _ in sweep.keys]}


def designs(sweep: Sweep) -> list[dict]:
    """Overrides {dotted key: value} for every design, in sampling order."""
    keys = sweep.keys
    if sweep.settings.sampler == "grid":
        axes = []
        for k in keys:
            if k.is_choice:
                axes.append(list(k.choices))
            else:
                axes.append(list(dict.fromkeys(value(k, u) for u in np.linspace(0.0, 1.0, sweep.settings.levels))))
        return [dict(zip((k.name for k in keys), combo)) for combo in itertools.product(*axes)]
    u = unit_samples(sweep)
    return [{k.name: value(k, row[j]) for j, k in enumerate(keys)} for row in u]
