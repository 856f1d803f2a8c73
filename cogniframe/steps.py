"""The build, as a Makefile: each step's target, what it needs, how it is made and what it reads.

    target                    needs                          reads (its cache key)
    estimate                  -                              (always, thread: k and the joint models, mass-independent, cached on disk)
    part:{material}/{part}    -                              part digest, bed, mesh tolerances, CAD code
    plates:{material}         part:{material}/*              each part's STL hash and qty, bed, margin, print settings
    budget                    estimate part:*                (always, thread: mass with CAD volumes, drop model; milliseconds)
    physics                   budget                         (always, thread: load cases and peaks for that mass, cached on disk)
    clash                     part:*                         STL hashes, copies and placements, rods, vitamins, prop margin (issue 13)
    slice:{material}          plates:{material}              plate files, profile, PrusaSlicer version (each plate on its own key)
    assembly                  part:*                         STEP hashes, copies and placements, rods, vitamins
    glb                       part:*                         STL hashes, copies and placements, rods, vitamins
    check                     budget physics clash           (always: check.json, cut list, mass.md from the cached physics)
    plots                     budget                         the drop model's numbers
    figures                   budget                         the mass budget's and drop model's numbers
    previews:{material}       plates:{material}              plate layouts
    render:{part}             part:*/{part}                  the part's STL hash, material
    renders                   part:*                         STL hashes, placements, rods, vitamins
    viewer                    check plates:*                 STL hashes, placements, grams each, plates, rods, cut list
    bom                       check slice:*                  (always: BOM, assembly steps)
    report                    everything above               (always: HTML and Markdown from the files above)

A step with a key runs only when its key changes; otherwise its files come from the cache
(graph.py). `part`, `slice`, `assembly` and `clash` run in threads that wait for another process
(CAD pool, PrusaSlicer), `estimate`, `budget` and `physics` in threads (numpy releases the GIL;
`budget` in a thread so that the load cases start the moment the joints are solved, not when the
main thread's render under way ends), and each
starts the moment its needs are done: slicing a plate starts as soon as it is laid out while the
main thread lays out the other plates and draws plots, previews and renders. Heavy imports
(cadquery, trimesh, pyvista, matplotlib) happen only inside steps that run.
"""

from __future__ import annotations

import json
import threading
import time

from . import graph
from .cache import file_sha256
from .fabrication import (bom, figures_key, make_figures, make_plates, make_previews, make_render_part, make_renders,
                          make_slice, make_viewer, plates_key, previews_key, render_part_key, renders_key, report,
                          slice_key, viewer_key)
from .graph import Made, Step
from .runtime.pools import JOB_ORDER


class BuildContext(graph.Context):
    """graph.Context plus what many steps look up: parts by name, their step values and meshes."""

    @property
    def bed(self) -> tuple[float, float, float]:
        return tuple(float(b) for b in self.spec.printer.bed)

    def part(self, name: str):
        return next(p for p in self.design.parts if p.name == name)

    def parts_of(self, material: str):
        return [p for p in self.design.parts if p.material == material]

    def part_value(self, name: str) -> dict:
        (value,) = self.each(f"part:*/{name}").values()
        return value

    def built_parts(self):
        """BuiltPart per part, in the design's order, from the part steps' values."""
        from .export.build import _built

        return tuple(_built(p, self.part_value(p.name)) for p in self.design.parts)

    def warm_imports(self) -> None:
        """Start importing the main thread's libraries while it waits for the CAD workers
        (`runtime.warm`): called by the first part step that runs, since a rebuilt part means the
        plates, previews and renders run too."""
        self.warm.start()

    def plate_items(self, plate: dict):
        """What reading a plate's 3MF back gives (`plates.read_3mf_items`), when the plates step
        wrote it in this build (`plates.plate_3mf` returns it with the bytes); None for a plate
        that came from the cache (its readers read the file). `plate`: a plates step's entry."""
        return self.__dict__.get("_plate_items", {}).get(plate.get("model_sha256"))

    def keep_plate_items(self, model_sha256: str, items) -> None:
        self.__dict__.setdefault("_plate_items", {})[model_sha256] = items

    def mesh(self, name: str):
        """The part's STL as a trimesh, read once per build (plates, part renders and assembly
        renders all read it; they copy before they move it)."""
        import trimesh

        v = self.part_value(name)
        memo = self.__dict__.setdefault("_meshes", {})
        key = (name, v["stl_sha256"])
        if key not in memo:
            memo[key] = trimesh.load(self.out / v["stl"], force="mesh")
        return memo[key]


