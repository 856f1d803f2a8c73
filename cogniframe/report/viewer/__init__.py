"""The interactive 3D view at the top of report.html: the assembly as a list of named meshes.

Data-driven: `viewer_section(items)` takes `ViewerItem`s (a mesh in its own frame, a 4x4 world
matrix and the metadata shown on click: name, kind part|rod|vitamin, material, mass, quantity,
plate, colour, note). `design_items` makes them for the printed parts (one per copy) and the rods;
any other stage (the vitamins, say) adds its own items to the list.

Everything is inline, so the report works offline as one file and makes no network request:
three.js (vendored in this folder, see README.md) and the viewer's own `viewer.js` go in
`<script type="text/plain">` blocks that a small module loader turns into blob: URLs and
imports; the geometry is one base64 buffer (positions quantised to uint16 over each geometry's
bounding box, about 1 micrometre steps on a part, and uint16/uint32 triangle indices). Identical
meshes are stored once. Same items -> same bytes.
"""

from __future__ import annotations

import base64
import hashlib
import html
import json
from dataclasses import dataclass
from importlib import resources
from typing import TYPE_CHECKING, Iterable, Mapping, Sequence

import numpy as np

if TYPE_CHECKING:
    import trimesh

THREE_VERSION = "0.170.0"  # keep in step with README.md
BACKGROUND = "#f4f6f8"
ROD_COLOUR = "#1a1a1a"
KINDS = ("part", "rod", "vitamin")
TOGGLES = ("rod", "vitamin")  # kinds with a show/hide checkbox
_VENDORED = ("three.module.min.js", "OrbitControls.js", "viewer.js")


@dataclass(frozen=True, eq=False)
class ViewerItem:
    """One object in the 3D view. `mesh` (vertices in mm, in its own frame) is placed by `matrix`
    (4x4, world <- mesh; None = identity); the rest is what a click on it shows."""

    name: str
    kind: str  # part | rod | vitamin
    material: str
    mass_g: float | None  # each
    qty: int  # how many the design needs of this item's part (or 1)
    plate: str  # print plate(s) holding it, e.g. "tpu_95a_1"; "" if not printed
    colour: str  # "#rrggbb"
    mesh: "Mesh | trimesh.Trimesh"
    matrix: np.ndarray | None = None
    note: str = ""
    provisional: bool = False  # a stand-in until the exact shape is made (the studio's view of a new frame)


@dataclass(frozen=True, eq=False)
class Mesh:
    """Vertices (n x 3, mm) and triangles (m x 3 indices): all the viewer needs of a mesh
    (a trimesh.Trimesh works as well). Lets the report step run without importing trimesh."""

    vertices: np.ndarray
    faces: np.ndarray


def read_stl(path) -> Mesh:
    """A binary STL as an indexed mesh (identical corners merged), with numpy only."""
    data = open(path, "rb").read()
    n = int.from_bytes(data[80:84], "little") if len(data) >= 84 else -1
    if n < 0 or len(data) != 84 + 50 * n:  # ASCII or odd: let trimesh read it
        import trimesh

        m = trimesh.load(path, force="mesh")
        return Mesh(np.asarray(m.vertices, float), np.asarray(m.faces, np.int64))
    rec = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    corners = np.frombuffer(data, rec, n, 84)["v"].reshape(-1, 3)
    # np.unique(corners, axis=0, return_inverse=True), the same arrays 4x faster: unique on rows
    # sorts a structured view field by field (5 ms a part); lexsort sorts the columns as numbers
    order = np.lexsort((corners[:, 2], corners[:, 1], corners[:, 0]))
    ranked = corners[order]
    first = np.ones(len(ranked), bool)
    first[1:] = np.any(ranked[1:] != ranked[:-1], axis=1)
    inverse = np.empty(len(ranked), np.int64)
    inverse[order] = np.cumsum(first) - 1
    return Mesh(ranked[first].astype(float), inverse.reshape(-1, 3))


