"""The whole frame as one assembly: `assembly.step` (names, colours, placements) and `assembly.glb`.

`assembly.step` is CadQuery's (the parts' exact STEP solids); `assembly.glb` is written from the
meshes the build already has (the parts' STLs, the rods and vitamins as triangles; `write_glb`),
with the same names and colours: CadQuery's glTF export tessellated every solid again and took
1.0 s of the assembly's 1.9 s, in the CAD pool, on every change of any part.

Rods are cylinders of the rod diameter from `rod.start` to `rod.end` (the frame graph); each printed
part copy is its STEP (print orientation) moved by Placement.matrix() @ inv(print_from_local).
Names: the instance (`knee_fl`, `corner_top_rr`, `core_link_fl`), `motor_mount_fl` for the motor
mounts, the part name for single core parts, and the rod name (`rod_arm_fl_1`). Colours by
material: TPU red, ABS/PLA (any other filament) dark grey, rods black.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Sequence

import numpy as np

from .. import numfmt
from ..partlist import PartSpec
from ..spec import Spec

TPU_RED = (0.80, 0.10, 0.10)
CORE_GREY = (0.25, 0.25, 0.25)
ROD_BLACK = (0.03, 0.03, 0.03)


def colour_of(material: str) -> tuple[float, float, float]:
    return TPU_RED if material.startswith("tpu") else CORE_GREY


def instance_name(part: PartSpec, instance: str) -> str:
    if part.qty == 1:
        return part.name
    if instance.startswith(part.name) or instance.startswith(str(dict(part.params).get("kind", part.name))):
        return instance
    return f"{part.name}_{instance.rsplit('_', 1)[-1]}"


def world_from_print(part_placement_matrix: np.ndarray, print_from_local: np.ndarray) -> np.ndarray:
    return np.asarray(part_placement_matrix) @ np.linalg.inv(np.asarray(print_from_local))


def _location(m: np.ndarray):
    import cadquery as cq
    from OCP.gp import gp_Trsf

    t = gp_Trsf()
    t.SetValues(*[float(v) for v in np.asarray(m)[:3].ravel()])
    return cq.Location(t)


def build_assembly(spec: Spec, frame, parts: Sequence[PartSpec], built, out_dir: str | Path):
    """cq.Assembly of rods and placed part copies (parts read back from their STEP files)."""
    import cadquery as cq

    out_dir = Path(out_dir)
    by_name = {b.name: b for b in built}
    assy = cq.Assembly(name=spec.name)
    for p in parts:
        b = by_name[p.name]
        shape = cq.importers.importStep(str(out_dir / b.step)).val()
        for pl in p.placements:
            m = world_from_print(pl.matrix(), b.print_from_local)
            assy.add(shape, name=instance_name(p, pl.instance), color=cq.Color(*colour_of(p.material)), loc=_location(m))
    for rod in frame.rods.values():
        start, end = np.asarray(rod.start, float), np.asarray(rod.end, float)
        axis = end - start
        cyl = cq.Solid.makeCylinder(rod.diameter / 2, float(np.linalg.norm(axis)), cq.Vector(*start), cq.Vector(*axis))
        assy.add(cyl, name=rod.name, color=cq.Color(*ROD_BLACK))
    from ..vitamins import to_cq, vitamins

    for v in vitamins(spec, frame, parts):
        assy.add(to_cq(v), name=v.name, color=cq.Color(*v.colour))
    return assy


def write_assembly_step(spec: Spec, frame, parts: Sequence[PartSpec], built, out_dir: str | Path) -> Path:
    """out_dir/assembly.step: the parts' STEP solids placed, the rods and vitamins (deterministic)."""
    from .step import normalize_file

    step = Path(out_dir) / "assembly.step"
    build_assembly(spec, frame, parts, built, out_dir).export(str(step))
    normalize_file(step, spec.name)
    return step


def write_glb(spec: Spec, frame, parts: Sequence[PartSpec], meshes: dict, print_from_local: dict,
              path: str | Path) -> Path:
    """`assembly.glb`: every part copy (its print mesh moved by world <- print), rod and vitamin, by
    name and colour, in mm, y up (glTF's convention: world z becomes y). Copies of a part share one
    mesh. Byte-stable: the same meshes and placements give the same bytes.

    `meshes`: part name -> its print mesh (anything with `vertices` and `faces`). Written here
    (`glb_bytes`), not by trimesh's scene export: its scene graph, hashing and colour conversion
    took 0.1 s CPU of the main thread on each change of any part, for a file this simple."""
    from ..vitamins import mesh_arrays, vitamins

    up = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0], [0, -1.0, 0, 0], [0, 0, 0, 1.0]])  # z up -> y up
    shapes: dict[str, tuple] = {}
    nodes: list[tuple[str, str, np.ndarray]] = []

    def add(name: str, geom: str, arrays, colour, matrix) -> None:
        if geom not in shapes:
            shapes[geom] = (*arrays(), tuple(int(round(c * 255)) for c in colour) + (255,))
        nodes.append((name, geom, up @ matrix))

    for p in parts:
        m = meshes[p.name]
        for pl in p.placements:
            add(instance_name(p, pl.instance), p.name, lambda m=m: (m.vertices, m.faces), colour_of(p.material),
                world_from_print(pl.matrix(), np.asarray(print_from_local[p.name], float)))
    for rod in frame.rods.values():
        add(rod.name, rod.name, lambda rod=rod: cylinder_arrays(rod.start, rod.end, rod.diameter / 2), ROD_BLACK, np.eye(4))
    for v in vitamins(spec, frame, parts):
        add(v.name, v.name, lambda v=v: mesh_arrays(v), v.colour, np.eye(4))
    path = Path(path)
    path.write_bytes(glb_bytes(shapes, nodes))
    return path