def needs_joint_fe(spec, design) -> bool:
    """Whether this build meshes and solves a joint: the FE model and a joint geometry that is not
    in the joint cache yet (a few milliseconds: the cache keys are hashes of the parts' inputs)."""
    if spec.model.stiffness_model != "fe":
        return False
    from .analysis.joint_stiffness import has_unsolved
    from .analysis.stiffness import joint_parts

    return has_unsolved(spec, joint_parts(design.parts))


class Slicer:
    """PrusaSlicer's path and version, looked up once per build (None when it is not installed)."""

    def __init__(self, log):
        self.log = log
        self._found = None
        self._lock = threading.Lock()

    def get(self) -> tuple[str, str] | None:
        with self._lock:
            if self._found is None:
                from .export import slicer

                exe = slicer.find_slicer()
                self._found = (exe, slicer.known_version(exe)) if exe else ()
                if not exe:
                    self.log(f"{slicer.SLICER} not found on PATH: skipping the slicer check "
                             f"(install it with `apt-get install prusa-slicer` to get grams and print times).")
            return self._found or None


# -- steps -----------------------------------------------------------------------------------

def estimate(ctx) -> Made:
    """Solve what the physics needs and the mass does not change (the frame stiffness k and the
    joint models, each cached on disk by its own inputs) while the CAD pool builds the parts; the
    mass-dependent load cases wait for the CAD volumes (`physics`)."""
    spec = ctx.spec
    if ctx.cad.server and spec.model.stiffness_model == "fe":
        # new joint FEs on the CAD server's workers, after the parts (JOB_ORDER); the frame
        # model below then reads every joint from the cache
        from .analysis.joint_stiffness import solve_missing
        from .analysis.stiffness import joint_parts

        solve_missing(spec, joint_parts(ctx.design.parts), submit=lambda fn, *a: ctx.cad.submit(fn, *a, priority=JOB_ORDER["joint FE"]))
    if spec.model.k_n_per_m is None:
        from .analysis.drop import predicted_k_n_per_m

        predicted_k_n_per_m(spec, ctx.design.frame)
    else:
        from .analysis.stiffness import joint_models

        joint_models(spec, ctx.design.parts, spec.model.stiffness_model)
    return Made()


def part_key(ctx, material: str, part: str):
    from .export.build import cache_key

    return cache_key(ctx.part(part), ctx.bed)  # the part's CAD inputs (not its infill or placements), bed, code


def make_part(ctx, material: str, part: str) -> Made:
    from .export.build import build_part_files

    ctx.warm_imports()  # in a thread, while the CAD workers start and build
    spec = ctx.part(part)
    # a joint whose FE this build solves: its shape goes to the FE job too (`export.build.shared_brep`)
    made = ctx.cad.submit(build_part_files, spec, ctx.bed, str(ctx.out), ctx.cad.fe and spec.family == "joint",
                          priority=JOB_ORDER["part"])
    meta = made.result()
    meta["stl_sha256"] = file_sha256(ctx.out / meta["stl"])
    return Made((meta["stl"], meta["step"]), meta)


def _geometry(ctx) -> dict:
    from .analysis.mass import PartGeometry

    return {b.name: PartGeometry(b.volume_mm3, b.area_h_mm2, b.area_v_mm2, "cad") for b in ctx.built_parts()}


def budget(ctx) -> Made:
    """The mass budget with the CAD volumes and the drop model: milliseconds once k is known; what
    the mass and drop figures draw, so they need not wait for the load cases."""
    from . import pipeline

    _, mass, drop = pipeline.mass_and_drop(ctx.spec, _geometry(ctx), ctx.design)
    return Made((), {"mass": mass, "drop": drop})


def physics(ctx) -> Made:
    """The check's load cases and peak prediction for the CAD mass, solved into the analysis
    modules' disk caches (`check` reads them back in milliseconds). A thread of its own: LAPACK
    holds no GIL (measured: a busy Python thread beside it keeps ~97 % of its speed), so the main
    thread's plates, figures and renders go on meanwhile."""
    from . import pipeline

    pipeline.check(ctx.spec, _geometry(ctx), design_=ctx.design)
    return Made()