def _read(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def _unit_cylinder(sections: int = 16) -> Mesh:
    """Radius 1, from z = 0 to z = 1, closed, triangles wound outwards: a rod is this scaled and
    turned onto its axis."""
    a = 2 * np.pi * np.arange(sections) / sections
    ring = np.column_stack([np.cos(a), np.sin(a)])
    verts = np.vstack([np.column_stack([ring, np.zeros(sections)]), np.column_stack([ring, np.ones(sections)]),
                       [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]])
    i = np.arange(sections)
    j = (i + 1) % sections
    bottom, top = 2 * sections, 2 * sections + 1
    faces = np.vstack([np.column_stack([i, j, j + sections]), np.column_stack([i, j + sections, i + sections]),
                       np.column_stack([np.full(sections, bottom), j, i]),
                       np.column_stack([np.full(sections, top), i + sections, j + sections])])
    return Mesh(verts, faces.astype(np.int64))


def _rod_matrix(start, end, diameter: float) -> np.ndarray:
    a, b = np.asarray(start, float), np.asarray(end, float)
    axis = b - a
    length = float(np.linalg.norm(axis))
    z = axis / length
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x * diameter / 2, y * diameter / 2, z * length, a
    return m


def design_items(design, meshes: Mapping[str, "Mesh | trimesh.Trimesh"], print_from_local: Mapping[str, np.ndarray],
                 mass=None, plates: Sequence = (), provisional: Sequence[str] = ()) -> list[ViewerItem]:
    """Items for every copy of every printed part (world placement as in the renders) and every rod.

    `meshes`: part name -> mesh in print orientation; `print_from_local`: part name -> 4x4;
    `mass`: the `MassBudget` (grams each by part name); `plates`: `write_plates`' result;
    `provisional`: parts whose mesh is a stand-in (a previous shape at the new placements), drawn
    pale (their colour mixed with the background) and noted as updating."""
    from ...export.plates import material_colour, part_of
    from ..assembly_steps import copy_labels

    grams = {i.name: i.mass_g_each for i in mass.items} if mass is not None else {}
    on_plate: dict[str, list[str]] = {}
    for pf in plates:
        for copy in pf.copies:
            names = on_plate.setdefault(part_of(copy), [])
            if pf.name not in names:
                names.append(pf.name)
    items: list[ViewerItem] = []
    for p in design.parts:
        m = meshes.get(p.name)
        if m is None:
            continue
        local_from_print = np.linalg.inv(np.asarray(print_from_local.get(p.name, np.eye(4)), float))
        stand_in = p.name in provisional
        colour = _pale(material_colour(p.material)) if stand_in else material_colour(p.material)
        note = f"part {p.name}" + ("; updating: its previous shape at its new place, the exact part is being made"
                                   if stand_in else "")
        for label, pl in zip(copy_labels(p), p.placements):
            items.append(ViewerItem(label, "part", p.material, grams.get(p.name), p.qty, ", ".join(on_plate.get(p.name, [])),
                                    colour, m, pl.matrix() @ local_from_print, note=note, provisional=stand_in))
    rod_mass = {r: row.mass_g for row in design.cut.rows for r in row.rods}
    cut_len = {r: row.length_mm for row in design.cut.rows for r in row.rods}
    cyl = _unit_cylinder()
    for rod in design.frame.rods.values():
        note = f"cut to {cut_len[rod.name]:g} mm" if rod.name in cut_len else ""
        items.append(ViewerItem(rod.name, "rod", rod.material, rod_mass.get(rod.name), 1, "", ROD_COLOUR, cyl,
                                _rod_matrix(rod.start, rod.end, rod.diameter), note=note))
    return items


def _pale(colour: str, keep: float = 0.3) -> str:
    """`colour` mixed with the view's background (`keep` of the colour): a ghost of it."""
    a = [int(colour[i:i + 2], 16) for i in (1, 3, 5)]
    b = [int(BACKGROUND[i:i + 2], 16) for i in (1, 3, 5)]
    return "#" + "".join(f"{round(keep * x + (1 - keep) * y):02x}" for x, y in zip(a, b))


# -- packing ---------------------------------------------------------------------------------

def _mesh_key(mesh) -> str:
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(np.asarray(mesh.vertices, np.float64)).tobytes())
    h.update(np.ascontiguousarray(np.asarray(mesh.faces, np.int64)).tobytes())
    return h.hexdigest()