def cylinder_arrays(start, end, radius: float, sections: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """A closed cylinder from `start` to `end` (its axis), `sections` sides: (vertices, faces), faces
    turning outwards. What rods look like in the GLB (trimesh.creation.cylinder's shape, 20x cheaper)."""
    from ..vitamins import _frame_z

    start, end = np.asarray(start, float), np.asarray(end, float)
    axis = end - start
    rot = _frame_z(axis)
    a = np.arange(sections) * (2 * np.pi / sections)
    ring = radius * (np.outer(np.cos(a), rot[:, 0]) + np.outer(np.sin(a), rot[:, 1]))
    verts = np.vstack([start + ring, end + ring, start, end])
    i = np.arange(sections)
    j = (i + 1) % sections
    n = sections
    faces = np.vstack([np.column_stack([i, j, n + j]), np.column_stack([i, n + j, n + i]),  # sides
                       np.column_stack([np.full(n, 2 * n), j, i]),  # bottom cap, seen from below
                       np.column_stack([np.full(n, 2 * n + 1), n + i, n + j])])  # top cap
    return verts, faces


def glb_bytes(shapes: dict, nodes: Sequence[tuple[str, str, np.ndarray]]) -> bytes:
    """A binary glTF 2.0: `shapes` name -> (vertices, faces, (r, g, b, a) 0-255), one mesh each (float32
    positions with their bounds, uint32 indices, the colour as a constant COLOR_0); `nodes` (name,
    shape, 4x4 matrix), one scene node each, in order. Same input, same bytes."""
    import struct

    blob = bytearray()
    views: list[dict] = []
    accessors: list[dict] = []

    def put(data: np.ndarray, **accessor) -> int:
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": int(data.nbytes)})
        blob.extend(data.tobytes())
        accessors.append({"bufferView": len(views) - 1, **accessor})
        return len(accessors) - 1

    meshes, index = [], {}
    for name, (verts, faces, rgba) in shapes.items():
        v = np.ascontiguousarray(numfmt.on_grid(np.asarray(verts, float).reshape(-1, 3)), np.float32)  # stated precision
        f = np.ascontiguousarray(numfmt.canonical_faces(faces), np.uint32).reshape(-1)  # one order (numfmt)
        c = np.tile(np.asarray(rgba, np.uint8), (len(v), 1))
        ind = put(f, componentType=5125, count=int(f.size), type="SCALAR",
                  max=[int(f.max()) if f.size else 0], min=[int(f.min()) if f.size else 0])
        pos = put(v, componentType=5126, count=len(v), type="VEC3",
                  max=[float(x) for x in v.max(axis=0)], min=[float(x) for x in v.min(axis=0)])
        col = put(c, componentType=5121, normalized=True, count=len(v), type="VEC4")
        index[name] = len(meshes)
        meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": pos, "COLOR_0": col},
                                                     "indices": ind, "mode": 4}]})
    gltf = {"asset": {"version": "2.0", "generator": "cogniframe"}, "scene": 0,
            "scenes": [{"nodes": list(range(len(nodes)))}],
            "nodes": [{"name": name, "mesh": index[geom],
                       "matrix": numfmt.placement(m).T.ravel().tolist()} for name, geom, m in nodes],
            "meshes": meshes, "accessors": accessors, "bufferViews": views,
            "buffers": [{"byteLength": len(blob)}]}
    while len(blob) % 4:
        blob.append(0)
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(text), b"JSON") + text
            + struct.pack("<I4s", len(blob), b"BIN\0") + bytes(blob))


# -- the clash check over everything in the assembly --------------------------------

def rod_mesh(rod, sections: int = 48):
    import trimesh

    start, end = np.asarray(rod.start, float), np.asarray(rod.end, float)
    return trimesh.creation.cylinder(radius=rod.diameter / 2, segment=np.vstack([start, end]), sections=sections)


