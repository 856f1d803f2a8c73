"""The CAD steps: each printed part's files, the assembly STEP and GLB, and the clash check.
Each step's row sits beside its make and key functions; pipeline/steps.py lists them in order."""

from __future__ import annotations

import json

from ..cache import file_sha256
from ..parts.shapes import PART_CODE
from ..runtime.pools import JOB_ORDER
from .graph import Made, Step


def part_key(ctx, material: str, part: str):
    from ..export.part_files import cache_key

    return cache_key(ctx.part(part), ctx.bed)  # the part's CAD inputs (not its infill or placements), bed, code

def make_part(ctx, material: str, part: str) -> Made:
    from ..export.part_files import build_part_files

    ctx.warm_imports()  # in a thread, while the CAD workers start and build
    spec = ctx.part(part)
    # a joint whose FE this build solves: its shape goes to the FE job too (`parts.shapes.shared_brep`)
    made = ctx.cad.submit(build_part_files, spec, ctx.bed, str(ctx.out), ctx.cad.fe and spec.family == "joint",
                          priority=JOB_ORDER["part"])
    meta = made.result()
    meta["stl_sha256"] = file_sha256(ctx.out / meta["stl"])
    return Made((meta["stl"], meta["step"]), meta)

def _copies(ctx, file_hash: str) -> list:
    """What the assembly and the clash check read of the printed parts: each copy's name, colour
    and placement, and its part's file (by hash: `stl` or `step`) and print <- local transform."""
    import numpy as np

    from ..cache import file_sha256
    from ..export.assembly import instance_name

    out = []
    for p in ctx.design.parts:
        v = ctx.part_value(p.name)
        sha = v["stl_sha256"] if file_hash == "stl" else file_sha256(ctx.out / v[file_hash])
        out.append([p.name, p.material, sha, np.round(np.asarray(v["print_from_local"], float), 9).tolist(),
                    [[instance_name(p, pl.instance), pl.rotation_deg, list(pl.origin)] for pl in p.placements]])
    return out

def _rods_and_vitamins(ctx) -> list:
    import numpy as np

    rods = [[r.name, np.round(r.start, 9).tolist(), np.round(r.end, 9).tolist(), r.diameter]
            for r in ctx.design.frame.rods.values()]
    return [rods, ctx.vitamin_key()]

def assembly_key(ctx):
    """The assembly reads each part's STEP file (by its bytes, not the CAD inputs: a code edit that
    leaves a part's STEP as it was does not redo the assembly), the copies' names, colours and
    placements, the rods, the vitamins and the design's name."""
    return [ctx.spec.name, _copies(ctx, "step"), _rods_and_vitamins(ctx)]

def make_assembly(ctx) -> Made:
    from ..export.assembly import write_assembly_step

    ctx.cad.run(write_assembly_step, ctx.spec, ctx.design.frame, ctx.design.parts, ctx.built_parts(), str(ctx.out),
                priority=JOB_ORDER["assembly"])
    return Made(("assembly.step",))

def glb_key(ctx):
    """The GLB reads each part's STL (by hash), the copies' names, colours and placements, the rods
    and the vitamins."""
    return [_copies(ctx, "stl"), _rods_and_vitamins(ctx)]

def make_glb(ctx) -> Made:
    from ..export.assembly import write_glb

    d = ctx.design
    write_glb(ctx.spec, d.frame, d.parts, {p.name: ctx.mesh(p.name) for p in d.parts},
              {p.name: ctx.part_value(p.name)["print_from_local"] for p in d.parts}, ctx.out / "assembly.glb")
    return Made(("assembly.glb",))

def clash_key(ctx):
    """The clash check reads each part's STL (by hash), the copies' names and placements, the rods,
    the vitamins (propellers and their motors), the propeller margin and the tolerance."""
    from ..analysis.clash import TOLERANCE_MM3

    return [_copies(ctx, "stl"), _rods_and_vitamins(ctx), ctx.spec.requirements.prop_margin, TOLERANCE_MM3]

def make_clash(ctx) -> Made:
    """Every pair of solids of the aircraft (printed part copies, rods, vitamins) and every
    propeller's clearance (analysis/clash.py); clash.json; its clashes are FAIL problems of `check`."""
    from .. import cache
    from ..export.assembly import check_clashes

    memo = (str(cache.cache_dir()), f"{cache.code_hash(*CLASH_CODE)}/{ctx.stack}") if ctx.use_cache else None
    # in the CAD pool when it is up (manifold3d holds the GIL: here it would stall the main thread)
    result = ctx.cad.run_in_pool_if_started(check_clashes, ctx.spec, ctx.design.frame, ctx.design.parts,
                                            ctx.built_parts(), str(ctx.out), memo, priority=JOB_ORDER["clash"])
    (ctx.out / "clash.json").write_text(json.dumps(result.to_dict(), indent=2) + "\n", encoding="utf-8")
    return Made(("clash.json",), result.to_dict())

CLASH_CODE = ("analysis/clash.py", "analysis/fit_check.py", "export/assembly.py", "export/mesh.py", "vitamins.py", "fasteners.py", "materials.py",
              "partlist.py", "families/*.py", "families/joint_kinds/*.py", "numfmt.py")


PART = Step("part:{material}/{part}", (), make_part, part_key, PART_CODE, "wait",
            reads="the part's CAD inputs, bed, mesh tolerances, CAD code")
CLASH = Step("clash", ("part:*",), make_clash, clash_key, CLASH_CODE, "wait",
             after=("plates:*",),  # the plates (then the slicer) are the critical path: they get the CPU first
             reads="STL hashes, copies and placements, rods, vitamins, prop margin")
ASSEMBLY = Step("assembly", ("part:*",), make_assembly, assembly_key, ("export/assembly.py", "export/step.py", "vitamins.py", "fasteners.py"),
                "wait", after=("plates:*",), reads="STEP hashes, copies and placements, rods, vitamins")
GLB = Step("glb", ("part:*",), make_glb, glb_key, ("export/assembly.py", "vitamins.py", "fasteners.py", "numfmt.py"),
           reads="STL hashes, copies and placements, rods, vitamins")
