"""Sweep reports: pareto.png, sensitivity.png and summary.md from the results table.

Sensitivity: with `sampler: sobol` (Saltelli's design) and every design evaluated, SALib's Sobol
total-order indices ST (share of an output's variance an input explains, interactions included);
otherwise standardized regression coefficients (SRC = slope in standard deviations of the output
per standard deviation of the input, from a least-squares fit over the valid designs; R^2 says
how much of the variation the linear fit explains). A choice key enters the SRC fit as one 0/1
column per choice after the first, named `key=value`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

FRONT_X, FRONT_Y = "mass_g", "max_safe_drop_cm"  # minimise mass, maximise the safe drop
MAIN_OUTPUTS = ("mass_g", "k_n_per_m", "max_safe_drop_cm", "prop_margin_mm", "peak_g")
MAX_OUTPUTS = 8  # columns of the sensitivity figure: the main outputs first, then other stages' (stiffness.*, flight.*)
_EVALUATED = ("PASS", "FAIL")


def output_columns(table) -> list[str]:
    """The main outputs plus any numeric column another stage added (stiffness.*, flight.*)."""
    cols = [c for c in MAIN_OUTPUTS if c in table.columns]
    for c in table.columns:
        if "." in c and c.split(".")[0] in ("stiffness", "flight") and _numeric(table[c]):
            cols.append(c)
    cols = [c for c in cols if _numeric(table[c]) and table[c].notna().any() and table[c].nunique() > 1]
    return cols[:MAX_OUTPUTS]


def _numeric(s) -> bool:
    import pandas as pd

    return pd.api.types.is_numeric_dtype(s) and not pd.api.types.is_bool_dtype(s)


def pareto_front(table, x: str = FRONT_X, y: str = FRONT_Y):
    """Rows of PASS designs not dominated in (min x, max y), sorted by x."""
    ok = table[(table["verdict"] == "PASS") & table[x].notna() & table[y].notna()].sort_values([x, y], ascending=[True, False])
    keep, best_y = [], -math.inf
    for idx, r in ok.iterrows():
        if r[y] > best_y:
            keep.append(idx)
            best_y = r[y]
    return ok.loc[keep]


def sensitivity(sweep, table) -> tuple[str, list[str], list[str], np.ndarray, dict]:
    """(method, inputs, outputs, matrix[inputs, outputs], extra): Sobol ST or SRC."""
    outputs = output_columns(table)
    if sweep.settings.sampler == "sobol":
        got = _sobol(sweep, table, outputs)
        if got is not None:
            return got
    return _src(sweep, table, outputs)


def _sobol(sweep, table, outputs):
    from SALib.analyze import sobol

    from . import evaluate as ev
    from .sample import designs, salib_problem

    ids = [ev.design_id(ev.apply_overrides(sweep.base_data, o)) for o in designs(sweep)]
    by_id = table.set_index("design_id")
    if not set(ids) <= set(by_id.index):
        return None
    problem = salib_problem(sweep)
    m = np.full((len(sweep.keys), len(outputs)), np.nan)
    for j, out in enumerate(outputs):
        y = by_id.loc[ids, out].to_numpy(dtype=float)
        if not np.isfinite(y).all() or np.std(y) == 0:
            continue  # invalid designs in the Saltelli matrix: no indices for this output
        s = sobol.analyze(problem, y, calc_second_order=False, seed=sweep.settings.seed)
        m[:, j] = np.clip(s["ST"], 0, None)
    if np.isnan(m).all():
        return None
    return "Sobol total-order index ST (SALib, Saltelli design)", [k.name for k in sweep.keys], outputs, m, {}


def _src(sweep, table, outputs):
    ok = table[table["verdict"].isin(_EVALUATED)]
    cols, names = [], []
    for k in sweep.keys:
        if k.name not in ok.columns:
            continue
        if k.is_choice:
            for c in k.choices[1:]:
                cols.append((ok[k.name].astype(str) == str(c)).to_numpy(dtype=float))
                names.append(f"{k.name}={c}")
        else:
            cols.append(ok[k.name].to_numpy(dtype=float))
            names.append(k.name)
    m = np.full((len(names), len(outputs)), np.nan)
    r2 = {}
    if len(ok) < len(names) + 2 or not cols:
        return "standardized regression coefficient (too few valid designs)", names, outputs, m, r2
    x = np.column_stack(cols)
    sx = x.std(axis=0)
    live = sx > 0
    xs = (x[:, live] - x[:, live].mean(axis=0)) / sx[live]
    for j, out in enumerate(outputs):
        y = ok[out].to_numpy(dtype=float)
        fin = np.isfinite(y)
        if fin.sum() < live.sum() + 2 or np.std(y[fin]) == 0:
            continue
        ys = (y[fin] - y[fin].mean()) / y[fin].std()
        a = np.column_stack([xs[fin], np.ones(fin.sum())])
        coef, *_ = np.linalg.lstsq(a, ys, rcond=None)
        full = np.zeros(len(names))
        full[live] = coef[:-1]
        m[:, j] = full
        resid = ys - a @ coef
        r2[out] = float(1 - resid @ resid / (ys @ ys))
    return "standardized regression coefficient (SRC)", names, outputs, m, r2


# -- figures ---------------------------------------------------------------------------------

def plot_pareto(table, path: Path, title: str) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5), dpi=110)
    for verdict, colour, label in (("FAIL", "#e69f00", "FAIL"), ("PASS", "#56b4e9", "PASS")):
        s = table[(table["verdict"] == verdict) & table[FRONT_X].notna()]
        if len(s):
            ax.scatter(s[FRONT_X], s[FRONT_Y], s=14, c=colour, alpha=0.7, label=f"{label} ({len(s)})", edgecolors="none")
    front = pareto_front(table)
    if len(front):
        ax.step(front[FRONT_X], front[FRONT_Y], where="post", color="#d55e00", lw=1.2)
        ax.scatter(front[FRONT_X], front[FRONT_Y], s=36, facecolors="none", edgecolors="#d55e00", lw=1.4,
                   label=f"feasible front ({len(front)})")
    ax.set_xlabel("all-up mass, g (lower is better)")
    ax.set_ylabel("max safe drop, cm (higher is better)")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, loc="best")
    else:
        ax.text(0.5, 0.5, "no evaluated designs", ha="center", va="center", transform=ax.transAxes)
    fig.tight_layout()
    fig.savefig(path, metadata={"Software": "cogniframe"})
    plt.close(fig)
    return path


def plot_sensitivity(method: str, inputs: list[str], outputs: list[str], m: np.ndarray, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(1.6 + 1.5 * max(1, len(outputs)), 1.4 + 0.45 * max(1, len(inputs))), dpi=110)
    if m.size == 0:  # no design was evaluated: say so instead of an empty axis
        ax.text(0.5, 0.5, "no evaluated designs", ha="center", va="center")
        ax.set_axis_off()
        fig.savefig(path, metadata={"Software": "cogniframe"})
        plt.close(fig)
        return path
    sobol = method.startswith("Sobol")
    vmax = 1.0 if sobol else max(1e-9, float(np.nanmax(np.abs(m))) if np.isfinite(m).any() else 1.0)
    im = ax.imshow(np.nan_to_num(m), cmap="viridis" if sobol else "RdBu_r", vmin=0 if sobol else -vmax, vmax=vmax, aspect="auto")
    ax.set_xticks(range(len(outputs)), outputs, rotation=20, ha="right", fontsize=8)
    ax.set_yticks(range(len(inputs)), inputs, fontsize=8)
    for i in range(len(inputs)):
        for j in range(len(outputs)):
            v = m[i, j]
            ax.text(j, i, "-" if not np.isfinite(v) else f"{v:.2f}", ha="center", va="center", fontsize=8,
                    color="white" if np.isfinite(v) and abs(v) > 0.5 * vmax else "black")
    ax.set_title(method, fontsize=9)
    fig.colorbar(im, ax=ax, shrink=0.8)
    fig.tight_layout()
    fig.savefig(path, metadata={"Software": "cogniframe"})
    plt.close(fig)
    return path


# -- summary ---------------------------------------------------------------------------------

def _fmt(v) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def _md_table(header: list[str], rows: list[list]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(_fmt(v) for v in r) + " |" for r in rows]
    return out


def base_outputs(sweep) -> dict:
    """The base design's row (evaluated here, on the client: it is one check)."""
    from . import evaluate as ev

    return ev.evaluate_one(sweep.base_data, {}, sweep.settings.timeout_s, "client", sweep.base_text, sweep.base_label)


