"""Print plates: every copy of every printed part laid out on the printer's bed, per material.

Input meshes are already in print orientation (lowest z = 0). Each part may be turned about z
once (to its smallest-area footprint, when that saves at least 10 % of bed area), then the
copies' footprints (bounding rectangles grown by `printer.margin`) are packed onto as many beds
as needed with rectpack's MaxRects (best short-side fit; the Global bin strategy fills one
plate at a time with the best-fitting rectangles, so the plate count stays low). Rectangles
are integers in 0.01 mm; packing has no randomness, so the same input gives the same layout.

Coordinates on a plate are PrusaSlicer's: the bed runs from (0, 0) to (bed x, bed y). Parts
keep `margin` mm from each other and `margin / 2` mm from the bed edges, and the packed group
is centred on the bed.

Files (`write_plates`): `<material>_<n>.3mf` (a named build item per copy, `knee_1` ...; copies
of one shape share one mesh, so PrusaSlicer sees one object with several instances and slices it
once; it opens the file directly and keeps the layout with `--dont-arrange`; with `configs`, the
material's print settings ride along as PrusaSlicer's `Metadata/Slic3r_PE.config`, so the plate
slices with them and no .ini) and `<material>_<n>.png` (top view, parts filled and labelled).
Both are byte-stable: the 3MF is written here with no UUIDs or dates (zip entries get a fixed
date); the PNG has no Software/date metadata.
"""

from __future__ import annotations

import io
import math
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np

from .. import numfmt
from ..errors import UserError

if TYPE_CHECKING:  # trimesh is imported where it is used: reading a plate's names needs none of it
    import trimesh

SCALE = 100  # packing units per mm (rectpack works best with integers)
TURN_GAIN = 0.10  # turn a part to its min-area footprint only if that saves this much bed area
ZIP_DATE = (1980, 1, 1, 0, 0, 0)

# Top-view fill colours by material (the renders use the same scheme).
MATERIAL_COLOURS = {"tpu_95a": "#d62728", "abs": "#404040", "pla": "#404040", "petg": "#5a5a7a"}
DEFAULT_COLOUR = "#1f77b4"


def material_colour(material: str) -> str:
    """Hex colour for a material: TPU red, ABS/PLA dark grey, anything else blue."""
    if material in MATERIAL_COLOURS:
        return MATERIAL_COLOURS[material]
    return MATERIAL_COLOURS["tpu_95a"] if material.startswith("tpu") else DEFAULT_COLOUR


@dataclass(frozen=True, eq=False)
class PlateItem:
    """A printed part to lay out: `qty` copies of `mesh` (print orientation, mm) in `material`."""

    name: str
    material: str
    qty: int
    mesh: trimesh.Trimesh


@dataclass(frozen=True, eq=False)
class PlacedCopy:
    """One copy on a plate. `mesh` is in bed coordinates; (x, y) is its footprint's lower-left corner."""

    name: str  # copy name, e.g. knee_3
    part: str  # part name, e.g. knee
    x: float
    y: float
    size: tuple[float, float, float]  # footprint x, y and height, mm
    rotation_deg: float  # turn about z applied to the print-orientation mesh before placing
    mesh: trimesh.Trimesh

    @property
    def volume_mm3(self) -> float:
        return float(self.mesh.volume)


@dataclass(frozen=True, eq=False)
class Plate:
    material: str
    index: int  # 1-based, per material
    bed: tuple[float, float, float]
    margin: float
    copies: tuple[PlacedCopy, ...]

    @property
    def name(self) -> str:
        """File stem, e.g. tpu_95a_1."""
        return f"{self.material}_{self.index}"

    @property
    def fill(self) -> float:
        """Fraction of the bed area covered by the copies' footprints."""
        return sum(c.size[0] * c.size[1] for c in self.copies) / (self.bed[0] * self.bed[1])

    @property
    def volume_mm3(self) -> float:
        return sum(c.volume_mm3 for c in self.copies)


