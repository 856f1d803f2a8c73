"""The assembly guide as pictures (NopSCADlib's assembly views are the model): for each step of
`assembly_steps`, the sub-assembly so far with the step's new parts in one highlight colour and,
where they go in along an axis, an exploded view with them drawn back along it.

Two halves. `step_views(design, steps)` is pure numpy: what each picture shows, which of it is new
(the step's part copies and rods, and the screws, nuts, standoffs and bought parts of the stages it
fits, `Step.stages`) and how far each new thing is drawn back in the exploded view. The tests read
these render inputs. `render_step_views` draws them with the report's renderer (`renders.py`:
pyvista off-screen through EGL, one plotter for every picture, the same scene gives the same
bytes).

The exploded view moves what goes in along a line: a screw back out of its hole along its axis, a
nut off its tip, a motor and a propeller up off their seat, the battery out of the holder's open
front end; a step's stacked parts (the core's holder, spacer, plate and links, the FC/ESC stack's
boards and spacers, the computer) apart along z, one `GAP` per level, bottom level in place, each
screw moving with the level its head bears on. Rods and the cage's joints are pushed together along
several lines at once: their steps have no exploded view.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Mapping, Protocol, Sequence

import numpy as np

if TYPE_CHECKING:
    from ..design import Derived
    from .assembly_steps import Step

# The new parts' colour: an orange no part, rod or bought part is drawn in (TPU red, ABS grey, the
# battery's yellow lie either side of it; image_stats' `highlight` counts it).
HIGHLIGHT = (1.0, 0.45, 0.0)
SIZE = (480, 360)  # modest: ten pictures cost about one assembly render
GAP = 10.0  # mm between levels of an exploded view
LIFT = 15.0  # mm a motor or propeller is drawn above its seat
VIEW = "iso"
# A step's picture zooms in on its new parts when they are small beside what is shown (a camera on
# the core): fit to their box grown by this factor rather than to the whole frame.
ZOOM_BELOW = 0.4
ZOOM_PAD = 1.6
# Bought parts that slide along one line, the rest of a step's stack moves in levels along z.
_LIFTED = ("motor", "propeller")
_FASTENED = ("screw", "nut")


@dataclass(frozen=True)
class StepView:
    """What step `number`'s pictures show (item names: part copies, rods, bought parts), which of it
    is new and highlighted, and the exploded view's offsets (name, (dx, dy, dz) mm); no offsets: no
    exploded view."""

    number: int
    title: str
    shown: tuple[str, ...]
    new: tuple[str, ...]
    explode: tuple[tuple[str, tuple[float, float, float]], ...] = ()

    def files(self) -> tuple[str, ...]:
        """The pictures' paths in the build folder."""
        base = f"renders/steps/step_{self.number:02d}"
        return (f"{base}.png",) + ((f"{base}_exploded.png",) if self.explode else ())


def fitted_in(design: "Derived", steps: Sequence["Step"]) -> dict[str, int]:
    """Every item of the assembly (part copy, rod, screw, nut, standoff, bought part) and the step
    it is fitted in: a part or rod in the step that names it, a bought part in the step that fits
    its stage."""
    from ..fasteners import VITAMIN_STAGES
    from ..vitamins import vitamins

    out: dict[str, int] = {}
    by_stage = {st: s.number for s in steps for st in s.stages}
    for s in steps:
        out.update({n: s.number for n in s.parts})
        out.update({n: s.number for n, _ in s.rods})
    for v in vitamins(design.spec, design.frame, design.parts):
        out[v.name] = by_stage[v.stage or VITAMIN_STAGES.get(v.family, "frame")]
    return out


def step_views(design: "Derived", steps: Sequence["Step"]) -> tuple[StepView, ...]:
    """One view per step (module docstring)."""
    fitted = fitted_in(design, steps)
    apart = {s.number for s in steps if s.apart}
    placed = {n: s.number for s in steps for n in s.places}  # an apart step -> the step that puts it in place
    z, kinds, geometry = _whereabouts(design)
    out = []
    for s in steps:
        own = {n for n, k in fitted.items() if k == s.number}
        new = own | {n for n, k in fitted.items() if k in s.places}
        if s.apart:
            shown = own
        else:
            shown = {n for n, k in fitted.items() if k <= s.number and (k not in apart or placed.get(k, 0) <= s.number)}
        explode = _explode(sorted(own), z, kinds, geometry, design)
        out.append(StepView(s.number, s.title, tuple(sorted(shown)), tuple(sorted(new)), explode))
    return tuple(out)


