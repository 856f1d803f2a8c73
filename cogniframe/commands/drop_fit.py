"""`cogniframe drop` (the impact model) and `cogniframe fit` (c, k from drop tests).

Both raise :class:`cogniframe.errors.UserError` for anything the user can fix; the CLI entry
point prints it and exits with code 2. The work is the API's (`api.droptests`); these parse the
options and print. ``register(app)`` adds both commands to a Typer app.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Annotated, Optional

import typer

from cogniframe.errors import UserError


def _stdout():
    from rich.console import Console

    return Console()


def _stderr():
    from rich.console import Console

    return Console(stderr=True)


def _positive(value: float, option: str, unit: str, example: str, allow_zero: bool = False) -> float:
    ok = (value >= 0 if allow_zero else value > 0) and math.isfinite(value)
    if not ok:
        need = "zero or more" if allow_zero else "greater than zero"
        raise UserError(f"Option {option} is {value:g}; it must be a number {need} in {unit} "
                        f"(e.g. {option} {example}).")
    return value


def _parse_heights(text: str) -> list[float]:
    try:
        heights = [float(p) for p in text.replace(" ", "").split(",") if p]
    except ValueError:
        raise UserError(f"Option --heights is '{text}'; give drop heights in cm separated by "
                        "commas, e.g. --heights 50,100,150.") from None
    if not heights:
        raise UserError("Option --heights is empty; give drop heights in cm separated by "
                        "commas, e.g. --heights 50,100,150.")
    for h in heights:
        _positive(h, "--heights", "cm", "50,100,150", allow_zero=True)
    return heights


# --------------------------------------------------------------------------------------------
# drop


def drop(
    mass_kg: Annotated[float, typer.Option("--mass-kg", "--mass", help="Total mass in kg (paper's crash-test build: 0.241).")],
    k: Annotated[float, typer.Option("--k", help="Stiffness k in N/m (paper: 7040).")],
    c: Annotated[Optional[float], typer.Option("--c", help="Damping c in N s/m (paper: 46). Give --c or --zeta.")] = None,
    zeta: Annotated[Optional[float], typer.Option("--zeta", help="Damping ratio instead of --c: c = 2 zeta sqrt(k m) (paper: 0.558).")] = None,
    heights: Annotated[str, typer.Option("--heights", help="Drop heights in cm, comma-separated.")] = "50,100,150",
    clearance_mm: Annotated[float, typer.Option("--clearance-mm", help="Payload travel before the battery holder hits the ground, mm.")] = 16.0,
    as_json: Annotated[bool, typer.Option("--json", help="Print the result as one JSON object and nothing else.")] = False,
    plots: Annotated[Optional[Path], typer.Option("--plots", help="Folder to write drop_response.png and energy_split.png into.")] = None,
) -> None:
    """Drop the payload on the exoskeleton (mass-spring-damper model): compression, peak G,
    energy split and the highest drop that keeps the battery holder off the ground."""
    from cogniframe.api import droptests

    _positive(mass_kg, "--mass-kg", "kg", "0.241")
    _positive(k, "--k", "N/m", "7040")
    _positive(clearance_mm, "--clearance-mm", "mm", "16")
    if (c is None) == (zeta is None):
        raise UserError("Give exactly one of --c (damping in N s/m, e.g. --c 46) or --zeta "
                        "(damping ratio, e.g. --zeta 0.558); "
                        + ("both were given." if c is not None else "neither was given."))
    if zeta is not None:
        _positive(zeta, "--zeta", "(dimensionless)", "0.558", True)
    else:
        _positive(c, "--c", "N s/m", "46", allow_zero=True)
    run = droptests.drop(mass_kg, k, _parse_heights(heights), clearance_mm, c=c, zeta=zeta, plots=plots)
    result, c, written = run.result, run.c_n_s_per_m, run.written

    if as_json:
        sys.stdout.write(json.dumps(result.to_dict()) + "\n")
        for p in written:
            _stderr().print(f"wrote {p}")
        return

    from rich.table import Table

    out = _stdout()
    table = Table(title=f"Drop model: m = {mass_kg:g} kg, c = {c:.4g} N s/m, k = {k:.4g} N/m, "
                        f"zeta = {result.damping_ratio:.3f}")
    for col in ("h cm", "v m/s", "x_max mm", "t_max ms", "peak G", "spring %",
                "damper %", "rigid %", "strike"):
        table.add_column(col, justify="right")
    for h in result.heights:
        table.add_row(
            f"{h.height_cm:g}", f"{h.v_impact_m_per_s:.2f}", f"{h.x_max_mm:.2f}",
            f"{h.t_max_s * 1e3:.2f}" if math.isfinite(h.t_max_s) else "-",
            f"{h.peak_g:.1f}", f"{h.energy_spring_pct:.1f}", f"{h.energy_damper_pct:.1f}",
            f"{h.energy_rigid_pct:.1f}", "[red]yes[/red]" if h.strikes else "no",
        )
    out.print(table)
    out.print(f"Max safe height: {result.max_safe_height_cm:.1f} cm "
              f"(x_max stays within the {clearance_mm:g} mm clearance)")
    for p in written:
        out.print(f"wrote {p}")


# --------------------------------------------------------------------------------------------
# fit


def fit(
    data: Annotated[list[Path], typer.Argument(help="Folders of trials (.bin logger files or .csv), or trial files. One height per argument.", show_default=False)],
    height: Annotated[Optional[list[float]], typer.Option("--height", help="Drop height in cm, once per DATA argument in order. Without it: 'height_cm' from the folder's drop.yaml, else a height in the folder name (SoftBottom_50cm).")] = None,
    mass_kg: Annotated[Optional[float], typer.Option("--mass", "--mass-kg", help="Mass in kg of the dropped build; defaults to 'mass_kg' in drop.yaml.")] = None,
    static: Annotated[Optional[Path], typer.Option("--static", help="Static test CSV (force_n, displacement_mm): also report the static k.")] = None,
    write: Annotated[Optional[Path], typer.Option("--write", help="Params YAML: store the fitted k_n_per_m and c_n_s_per_m under 'model:' (comments kept).")] = None,
    plot: Annotated[Optional[Path], typer.Option("--plot", help="Write the measured-vs-model figure to this PNG (no figure without it).")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the fit as one JSON object and nothing else on stdout.")] = False,
    no_lowpass: Annotated[bool, typer.Option("--no-lowpass", help="Compare the raw model, without the paper's low-pass filter.")] = False,
    lowpass_rad_per_s: Annotated[float, typer.Option("--lowpass-rad-per-s", help="Low-pass corner w of H(s) = w/(s+w), rad/s.")] = 500.0,
    loss: Annotated[str, typer.Option("--loss", help="cauchy: log(1 + total MSE) as the paper; mse: the total.")] = "cauchy",
    model: Annotated[str, typer.Option("--model", help="kelvin-voigt: the paper's one-mass model (default); nonlinear: the two-mass model with the exoskeleton's own mass on a unilateral floor contact (docs/impact-model.md).")] = "kelvin-voigt",
    predict: Annotated[Optional[list[float]], typer.Option("--predict", help="Drop height in cm to predict (repeatable): the mean pulse's peak |a| as the logger sees it (500 rad/s low-pass), one drop's median and 90th-percentile peak (scatter learnt from these drops), x_max and whether the holder strikes.")] = None,
    exo_mass_kg: Annotated[float, typer.Option("--exo-mass-kg", help="Exoskeleton (rods + joints) mass in kg for --model nonlinear (paper's build: 0.062).")] = 0.062,
    clearance_mm: Annotated[float, typer.Option("--clearance-mm", help="Battery-holder clearance for the strike flag of --predict, mm.")] = 16.0,
) -> None:
    """Fit damping c and stiffness k to accelerometer drop tests with the paper's procedure."""
    from cogniframe.api import droptests

    if loss not in droptests.losses():
        raise UserError(f"Option --loss is '{loss}'; use 'cauchy' (the paper's) or 'mse'.")
    if model not in droptests.models():
        raise UserError(f"Option --model is '{model}'; use 'kelvin-voigt' (the paper's, default) or 'nonlinear'.")
    for h in predict or []:
        _positive(h, "--predict", "cm", "100")
    _positive(clearance_mm, "--clearance-mm", "mm", "16")
    if model == "nonlinear" and write is not None:
        raise UserError("Option --write stores the Kelvin-Voigt c and k in the params file; it cannot be combined "
                        "with --model nonlinear. Drop --write, or fit with --model kelvin-voigt.")
    if not no_lowpass:
        _positive(lowpass_rad_per_s, "--lowpass-rad-per-s", "rad/s", "500")
    if write is not None:
        droptests.check_params_file(write)  # before any work is done
    for h in height or []:
        _positive(h, "--height", "cm", "50")
    pairs, manifest_masses = droptests.drop_sources(list(data), list(height or []))
    mass_kg = _one_mass(mass_kg, manifest_masses)
    if model == "nonlinear" and not 0 < exo_mass_kg < mass_kg:
        raise UserError(f"Option --exo-mass-kg is {exo_mass_kg:g}; it must be more than 0 and less than the total "
                        f"mass {mass_kg:g} kg (the paper's exoskeleton: --exo-mass-kg 0.062).")
    k_static = droptests.static_stiffness(static, mass_kg) if static is not None else None

    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    with Progress(TextColumn("reading trials"), BarColumn(), MofNCompleteColumn(),
                  console=_stderr(), transient=True) as progress:
        task = progress.add_task("read", total=None)
        heights_data = droptests.read_drops(pairs, on_total=lambda n: progress.update(task, total=n),
                                            on_file=lambda _p: progress.advance(task))

    run = droptests.fit(heights_data, mass_kg, model=model, lowpass_rad_per_s=None if no_lowpass else lowpass_rad_per_s,
                        loss=loss, predict_cm=predict or [], exo_mass_kg=exo_mass_kg, clearance_mm=clearance_mm,
                        static_k_n_per_m=k_static, plot=plot if model != "nonlinear" else None, write=write)
    if as_json:
        sys.stdout.write(json.dumps(run.to_dict()) + "\n")
        if model != "nonlinear":
            err = _stderr()
            for s in run.result.skipped:
                err.print(f"skipped {s}", markup=False, highlight=False, soft_wrap=True)
        return
    out = _stdout()
    if model == "nonlinear":
        _print_nonlinear(out, run, exo_mass_kg)
        return
    _print_fit(out, run, mass_kg)
    if plot is not None:
        out.print(f"wrote {plot}")
    if write is not None:
        out.print(f"wrote model.k_n_per_m and model.c_n_s_per_m to {write}")