@dataclass(frozen=True)
class PlateFile:
    """What `write_plates` wrote for one plate."""

    name: str  # tpu_95a_1
    material: str
    threemf: Path
    preview: Path
    copies: tuple[str, ...]  # object names in the 3MF
    volume_mm3: float = field(default=0.0)


# -- layout ----------------------------------------------------------------------------------

def _rot_z(deg: float) -> np.ndarray:
    import trimesh

    return trimesh.transformations.rotation_matrix(math.radians(deg), [0, 0, 1])


def _footprint_turn(mesh: trimesh.Trimesh) -> float:
    """Degrees to turn about z so the footprint's bounding rectangle is smallest (0 if not worth it)."""
    import trimesh

    pts = np.asarray(mesh.vertices)[:, :2]
    ext = np.ptp(pts, axis=0)
    area = float(ext[0] * ext[1])
    try:
        tf, rect = trimesh.bounds.oriented_bounds_2D(pts)
    except Exception:  # degenerate (collinear) footprints: nothing to gain
        return 0.0
    if area <= 0 or rect[0] * rect[1] > (1 - TURN_GAIN) * area:
        return 0.0
    deg = math.degrees(math.atan2(tf[1, 0], tf[0, 0]))
    return round(deg, 3)


def _normalised(mesh: trimesh.Trimesh, deg: float) -> trimesh.Trimesh:
    """Copy of `mesh` turned `deg` about z and moved so its bounding box starts at the origin, its
    vertices on the grid the 3MF states them on (numfmt.GRID_MM): the layout measures what is written."""
    m = mesh.copy()
    if deg:
        m.apply_transform(_rot_z(deg))
    m.apply_translation(-m.bounds[0])
    m.vertices = numfmt.on_grid(m.vertices)
    return m


def _check_item(item: PlateItem, bed: tuple[float, float, float], margin: float) -> None:
    if item.qty < 0:
        raise ValueError(f"{item.name}: negative quantity {item.qty}")
    if item.mesh is None or len(item.mesh.faces) == 0:
        raise ValueError(f"{item.name}: empty mesh")
    lo = item.mesh.bounds[0]
    if abs(lo[2]) > 1e-3:
        raise ValueError(f"{item.name}: mesh is not in print orientation (lowest z = {lo[2]:.3f}, expected 0)")