def _whereabouts(design: "Derived"):
    """Each item's height (a part copy's placement, a bought part's box centre), its kind (a part's
    family, 'rod', a bought part's family) and, for screws and nuts, (axis, length, base)."""
    from ..fasteners import fasteners
    from ..vitamins import vitamins
    from .assembly_steps import copy_labels

    z: dict[str, float] = {}
    kinds: dict[str, str] = {}
    for p in design.parts:
        for label, pl in zip(copy_labels(p), p.placements):
            z[label], kinds[label] = float(pl.origin[2]), p.family
    for r in design.frame.rods.values():
        kinds[r.name] = "rod"
    for v in vitamins(design.spec, design.frame, design.parts):
        lo, hi = v.bounds
        z[v.name], kinds[v.name] = float(lo[2] + hi[2]) / 2, v.family
    geometry = {f.name: (np.asarray(f.axis, float), float(f.length), np.asarray(f.base, float))
                for f in fasteners(design.spec, design.frame, design.parts)}
    return z, kinds, geometry


def _explode(names: Sequence[str], z: Mapping[str, float], kinds: Mapping[str, str], geometry, design: "Derived"):
    """The exploded view's offsets of a step's own items (module docstring), rounded to 1e-6 mm."""
    offsets: dict[str, np.ndarray] = {}
    stacked = [n for n in names if kinds[n] not in ("rod", "joint", "motor_mount", "battery", *_LIFTED, *_FASTENED)]
    levels = sorted({round(z[n]) for n in stacked})
    lift = {lv: GAP * i for i, lv in enumerate(levels)}
    for n in stacked:
        offsets[n] = np.array([0.0, 0.0, lift[round(z[n])]])

    def level_of(height: float) -> float:  # the lift of the stacked level nearest a height
        return lift[min(levels, key=lambda lv: (abs(lv - height), lv))] if levels else 0.0

    for n in names:
        kind = kinds[n]
        if kind in _LIFTED:
            offsets[n] = np.array([0.0, 0.0, LIFT])
        elif kind == "battery":
            core = design.frame.core
            offsets[n] = np.array([0.0, float(core.holder.hi[1] - core.battery.lo[1]) + GAP, 0.0])
        elif kind in _FASTENED and n in geometry:
            axis, length, base = geometry[n]
            back = -axis * (length + GAP) if kind == "screw" else axis * GAP  # a screw out of its hole, a nut off its tip
            offsets[n] = back + np.array([0.0, 0.0, level_of(float(base[2]))])
    return tuple((n, tuple(round(float(v), 6) + 0.0 for v in offsets[n])) for n in sorted(offsets)
                 if np.any(np.abs(offsets[n]) > 1e-9))