def check(ctx) -> Made:
    import json

    from . import cutlist, pipeline
    from .analysis import clash

    result = pipeline.check(ctx.spec, _geometry(ctx), clash=clash.from_dict(ctx["clash"]), design_=ctx.design)  # physics: from the cache
    out = ctx.out
    files = {"check.json": json.dumps(pipeline.check_dict(result), indent=2) + "\n",
             "cutlist.csv": cutlist.to_csv(ctx.design.cut), "cutlist.md": cutlist.to_markdown(ctx.design.cut),
             "mass.md": mass_markdown(result)}
    for rel, text in files.items():
        (out / rel).write_text(text, encoding="utf-8")
    return Made(tuple(files), result)


def mass_markdown(check) -> str:
    m = check.mass
    lines = [f"# Mass budget: {check.design.spec.name}", "", "| item | group | qty | g each | g | source |",
             "|---|---|---:|---:|---:|---|"]
    for i in m.items:
        lines.append(f"| {i.name} | {i.group} | {i.qty} | {i.mass_g_each:.2f} | {i.mass_g:.1f} | {i.source} |")
    lines += ["", "| group | g |", "|---|---:|"] + [f"| {g} | {v:.1f} |" for g, v in m.groups.items()]
    lines += [f"| **all-up weight** | **{m.total_g:.1f}** |", f"| limit | {m.limit_g:g} |", f"| margin | {m.margin_g:+.1f} |"]
    return "\n".join(lines) + "\n"


def _copies(ctx, file_hash: str) -> list:
    """What the assembly and the clash check read of the printed parts: each copy's name, colour
    and placement, and its part's file (by hash: `stl` or `step`) and print <- local transform."""
    import numpy as np

    from .cache import file_sha256
    from .export.assembly import instance_name

    out = []
    for p in ctx.design.parts:
        v = ctx.part_value(p.name)
        sha = v["stl_sha256"] if file_hash == "stl" else file_sha256(ctx.out / v[file_hash])
        out.append([p.name, p.material, sha, np.round(np.asarray(v["print_from_local"], float), 9).tolist(),
                    [[instance_name(p, pl.instance), pl.rotation_deg, list(pl.origin)] for pl in p.placements]])
    return out


def _rods_and_vitamins(ctx) -> list:
    import numpy as np

    from .export.assembly import _vitamin_key

    rods = [[r.name, np.round(r.start, 9).tolist(), np.round(r.end, 9).tolist(), r.diameter]
            for r in ctx.design.frame.rods.values()]
    return [rods, _vitamin_key(ctx.spec, ctx.design.frame)]


def assembly_key(ctx):
    """The assembly reads each part's STEP file (by its bytes, not the CAD inputs: a code edit that
    leaves a part's STEP as it was does not redo the assembly), the copies' names, colours and
    placements, the rods, the vitamins and the design's name."""
    return [ctx.spec.name, _copies(ctx, "step"), _rods_and_vitamins(ctx)]


def make_assembly(ctx) -> Made:
    from .export.assembly import write_assembly_step

    ctx.cad.run(write_assembly_step, ctx.spec, ctx.design.frame, ctx.design.parts, ctx.built_parts(), str(ctx.out),
                priority=JOB_ORDER["assembly"])
    return Made(("assembly.step",))


def glb_key(ctx):
    """The GLB reads each part's STL (by hash), the copies' names, colours and placements, the rods
    and the vitamins."""
    return [_copies(ctx, "stl"), _rods_and_vitamins(ctx)]


def make_glb(ctx) -> Made:
    from .export.assembly import write_glb

    d = ctx.design
    write_glb(ctx.spec, d.frame, d.parts, {p.name: ctx.mesh(p.name) for p in d.parts},
              {p.name: ctx.part_value(p.name)["print_from_local"] for p in d.parts}, ctx.out / "assembly.glb")
    return Made(("assembly.glb",))


def clash_key(ctx):
    """The clash check reads each part's STL (by hash), the copies' names and placements, the rods,
    the vitamins (propellers and their motors), the propeller margin and the tolerance."""
    from .analysis.clash import TOLERANCE_MM3

    return [_copies(ctx, "stl"), _rods_and_vitamins(ctx), ctx.spec.requirements.prop_margin, TOLERANCE_MM3]