def _one_mass(mass_kg: float | None, manifest_masses: list[float]) -> float:
    """--mass, else the one mass the data folders' manifests declare."""
    from cogniframe.api.droptests import MANIFEST

    if mass_kg is None:
        if not manifest_masses:
            raise UserError("No mass: give --mass <kg> (the dropped build's total mass, e.g. "
                            f"--mass 0.241) or add 'mass_kg: <kg>' to each folder's {MANIFEST}.")
        if max(manifest_masses) - min(manifest_masses) > 1e-9:
            raise UserError(f"The {MANIFEST} files declare different masses "
                            f"({', '.join(f'{m:g}' for m in sorted(set(manifest_masses)))} kg); "
                            "the model fits one mass. Give --mass <kg> to choose.")
        mass_kg = manifest_masses[0]
    return _positive(mass_kg, "--mass", "kg", "0.241")


def _print_fit(out, run, mass_kg: float) -> None:
    """The Kelvin-Voigt fit's tables: c, k and the loss; each height; the predictions."""
    from rich.table import Table

    result, k_static, lowpass = run.result, run.static_k_n_per_m, run.lowpass_rad_per_s
    summary = Table(title="Drop-test fit")
    summary.add_column("quantity")
    summary.add_column("value", justify="right")
    summary.add_row("c (N s/m)", f"{result.c_n_s_per_m:.2f}")
    summary.add_row("k (N/m)", f"{result.k_n_per_m:.1f}")
    summary.add_row("damping ratio", f"{result.damping_ratio:.3f}")
    summary.add_row("loss", f"{result.loss:.4f}")
    if k_static is not None:
        summary.add_row("static k (N/m)", f"{k_static:.1f}")
    if not result.converged:
        summary.add_row("[red]converged[/red]", "[red]no[/red]")
    out.print(summary)
    per = Table(title="Per height")
    for col in ("height cm", "trials used", "skipped", "median peak G", "RMSE G"):
        per.add_column(col, justify="right")
    for h in result.heights:
        per.add_row(f"{h.height_cm:g}", str(h.trials_used), str(h.trials_skipped),
                    f"{h.peak_median_g:.1f}", f"{h.rmse_g:.1f}")
    out.print(per)
    if run.predictions:
        _print_predictions(out, run.predictions, run.scatter)
    out.print(f"m = {mass_kg:g} kg, loss {run.loss}, "
              + ("no low-pass" if lowpass is None else f"low-pass {lowpass:g} rad/s")
              + f", {result.evaluations} evaluations")
    for s in result.skipped:
        out.print(f"skipped {s}", markup=False, highlight=False, soft_wrap=True)


