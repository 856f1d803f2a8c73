"""Load a CAD assembly into named solids in one frame (mm): STEP (.step/.stp) or FreeCAD (.FCStd).

- STEP: `cq.Assembly.importStep` keeps the product names and the placements of the assembly tree;
  each leaf's shape is moved by the product of the locations from the root. A leaf holding several
  solids gives `name#1`, `name#2`, ... A STEP without an assembly structure (one part, one compound) reads the
  without its names: cadquery reads it as one shape, whose solids are named after the file
  (`stem#k`).
- FreeCAD: the `.FCStd` is a zip of `Document.xml` (each object's properties: its `Label`, its
  `Placement` as position + quaternion, its `Shape` as the name of a `.brp` (text BRep) or `.bin`
  (binary BRep) file in the zip) and the shape files. Only the visible objects are read when any
  object carries a `Visibility` (a boolean's inputs are hidden and are not parts). FreeCAD writes a
  shape with its placement already applied (the BRep's root location): a shape whose own location
  matches the object's placement is taken as placed; one stored at the identity is moved by the
  placement (older files, hand-made ones).

Errors are `UserError`s that name the file: missing, not a STEP/FCStd, unreadable, no solids.
"""

from __future__ import annotations

import math
import os
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import UserError

STEP_EXT = (".step", ".stp")
FREECAD_EXT = (".fcstd",)


@dataclass(frozen=True)
class NamedSolid:
    name: str
    solid: object  # cadquery.Solid, in the assembly's frame (mm)


def load_solids(path: str | os.PathLike) -> list[NamedSolid]:
    """Every solid of the assembly at `path`, placed, named (names made unique)."""
    p = Path(path)
    if not p.is_file():
        raise UserError(f"{p}: no such file (give a STEP assembly, .step/.stp, or a FreeCAD document, .FCStd)")
    ext = p.suffix.lower()
    if ext in STEP_EXT:
        out = _load_step(p)
    elif ext in FREECAD_EXT:
        out = _load_fcstd(p)
    else:
        raise UserError(f"{p}: not a CAD assembly cogniframe reads (the extension {p.suffix or '(none)'!r}); "
                        f"give a STEP file (.step, .stp) or a FreeCAD document (.FCStd)")
    if not out:
        raise UserError(f"{p}: the file holds no solids (only surfaces, wires or nothing): export the parts as solids")
    return _unique(out)


def _unique(items: list[NamedSolid]) -> list[NamedSolid]:
    seen: dict[str, int] = {}
    out = []
    for it in items:
        n = seen.get(it.name, 0)
        seen[it.name] = n + 1
        out.append(it if n == 0 else NamedSolid(f"{it.name}~{n + 1}", it.solid))
    return out


def _solids_named(name: str, shape) -> list[NamedSolid]:
    sols = list(shape.Solids()) if shape is not None else []
    if len(sols) == 1:
        return [NamedSolid(name, sols[0])]
    return [NamedSolid(f"{name}#{i + 1}", s) for i, s in enumerate(sols)]


# -- STEP ---------------------------------------------------------------------------------------

def _load_step(p: Path) -> list[NamedSolid]:
    import cadquery as cq

    head = p.read_bytes()[:2048].lstrip()
    if not head.startswith(b"ISO-10303-21"):
        raise UserError(f"{p}: not a STEP file (a STEP file starts with 'ISO-10303-21;'); export the assembly as STEP AP214/AP242")
    try:
        assy = cq.Assembly.importStep(str(p))
    except Exception as exc:  # OCC's reader reports a broken file as a generic error
        if "does not contain an assembly" in str(exc):  # one part or one compound: its solids
            try:
                shape = cq.importers.importStep(str(p))
            except Exception as exc2:
                raise UserError(f"{p}: the STEP file could not be read ({type(exc2).__name__}: {exc2}); "
                                f"export it again from the CAD program as STEP AP214/AP242") from None
            return _solids_named(p.stem, cq.Compound.makeCompound(shape.vals()))
        raise UserError(f"{p}: the STEP file could not be read ({type(exc).__name__}: {exc}); "
                        f"export it again from the CAD program as STEP AP214/AP242") from None
    out: list[NamedSolid] = []

    def walk(node, loc) -> None:
        here = loc * node.loc
        if node.obj is not None:
            shape = node.obj if isinstance(node.obj, cq.Shape) else cq.Compound.makeCompound(
                [v for v in node.obj.vals() if isinstance(v, cq.Shape)])
            out.extend(_solids_named(node.name, shape.moved(here)))
        for ch in node.children:
            walk(ch, here)

    walk(assy, cq.Location())
    return out