def make_clash(ctx) -> Made:
    """Issue 13: every pair of solids of the aircraft (printed part copies, rods, vitamins) and every
    propeller's clearance (analysis/clash.py); clash.json; its clashes are FAIL problems of `check`."""
    from . import cache
    from .export.assembly import check_clashes

    memo = (str(cache.cache_dir()), f"{cache.code_hash(*CLASH_CODE)}/{ctx.stack}") if ctx.use_cache else None
    # in the CAD pool when it is up (manifold3d holds the GIL: here it would stall the main thread)
    result = ctx.cad.run_in_pool_if_started(check_clashes, ctx.spec, ctx.design.frame, ctx.design.parts,
                                            ctx.built_parts(), str(ctx.out), memo, priority=JOB_ORDER["clash"])
    (ctx.out / "clash.json").write_text(json.dumps(result.to_dict(), indent=2) + "\n", encoding="utf-8")
    return Made(("clash.json",), result.to_dict())


def plots_key(ctx):
    return ctx["budget"]["drop"]


def make_plots(ctx) -> Made:
    drop = ctx["budget"]["drop"]
    if drop is None:
        return Made()
    from .report import drop_plots

    drop_plots.plot_drop_response(drop, ctx.out / "plots" / "drop_response.png")
    drop_plots.plot_energy_split(drop, ctx.out / "plots" / "energy_split.png")
    return Made(("plots/drop_response.png", "plots/energy_split.png"))


CLASH_CODE = ("analysis/clash.py", "export/assembly.py", "export/mesh.py", "vitamins.py", "materials.py", "partlist.py")

STEPS = (
    #    target                    needs                                  make           key               code / where
    Step("estimate",               (),                                    estimate,      None,             (),        "wait"),
    Step("part:{material}/{part}", (),                                    make_part,     part_key,         (),        "wait"),
    Step("plates:{material}",      ("part:{material}/*",),                make_plates,   plates_key,       ("export/plates.py",)),
    Step("budget",                 ("estimate", "part:*"),                budget,        None,             (),        "wait"),
    Step("physics",                ("budget",),                           physics,       None,             (),        "wait"),
    Step("clash",                  ("part:*",),                           make_clash,    clash_key,        CLASH_CODE, "wait",
         after=("plates:*",)),  # the plates (then the slicer) are the critical path: they get the CPU first
    Step("slice:{material}",       ("plates:{material}",),                make_slice,    slice_key,        ("export/slicer.py",), "wait"),
    Step("assembly",               ("part:*",),                           make_assembly, assembly_key,     ("export/assembly.py", "export/step.py", "vitamins.py"), "wait",
         after=("plates:*",)),
    Step("glb",                    ("part:*",),                           make_glb,      glb_key,          ("export/assembly.py", "vitamins.py")),
    Step("check",                  ("budget", "physics", "clash"),        check),
    Step("plots",                  ("budget",),                           make_plots,    plots_key,        ("report/drop_plots.py", "analysis/impact.py")),
    Step("figures",                ("budget",),                           make_figures,  figures_key,      ("report/html.py", "report/drop_plots.py")),
    Step("previews:{material}",    ("plates:{material}",),                make_previews, previews_key,     ("export/plates.py",)),
    Step("render:{part}",          ("part:*/{part}",),                    make_render_part, render_part_key, ("report/renders.py", "export/plates.py"),
         after=("plates:*",)),  # a render never holds up the slicer
    Step("renders",                ("part:*",),                           make_renders,  renders_key,      ("report/renders.py", "export/plates.py", "report/assembly_steps.py", "vitamins.py")),
    Step("viewer",                 ("check", "plates:*"),                 make_viewer,   viewer_key,       ("report/viewer/*", "export/plates.py", "report/assembly_steps.py", "report/renders.py", "vitamins.py")),
    Step("bom",                    ("check", "slice:*"),                  bom),
    Step("report",                 ("check", "bom", "plots", "figures", "previews:*", "render:*", "renders", "viewer"), report),
)


def rows(design) -> list[dict]:
    """What the {vars} of STEPS range over: one row per printed part."""
    return [{"material": p.material, "part": p.name} for p in design.parts]