def pack_plates(items: Sequence[PlateItem], bed: Sequence[float], margin: float) -> tuple[Plate, ...]:
    """Lay out every copy of every item on as few beds as rectpack finds, per material.

    `bed` is the build volume (x, y, z) in mm (`printer.bed`); `margin` the gap between parts
    (`printer.margin`). Plates are ordered by material name, then index. Raises UserError if a
    part is taller than the build volume or its footprint does not fit the bed.
    """
    import rectpack

    bed3 = (float(bed[0]), float(bed[1]), float(bed[2]))
    margin = float(margin)
    edge = margin / 2
    by_material: dict[str, list[PlateItem]] = {}
    for item in items:
        _check_item(item, bed3, margin)
        if item.qty:
            by_material.setdefault(item.material, []).append(item)

    plates: list[Plate] = []
    for material in sorted(by_material):
        group = sorted(by_material[material], key=lambda i: i.name)
        shapes: dict[str, tuple[trimesh.Trimesh, float]] = {}
        for item in group:
            deg = _footprint_turn(item.mesh)
            m = _normalised(item.mesh, deg)
            w, d, h = (float(v) for v in m.extents)
            usable = (bed3[0] - 2 * edge, bed3[1] - 2 * edge)
            fits = (w <= usable[0] and d <= usable[1]) or (d <= usable[0] and w <= usable[1])
            if h > bed3[2] or not fits:
                raise UserError(
                    f"part {item.name} ({w:.1f} x {d:.1f} x {h:.1f} mm in print orientation) does not fit the "
                    f"{bed3[0]:g} x {bed3[1]:g} x {bed3[2]:g} mm build volume (printer.bed) with {edge:g} mm kept "
                    f"from the bed edges (half of printer.margin). Fix: set printer.bed to your printer's real build "
                    f"volume, lower printer.margin, or make the part smaller (e.g. frame or core sizes).", key="printer.bed")
            shapes[item.name] = (m, deg)

        packer = rectpack.newPacker(mode=rectpack.PackingMode.Offline, bin_algo=rectpack.PackingBin.Global,
                                    pack_algo=rectpack.MaxRectsBssf, sort_algo=rectpack.SORT_AREA, rotation=True)
        bin_w = int(math.floor((bed3[0] - 2 * edge + margin) * SCALE))
        bin_h = int(math.floor((bed3[1] - 2 * edge + margin) * SCALE))
        packer.add_bin(bin_w, bin_h, count=float("inf"))
        rid_of: dict[int, tuple[PlateItem, int]] = {}
        rid = 0
        for item in group:
            m, _ = shapes[item.name]
            w, d = (int(math.ceil((float(v) + margin) * SCALE)) for v in m.extents[:2])
            for k in range(1, item.qty + 1):
                packer.add_rect(w, d, rid=rid)
                rid_of[rid] = (item, k)
                rid += 1
        packer.pack()
        placed = packer.rect_list()
        if len(placed) != rid:  # cannot happen after the size check above, but never drop a part silently
            missing = sorted(set(rid_of) - {r[5] for r in placed})
            raise RuntimeError(f"packing left out {[f'{rid_of[i][0].name}_{rid_of[i][1]}' for i in missing]}")

        per_bin: dict[int, list[tuple[int, int, int, int, int]]] = {}
        for b, x, y, w, h, r in placed:
            per_bin.setdefault(b, []).append((x, y, w, h, r))
        for index, b in enumerate(sorted(per_bin), start=1):
            rects = sorted(per_bin[b], key=lambda t: t[4])
            copies = []
            for x, y, w, h, r in rects:
                item, k = rid_of[r]
                m, deg = shapes[item.name]
                turned = w != int(math.ceil((float(m.extents[0]) + margin) * SCALE))  # rectpack swapped w, h
                mesh = m.copy()
                total = deg
                if turned:
                    mesh.apply_transform(_rot_z(90.0))
                    mesh.apply_translation(-mesh.bounds[0])
                    total = deg + 90.0
                copies.append((item, k, x / SCALE, y / SCALE, mesh, total))
            # centre the packed group on the bed
            lo = np.min([[c[2], c[3]] for c in copies], axis=0)
            hi = np.max([[c[2] + c[4].extents[0], c[3] + c[4].extents[1]] for c in copies], axis=0)
            shift = (np.array(bed3[:2]) - (hi - lo)) / 2 - lo
            shift = np.round(shift, 2)
            out = []
            for item, k, x, y, mesh, total in copies:
                px, py = round(x + shift[0], 2), round(y + shift[1], 2)
                mesh.apply_translation([px, py, 0.0])
                ext = mesh.extents
                out.append(PlacedCopy(f"{item.name}_{k}", item.name, float(px), float(py),
                                      (float(ext[0]), float(ext[1]), float(ext[2])), total % 360.0, mesh))
            out.sort(key=lambda c: (c.part, int(c.name.rsplit("_", 1)[1])))
            plates.append(Plate(material, index, bed3, margin, tuple(out)))
    return tuple(plates)


# -- files -----------------------------------------------------------------------------------

PRUSA_CONFIG = "Metadata/Slic3r_PE.config"  # PrusaSlicer's project (print + filament + printer) settings
PRUSA_MODEL_CONFIG = "Metadata/Slic3r_PE_model.config"  # PrusaSlicer's objects: names, instance counts

_CONTENT_TYPES = ('<?xml version="1.0" encoding="UTF-8"?>\n'
                  '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
                  '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
                  '<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
                  '</Types>\n')
_RELS = ('<?xml version="1.0" encoding="UTF-8"?>\n'
         '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
         '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
         'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>\n')


