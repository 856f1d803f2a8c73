"""Build every distinct printed part: CAD in print orientation -> STL + STEP + metrics.

`build_parts(spec, frame, parts, out_dir, submit=None, cache_dir=None, progress=None)` writes
`stl/<material>/<part>.stl` and `step/<part>.step` under `out_dir` and returns one `BuiltPart` per
part, in the order given.

* Cache: each part's STL, STEP and metrics are stored under `cache_dir/parts/<key>/` (cache.put_files:
  each file's sha256 is kept and checked on every read), keyed by `geometry_digest(part)` (every part
  field the CAD reads), the source of the CAD code (PART_CODE), the mesh tolerances and the bed.
  A rebuild with nothing changed only copies files and never imports CadQuery.
* Parallel: on the caller's worker processes, `submit(fn, *args) -> Future` (for example
  `runtime.pools.cad_workers(n)`); here, one part after another, when `submit` is None.
* Every part must fit `spec.printer.bed`; a part that fits only turned 90 deg on the bed is turned
  (its `print_from_local` includes the turn); otherwise UserError names the part, its size, the bed
  and the key that drives the size.
"""

from __future__ import annotations

from concurrent.futures import as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..errors import UserError
from ..partlist import PartSpec
from ..parts.shapes import CAD_VERSION, PART_CODE, SHAPE_KIND, brep_text, geometry_digest, shape_key
from ..spec import Spec



@dataclass(frozen=True)
class BuiltPart:
    name: str
    family: str
    material: str
    qty: int
    stl: str  # relative to out_dir
    step: str  # relative to out_dir
    volume_mm3: float
    area_h_mm2: float  # faces with |n_z| > 0.7 in print orientation
    area_v_mm2: float
    bbox_mm: tuple[float, float, float]  # print orientation
    shells: int
    watertight: bool
    print_from_local: np.ndarray  # 4x4, print <- part local frame

    def as_dict(self) -> dict:
        return {"name": self.name, "family": self.family, "material": self.material, "qty": self.qty, "stl": self.stl,
                "step": self.step, "volume_mm3": self.volume_mm3, "area_h_mm2": self.area_h_mm2,
                "area_v_mm2": self.area_v_mm2, "bbox_mm": list(self.bbox_mm), "shells": self.shells,
                "watertight": self.watertight, "print_from_local": np.asarray(self.print_from_local).tolist()}


def stl_relpath(part: PartSpec) -> str:
    return f"stl/{part.material}/{part.name}.stl"


def step_relpath(part: PartSpec) -> str:
    return f"step/{part.name}.step"


# STL tessellation (mm, rad); equal to export.mesh's defaults (kept here so a cache hit never
# imports trimesh).
LINEAR_TOL, ANGULAR_TOL = 0.02, 0.15


def cache_key(part: PartSpec, bed) -> str:
    from .. import cache

    return cache.key([geometry_digest(part), CAD_VERSION, LINEAR_TOL, ANGULAR_TOL, [float(b) for b in bed]], PART_CODE)


# -- a part's shape, shared with the joint FE ---------------------------------------------------


def build_parts(spec: Spec, frame, parts: Sequence[PartSpec], out_dir: str | Path, submit=None,
                cache_dir: str | Path | None = None, progress: Callable[[str], None] | None = None) -> tuple[BuiltPart, ...]:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)  # here, not in the workers (they never recreate a removed folder)
    bed = tuple(float(b) for b in spec.printer.bed)
    results: dict[str, dict] = {}
    todo: list[PartSpec] = []
    for p in parts:
        hit = _cache_get(p, bed, out_dir, cache_dir)
        if hit is not None:
            results[p.name] = hit
            if progress:
                progress(p.name)
        else:
            todo.append(p)
    if submit is None:
        for p in todo:
            results[p.name] = build_part_files(p, bed, str(out_dir))
            _cache_put(p, bed, out_dir, cache_dir, results[p.name])
            if progress:
                progress(p.name)
    elif todo:
        futures = {submit(build_part_files, p, bed, str(out_dir)): p for p in todo}
        for fut in as_completed(futures):
            p = futures[fut]
            results[p.name] = fut.result()
            _cache_put(p, bed, out_dir, cache_dir, results[p.name])
            if progress:
                progress(p.name)
    return tuple(_built(p, results[p.name]) for p in parts)


