"""What the API hands back: `CheckResult` (what `cogniframe check` found, read from its `--json`
object) and `BuildResult` (what `cogniframe build` wrote, from its manifest). Views of finished
work, made by `Design.check` / `Design.build` (api/__init__.py) and never by the user; they read
nothing of the Design that made them.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from ..analysis import verdict


def _json_copy(node):
    """A fresh copy of a JSON tree (dicts, lists, scalars): what `copy.deepcopy` gives for it, at a
    fifth of the time (no memo: a JSON tree shares no nodes). The plain containers by their
    exact type first (the tree is made of them), subclasses as their base."""
    t = type(node)
    if t is float or t is str or t is int or t is bool or node is None:
        return node
    if t is dict:
        return {k: _json_copy(v) for k, v in node.items()}
    if t is list:
        return [_json_copy(v) for v in node]
    if isinstance(node, dict):
        return {k: _json_copy(v) for k, v in node.items()}
    if isinstance(node, list):
        return [_json_copy(v) for v in node]
    if isinstance(node, tuple):
        return tuple(_json_copy(v) for v in node)
    return node


class CheckResult:
    """What `cogniframe check` finds. The figures are read from `to_dict()` (the `check --json`
    object), so they equal the CLI's JSON exactly. `result` is the check's own object (`analysis.verdict.Findings`)."""

    def __init__(self, result: verdict.Findings):
        self.result = result
        self._json: dict | None = None

    @property
    def _dict(self) -> dict:
        if self._json is None:
            from ..analysis import verdict

            self._json = verdict.check_dict(self.result)
        return self._json

    def to_dict(self) -> dict:
        """The `cogniframe check --json` object (a fresh copy)."""
        return _json_copy(self._dict)

    def tables(self, console) -> str:
        """The `cogniframe check` tables (mass budget, cut list, drop model, verdict) as rendered
        for `console` (a rich Console: its width and colours)."""
        from ..report.console import print_check

        with console.capture() as captured:
            print_check(self.result, console)
        return captured.get()

    def write_drop_plots(self, folder: str | Path) -> tuple[Path, ...]:
        """`check --plots`: drop_response.png and energy_split.png into `folder`, both checked
        before either is written (never over a file cogniframe did not write). Nothing when the
        design has no drop model. Returns the files written."""
        from ..outdir import claim_file
        from ..report import drop_plots

        if self.result.drop is None:
            return ()
        folder = Path(folder)
        for name in ("drop_response.png", "energy_split.png"):
            claim_file(folder / name)
        folder.mkdir(parents=True, exist_ok=True)
        return (drop_plots.plot_drop_response(self.result.drop, folder / "drop_response.png"),
                drop_plots.plot_energy_split(self.result.drop, folder / "energy_split.png"))

    @property
    def verdict(self) -> str:
        return self._dict["verdict"]

    @property
    def problems(self) -> list[str]:
        return list(self._dict["problems"])

    @property
    def mass_g(self) -> float:
        """All-up weight, g (`mass.total_g`)."""
        return self._dict["mass"]["total_g"]

    @property
    def mass_margin_g(self) -> float:
        return self._dict["mass"]["margin_g"]

    @property
    def k_n_per_m(self) -> float | None:
        """Vertical stiffness the drop model uses, N/m (`drop.k_n_per_m`: predicted, or the measured `model.k_n_per_m`)."""
        return (self._dict.get("drop") or {}).get("k_n_per_m")

    @property
    def max_safe_drop_cm(self) -> float | None:
        """Highest drop with no battery-holder strike, cm (`drop.max_safe_height_cm`)."""
        return (self._dict.get("drop") or {}).get("max_safe_height_cm")

    @property
    def peak_g(self) -> float | None:
        """Predicted peak deceleration at `requirements.design_drop_height_cm`, G."""
        peak = self._dict.get("peak_g") or {}
        design = self.result.design.spec.requirements.design_drop_height_cm
        return next((h["peak_g"] for h in peak.get("heights", ()) if h["height_cm"] == design), None)

    @property
    def hover_time_min(self) -> float | None:
        return (self._dict.get("flight") or {}).get("hover_time_min")

    @property
    def thrust_to_weight(self) -> float | None:
        return (self._dict.get("flight") or {}).get("thrust_to_weight")

    @property
    def stiffness_model(self) -> str | None:
        """"fe" or "analytic": how the joints were modelled."""
        return (self._dict.get("stiffness") or {}).get("joint_model")

    def __repr__(self) -> str:
        return (f"<cogniframe.CheckResult {self.verdict}: {self.mass_g:.1f} g, k {self.k_n_per_m or 0:.0f} N/m, "
                f"safe drop {self.max_safe_drop_cm or 0:.0f} cm>")

    def _repr_html_(self) -> str:
        import html

        rows = [("verdict", self.verdict), ("all-up weight", f"{self.mass_g:.1f} g (margin {self.mass_margin_g:+.1f} g)")]
        if self.k_n_per_m is not None:
            rows.append(("stiffness k", f"{self.k_n_per_m:.0f} N/m ({self.stiffness_model or 'measured'})"))
        if self.max_safe_drop_cm is not None:
            rows.append(("max safe drop", f"{self.max_safe_drop_cm:.1f} cm"))
        if self.peak_g is not None:
            rows.append(("peak at the design drop", f"{self.peak_g:.0f} G"))
        if self.hover_time_min is not None:
            rows.append(("hover time", f"{self.hover_time_min:.1f} min"))
        rows += [("problem", p) for p in self.problems]
        body = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th><td style='text-align:left'>{html.escape(str(v))}</td></tr>"
                       for k, v in rows)
        return f"<table>{body}</table>"


class BuildResult:
    """What `cogniframe build` wrote: `out_dir`, `files` (every file, from the manifest),
    `verdict`, `report` (report.html), `plates` (the print plates' 3MF files), `check`
    (a CheckResult; None when the folder was already up to date), `steps`."""

    def __init__(self, result):
        import json

        self.raw = result
        self.out_dir = Path(result.out_dir)
        self.verdict: str = result.verdict
        self.check = CheckResult(result.check) if result.check is not None else None
        self.steps = tuple(result.steps)
        manifest = json.loads((self.out_dir / "manifest.json").read_text(encoding="utf-8"))
        self.files = [self.out_dir / f["path"] for f in manifest["files"]] + [self.out_dir / "manifest.json"]
        report = self.out_dir / "report.html"
        self.report = report if report.is_file() else None
        self.plates = sorted(p for p in self.files if p.suffix == ".3mf")

    @property
    def up_to_date(self) -> bool:
        """True when nothing was rebuilt (same params, same cogniframe)."""
        return self.raw.check is None

    def __repr__(self) -> str:
        return f"<cogniframe.BuildResult {self.verdict}: {self.out_dir} ({len(self.files)} files)>"