def _print_predictions(out, predictions, scatter=None) -> None:
    from rich.table import Table

    t = Table(title="Predictions (peak |a| as the logger sees it: the mean pulse through the 500 rad/s low-pass, and one drop's median and 90th percentile)")
    for col in ("height cm", "mean-pulse peak G", "one drop: median G", "p90 G", "x_max mm", "strike"):
        t.add_column(col, justify="right")
    for p in predictions:
        t.add_row(f"{p['height_cm']:g}", f"{p['peak_g']:.1f}", f"{p['peak_g_drop_median']:.1f}", f"{p['peak_g_drop_p90']:.1f}",
                  f"{p['x_max_mm']:.2f}", "yes" if p["strikes"] else "no")
    out.print(t)
    if scatter is not None:
        s = scatter.scatter
        out.print(f"single-drop scatter learnt from these drops: mount {s.mount_hz:.0f} Hz, damping {s.mount_zeta:.3f}, "
                  f"release spin {s.spin_sigma_deg_s:.2f} deg/s (Rayleigh scale; a tilt of "
                  f"{s.tilt_scale_deg(100.0):.2f} deg at touch-down from 100 cm)")


def _print_nonlinear(out, run, exo_mass_kg: float) -> None:
    """The two-mass fit's table: frame and contact springs and dampers; each height; the predictions."""
    from rich.table import Table

    r = run.result
    t = Table(title="Drop-test fit: two-mass model (nonlinear)")
    t.add_column("quantity")
    t.add_column("value", justify="right")
    for label, v in (("c (N s/m)", f"{r.c_n_s_per_m:.2f}"), ("k (N/m)", f"{r.k_n_per_m:.1f}"),
                     ("contact k_c (N/m)", f"{r.contact_k_n_per_m:.4g}"), ("contact c_c (N s/m)", f"{r.contact_c_n_s_per_m:.4g}"),
                     ("exoskeleton mass (kg)", f"{exo_mass_kg:g}"), ("loss", f"{r.loss:.4f}")):
        t.add_row(label, v)
    if run.static_k_n_per_m is not None:
        t.add_row("static k (N/m)", f"{run.static_k_n_per_m:.1f}")
    out.print(t)
    for h in r.heights:
        out.print(f"{h['height_cm']:g} cm: {h['trials_used']} trials, median peak {h['peak_median_g']:.1f} G, RMSE {h['rmse_g']:.1f} G")
    if run.predictions:
        _print_predictions(out, run.predictions, run.scatter)


def register(app: typer.Typer) -> None:
    """Add `drop` and `fit` to ``app``."""
    app.command("drop")(drop)
    app.command("fit")(fit)