def pack(items: Iterable[ViewerItem]) -> tuple[dict, bytes]:
    """(scene metadata for the JSON block, geometry buffer). Raises ValueError on a bad item."""
    items = list(items)
    geometries: list[dict] = []
    index_of: dict[str, int] = {}
    buf = bytearray()
    objects = []
    for it in items:
        if it.kind not in KINDS:
            raise ValueError(f"{it.name}: kind {it.kind!r} is not one of {KINDS}")
        if not (isinstance(it.colour, str) and len(it.colour) == 7 and it.colour.startswith("#")):
            raise ValueError(f"{it.name}: colour {it.colour!r} is not #rrggbb")
        key = _mesh_key(it.mesh)
        if key not in index_of:
            v = np.asarray(it.mesh.vertices, np.float64)
            f = np.asarray(it.mesh.faces, np.int64)
            if len(v) == 0 or len(f) == 0:
                raise ValueError(f"{it.name}: empty mesh")
            lo, hi = v.min(axis=0), v.max(axis=0)
            step = np.where(hi > lo, (hi - lo) / 65535.0, 1.0)
            q = np.clip(np.rint((v - lo) / step), 0, 65535).astype("<u2")
            pos_off = len(buf)
            buf += q.tobytes()
            buf += b"\0" * (-len(buf) % 4)
            index_bytes = 2 if len(v) <= 65536 else 4
            idx_off = len(buf)
            buf += f.astype("<u2" if index_bytes == 2 else "<u4").tobytes()
            buf += b"\0" * (-len(buf) % 4)
            index_of[key] = len(geometries)
            geometries.append({"n_vertices": int(len(v)), "n_triangles": int(len(f)), "positions": pos_off,
                               "indices": idx_off, "index_bytes": index_bytes,
                               "min": [round(float(x), 6) for x in lo], "step": [float(f"{s:.9g}") for s in step]})
        m = np.eye(4) if it.matrix is None else np.asarray(it.matrix, float)
        objects.append({"name": it.name, "kind": it.kind, "material": it.material,
                        "mass_g": None if it.mass_g is None else round(float(it.mass_g), 4), "qty": int(it.qty),
                        "plate": it.plate, "colour": it.colour, "note": it.note, "geometry": index_of[key],
                        "matrix": [round(float(x), 6) + 0.0 for x in m.T.ravel()],  # column-major for three.js
                        **({"provisional": True} if it.provisional else {})})  # absent otherwise: the report's bytes as before
    meta = {"background": BACKGROUND, "geometries": geometries, "objects": objects}
    return meta, bytes(buf)


def _script_text(text: str, what: str) -> str:
    """Text that is safe inside a <script> element (no closing tag, no comment opener)."""
    low = text.lower()
    if "</script" in low or "<!--" in text:
        raise ValueError(f"{what} contains '</script' or '<!--' and cannot be inlined")
    return text


CSS = """
.cf-viewer{position:relative;border:1px solid #ccc;border-radius:4px;background:""" + BACKGROUND + """;margin:.8em 0}
.cf-viewer canvas{display:block;width:100%;touch-action:none;cursor:grab}
.cf-bar{position:absolute;top:.4em;left:.5em;font-size:.85em;background:rgba(255,255,255,.85);padding:.2em .5em;border-radius:3px}
.cf-bar label{margin-right:.8em} .cf-bar button{font-size:.85em}
.cf-info{position:absolute;top:.4em;right:.5em;max-width:20em;font-size:.85em;background:rgba(255,255,255,.9);padding:.3em .6em;border-radius:3px}
.cf-info dl{display:grid;grid-template-columns:auto auto;gap:0 .6em;margin:0} .cf-info dt{color:#666} .cf-info dd{margin:0;font-weight:600}
.cf-help{font-size:.8em;color:#666;margin:.2em 0 0}
"""


