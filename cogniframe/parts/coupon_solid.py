"""Socket-fit coupon: a small flat TPU print with a row of vertical test sockets.

Each socket is a boss of the joints' wall around a blind hole of diameter rod diameter +
clearance, rod pushed in from the top (vertical holes print roundest), with the joints' socket
depth, bottom wall and mouth chamfer. The clearances step from -0.40 to +0.30 mm in 0.05 mm
(15 sockets): the authors press 3 mm rods into blind sockets of 2.69-2.70 mm (-0.30, a deliberate
interference in TPU: the reference fit) and slide them through sleeves of 3.19-3.20 mm (+0.20),
measured across each socket's axis on thecognifly/CogniFly-STL `CogniFly_v8_Crash_Tests`
(docs/authors-parts.md), the presets' fits; the coupon runs 0.10 mm past both.
Each socket is labelled with its clearance engraved in the base plate in front of it (DejaVu Sans
Bold when installed, else OpenCASCADE's fallback font).
The sockets run in as few rows as the bed's width allows, tightest first.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..spec import Spec
from .joint_solid import CHAMFER, Built
from .joint_plan import transform

CLEARANCES = tuple(round(-0.40 + 0.05 * i, 2) for i in range(15))
BASE = 2.0  # base plate thickness, mm
ENGRAVE = 0.6  # label depth, mm
FONT_SIZE = 3.0
FONTS = ("/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf", "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf")


def label(c: float) -> str:
    """'-.10', '0', '+.05' ...: short enough to sit under a socket."""
    if abs(c) < 1e-9:
        return "0"
    return f"{c:+.2f}".replace("0.", ".")


def font_path() -> str | None:
    return next((f for f in FONTS if Path(f).is_file()), None)


def layout(spec: Spec, clearances=CLEARANCES) -> dict:
    """Pure geometry of the coupon: socket centres, bores, the boss size, the plate outline (mm)."""
    d, wall, depth = spec.rods.diameter, spec.joints.wall, spec.joints.socket_depth
    bores = [round(d + c, 4) for c in clearances]
    od = max(bores) + 2 * wall
    pitch = max(od + 2.0, 9.0)
    per_row = max(1, min(len(bores), int(spec.printer.bed[0] // pitch)))
    margin = 2.0
    label_h = FONT_SIZE + 2.0
    row_pitch = od + label_h + margin / 2
    xs = [(i % per_row) * pitch for i in range(len(bores))]
    ys = [-(i // per_row) * row_pitch for i in range(len(bores))]
    return {"bores": bores, "od": od, "pitch": pitch, "xs": xs, "ys": ys, "height": depth + wall,
            "x0": -pitch / 2, "x1": max(xs) + pitch / 2, "y0": min(ys) - od / 2 - label_h, "y1": od / 2 + margin / 2,
            "label_dy": -od / 2 - label_h / 2, "depth": depth, "wall": wall}


def solid(spec: Spec, clearances=CLEARANCES) -> Built:
    import cadquery as cq

    g = layout(spec, clearances)
    body = cq.Workplane("XY").box(g["x1"] - g["x0"], g["y1"] - g["y0"], BASE, centered=False).translate((g["x0"], g["y0"], 0)).val()
    bosses = [cq.Solid.makeCylinder(g["od"] / 2, g["height"], cq.Vector(x, y, 0)) for x, y in zip(g["xs"], g["ys"])]
    body = body.fuse(*bosses).clean()
    cutters = []
    for x, y, bore in zip(g["xs"], g["ys"], g["bores"]):
        rb = bore / 2
        cutters.append(cq.Solid.makeCylinder(rb, g["depth"] + 2.0, cq.Vector(x, y, g["wall"])))
        cutters.append(cq.Solid.makeCone(rb, rb + CHAMFER + 2.0, CHAMFER + 2.0, cq.Vector(x, y, g["height"] - CHAMFER)))
    fp = font_path()
    for x, y, c in zip(g["xs"], g["ys"], clearances):
        wp = cq.Workplane("XY", origin=(x, y + g["label_dy"], BASE))
        txt = wp.text(label(c), FONT_SIZE, -ENGRAVE, combine=False, kind="bold", halign="center", valign="center",
                      **({"fontPath": fp} if fp else {}))
        cutters.extend(txt.vals())
    first, *rest = cutters
    shape = body.cut(first.fuse(*rest)).clean()
    solids = shape.Solids()
    if len(solids) != 1:
        raise RuntimeError(f"coupon geometry produced {len(solids)} solids")
    return Built(solids[0], transform(np.eye(3), (0, 0, 0)))