def bodies(spec: Spec, frame, parts: Sequence[PartSpec], built, meshes: dict) -> list:
    """Every solid of the aircraft for the clash check: part copies (their print meshes with the
    world <- print transform), rods, vitamins (propellers as discs)."""
    from ..analysis.clash import Body
    from ..fasteners import VITAMIN_STAGES, part_stage, rod_stage
    from ..vitamins import to_trimesh, vitamins

    by_name = {b.name: b for b in built}
    out = []
    for p in parts:
        for pl in p.placements:
            out.append(Body(instance_name(p, pl.instance), "part", meshes[p.name],
                            world_from_print(pl.matrix(), by_name[p.name].print_from_local), stage=part_stage(p)))
    for rod in frame.rods.values():
        out.append(Body(rod.name, "rod", rod_mesh(rod), stage=rod_stage(rod)))
    for v in vitamins(spec, frame, parts):
        out.append(Body(v.name, "propeller" if v.disc else "vitamin", to_trimesh(v), None, v.disc is not None,
                        v.stage or VITAMIN_STAGES.get(v.family, "frame")))
    return out


def own_motor_pairs(frame) -> frozenset:
    """Each propeller sits on its own motor's shaft: that pair is not a clash."""
    return frozenset(frozenset((f"propeller_{m.corner}", f"motor_{m.corner}")) for m in frame.motors)


def not_clashes(spec: Spec, frame, parts: Sequence[PartSpec]) -> frozenset:
    """The pairs that share space by design: a propeller and its motor, a screw and the thread it
    engages (its motor, its nut). A screw in its own clearance hole is tested like any pair: the
    hole clears its shank and its head sits on the part's face, so their overlap is ~0."""
    from ..vitamins import thread_pairs

    return own_motor_pairs(frame) | thread_pairs(spec, frame, parts)


def press_fits(spec: Spec, frame) -> dict[frozenset, float]:
    """The rod ends pressed into a narrower blind socket (joints.fit_clearance < 0), as (joint, rod)
    name pairs, each with its designed interference volume: the ring between the rod and the hole
    along the socket's depth, mm^3. The clash check lets those pairs overlap by that much. Each
    rod's diameter is its own (`frame.Rod`); the spec gives the hole (`Spec.bore`)."""
    bore = spec.bore
    return {frozenset((end.node, rod.name)): math.pi / 4 * (rod.diameter * rod.diameter - bore * bore) * end.depth
            for rod in frame.rods.values() if bore < rod.diameter for end in (rod.a, rod.b)}


def check_clashes(spec: Spec, frame, parts: Sequence[PartSpec], built, out_dir: str | Path,
                  memo: tuple[str, str] | None = None):
    """The build's clash check: part meshes read back from their STL files; returns
    analysis.clash.ClashResult (its clashes are FAIL problems). `memo`: (cache folder, salt) of
    the pair results kept between builds (cache.Memo), so only pairs with a changed solid are
    tested again; None tests every pair."""
    from ..analysis import clash
    from .mesh import load_stl

    out_dir = Path(out_dir)
    meshes = {b.name: load_stl(out_dir / b.stl) for b in built}
    store = None
    if memo is not None:
        from ..cache import Memo

        store = Memo("clash-pairs", memo[1], memo[0])
    from ..analysis.fit_check import keepouts
    from ..fasteners import fasteners

    return clash.check(bodies(spec, frame, parts, built, meshes), prop_margin=spec.requirements.prop_margin,
                       ignore=not_clashes(spec, frame, parts), memo=store, allowed=press_fits(spec, frame),
                       keepouts=keepouts(spec, frame, fasteners(spec, frame, parts)))


def _vitamin_key(spec: Spec, frame, vits=None) -> list:
    """What a step reads of the bought parts: each one's name, colour and primitives. `vits`: the
    design's `vitamins.vitamins(...)` when the caller has them (a build makes them once:
    `BuildContext.vitamins`), else made here."""
    if vits is None:
        from ..vitamins import vitamins

        vits = vitamins(spec, frame)
    return [[v.name, v.colour, [[p.kind, p.centre, p.size, p.rot, p.axis, p.radius, p.length, p.radius_end] for p in v.prims]]
            for v in vits]


def write_assembly(spec: Spec, frame, parts: Sequence[PartSpec], built, out_dir: str | Path) -> tuple[Path, Path]:
    """Write out_dir/assembly.step (deterministic) and out_dir/assembly.glb (the build makes them
    as two cached steps of their own: pipeline/cad_steps.py)."""
    from .mesh import load_stl

    out_dir = Path(out_dir)
    step, glb = out_dir / "assembly.step", out_dir / "assembly.glb"
    write_assembly_step(spec, frame, parts, built, out_dir)
    write_glb(spec, frame, parts, {b.name: load_stl(out_dir / b.stl) for b in built},
              {b.name: b.print_from_local for b in built}, glb)
    return step, glb
