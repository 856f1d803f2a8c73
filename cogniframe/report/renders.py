"""PNG renders of the assembled frame and of each part (pyvista/VTK, off-screen).

Headless Linux renders through EGL with Mesa's software driver: the environment variable
`VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow` is set (when no display is configured) before
the first render window is created; VTK reads it at that moment, so it works even if another
module imported vtk earlier. Colours: TPU red, ABS/PLA dark grey, rods black, on white.

Inputs are plain: world-space meshes (`SceneMesh`) and rod segments (`RodSegment`). Helpers
build them from the part list (`world_meshes`: world_from_print = placement.matrix() @
inv(print_from_local)) and from the frame graph (`rod_segments`). Images have a fixed pixel
size and are written with Pillow without metadata, so the same scene gives the same bytes.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Mapping, Sequence

import numpy as np

from ..export.plates import material_colour

if TYPE_CHECKING:
    import trimesh

    from ..frame import Frame
    from ..partlist import PartSpec

ROD_COLOUR = "#111111"
BACKGROUND = "white"
SIZE = (1024, 768)
PART_SIZE = (640, 480)
VIEW_ANGLE = 30.0  # degrees, the perspective views' (VTK's default)
# Label heights in pixels: the part's name on its render, the design's name on the assembly views.
# (The sizes pyvista's `add_text(position="upper_left", font_size=9 / 10)` chose for these windows,
# so the images kept their look when `_label` replaced it.)
PART_LABEL_PX = 15
TITLE_PX = 25
LABEL_MARGIN_PX = 5
# Camera directions (from the target towards the camera) and view-up vectors. y is the front.
VIEWS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float], bool]] = {
    "iso": ((1.0, 1.0, 0.8), (0.0, 0.0, 1.0), False),
    "top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), True),
    "front": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0), True),
}


@dataclass(frozen=True, eq=False)
class SceneMesh:
    """A mesh in world coordinates (mm) and the material that colours it."""

    name: str
    material: str
    mesh: "trimesh.Trimesh"


@dataclass(frozen=True)
class RodSegment:
    name: str
    start: tuple[float, float, float]
    end: tuple[float, float, float]
    diameter: float


def rod_segments(frame: "Frame") -> list[RodSegment]:
    """The frame's rods as segments between their ends (rod.start -> rod.end)."""
    return [RodSegment(r.name, tuple(float(v) for v in r.start), tuple(float(v) for v in r.end), r.diameter)
            for r in frame.rods.values()]


def world_meshes(parts: Sequence["PartSpec"], meshes: Mapping[str, "trimesh.Trimesh"],
                 print_from_local: Mapping[str, np.ndarray] | None = None) -> list[SceneMesh]:
    """Every copy of every part in world space.

    `meshes`: part name -> mesh in print orientation; `print_from_local`: part name -> 4x4
    (identity when missing, i.e. the mesh is in the part's local frame). Parts without a mesh
    are skipped."""
    out = []
    from .assembly_steps import copy_labels

    for p in parts:
        m = meshes.get(p.name)
        if m is None:
            continue
        pfl = np.eye(4) if print_from_local is None or p.name not in print_from_local else np.asarray(print_from_local[p.name])
        local_from_print = np.linalg.inv(pfl)
        for label, pl in zip(copy_labels(p), p.placements):
            w = m.copy()
            w.apply_transform(pl.matrix() @ local_from_print)
            out.append(SceneMesh(label, p.material, w))
    return out


def _pyvista():
    """pyvista with `pyvista.plotting` fully imported. pyvista resolves `Plotter`, `Text` and the
    like from that module on first use, and takes a half-imported one as missing: an import
    statement is what waits for an import under way elsewhere to finish."""
    import pyvista
    import pyvista.plotting  # noqa: F401

    return pyvista