def write_reports(out_dir: Path, sweep, table, result, base: dict | None = None) -> None:
    """pareto.png, sensitivity.png and summary.md; `base`: the base design's row when a worker
    evaluated it already (else it is evaluated here)."""
    if not len(table):
        return
    keys = [k.name for k in sweep.keys]
    plot_pareto(table, out_dir / "pareto.png", f"{sweep.stem}: {len(table)} designs from {Path(sweep.base_path).name}")
    method, inputs, outputs, m, r2 = sensitivity(sweep, table)
    plot_sensitivity(method, inputs, outputs, m, out_dir / "sensitivity.png")
    base = base if base is not None else base_outputs(sweep)
    c = result.as_dict()
    lines = [f"# Sweep {sweep.stem}", "",
             f"Base `{sweep.base_path}` ({base['verdict']}, {_fmt(base['mass_g'])} g, max safe drop "
             f"{_fmt(base['max_safe_drop_cm'])} cm); sampler `{sweep.settings.sampler}`, seed {sweep.settings.seed}; "
             f"{c['designs']} designs: {c['pass']} PASS, {c['fail']} FAIL, {c['invalid']} INVALID, "
             f"{c['timeout']} TIMEOUT, {c['error']} ERROR.", "",
             "Varied: " + ", ".join(f"`{k.name}` " + (f"{{{', '.join(map(str, k.choices))}}}" if k.is_choice else f"[{k.lo:g}, {k.hi:g}]")
                                    for k in sweep.keys), ""]
    joint_model = str(sweep.base_data.get("model", {}).get("stiffness_model", "fe"))
    if joint_model == "analytic":
        lines += ["Joints from the closed forms (`model.stiffness_model: analytic`): milliseconds per design, but "
                  "they differ from the solid-FE joints of the presets by -49 % to +40 % in k (docs/stiffness-model.md). "
                  "Read trends here; re-check a chosen design with `cogniframe check` (FE), as `cogniframe optimize` "
                  "does for its finalists.", ""]
    elif joint_model == "surrogate":
        outside = int((table["joints_outside_box"].fillna("") != "").sum()) if "joints_outside_box" in table else 0
        lines += ["Joints from the solid FE's surrogate (`model.stiffness_model: surrogate`, the sweeps' default): "
                  "within a few per cent of the FE (docs/stiffness-model.md); "
                  f"{outside} design(s) had a joint outside its training box, solved by FE (column `joints_outside_box`).", ""]
    else:
        lines += [f"Joints from `{joint_model}` (the solid FE of each joint geometry).", ""]
    passed = table[table["verdict"] == "PASS"].sort_values("mass_g")
    if len(passed):
        best = passed.iloc[0]
        lines += ["## Lightest design that passes", "",
                  *_md_table(["key", "base", "lightest PASS"],
                             [[k, _get(sweep.base_data, k), best[k]] for k in keys]
                             + [[o, base.get(o), best[o]] for o in ("mass_g", "k_n_per_m", "max_safe_drop_cm", "prop_margin_mm")]),
                  "", f"design_id `{best['design_id']}`; {_fmt(base['mass_g'] - best['mass_g']) if base['mass_g'] is not None else '-'} g lighter than the base.", ""]
    else:
        lines += ["No design passes.", ""]
    front = pareto_front(table)
    if len(front):
        lines += ["## Feasible front (mass against max safe drop)", "", "![pareto](pareto.png)", "",
                  *_md_table(["design_id", *keys, "mass_g", "max_safe_drop_cm"],
                             [[r["design_id"], *[r[k] for k in keys], r["mass_g"], r["max_safe_drop_cm"]] for _, r in front.head(20).iterrows()]), ""]
    lines += ["## Sensitivity", "", f"{method}; rows are inputs, columns outputs.", "", "![sensitivity](sensitivity.png)", "",
              *_md_table(["input", *outputs], [[name, *m[i].tolist()] for i, name in enumerate(inputs)]), ""]
    if r2:
        lines += ["Linear-fit R^2: " + ", ".join(f"{o} {v:.2f}" for o, v in r2.items()) + ".", ""]
    bad = table[table["verdict"].isin(["INVALID", "ERROR", "TIMEOUT"])]
    if len(bad):
        reasons = bad["error"].map(_reason).value_counts().head(8)
        lines += ["## Designs not evaluated", "", *_md_table(["count", "reason"], [[int(n), r] for r, n in reasons.items()]), ""]
    fails = table[table["verdict"] == "FAIL"]["problems"].map(_reason).value_counts().head(8)
    if len(fails):
        lines += ["## Why designs fail", "", *_md_table(["count", "first problem"], [[int(n), r] for r, n in fails.items()]), ""]
    lines += ["## Run", "", f"{c['evaluated']} designs evaluated in this run ({c['skipped']} reused from earlier runs) in "
              f"{c['seconds']:.1f} s on {c['workers']} Dask workers ({c['scheduler'] or 'no cluster needed'}).", ""]
    (out_dir / "summary.md").write_text("\n".join(lines))


def _get(data: dict, dotted: str):
    node = data
    for p in dotted.split("."):
        if not isinstance(node, dict) or p not in node:
            return None
        node = node[p]
    return node


def _reason(text) -> str:
    """The gist of an error or problem text: drop the design id and numbers that differ per design."""
    import re

    t = str(text or "").split("; ")[0]
    t = re.sub(r"^design [0-9a-f]+ of [^:]+: ", "", t)
    t = re.sub(r"\d+(\.\d+)?", "#", t)
    return t[:160].replace("|", "/")
