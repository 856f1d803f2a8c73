"""`cogniframe build`: the whole fabrication folder, built in a temp dir and moved into place whole.

Order: design (no CAD) -> part CAD + STL/STEP -> assembly -> mass with CAD volumes -> drop
model -> text outputs and plots -> fabrication package (plates, slicer, BOM, renders, report)
-> manifest. Nothing appears in the output folder unless every step succeeded, and a folder
cogniframe did not make is never touched (outdir.py: lock, ownership check, atomic swap).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from . import __version__, cutlist, outdir, pipeline
from .analysis.mass import PartGeometry
from .cache import cache_dir
from .spec import Spec

STACK = ("cadquery", "cadquery-ocp", "trimesh", "manifold3d", "numpy", "scipy", "pynitefea", "pyvista", "vtk", "matplotlib")


@dataclass(frozen=True)
class BuildResult:
    out_dir: Path
    files: int
    verdict: str
    check: pipeline.CheckResult | None  # None when the folder was already up to date
    built: tuple


def run_build(spec: Spec, params_path: Path, out: Path | None, jobs: int | None = None, use_cache: bool = True,
              console: Console | None = None) -> BuildResult:
    console = console or Console(stderr=True)
    with spec.blamed():
        pipeline.design(spec)  # a design that cannot exist is refused before any folder is touched
    final = pipeline.output_dir(spec, out)
    key = build_key(spec, params_path)
    if use_cache and _up_to_date(final, key):
        verdict = json.loads((final / "check.json").read_text())["verdict"]
        console.print(f"{final} is up to date (same params, same cogniframe): nothing rebuilt", markup=False)
        files = len(json.loads((final / "manifest.json").read_text())["files"]) + 1
        return BuildResult(final, files, verdict, None, ())
    with outdir.writing(final) as tmp, spec.blamed():
        result = _build_into(spec, params_path, tmp, jobs, use_cache, console, key)
    return BuildResult(final, result[0], result[1].verdict, result[1], result[2])


def build_key(spec: Spec, params_path: Path) -> str:
    """Everything a build's bytes depend on: the params, the installed stack and cogniframe's code."""
    h = hashlib.sha256()
    h.update(Path(params_path).read_bytes())
    h.update(spec.digest().encode())
    h.update(json.dumps(_versions(), sort_keys=True).encode())
    pkg = Path(__file__).resolve().parent
    for src in sorted(pkg.rglob("*.py")):
        h.update(src.relative_to(pkg).as_posix().encode())
        h.update(src.read_bytes())
    return h.hexdigest()


def _up_to_date(final: Path, key: str) -> bool:
    """True when `final` was built with this key and every file it lists is still as written."""
    try:
        manifest = json.loads((final / "manifest.json").read_text())
    except (OSError, ValueError):
        return False
    if manifest.get("build_key") != key:
        return False
    listed = {f["path"] for f in manifest["files"]}
    present = {p.relative_to(final).as_posix() for p in final.rglob("*") if p.is_file()} - {"manifest.json"}
    return listed == present and all(_sha256(final / f["path"]) == f["sha256"] for f in manifest["files"])


def _build_into(spec: Spec, params_path: Path, out: Path, jobs: int | None, use_cache: bool, console: Console,
                key: str):
    from .export.assembly import write_assembly
    from .export.build import build_parts

    design = pipeline.design(spec)
    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=console, transient=True) as progress:
        task = progress.add_task(f"building {spec.name} parts", total=len(design.parts))
        built = build_parts(spec, design.frame, design.parts, out, jobs=jobs,
                            cache_dir=cache_dir() if use_cache else None,
                            progress=lambda name: progress.update(task, advance=1, description=f"built {name}"))
    write_assembly(spec, design.frame, design.parts, built, out, cache_dir=cache_dir() if use_cache else None)
    clash = _clash_check(spec, design, built, out, use_cache)

    geometry = {b.name: PartGeometry(b.volume_mm3, b.area_h_mm2, b.area_v_mm2, "cad") for b in built}
    check = pipeline.check(spec, geometry, clash=clash)
    data = pipeline.check_dict(check)
    _write(out / "check.json", json.dumps(data, indent=2) + "\n")
    _write(out / "cutlist.csv", cutlist.to_csv(design.cut))
    _write(out / "cutlist.md", cutlist.to_markdown(design.cut))
    _write(out / "mass.md", _mass_markdown(check))
    if check.drop is not None:
        from .report import drop_plots

        (out / "plots").mkdir(exist_ok=True)
        drop_plots.plot_drop_response(check.drop, out / "plots" / "drop_response.png")
        drop_plots.plot_energy_split(check.drop, out / "plots" / "energy_split.png")

    from .fabrication import write_fabrication

    write_fabrication(spec, check, built, out, console)
    n = _write_manifest(spec, params_path, out, key)
    return n, check, built


def _clash_check(spec: Spec, design, built, out: Path, use_cache: bool):
    """Issue 13: every pair of solids in the assembly (printed parts, rods, vitamins) and every
    propeller's clearance; writes clash.json; its clashes become FAIL problems of the check."""
    from .export.assembly import run_clash_check

    return run_clash_check(spec, design.frame, design.parts, built, out, cache_dir=cache_dir() if use_cache else None)


def _mass_markdown(check: pipeline.CheckResult) -> str:
    m = check.mass
    lines = [f"# Mass budget: {check.design.spec.name}", "", "| item | group | qty | g each | g | source |",
             "|---|---|---:|---:|---:|---|"]
    for i in m.items:
        lines.append(f"| {i.name} | {i.group} | {i.qty} | {i.mass_g_each:.2f} | {i.mass_g:.1f} | {i.source} |")
    lines += ["", "| group | g |", "|---|---:|"] + [f"| {g} | {v:.1f} |" for g, v in m.groups.items()]
    lines += [f"| **all-up weight** | **{m.total_g:.1f}** |", f"| limit | {m.limit_g:g} |", f"| margin | {m.margin_g:+.1f} |"]
    return "\n".join(lines) + "\n"


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _versions() -> dict:
    versions = {"cogniframe": __version__}
    for dist in STACK:
        try:
            versions[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            versions[dist] = None
    return versions


def _write_manifest(spec: Spec, params_path: Path, out: Path, key: str) -> int:
    files = sorted(p for p in out.rglob("*") if p.is_file() and p.name != outdir.TEMP_MARK)
    manifest = {
        "generator": outdir.GENERATOR,
        "name": spec.name,
        "build_key": key,
        "params_file": Path(params_path).name,
        "params_sha256": _sha256(Path(params_path)),
        "spec_sha256": spec.digest(),
        "versions": _versions(),
        "files": [{"path": p.relative_to(out).as_posix(), "size": p.stat().st_size, "sha256": _sha256(p)} for p in files],
    }
    _write(out / "manifest.json", json.dumps(manifest, indent=2) + "\n")
    return len(files) + 1