def ensure_headless() -> None:
    """VTK renders off-screen through EGL when there is no display (set before the first render window)."""
    if (sys.platform.startswith("linux") and "VTK_DEFAULT_OPENGL_WINDOW" not in os.environ
            and not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY")):
        os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"


def _plotter(size: tuple[int, int], antialiasing: str = "ssaa"):
    ensure_headless()
    pv = _pyvista()

    pv.OFF_SCREEN = True
    p = pv.Plotter(off_screen=True, window_size=list(size), lighting="light_kit")
    p.set_background(BACKGROUND)
    # FXAA is not supported with EGL. SSAA renders 4x the pixels and downsamples; 8x MSAA smooths
    # the edges alike (the faces are flat-shaded) and costs less for a part's 640 x 480 image, more
    # for the assembly's 1024 x 768 (llvmpipe, CPU seconds: 11 part renders 1.2-1.5 SSAA, 0.8 MSAA;
    # the assembly views 0.9 SSAA, 1.05 MSAA)
    if antialiasing == "msaa":
        p.enable_anti_aliasing("msaa", multi_samples=8)
    else:
        p.enable_anti_aliasing("ssaa")
    return p


def _label(p, text: str, height_px: int):
    """`text` in black in the upper-left corner, `height_px` high: a plain text actor at a pixel
    position. (pyvista's `add_text(position="upper_left")` makes a vtkCornerAnnotation, which
    fits its font to the window again at every render: 23 ms of each part render's ~85 ms of CPU
    on llvmpipe; this draws the same pixels.)"""
    pv = _pyvista()

    actor = pv.Text(text, position=(LABEL_MARGIN_PX - 1, p.window_size[1] - LABEL_MARGIN_PX - 1))
    actor.prop.color = "black"
    actor.prop.font_size = height_px
    actor.prop.justification_vertical = "top"
    p.add_actor(actor, reset_camera=False, pickable=False, render=False)
    return actor


def _pv(mesh: "trimesh.Trimesh"):
    pv = _pyvista()

    faces = np.hstack([np.full((len(mesh.faces), 1), 3), np.asarray(mesh.faces)]).ravel()
    return pv.PolyData(np.asarray(mesh.vertices, dtype=float), faces)


def _rods_polydata(rods: Sequence[RodSegment]):
    pv = _pyvista()

    tubes = []
    for r in rods:
        line = pv.Line(r.start, r.end)
        tubes.append(line.tube(radius=r.diameter / 2, n_sides=16, capping=True))
    return pv.merge(tubes) if tubes else None


def _set_view(p, view: str, bounds: np.ndarray, zoom: float = 1.0) -> None:
    direction, up, parallel = VIEWS[view]
    lo, hi = bounds
    centre = (lo + hi) / 2
    d = np.asarray(direction, float)
    d /= np.linalg.norm(d)
    dist = 3.0 * float(np.linalg.norm(hi - lo))
    p.camera.parallel_projection = parallel
    # the camera's own setters: Plotter.camera_position would render the scene once more (0.13 s)
    p.camera.position = tuple(centre + d * dist)
    p.camera.focal_point = tuple(centre)
    p.camera.up = tuple(up)
    p.camera.view_angle = VIEW_ANGLE  # VTK's default; zoom() below narrows it, and a plotter may be reused
    p.renderer.reset_camera(render=False, bounds=(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))  # Plotter.reset_camera renders anyway
    if zoom != 1.0 and not parallel:
        p.camera.zoom(zoom)
    if parallel:  # fit the projected box (reset_camera fits the bounding sphere, which wastes space)
        u = np.asarray(up, float)
        right = np.cross(d, u) if np.linalg.norm(np.cross(d, u)) else np.array([1.0, 0.0, 0.0])
        ext = hi - lo
        w, h = float(np.abs(right) @ ext), float(np.abs(u) @ ext)
        width_px, height_px = p.window_size
        p.camera.parallel_scale = 0.55 * max(h, w * height_px / width_px)
    # screenshot() does not render again: render explicitly so the image shows this view.
    p.render()


def _save(img: np.ndarray, path: Path) -> Path:
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.ascontiguousarray(img[:, :, :3])).save(path, format="PNG", optimize=False, compress_level=6)
    return path


def _group_by_material(meshes: Iterable[SceneMesh]) -> dict[str, list["trimesh.Trimesh"]]:
    out: dict[str, list] = {}
    for m in meshes:
        out.setdefault(m.material, []).append(m.mesh)
    return dict(sorted(out.items()))


@dataclass(frozen=True, eq=False)
class VitaminMesh:
    """A bought part in world coordinates, its colour (r, g, b in 0-1) and opacity."""

    name: str
    colour: tuple[float, float, float]
    mesh: "trimesh.Trimesh"
    opacity: float = 1.0


def vitamin_meshes(spec, frame, vits=None) -> list[VitaminMesh]:
    """The aircraft's vitamins (cogniframe.vitamins) as meshes; propeller discs see-through.
    `vits`: the design's `vitamins.vitamins(...)` when the caller has them, else made here."""
    from ..vitamins import to_trimesh, vitamins

    vits = vitamins(spec, frame) if vits is None else vits
    return [VitaminMesh(v.name, v.colour, to_trimesh(v), 0.35 if v.disc else 1.0) for v in vits]


def vitamin_viewer_items(spec, frame, mass=None, vits=None) -> list:
    """The vitamins as items of the report's 3D view (kind "vitamin"): their mesh in world
    coordinates (manifold3d, no mesh library), colour, what to buy and which budget line holds
    their mass (the grams themselves only when `mass` is given). `vits`: the design's
    `vitamins.vitamins(...)` when the caller has them, else made here."""
    from ..vitamins import mesh_arrays, vitamins
    from .viewer import Mesh, ViewerItem

    def mesh_of(v):
        verts, faces = mesh_arrays(v)
        return Mesh(verts, faces)

    grams = {i.name: i.mass_g_each for i in mass.items} if mass is not None else {}
    vits = vitamins(spec, frame) if vits is None else vits
    count: dict[str, int] = {}
    for v in vits:
        count[v.bom] = count.get(v.bom, 0) + 1
    return [ViewerItem(v.name, "vitamin", "", grams.get(v.budget_line), count[v.bom], "",
                       "#" + "".join(f"{int(round(c * 255)):02x}" for c in v.colour), mesh_of(v), None,
                       note=f"{v.bom}; its mass is the budget line '{v.budget_line}'") for v in vits]