# -- FreeCAD ------------------------------------------------------------------------------------

def _placement_matrix(el) -> np.ndarray:
    """4x4 from a FreeCAD `PropertyPlacement` element (position + quaternion Q0..Q3 = x, y, z, w)."""
    g = lambda k, d=0.0: float(el.get(k, d))  # noqa: E731
    x, y, z, w = g("Q0"), g("Q1"), g("Q2"), g("Q3", 1.0)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n < 1e-12:  # no quaternion: the axis-angle
        ax = np.array([g("Ox"), g("Oy"), g("Oz", 1.0)])
        ax = ax / (np.linalg.norm(ax) or 1.0)
        s = math.sin(g("A") / 2)
        x, y, z, w, n = *(ax * s), math.cos(g("A") / 2), 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = g("Px"), g("Py"), g("Pz")
    return m


def _trsf_matrix(loc) -> np.ndarray:
    t = loc.Transformation()
    m = np.eye(4)
    for i in range(3):
        for j in range(4):
            m[i, j] = t.Value(i + 1, j + 1)
    return m


def _location(m: np.ndarray):
    import cadquery as cq
    from OCP.gp import gp_Trsf

    t = gp_Trsf()
    t.SetValues(*[float(v) for v in np.asarray(m)[:3].ravel()])
    return cq.Location(t)


def _read_brep(data: bytes, binary: bool, what: str):
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Shape

    shape = TopoDS_Shape()
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / ("s.bin" if binary else "s.brp")
        f.write_bytes(data)
        if binary:
            from OCP.BinTools import BinTools

            ok = BinTools.Read_s(shape, str(f))
        else:
            from OCP.BRepTools import BRepTools

            ok = BRepTools.Read_s(shape, str(f), BRep_Builder())
    if not ok or shape.IsNull():
        raise UserError(f"{what}: the shape file could not be read (a broken or truncated FreeCAD document)")
    return shape


def _load_fcstd(p: Path) -> list[NamedSolid]:
    import cadquery as cq

    try:
        zf = zipfile.ZipFile(p)
    except (zipfile.BadZipFile, OSError):
        raise UserError(f"{p}: not a FreeCAD document (an .FCStd is a zip holding Document.xml)") from None
    with zf:
        try:
            root = ET.fromstring(zf.read("Document.xml"))
        except KeyError:
            raise UserError(f"{p}: not a FreeCAD document (no Document.xml in the zip)") from None
        except ET.ParseError as exc:
            raise UserError(f"{p}: Document.xml is not valid XML ({exc})") from None
        objs = []
        for ob in root.iter("Object"):
            props = {pr.get("name"): pr for pr in ob.iter("Property")}
            shape_el = props.get("Shape")
            part = shape_el.find("Part") if shape_el is not None else None
            if part is None or not part.get("file"):
                continue
            label_el = props.get("Label")
            label = label_el.find("String").get("value") if label_el is not None and label_el.find("String") is not None else None
            vis_el = props.get("Visibility")
            vis = None if vis_el is None or vis_el.find("Bool") is None else vis_el.find("Bool").get("value") == "true"
            pl_el = props.get("Placement")
            pl = pl_el.find("PropertyPlacement") if pl_el is not None else None
            objs.append((label or ob.get("name"), part.get("file"), vis, _placement_matrix(pl) if pl is not None else np.eye(4)))
        if any(v is not None for _, _, v, _ in objs):
            objs = [o for o in objs if o[2] is not False]
        out: list[NamedSolid] = []
        for label, fname, _vis, m in objs:
            try:
                data = zf.read(fname)
            except KeyError:
                raise UserError(f"{p}: {label}'s shape file {fname} is missing from the document") from None
            if not data.strip():
                continue  # an empty shape (FreeCAD writes one for a feature without geometry)
            shape = cq.Shape.cast(_read_brep(data, fname.lower().endswith(".bin"), f"{p} ({fname})"))
            own = _trsf_matrix(shape.wrapped.Location())
            if not np.allclose(own, m, atol=1e-6) and np.allclose(own, np.eye(4), atol=1e-9):
                shape = shape.moved(_location(m))  # stored unplaced: apply the object's placement
            out.extend(_solids_named(label, shape))
    return out