def _instances(plate: Plate) -> list[tuple[np.ndarray, np.ndarray, list[PlacedCopy]]]:
    """The plate's copies grouped by shape: copies of a part laid out the same way round are one mesh
    (vertices relative to the footprint's lower-left corner) placed several times."""
    import hashlib

    groups: dict[str, tuple[np.ndarray, np.ndarray, list[PlacedCopy]]] = {}
    for c in plate.copies:
        verts = numfmt.on_grid(np.asarray(c.mesh.vertices, float) - [c.x, c.y, 0.0])  # the stated precision
        faces = np.asarray(c.mesh.faces, np.int64)
        key = hashlib.sha256(c.part.encode() + np.round(verts, 6).tobytes() + faces.tobytes()).hexdigest()
        groups.setdefault(key, (verts, faces, []))[2].append(c)
    return list(groups.values())


def _num(v: float) -> str:
    return f"{v:.9g}" if v != 0 else "0"


def plate_3mf_bytes(plate: Plate, config: str | None = None) -> bytes:
    """The plate as a 3MF (`plate_3mf`'s bytes)."""
    return plate_3mf(plate, config)[0]


def plate_3mf(plate: Plate, config: str | None = None) -> tuple[bytes, tuple[tuple[str, trimesh.Trimesh, np.ndarray], ...]]:
    """The plate as a 3MF, byte-stable: one mesh per shape, placed once per copy.

    Copies of one part (the same way round) are one mesh object; every further copy is an object
    whose single component is that mesh, and each copy is a build item translated to its place on
    the bed, named after the copy (`knee_3`, also its `partnumber`). PrusaSlicer reads the shared
    mesh as one object with several instances (`Metadata/Slic3r_PE_model.config` says how many)
    and slices it once, in a fraction of the time and with the same grams (docs/measurements.md).
    Other slicers read the plain 3MF core spec.

    `config`: PrusaSlicer project settings (`slicer.project_config`), stored as
    `Metadata/Slic3r_PE.config` so PrusaSlicer slices the plate with them and no .ini.

    Returns (bytes, items): items are what `read_3mf_items` reads back from those bytes, equal to
    the last bit (parsed from the same text, shared meshes shared), so the build draws a plate's
    preview without reading the file it just wrote (`read_plate(items=)`)."""
    import trimesh
    from xml.sax.saxutils import quoteattr

    objects, items, prusa = [], [], []
    read: list[tuple[str, trimesh.Trimesh, np.ndarray]] = []
    oid = 0
    for verts, faces, copies in _instances(plate):
        oid += 1
        base = oid
        text = [_num(x) for x in verts.ravel().tolist()]
        it = iter(text)
        vx = "".join(f'<vertex x="{x}" y="{y}" z="{z}"/>' for x, y, z in zip(it, it, it))
        tr = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in faces.tolist())
        # the mesh read_3mf_items builds from this text
        mesh = trimesh.Trimesh(np.array([float(x) for x in text], float).reshape(-1, 3),
                               np.array(faces, np.int64).reshape(-1, 3), process=False)
        objects.append(f'<object id="{base}" name={quoteattr(copies[0].name)} type="model">'
                       f'<mesh><vertices>{vx}</vertices><triangles>{tr}</triangles></mesh></object>')
        for k, c in enumerate(copies):
            if k:
                oid += 1
                objects.append(f'<object id="{oid}" name={quoteattr(c.name)} type="model">'
                               f'<components><component objectid="{base}"/></components></object>')
            transform = f"1 0 0 0 1 0 0 0 1 {_num(c.x)} {_num(c.y)} 0"
            items.append(f'<item objectid="{oid}" transform="{transform}" '
                         f'partnumber={quoteattr(c.name)} printable="1"/>')
            read.append((c.name, mesh, _transform(transform)))
        part = quoteattr(copies[0].part)
        prusa.append(f' <object id="{base}" instances_count="{len(copies)}">\n'
                     f'  <metadata type="object" key="name" value={part}/>\n'
                     f'  <volume firstid="0" lastid="{len(faces) - 1}">\n'
                     f'   <metadata type="volume" key="name" value={part}/>\n'
                     f'  </volume>\n </object>\n')
    model = ('<?xml version="1.0" encoding="UTF-8"?>\n'
             '<model unit="millimeter" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" '
             'xmlns:slic3rpe="http://schemas.slic3r.org/3mf/2017/06">\n'
             ' <metadata name="slic3rpe:Version3mf">1</metadata>\n'
             f' <metadata name="Title">{plate.name}</metadata>\n'
             ' <metadata name="Application">cogniframe</metadata>\n'
             ' <resources>\n  ' + "\n  ".join(objects) + '\n </resources>\n'
             ' <build>\n  ' + "\n  ".join(items) + '\n </build>\n</model>\n')
    entries = {"[Content_Types].xml": _CONTENT_TYPES, "_rels/.rels": _RELS, "3D/3dmodel.model": model,
               PRUSA_MODEL_CONFIG: '<?xml version="1.0" encoding="UTF-8"?>\n<config>\n' + "".join(prusa) + '</config>\n'}
    if config:
        entries[PRUSA_CONFIG] = config
    return _zip({k: v.encode("utf-8") for k, v in entries.items()}), tuple(read)