# -- drawing ------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Item:
    """A thing in the pictures: its mesh in world coordinates (mm), colour (0-1) and opacity."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    colour: tuple[float, float, float]
    opacity: float = 1.0


def scene_items(design: "Derived", meshes: Mapping[str, object], print_from_local: Mapping[str, np.ndarray]) -> list[Item]:
    """Every part copy (its print mesh moved by world <- print), rod and bought part, as `Item`s."""
    from ..export.assembly import cylinder_arrays, world_from_print
    from ..export.plates import material_colour
    from ..vitamins import mesh_arrays, vitamins
    from .assembly_steps import copy_labels
    from .renders import ROD_COLOUR

    def rgb(hex_colour: str) -> tuple[float, float, float]:
        return tuple(int(hex_colour[i:i + 2], 16) / 255 for i in (1, 3, 5))

    out = []
    for p in design.parts:
        m = meshes[p.name]
        v, f = np.asarray(m.vertices, float), np.asarray(m.faces)
        for label, pl in zip(copy_labels(p), p.placements):
            w = world_from_print(pl.matrix(), np.asarray(print_from_local[p.name], float))
            out.append(Item(label, v @ w[:3, :3].T + w[:3, 3], f, rgb(material_colour(p.material))))
    for r in design.frame.rods.values():
        v, f = cylinder_arrays(r.start, r.end, r.diameter / 2, sections=16)
        out.append(Item(r.name, v, f, rgb(ROD_COLOUR)))
    for vit in vitamins(design.spec, design.frame, design.parts):
        v, f = mesh_arrays(vit)
        out.append(Item(vit.name, np.asarray(v, float), np.asarray(f), tuple(float(c) for c in vit.colour),
                        0.35 if vit.disc else 1.0))
    return out


def render_step_views(views: Sequence[StepView], items: Sequence[Item], out_dir: Path | str,
                      size: tuple[int, int] = SIZE, known: "PictureStore | None" = None) -> dict[int, tuple[Path, ...]]:
    """Each view's pictures into `out_dir` (StepView.files, relative to it): {step: (paths)}.
    One plotter, every item added once; each picture sets what shows, its colour and offset.

    `known`: pictures drawn before, by `picture_key` (`get(key)` -> PNG bytes or None,
    `put(key, bytes)`); a picture found there is written as it is, not drawn again: a one-part
    edit draws only the pictures that show that part. An item a picture hides draws no pixel in
    it (VTK renders, bounds and clips by the visible props only), so the key reads the items
    shown, not every item of the scene: the same picture drawn beside other pictures or alone is
    the same bytes (tested)."""
    from . import renders

    out_dir = Path(out_dir)
    by_name = {i.name: i for i in items}
    wanted = sorted({n for v in views for n in v.shown})
    lo_hi = {n: (by_name[n].vertices.min(axis=0), by_name[n].vertices.max(axis=0)) for n in wanted}
    digests: dict[str, str] = {}
    pictures = []  # (view, exploded, offsets, label, path, key)
    for view in views:
        for exploded in ((False, True) if view.explode else (False,)):
            offsets = dict(view.explode) if exploded else {}
            label = f"{view.number}. {view.title}" + (" (exploded)" if exploded else "")
            key = None if known is None else picture_key(view, offsets, label, size, by_name, digests)
            pictures.append((view, exploded, offsets, label, out_dir / view.files()[int(exploded)], key))
    written: dict[int, tuple[Path, ...]] = {}
    todo = []
    for view, exploded, offsets, label, path, key in pictures:
        png = known.get(key) if known is not None else None
        if png is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(png)
        else:
            todo.append((view, offsets, label, path, key))
        written[view.number] = written.get(view.number, ()) + (path,)
    if not todo:
        return written
    p = renders._plotter(size)  # SSAA: 85 ms a picture here against MSAA's 125 (llvmpipe, 480 x 360)
    actors = {}
    try:
        p.suppress_rendering = True
        for n in wanted:
            it = by_name[n]
            actors[n] = p.add_mesh(renders._pv(it), color=it.colour, opacity=it.opacity,
                                   smooth_shading=False, reset_camera=False, render=False)
        label_actor = None
        for view, offsets, label, path, key in todo:
            new = set(view.new)
            shown = set(view.shown)
            p.suppress_rendering = True
            for n, a in actors.items():
                a.visibility = n in shown
                a.prop.color = HIGHLIGHT if n in new else by_name[n].colour
                a.position = offsets.get(n, (0.0, 0.0, 0.0))
            if label_actor is not None:
                p.remove_actor(label_actor, render=False)
            label_actor = renders._label(p, label, renders.PART_LABEL_PX)
            p.suppress_rendering = False
            renders._set_view(p, VIEW, _bounds(view, lo_hi, offsets))
            renders._save(p.screenshot(return_img=True), path)
            if known is not None:
                known.put(key, path.read_bytes())
    finally:
        p.close()
    return written


class PictureStore(Protocol):
    """Where `render_step_views` finds the pictures drawn before (the build's: `cache.BytesMemo`)."""

    def get(self, key: str) -> bytes | None: ...

    def put(self, key: str, data: bytes) -> None: ...


def picture_key(view: StepView, offsets: Mapping, label: str, size: tuple[int, int], by_name: Mapping[str, Item],
                digests: dict[str, str]) -> str:
    """What one picture shows, as a key: its size, label, camera's view, and each item shown with
    its mesh (sha256 of its vertices and faces, in `digests` once per item), colour (the
    highlight for a new one), opacity and offset. What draws it (the code and the renderer's
    versions) is the store's salt."""
    import hashlib
    import json

    def digest(n: str) -> str:
        if n not in digests:
            it = by_name[n]
            h = hashlib.sha256(np.ascontiguousarray(it.vertices, dtype=np.float64).tobytes())
            h.update(np.ascontiguousarray(it.faces, dtype=np.int64).tobytes())
            digests[n] = h.hexdigest()
        return digests[n]

    new = set(view.new)
    shown = [[n, digest(n), list(HIGHLIGHT if n in new else by_name[n].colour), by_name[n].opacity,
              list(offsets.get(n, (0.0, 0.0, 0.0)))] for n in sorted(view.shown)]
    payload = json.dumps([list(size), label, VIEW, list(view.new), shown], sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()


def _bounds(view: StepView, lo_hi, offsets) -> np.ndarray:
    """What the camera fits: everything shown, or the new parts' box grown by ZOOM_PAD when they are
    small beside it (their offsets included)."""
    def box(names):
        pts = np.vstack([np.vstack(lo_hi[n]) + np.asarray(offsets.get(n, (0.0, 0.0, 0.0))) for n in names])
        return np.array([pts.min(axis=0), pts.max(axis=0)])

    whole = box(view.shown)
    if not view.new:
        return whole
    new = box(view.new)
    if np.linalg.norm(new[1] - new[0]) < ZOOM_BELOW * np.linalg.norm(whole[1] - whole[0]):
        centre, half = new.mean(axis=0), (new[1] - new[0]) / 2 * ZOOM_PAD
        return np.array([centre - half, centre + half])
    return whole


def highlight_fraction(path: Path | str) -> float:
    """The share of a picture's pixels in the highlight's orange (lit or shaded: hue between the
    TPU's red and the battery's yellow, saturated)."""
    from PIL import Image

    img = np.asarray(Image.open(path).convert("HSV")).astype(int)
    h, s, v = img[..., 0], img[..., 1], img[..., 2]
    return float(((h >= 14) & (h <= 26) & (s > 180) & (v > 60)).mean())