_LOADER = """
%(prelude)sconst text = (%(arg)s) => document.getElementById(%(element)s).textContent;
const url = (src) => URL.createObjectURL(new Blob([src], {type: "text/javascript"}));
const threeUrl = url(text(%(three)s));
const orbitUrl = url(text(%(orbit)s).replace(/from\\s*['"]three['"]/g, "from '" + threeUrl + "'"));
const viewerUrl = url(text(%(viewer)s));
const root = document.getElementById(%(root)s);
try {
  const [THREE, orbit, viewer] = await Promise.all([import(threeUrl), import(orbitUrl), import(viewerUrl)]);
  viewer.start(THREE, orbit.OrbitControls, root, JSON.parse(text(%(scene)s)), text(%(geometry)s));
} catch (e) {
  root.dataset.error = String(e);
  root.querySelector(".cf-info").textContent = "The 3D view could not start here (" + e + ")%(fallback)s.";
}
"""


def module_loader(script_id, root: str, fallback: str = "", uid: str | None = None) -> str:
    """The <script type="module"> that imports three.js, OrbitControls and viewer.js from the
    page's text scripts (as blob URLs: the page fetches nothing) and starts the view. The
    report's section and the notebook's fragment (api.view) differ only in how their elements
    are named: `script_id(name)` is the JS expression of a text script's id for a name of
    three, orbit, viewer, scene, geometry; `root` that of the viewer's element; with `uid`, the
    ids are `uid + "-" + name`."""
    names = ("three", "orbit", "viewer", "scene", "geometry")
    return _LOADER % {"prelude": "" if uid is None else f"const uid = {uid};\n",
                      "arg": "id" if uid is None else "name",
                      "element": "id" if uid is None else 'uid + "-" + name',
                      "root": root, "fallback": fallback, **{n: script_id(n) for n in names}}


def viewer_section(items: Sequence[ViewerItem], title: str = "3D view") -> str:
    """The report's 3D-view <section> (HTML), with three.js, the viewer and the geometry inline."""
    meta, buf = pack(items)
    counts = {k: sum(1 for o in meta["objects"] if o["kind"] == k) for k in KINDS}
    code = {n: _script_text(_read(n), n) for n in _VENDORED}
    data = json.dumps(meta, separators=(",", ":"), sort_keys=True).replace("</", "<\\/")
    toggles = "".join(f'<label><input type="checkbox" data-kind="{k}" checked> {k}s ({counts[k]})</label>' for k in TOGGLES)
    b64 = base64.b64encode(buf).decode("ascii")
    loader = module_loader(lambda name: json.dumps(f"cf-{'viewer-js' if name == 'viewer' else name}"),
                           '"cf-viewer"', "; the renders below show the assembly")
    return "\n".join([
        f'<section id="viewer-section"><h2>{html.escape(title)}</h2>',
        f"<style>{CSS}</style>",
        f'<div id="cf-viewer" class="cf-viewer" data-objects="{len(meta["objects"])}">',
        '<canvas id="cf-canvas" width="960" height="560" aria-label="3D view of the assembly"></canvas>',
        f'<div class="cf-bar">{toggles}<button type="button" class="cf-reset">reset view</button></div>',
        '<div class="cf-info">The 3D view needs JavaScript and WebGL.</div>',
        "</div>",
        f'<p class="cf-help">Drag to rotate, scroll to zoom, right-drag to pan; click a part for its name, material, '
        f'mass, quantity and print plate. {counts["part"]} part copies, {counts["rod"]} rods, {counts["vitamin"]} vitamins. '
        f'three.js r{THREE_VERSION.split(".")[1]} (MIT licence, three.js authors) is embedded.</p>',
        f'<script type="text/plain" id="cf-three">{code["three.module.min.js"]}</script>',
        f'<script type="text/plain" id="cf-orbit">{code["OrbitControls.js"]}</script>',
        f'<script type="text/plain" id="cf-viewer-js">{code["viewer.js"]}</script>',
        f'<script type="application/json" id="cf-scene">{data}</script>',
        f'<script type="text/plain" id="cf-geometry">{b64}</script>',
        f'<script type="module">{loader}</script>',
        "</section>",
    ])
