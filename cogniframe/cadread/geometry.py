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
    """Every cylindrical face of `solid` (a cadquery Shape) as a `Cyl`, B-spline faces that are
    cylinders within `SPLINE_TOL` included (a CAD program's mirror or export can turn a hole into a
    B-spline surface: one socket of each mirrored pair in the authors' FreeCAD document)."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_BSplineSurface, GeomAbs_BezierSurface, GeomAbs_Cylinder

    out = []
    for f in solid.Faces():
        ad = BRepAdaptor_Surface(f.wrapped, True)
        kind = ad.GetType()
        if kind == GeomAbs_Cylinder:
            c = ad.Cylinder()
            out.append(_cyl(f, ad, c.Axis(), c.Radius(), analytic=True))
        elif kind in (GeomAbs_BSplineSurface, GeomAbs_BezierSurface):
            c = _spline_cylinder(f, ad)
            if c is not None:
                out.append(_cyl(f, ad, _Ax(*c[:2]), c[2], analytic=False))
    return out


SPLINE_TOL = 5e-3  # mm from the fitted cylinder; also the normals' component along its axis


def _spline_cylinder(f, ad):
    """(origin, unit axis, radius) of the cylinder a B-spline face is (within SPLINE_TOL), or None:
    its normals on a 9 x 9 grid are all square to one direction (the axis, their least singular
    vector) and its points lie on a circle about it (a least-squares circle in the plane across it)."""
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.BRepTools import BRepTools

    u0, u1, v0, v1 = BRepTools.UVBounds_s(f.wrapped)
    pts, nrm = [], []
    for u in np.linspace(u0, u1, 9):
        for v in np.linspace(v0, v1, 9):
            pr = BRepLProp_SLProps(ad, u, v, 1, 1e-7)
            if not pr.IsNormalDefined():
                return None
            p, n = pr.Value(), pr.Normal()
            pts.append((p.X(), p.Y(), p.Z()))
            nrm.append((n.X(), n.Y(), n.Z()))
    pts, nrm = np.array(pts), np.array(nrm)
    d = np.linalg.svd(nrm)[2][-1]
    if np.abs(nrm @ d).max() > SPLINE_TOL * 10:
        return None
    x, y = _perp(d)
    q = np.column_stack([pts @ x, pts @ y])
    A = np.column_stack([2 * q, np.ones(len(q))])
    sol, *_ = np.linalg.lstsq(A, (q * q).sum(axis=1), rcond=None)
    cx, cy = sol[0], sol[1]
    r = float(np.sqrt(max(sol[2] + cx * cx + cy * cy, 0.0)))
    if r <= 0 or np.abs(np.hypot(q[:, 0] - cx, q[:, 1] - cy) - r).max() > SPLINE_TOL:
        return None
    if np.ptp(np.arctan2(q[:, 1] - cy, q[:, 0] - cx)) < 0.2:  # a sliver: not enough arc to call it a cylinder
        return None
    return cx * x + cy * y, d, r


class _Ax:
    """A gp_Ax1-like axis from numpy (what `_cyl` reads)."""

    class _P:
        def __init__(self, v):
            self.v = v

        def X(self):  # noqa: N802 - gp's names
            return float(self.v[0])

        def Y(self):  # noqa: N802
            return float(self.v[1])

        def Z(self):  # noqa: N802
            return float(self.v[2])

    def __init__(self, o, d):
        self.o, self.d = self._P(o), self._P(d)

    def Location(self):  # noqa: N802
        return self.o

    def Direction(self):  # noqa: N802
        return self.d


def _cyl(f, ad, ax, radius: float, analytic: bool) -> Cyl:
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.BRepTools import BRepTools
    from OCP.TopAbs import TopAbs_REVERSED

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
    span = float(u1 - u0)
    if not analytic:  # the extent along the axis from points of the face; the span from them too
        pts = np.array([[*(lambda q: (q.X(), q.Y(), q.Z()))(ad.Value(u, v))]
                        for u in np.linspace(u0, u1, 9) for v in np.linspace(v0, v1, 9)])
        t = (pts - o) @ d
        v0, v1 = float(t.min()), float(t.max())
        rad = pts - o - np.outer((pts - o) @ d, d)
        ang = np.unwrap(np.sort(np.arctan2(rad @ _perp(d)[1], rad @ _perp(d)[0])))
        gaps = np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi]))
        span = float(2 * np.pi - gaps.max())
    return Cyl(o, d, float(radius), float(v0), float(v1), span, bool(np.dot(nrm, radial) < 0))


def _perp(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(d, a)
    x /= np.linalg.norm(x)
    return x, np.cross(d, x)


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


MESH_TOL = 0.05  # mm


def bbox(solid) -> tuple[np.ndarray, np.ndarray]:
    """A box around the solid from a coarse mesh of it (made here if it has none; within about
    `MESH_TOL` of the solid: every use here adds a margin). cadquery's exact `BoundingBox` took 9 s
    for the authors' 54 parts, the geometry's own box (a B-spline's control points) is loose
    enough to double the contact checks."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib
    from OCP.BRepMesh import BRepMesh_IncrementalMesh

    BRepMesh_IncrementalMesh(solid.wrapped, MESH_TOL, False, 0.3, True)

    b = Bnd_Box()
    BRepBndLib.Add_s(solid.wrapped, b, True)
    x0, y0, z0, x1, y1, z1 = b.Get()
    return np.array([x0, y0, z0]), np.array([x1, y1, z1])


def mass_props(solid) -> tuple[float, tuple[float, float, float]]:
    """(volume mm^3, centroid) in one pass."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    g = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid.wrapped, g)
    c = g.CentreOfMass()
    return float(g.Mass()), (c.X(), c.Y(), c.Z())


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
        BRepBndLib.Add_s(f.wrapped, b, True)  # from the mesh `bbox` made: within MESH_TOL
        b.Enlarge(MESH_TOL)
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


@dataclass(frozen=True)
class Cone:
    """A conical face (a chamfer, a countersink): its axis and its extent [v0, v1] along it."""

    origin: np.ndarray
    direction: np.ndarray
    v0: float
    v1: float


def cones(solid) -> list[Cone]:
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepTools import BRepTools
    from OCP.GeomAbs import GeomAbs_Cone

    out = []
    for f in solid.Faces():
        ad = BRepAdaptor_Surface(f.wrapped, True)
        if ad.GetType() != GeomAbs_Cone:
            continue
        ax = ad.Cone().Axis()
        o = np.array([ax.Location().X(), ax.Location().Y(), ax.Location().Z()])
        d = np.array([ax.Direction().X(), ax.Direction().Y(), ax.Direction().Z()])
        u0, u1, v0, v1 = BRepTools.UVBounds_s(f.wrapped)
        pts = np.array([[(q := ad.Value(u, v)).X(), q.Y(), q.Z()] for u in np.linspace(u0, u1, 5) for v in (v0, v1)])
        t = (pts - o) @ d
        out.append(Cone(o, d, float(t.min()), float(t.max())))
    return out