def _built(p: PartSpec, m: dict) -> BuiltPart:
    return BuiltPart(p.name, p.family, p.material, p.qty, m["stl"], m["step"], m["volume_mm3"], m["area_h_mm2"],
                     m["area_v_mm2"], tuple(m["bbox_mm"]), m["shells"], m["watertight"], np.asarray(m["print_from_local"]))


# -- one part (runs in a worker) -------------------------------------------------------------

def build_part_files(part: PartSpec, bed, out_dir: str, share_shape: bool = False) -> dict:
    """Build one part's CAD, fit it on the bed, write its STL and STEP; return its metrics.
    `share_shape`: also store the shape's BREP text in the cache for the joint FE (`shared_brep`)."""
    from ..families import registry
    from ..parts.joint_solid import apply
    from . import mesh as mesh_mod
    from .step import write_step

    built = registry.solid(part)
    shape = built.shape
    if share_shape:
        from ..cache import store_text

        store_text(SHAPE_KIND, shape_key(part), brep_text(shape), ".brep")
    pfl = np.asarray(built.print_from_local, float)
    bb = shape.BoundingBox()
    size = np.array([bb.xlen, bb.ylen, bb.zlen])
    if not fits(size, bed) and fits(size[[1, 0, 2]], bed):
        turn = np.array([[0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
        shape = apply(shape, turn)
        pfl = turn @ pfl
        bb = shape.BoundingBox()
        size = np.array([bb.xlen, bb.ylen, bb.zlen])
    if not fits(size, bed):
        key = registry.get(part.family).SIZE_KEY
        raise UserError(
            f"{part.name}: {size[0]:.1f} x {size[1]:.1f} x {size[2]:.1f} mm in print orientation does not fit the "
            f"{bed[0]:g} x {bed[1]:g} x {bed[2]:g} mm printer bed. Fix: set printer.bed to at least "
            f"{np.ceil(size[0]):.0f} x {np.ceil(size[1]):.0f} x {np.ceil(size[2]):.0f}, or make the part smaller ({key}).",
            key="printer.bed")
    stl_rel, step_rel = stl_relpath(part), step_relpath(part)
    if not Path(out_dir).is_dir():  # the build was stopped and its temp folder removed: never recreate it
        raise FileNotFoundError(f"{out_dir}: the build folder is gone")
    mesh = mesh_mod.write_stl(shape, Path(out_dir) / stl_rel, LINEAR_TOL, ANGULAR_TOL, name=part.name)
    write_step(shape, Path(out_dir) / step_rel, part.name)
    ah, av = mesh_mod.area_split(mesh)
    return {"stl": stl_rel, "step": step_rel, "volume_mm3": round(float(mesh.volume), 3), "area_h_mm2": round(ah, 3),
            "area_v_mm2": round(av, 3), "bbox_mm": [round(float(v), 4) for v in mesh.extents],
            "shells": int(mesh.body_count), "watertight": bool(mesh.is_watertight),
            "print_from_local": [[round(float(v), 12) for v in row] for row in pfl]}


def fits(size, bed, tol: float = 1e-6) -> bool:
    return all(float(s) <= float(b) + tol for s, b in zip(size, bed))


# -- cache -----------------------------------------------------------------------------------

def _cache_get(part: PartSpec, bed, out_dir: Path, cache_dir) -> dict | None:
    """The part's files copied from a verified cache entry into out_dir, and its metrics; None on a miss."""
    if cache_dir is None:
        return None
    from .. import cache

    hit = cache.get_files("parts", cache_key(part, bed), out_dir, root=Path(cache_dir))
    return None if hit is None else hit["value"]


def _cache_put(part: PartSpec, bed, out_dir: Path, cache_dir, meta: dict) -> None:
    """Store atomically with every file's sha256; a cache that cannot be written is skipped."""
    if cache_dir is None:
        return
    from .. import cache

    cache.put_files("parts", cache_key(part, bed), out_dir, [meta["stl"], meta["step"]], meta, root=Path(cache_dir))
