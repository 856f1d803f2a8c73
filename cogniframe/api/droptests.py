"""The impact model and drop-test fitting: what `cogniframe drop` and `cogniframe fit` do, from Python.

    run = drop(0.241, 7040.0, [50, 100, 150], 16.0, zeta=0.558)     # DropRun: the model per height
    pairs, masses = drop_sources([Path("examples/droptests/SoftBottom_50cm")], [])
    heights = read_drops(pairs)                                      # the trials, trimmed, per height
    fitted = fit(heights, 0.241, predict_cm=[100])                   # FitRun: c, k, the predictions

A drop-test folder may hold a `drop.yaml` manifest (`height_cm:`, optional `mass_kg:`); without
one, the height comes from the folder's name (SoftBottom_50cm). `fit(..., write=PATH)` stores the
fitted Kelvin-Voigt k and c under `model:` in a params file, comments and order kept
(`check_params_file` checks that file before any work). Problems the user can fix raise UserError
naming the file and the fix.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import UserError

MANIFEST = "drop.yaml"
"""Per-folder manifest read by `fit`: ``height_cm:`` and optional ``mass_kg:``."""

_HEIGHT_IN_NAME = re.compile(r"(\d+(?:\.\d+)?)\s*cm", re.IGNORECASE)

def models() -> tuple[str, ...]:
    """The fit's models: kelvin-voigt (the paper's one mass) and nonlinear (two masses on a
    unilateral floor contact, docs/impact-model.md)."""
    from ..analysis.impact_nl import MODELS

    return tuple(MODELS)


def losses() -> tuple[str, ...]:
    """The fit's loss functions: cauchy (the paper's log(1 + total MSE)) and mse."""
    from ..analysis.fit import LOSSES

    return tuple(LOSSES)


# -- the impact model -----------------------------------------------------------------------------

@dataclass(frozen=True)
class DropRun:
    result: Any  # analysis.impact.DropResult: per height compression, peak G, energy split, strike
    c_n_s_per_m: float  # the damping used (from zeta when that was given)
    written: tuple[Path, ...]  # the plots written


def drop(mass_kg: float, k: float, heights_cm: Sequence[float], clearance_mm: float, *, c: float | None = None,
         zeta: float | None = None, plots: Path | None = None) -> DropRun:
    """The payload dropped on the exoskeleton (mass-spring-damper): damping `c` (N s/m) or its
    ratio `zeta` (c = 2 zeta sqrt(k m)); with `plots`, drop_response.png and energy_split.png
    written into that folder."""
    from ..analysis.impact import damping_from_ratio, evaluate

    if (c is None) == (zeta is None):
        raise ValueError("give exactly one of c and zeta")
    if zeta is not None:
        c = damping_from_ratio(zeta, k, mass_kg)
    result = evaluate(mass_kg, c, k, list(heights_cm), clearance_mm)
    written: tuple[Path, ...] = ()
    if plots is not None:
        from ..report.drop_plots import plot_drop_response, plot_energy_split

        written = (plot_drop_response(result, plots / "drop_response.png"),
                   plot_energy_split(result, plots / "energy_split.png"))
    return DropRun(result, c, written)


# -- drop-test data -------------------------------------------------------------------------------

def read_manifest(folder: Path) -> dict:
    """``drop.yaml`` of a folder as {"height_cm": float, "mass_kg": float}, the keys it has."""
    path = folder / MANIFEST
    if not path.is_file():
        return {}
    from ruamel.yaml import YAML, YAMLError

    try:
        data = YAML(typ="safe").load(path.read_text())
    except YAMLError as exc:
        raise UserError(f"Manifest '{path}' is not valid YAML ({str(exc).splitlines()[0]}). "
                        "Write it as two lines, e.g. 'height_cm: 50' and 'mass_kg: 0.241'.") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise UserError(f"Manifest '{path}' must be a mapping such as 'height_cm: 50' "
                        "(and optionally 'mass_kg: 0.241').")
    unknown = set(data) - {"height_cm", "mass_kg"}
    if unknown:
        raise UserError(f"Manifest '{path}' has unknown key(s) {', '.join(sorted(map(str, unknown)))}; "
                        "the keys are 'height_cm' (required) and 'mass_kg' (optional).")
    out = {}
    for key, unit, example in (("height_cm", "cm", "50"), ("mass_kg", "kg", "0.241")):
        if key in data:
            v = data[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0 or not math.isfinite(v):
                raise UserError(f"Manifest '{path}': key '{key}' is {v!r}; it must be a positive "
                                f"number in {unit} (e.g. '{key}: {example}').")
            out[key] = float(v)
    return out


def drop_sources(data: Sequence[Path], heights: Sequence[float]) -> tuple[list[tuple[float, Path]], list[float]]:
    """Every data path (a folder of trials or a trial file) with its drop height in cm: `heights`
    in order when given, else the folder's manifest, else the height in the folder's name; and the
    masses the manifests declare."""
    if heights and len(heights) != len(data):
        raise UserError(f"Got {len(heights)} --height value(s) for {len(data)} DATA argument(s). "
                        "Give --height once per DATA argument, in the same order, or leave it "
                        f"out and put a '{MANIFEST}' with 'height_cm: <cm>' in each data folder.")
    pairs, masses = [], []
    for i, p in enumerate(data):
        if not p.exists():
            raise UserError(f"Drop-test data '{p}' does not exist. Give folders of trial files "
                            "(.bin from the logger, or .csv) or the files themselves.")
        folder = p if p.is_dir() else p.parent
        manifest = read_manifest(folder)
        if "mass_kg" in manifest:
            masses.append(manifest["mass_kg"])
        if heights:
            h = heights[i]
        elif "height_cm" in manifest:
            h = manifest["height_cm"]
        else:
            m = _HEIGHT_IN_NAME.findall(folder.name)
            if not m:
                raise UserError(
                    f"No drop height for '{p}': give --height <cm> (once per DATA argument), or "
                    f"add '{folder / MANIFEST}' containing 'height_cm: <cm>', or name the folder "
                    "after the height (e.g. SoftBottom_50cm).")
            h = float(m[-1])
        pairs.append((h, p))
    return pairs, masses


def static_stiffness(path: Path, mass_kg: float) -> float:
    """k (N/m) of a static test CSV (force_n, displacement_mm)."""
    from ..analysis.fit import fit_static_stiffness

    return fit_static_stiffness(path, mass_kg)


def read_drops(pairs: Sequence[tuple[float, Path]], on_total: Callable[[int], None] | None = None,
               on_file: Callable[[Path], None] | None = None) -> list:
    """The trials of every height (`analysis.droplogs.HeightData`, lowest first): several data
    paths at one height are one height, trimmed and averaged together. `on_total(n)` is told the
    number of trial files before they are read, `on_file(path)` each as it is read."""
    from ..analysis import droplogs as L

    groups: dict[float, list[Path]] = {}
    for h, p in pairs:
        groups.setdefault(h, []).append(p)
    collected = {h: L.collect_files(ps) for h, ps in groups.items()}
    if on_total is not None:
        on_total(sum(len(files) for files, _ in collected.values()))
    out = []
    for h, (files, skipped) in sorted(collected.items()):
        trials, bad = L.load_trials(files, on_file=on_file or (lambda _p: None))
        out.append(L.prepare_height(trials, h, skipped=skipped + bad, source=", ".join(map(str, groups[h]))))
    return out


# -- the fit ----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class FitRun:
    model: str  # "kelvin-voigt" | "nonlinear"
    result: Any  # analysis.fit.FitResult (kelvin-voigt) or analysis.fit.NonlinearFit
    loss: str
    lowpass_rad_per_s: float | None
    static_k_n_per_m: float | None = None
    scatter: Any = None  # analysis.single_drop's fitted scatter, when predictions were asked for
    predictions: tuple[dict, ...] | None = None  # peaks.predict's rows per height

    def to_dict(self) -> dict:
        """`fit --json`."""
        d = self.result.to_dict()
        if self.model == "nonlinear":
            if self.scatter is not None:
                d["single_drop"] = self.scatter.to_dict()
            d["lowpass_rad_per_s"] = self.lowpass_rad_per_s
            d["loss_kind"] = self.loss
            d["predictions"] = list(self.predictions or ())
            if self.static_k_n_per_m is not None:
                d["static_k_n_per_m"] = self.static_k_n_per_m
            return d
        if self.static_k_n_per_m is not None:
            d["static_k_n_per_m"] = self.static_k_n_per_m
        if self.predictions is not None:
            d["model"] = "kelvin-voigt"
            d["single_drop"] = self.scatter.to_dict()
            d["predictions"] = list(self.predictions)
        return d


def fit(heights_data: Sequence, mass_kg: float, *, model: str = "kelvin-voigt", lowpass_rad_per_s: float | None = 500.0,
        loss: str = "cauchy", predict_cm: Sequence[float] = (), exo_mass_kg: float = 0.062, clearance_mm: float = 16.0,
        static_k_n_per_m: float | None = None, plot: Path | None = None, write: Path | None = None) -> FitRun:
    """Fit the frame's damping c and stiffness k (and, for the two-mass `nonlinear` model, the
    floor contact's) to the drops (`read_drops`) with the paper's procedure. With `predict_cm`,
    the single-drop scatter is learnt from the same drops with the fitted pulse and each height's
    peaks predicted. Kelvin-Voigt only: `plot` writes the measured-vs-model PNG, `write` stores k
    and c in that params file (`check_params_file` first)."""
    from ..analysis import fit as F
    from ..analysis import peaks
    from ..analysis import single_drop as S

    if model == "nonlinear":
        r = F.fit_nonlinear(list(heights_data), mass_kg, exo_mass_kg, lowpass_rad_per_s=lowpass_rad_per_s, loss=loss)
        scatter = (S.fit_scatter(heights_data, lambda h: S.two_mass_pulse_g(r.params(), h))
                   if predict_cm else None)
        preds = peaks.predict("nonlinear", mass_kg, r.c_n_s_per_m, r.k_n_per_m, list(predict_cm), clearance_mm,
                              m_exo=exo_mass_kg, k_c=r.contact_k_n_per_m, c_c=r.contact_c_n_s_per_m,
                              lowpass_rad_per_s=lowpass_rad_per_s, scatter=scatter.scatter if scatter else None)
        return FitRun(model, r, loss, lowpass_rad_per_s, static_k_n_per_m, scatter, tuple(preds))
    result = F.fit_drop_tests(list(heights_data), mass_kg, lowpass_rad_per_s=lowpass_rad_per_s, loss=loss)
    predictions, scatter = None, None
    if predict_cm:
        scatter = S.fit_scatter(heights_data, lambda h: S.kv_pulse_g(mass_kg, result.c_n_s_per_m, result.k_n_per_m, h))
        predictions = tuple(peaks.predict("kelvin-voigt", mass_kg, result.c_n_s_per_m, result.k_n_per_m, list(predict_cm),
                                          clearance_mm, lowpass_rad_per_s=lowpass_rad_per_s, scatter=scatter.scatter))
    if plot is not None:
        from ..report.drop_plots import plot_fit

        plot_fit(result, plot)
    if write is not None:
        _store_model(write, result.c_n_s_per_m, result.k_n_per_m)
    return FitRun(model, result, loss, lowpass_rad_per_s, static_k_n_per_m, scatter, predictions)


# -- the params file the fit is stored in -----------------------------------------------------------

def check_params_file(path: Path) -> None:
    """Refuse a params file `fit(write=path)` cannot store k and c in (missing, not YAML, not a
    mapping, `model` not a section): checked before any work is done."""
    _round_trip(path)


def _round_trip(path: Path):
    """(the round-trip YAML loader, the document) of a params file, comments and order kept."""
    from ruamel.yaml import YAML, YAMLError
    from ruamel.yaml.comments import CommentedMap

    if not path.is_file():
        raise UserError(f"Params file '{path}' (from --write) does not exist. Give the params "
                        "file of your build; the fitted values go into its 'model:' section.")
    yaml = YAML()  # round-trip: keeps comments, key order and quoting
    yaml.preserve_quotes = True
    try:
        doc = yaml.load(path.read_text())
    except YAMLError as exc:
        raise UserError(f"Params file '{path}' (from --write) is not valid YAML "
                        f"({str(exc).splitlines()[0]}); fix it before writing into it.") from None
    if doc is None:
        doc = CommentedMap()
    if not isinstance(doc, dict):
        raise UserError(f"Params file '{path}' (from --write) must be a YAML mapping at the top "
                        "level (keys such as 'model:').")
    model = doc.get("model")
    if model is not None and not isinstance(model, dict):
        raise UserError(f"Params file '{path}': key 'model' is {model!r}, not a mapping. Make it "
                        "a section, e.g. 'model:' followed by indented 'k_n_per_m: 7040'.")
    return yaml, doc


def _store_model(path: Path, c: float, k: float) -> None:
    """Set model.k_n_per_m and model.c_n_s_per_m (creating 'model:' if absent) and save."""
    from ruamel.yaml.comments import CommentedMap

    yaml, doc = _round_trip(path)
    if doc.get("model") is None:
        doc["model"] = CommentedMap()
    # Six significant digits: more than the data supports, and the file stays readable.
    doc["model"]["k_n_per_m"] = float(f"{k:.6g}")
    doc["model"]["c_n_s_per_m"] = float(f"{c:.6g}")
    with path.open("w") as fh:
        yaml.dump(doc, fh)