def render_assembly(meshes: Sequence[SceneMesh], rods: Sequence[RodSegment], out_dir: Path | str,
                    size: tuple[int, int] = SIZE, views: Sequence[str] = ("iso", "top", "front"),
                    prefix: str = "assembly", title: str | None = None,
                    vitamins: Sequence[VitaminMesh] = ()) -> dict[str, Path]:
    """Render the assembled frame from each view into `<out_dir>/<prefix>_<view>.png`.

    Returns {view: path}. Printed parts coloured by material, rods black, vitamins in their own
    colours (propeller discs translucent)."""
    import trimesh

    out_dir = Path(out_dir)
    if not meshes and not rods:
        raise ValueError("nothing to render: no meshes and no rods")
    p = _plotter(size)
    pts = []
    for material, group in _group_by_material(meshes).items():
        merged = trimesh.util.concatenate(group)
        p.add_mesh(_pv(merged), color=material_colour(material), smooth_shading=False)
        pts.append(merged.bounds)
    for v in vitamins:
        p.add_mesh(_pv(v.mesh), color=tuple(float(c) for c in v.colour), opacity=v.opacity, smooth_shading=False)
        pts.append(v.mesh.bounds)
    tube = _rods_polydata(rods)
    if tube is not None:
        p.add_mesh(tube, color=ROD_COLOUR, smooth_shading=True)
        b = np.asarray(tube.bounds).reshape(3, 2).T
        pts.append(b)
    allb = np.vstack(pts)
    bounds = np.array([allb.min(axis=0), allb.max(axis=0)])
    if title:
        _label(p, title, TITLE_PX)
    written = {}
    try:
        for v in views:
            _set_view(p, v, bounds)
            img = p.screenshot(return_img=True)
            written[v] = _save(img, out_dir / f"{prefix}_{v}.png")
    finally:
        p.close()
    return written


def part_plotter(size: tuple[int, int] = PART_SIZE):
    """An off-screen plotter for `render_parts(..., plotter=)`, to draw many parts' renders in one
    window (the caller closes it): a new window costs a render context and a first render
    (~0.1 s CPU each, half of a part's render), and the images are the same bytes either way."""
    return _plotter(size, "msaa")


def render_parts(parts: Mapping[str, tuple[str, "trimesh.Trimesh"]], out_dir: Path | str,
                 size: tuple[int, int] = PART_SIZE, plotter=None) -> dict[str, Path]:
    """One isometric PNG per part: {name: (material, mesh)} -> {name: <out_dir>/<name>.png}.

    `plotter`: a `part_plotter(size)` to draw in and leave open (what it drew before does not show:
    the images are the bytes a new plotter gives); None: a new one, closed at the end."""
    out_dir = Path(out_dir)
    written: dict[str, Path] = {}
    if not parts:
        return written
    p = part_plotter(size) if plotter is None else plotter
    if tuple(p.window_size) != tuple(size):
        raise ValueError(f"plotter is {tuple(p.window_size)} px, not {tuple(size)}")
    try:
        for name in sorted(parts):
            material, mesh = parts[name]
            p.suppress_rendering = True  # one render per image (in _set_view), not one per change
            try:
                p.clear_actors()
                p.add_mesh(_pv(mesh), color=material_colour(material), smooth_shading=False)
                _label(p, f"{name} ({material})", PART_LABEL_PX)
            finally:
                p.suppress_rendering = False
            _set_view(p, "iso", np.asarray(mesh.bounds), zoom=1.35)  # one part: its bounding sphere is loose
            written[name] = _save(p.screenshot(return_img=True), out_dir / f"{name}.png")
    finally:
        if plotter is None:
            p.close()
    return written


def image_stats(path: Path | str, background: tuple[int, int, int] = (255, 255, 255)) -> dict[str, float]:
    """Pixel statistics of a render: size, fraction of non-background pixels, fraction of
    TPU-red pixels, standard deviation. Used by the tests and handy for sanity checks."""
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGB")).astype(int)
    bg = np.all(np.abs(img - np.asarray(background)) <= 8, axis=2)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    red = (r > 90) & (r > 1.8 * g) & (r > 1.8 * b)
    dark = (r < 60) & (g < 60) & (b < 60)
    return {"width": img.shape[1], "height": img.shape[0], "foreground": float(1 - bg.mean()),
            "red": float(red.mean()), "dark": float(dark.mean()), "std": float(img.std())}