def model_sha256(threemf: bytes) -> str:
    """sha256 of a 3MF's geometry and layout (`3D/3dmodel.model`), not of the settings beside it."""
    import hashlib

    with zipfile.ZipFile(io.BytesIO(threemf)) as z:
        return hashlib.sha256(z.read("3D/3dmodel.model")).hexdigest()


def _zip(entries: Mapping[str, bytes]) -> bytes:
    """A zip of `entries` (name -> bytes) in the given order, with fixed dates and modes."""
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=6) as dst:
        for name, data in entries.items():
            zi = zipfile.ZipInfo(name, date_time=ZIP_DATE)
            zi.compress_type = zipfile.ZIP_DEFLATED
            zi.external_attr = 0o644 << 16
            dst.writestr(zi, data)
    return out.getvalue()


def plot_plate(plate: Plate, path: Path | str, size_in: float = 6.0, dpi: int = 100) -> Path:
    """Top view of a plate: the bed, each copy's faces filled in its material colour, its
    footprint outlined (dashed) and its name written on it. PNG without metadata."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import PathPatch, Rectangle

    path = Path(path)
    bx, by = plate.bed[0], plate.bed[1]
    aspect = by / bx
    # fixed margins, not a layout engine: the texts around the bed are fixed, and the constrained
    # layout drew every triangle twice (half of the preview's time)
    fig = Figure(figsize=(size_in, size_in * aspect + 0.5), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    ax.add_patch(Rectangle((0, 0), bx, by, facecolor="#f4f4f0", edgecolor="black", linewidth=1.2))
    colour = material_colour(plate.material)
    pt_per_mm = size_in * 72 * 0.82 / (bx + 4)  # roughly: the axes take ~82 % of the figure width
    # add_artist, not add_patch: the limits are set below, no need to measure 30k triangles
    ax.add_artist(PathPatch(_silhouettes(plate.copies), facecolor=colour, edgecolor="none", alpha=0.85))
    for c in plate.copies:
        ax.add_patch(Rectangle((c.x, c.y), c.size[0], c.size[1], fill=False, edgecolor="#555555",
                               linewidth=0.6, linestyle="--"))
        base, _, k = c.name.rpartition("_")
        label = f"{base}\n#{k}" if c.size[0] < 0.62 * 9.0 * len(c.name) / pt_per_mm else c.name  # 2 lines if narrow
        longest = max(len(line) for line in label.splitlines())
        fs = max(5.5, min(9.0, 0.95 * c.size[0] * pt_per_mm / (0.62 * longest)))
        ax.text(c.x + c.size[0] / 2, c.y + c.size[1] / 2, label, ha="center", va="center", fontsize=fs,
                linespacing=1.0,
                color="black", bbox=dict(boxstyle="round,pad=0.15", facecolor="white", edgecolor="none", alpha=0.75))
    ax.set_xlim(-2, bx + 2)
    ax.set_ylim(-2, by + 2)
    ax.set_aspect("equal")
    h_in = size_in * aspect + 0.5
    fig.subplots_adjust(left=0.65 / size_in, right=1 - 0.12 / size_in, bottom=0.5 / h_in, top=1 - 0.5 / h_in)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"{plate.name}: {len(plate.copies)} parts in {plate.material}\n"
                 f"{bx:g} x {by:g} mm bed, footprints cover {100 * plate.fill:.0f} %", fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format="png", dpi=dpi, metadata={"Software": None})
    return path


def _silhouettes(copies: Sequence[PlacedCopy]):
    """The copies' top-view silhouettes as one matplotlib path: each copy's upward faces, projected.

    The upward faces of a closed solid cover its silhouette (every vertical line through it leaves
    through one); walls project to lines, and the downward faces would cover it again. Projected,
    they all turn counter-clockwise, so the path's nonzero fill is their union: one path drawn once,
    in one colour and one alpha, where a triangle per path (a PolyCollection of 30k triangles) cost
    most of the preview's time and drew overlaps darker."""
    from matplotlib.path import Path as MplPath

    tris = []
    for c in copies:
        faces = np.asarray(c.mesh.faces)
        up = np.asarray(c.mesh.face_normals)[:, 2] > 1e-3
        tris.append(np.asarray(c.mesh.vertices)[faces[up]][:, :, :2])
    tri = np.concatenate(tris) if tris else np.zeros((0, 3, 2))
    verts = np.concatenate([tri, tri[:, :1]], axis=1).reshape(-1, 2)  # each triangle closed: a b c a
    codes = np.tile(np.array([MplPath.MOVETO, MplPath.LINETO, MplPath.LINETO, MplPath.CLOSEPOLY], MplPath.code_type),
                    len(tri))
    return MplPath(verts, codes)


