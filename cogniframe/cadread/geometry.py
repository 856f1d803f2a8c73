"""B-rep facts the finders need: the cylindrical faces of a solid (axis, radius, extent along the
axis, hole or boss), points along an axis, inside/outside tests. OCP only, mm."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Cyl:
    """A cylindrical face: a line (origin, unit dir), radius, the face's extent [v0, v1] along the
    line from `origin`, the angle it spans (rad, 2 pi for a full turn) and whether it is a hole
    (the material outside the cylinder: a concave face) or a boss / rod surface (convex)."""

    origin: np.ndarray
    direction: np.ndarray
    radius: float
    v0: float
    v1: float
    span: float
    hole: bool

    def at(self, v: float) -> np.ndarray:
        return self.origin + self.direction * v


def cylinders(solid) -> list[Cyl]:
    """Every cylindrical face of `solid` (a cadquery Shape) as a `Cyl`."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.BRepTools import BRepTools
    from OCP.GeomAbs import GeomAbs_Cylinder
    from OCP.TopAbs import TopAbs_REVERSED

    out = []
    for f in solid.Faces():
        ad = BRepAdaptor_Surface(f.wrapped, True)
        if ad.GetType() != GeomAbs_Cylinder:
            continue
        c = ad.Cylinder()
        ax = c.Axis()
        o = np.array([ax.Location().X(), ax.Location().Y(), ax.Location().Z()])
        d = np.array([ax.Direction().X(), ax.Direction().Y(), ax.Direction().Z()])
        u0, u1, v0, v1 = BRepTools.UVBounds_s(f.wrapped)
        um, vm = (u0 + u1) / 2, (v0 + v1) / 2
        props = BRepLProp_SLProps(ad, um, vm, 1, 1e-7)
        p, n = props.Value(), props.Normal()
        nrm = np.array([n.X(), n.Y(), n.Z()])
        if f.wrapped.Orientation() == TopAbs_REVERSED:
            nrm = -nrm
        pt = np.array([p.X(), p.Y(), p.Z()])
        radial = pt - o - d * np.dot(pt - o, d)
        out.append(Cyl(o, d, float(c.Radius()), float(v0), float(v1), float(u1 - u0), bool(np.dot(nrm, radial) < 0)))
    return out


def vertices(solid) -> np.ndarray:
    return np.array([v.toTuple() for v in solid.Vertices()], float).reshape(-1, 3)


def line_distance(p: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> float:
    """Distance of point `p` from the line (origin, unit direction)."""
    r = np.asarray(p, float) - origin
    return float(np.linalg.norm(r - direction * np.dot(r, direction)))


def inside(solid, point, tol: float = 1e-4) -> bool:
    """Is `point` in the solid's material (not on its boundary)?"""
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN

    c = BRepClass3d_SolidClassifier(solid.wrapped, gp_Pnt(*[float(x) for x in point]), tol)
    return c.State() == TopAbs_IN


def bbox(solid) -> tuple[np.ndarray, np.ndarray]:
    b = solid.BoundingBox()
    return np.array([b.xmin, b.ymin, b.zmin]), np.array([b.xmax, b.ymax, b.zmax])


def distance(s1, s2) -> float:
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape

    d = BRepExtrema_DistShapeShape(s1.wrapped, s2.wrapped)
    return float(d.Value()) if d.IsDone() else float("inf")


def face_boxes(solid) -> tuple[list, np.ndarray, np.ndarray]:
    """(faces, their boxes' lower corners (n, 3), upper corners (n, 3))."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    faces, lo, hi = [], [], []
    for f in solid.Faces():
        b = Bnd_Box()
        BRepBndLib.Add_s(f.wrapped, b, False)
        x0, y0, z0, x1, y1, z1 = b.Get()
        faces.append(f)
        lo.append((x0, y0, z0))
        hi.append((x1, y1, z1))
    return faces, np.array(lo, float).reshape(-1, 3), np.array(hi, float).reshape(-1, 3)


def touching(fa, fb, tol: float) -> float | None:
    """The distance (<= tol) of two solids given as `face_boxes`, or None when they are farther
    apart. Face pairs whose boxes are within tol only: a whole-solid distance of two B-spline parts
    took seconds; this stops at the first pair that touches."""
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape

    faces_b, lo_b, hi_b = fb
    for f, l, h in zip(*fa):
        near = np.all(lo_b <= h + tol, axis=1) & np.all(l <= hi_b + tol, axis=1)
        for j in np.nonzero(near)[0]:
            d = BRepExtrema_DistShapeShape(f.wrapped, faces_b[j].wrapped)
            if d.IsDone() and d.Value() <= tol:
                return float(d.Value())
    return None
