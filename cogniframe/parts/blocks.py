"""CAD helpers the rigid core families share: a drilled plate, prisms, pointed windows.

CadQuery is imported inside each function, so importing this module stays cheap.
"""

from __future__ import annotations


def plate(size_x: float, size_y: float, t: float, holes):
    import cadquery as cq

    wp = cq.Workplane("XY").box(size_x, size_y, t, centered=(True, True, False))
    for d, pts in holes:
        wp = wp.faces(">Z").workplane(origin=(0, 0, t)).pushPoints([tuple(map(float, p)) for p in pts]).hole(d)
    return wp.val()


def prism_xz(pts_yz, x0: float, x1: float):
    """A prism through a side wall: polygon in (y, z), extruded along x from x0 to x1."""
    import cadquery as cq

    wp = cq.Workplane("YZ", origin=(x0, 0, 0)).polyline([tuple(map(float, p)) for p in pts_yz]).close()
    return wp.extrude(x1 - x0).val()


def prism_xy(pts_xy, z0: float, z1: float):
    import cadquery as cq

    return cq.Workplane("XY", origin=(0, 0, z0)).polyline([tuple(map(float, p)) for p in pts_xy]).close().extrude(z1 - z0).val()


def pointed(y0: float, y1: float, half: float) -> list[tuple[float, float]]:
    """A window from y0 to y1, `half` across, with 45 deg pointed ends along y: (y, across) points."""
    return [(y0, 0.0), (y0 + half, -half), (y1 - half, -half), (y1, 0.0), (y1 - half, half), (y0 + half, half)]