def write_plates(plates: Sequence[Plate], out_dir: Path | str,
                 configs: Mapping[str, str] | None = None) -> tuple[PlateFile, ...]:
    """Write `<name>.3mf` and `<name>.png` for each plate into `out_dir` (created).

    `configs`: material -> PrusaSlicer project settings embedded in that material's plates
    (`slicer.project_configs(spec, infill)`), so each 3MF opens ready to print.

    Stale plate files from an earlier build with more plates are removed, so the folder holds
    exactly these plates (the `slice` command slices every *.3mf in it)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    keep = {p.name for p in plates}
    for old in sorted(out_dir.glob("*.3mf")):
        if old.stem not in keep:
            old.unlink()
            old.with_suffix(".png").unlink(missing_ok=True)
            old.with_suffix(".gcode").unlink(missing_ok=True)
    written = []
    for p in plates:
        f3 = out_dir / f"{p.name}.3mf"
        f3.write_bytes(plate_3mf_bytes(p, (configs or {}).get(p.material)))
        png = plot_plate(p, out_dir / f"{p.name}.png")
        written.append(PlateFile(p.name, p.material, f3, png, tuple(c.name for c in p.copies), p.volume_mm3))
    return tuple(written)


_NS = "{http://schemas.microsoft.com/3dmanufacturing/core/2015/02}"


def _transform(text: str | None) -> np.ndarray:
    """A 3MF transform attribute (12 numbers, column by column) as a 4x4 matrix; identity when absent."""
    m = np.eye(4)
    if text:
        v = np.array(text.split(), float)
        if v.size != 12:
            raise ValueError(f"bad transform {text!r}")
        m[:3, :3] = v[:9].reshape(3, 3).T
        m[:3, 3] = v[9:12]
    return m


def read_3mf_items(path: Path | str) -> tuple[tuple[str, trimesh.Trimesh, np.ndarray], ...]:
    """The build items of a 3MF: (name, mesh in its object's coordinates, 4x4 item transform).

    The name is the item's `partnumber`, else its object's name, else `object_<id>`. An object made
    of components (another object placed with a transform: how `plate_3mf_bytes` writes a further
    copy of a shape) is resolved to one mesh; objects shared by several items are the same Trimesh,
    so a caller can check each shape once. Not trimesh's loader: it names component copies
    unreliably (two identical copies can swap names). Raises ValueError for what it cannot read."""
    import trimesh
    from xml.etree import ElementTree

    tf = _transform
    with zipfile.ZipFile(path) as z:
        root = ElementTree.fromstring(z.read("3D/3dmodel.model"))
    objects = {o.get("id"): o for o in root.iter(f"{_NS}object")}
    meshes: dict[str, trimesh.Trimesh] = {}

    def mesh_of(oid: str, depth: int = 0) -> trimesh.Trimesh:
        if oid in meshes:
            return meshes[oid]
        if oid not in objects or depth > 16:
            raise ValueError(f"object {oid} is missing or nested too deep")
        obj = objects[oid]
        mesh = obj.find(f"{_NS}mesh")
        if mesh is not None:
            v = np.array([[float(e.get("x")), float(e.get("y")), float(e.get("z"))]
                          for e in mesh.iter(f"{_NS}vertex")], float).reshape(-1, 3)
            f = np.array([[int(e.get("v1")), int(e.get("v2")), int(e.get("v3"))]
                          for e in mesh.iter(f"{_NS}triangle")], np.int64).reshape(-1, 3)
            out = trimesh.Trimesh(v, f, process=False)
        else:
            parts = []
            for c in obj.iter(f"{_NS}component"):
                m = mesh_of(c.get("objectid"), depth + 1)
                t = tf(c.get("transform"))
                parts.append(m if np.allclose(t, np.eye(4)) else m.copy().apply_transform(t))
            if not parts:
                raise ValueError(f"object {oid} has neither a mesh nor components")
            out = parts[0] if len(parts) == 1 else trimesh.util.concatenate(parts)
        meshes[oid] = out
        return out

    items = []
    for it in root.iter(f"{_NS}item"):
        oid = it.get("objectid")
        mesh = mesh_of(oid)  # raises for a missing object
        name = it.get("partnumber") or objects[oid].get("name") or f"object_{oid}"
        items.append((name, mesh, tf(it.get("transform"))))
    return tuple(items)


def read_plate(path: Path | str, bed: Sequence[float], margin: float, items=None) -> Plate:
    """A plate read back from its 3MF (what `plot_plate` needs: copies in bed coordinates, by name).

    The build draws each preview from the 3MF it wrote, so a preview is a function of the plate
    file alone and can be cached by the file's hash. `items`: what `plate_3mf` returned with the
    file's bytes (the same as reading them back): the file is not read."""
    path = Path(path)
    material, index = parse_plate_name(path.stem)
    copies = []
    for name, base, tf in (read_3mf_items(path) if items is None else items):
        mesh = base.copy()
        mesh.apply_transform(tf)
        lo, ext = mesh.bounds[0], mesh.extents
        copies.append(PlacedCopy(name, part_of(name), float(lo[0]), float(lo[1]),
                                 (float(ext[0]), float(ext[1]), float(ext[2])), 0.0, mesh))
    copies.sort(key=lambda c: (c.part, int(c.name.rsplit("_", 1)[1]) if c.name.rsplit("_", 1)[-1].isdigit() else 0))
    bed3 = (float(bed[0]), float(bed[1]), float(bed[2]))
    return Plate(material, index, bed3, float(margin), tuple(copies))


def parse_plate_name(stem: str) -> tuple[str, int]:
    """'tpu_95a_2' -> ('tpu_95a', 2). Raises ValueError for other names."""
    material, _, idx = stem.rpartition("_")
    if not material or not idx.isdigit():
        raise ValueError(f"not a plate file name: {stem!r} (expected <material>_<n>)")
    return material, int(idx)


def part_of(copy_name: str) -> str:
    """'knee_3' -> 'knee'."""
    base, _, k = copy_name.rpartition("_")
    return base if base and k.isdigit() else copy_name
