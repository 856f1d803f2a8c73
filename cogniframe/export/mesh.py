"""Watertight, deterministic STL from a CadQuery/OCP shape, and the mesh measurements the build
and the tests rely on (flat bed contact, overhang, point-in-solid, ray hits).

The STL recipe is the one measured in shared/reference/stack-notes.md: a plain
`cq.exporters.export(..., "x.stl")` leaves zero-area facets at fillet corners and is not
watertight. Here: drop any old triangulation (`BRepTools.Clean_s`), mesh with an ABSOLUTE linear
tolerance, collect the triangles face by face (respecting face orientation), weld with trimesh,
drop degenerate and duplicate faces, fix normals, write a binary STL, and re-read THAT file and
assert it is watertight and a positive volume. Same shape -> same bytes (no timestamps; a fixed
80-byte header).

Only numpy/scipy/trimesh here besides OCP: no rtree, no shapely, no embree.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import trimesh

from .. import numfmt

# Linear deflection (mm, absolute) and angular deflection (rad) of the tessellation. 0.02 mm /
# 0.15 rad keeps a 3.1 mm socket bore within ~0.01 mm of its diameter (the fit coupon steps by
# 0.05 mm) at a few thousand facets per joint.
LINEAR_TOL = 0.02
ANGULAR_TOL = 0.15

STL_HEADER = b"cogniframe binary STL".ljust(80, b" ")


class MeshError(RuntimeError):
    """The tessellation of a part is not a closed, positive volume (a CAD bug, not a user error)."""


def tessellate(shape, tol: float = LINEAR_TOL, angular: float = ANGULAR_TOL) -> trimesh.Trimesh:
    """Fresh triangulation of `shape` (cq.Shape/Workplane or a TopoDS_Shape) -> welded, cleaned Trimesh."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    occ = _occ(shape)
    BRepTools.Clean_s(occ)
    BRepMesh_IncrementalMesh(occ, tol, False, angular, True)
    verts: list[np.ndarray] = []
    faces: list[np.ndarray] = []
    offset = 0
    exp = TopExp_Explorer(occ, TopAbs_FACE)
    while exp.More():
        face = TopoDS.Face_s(exp.Current())
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face, loc)
        if tri is not None:
            trsf = loc.Transformation()
            n = tri.NbNodes()
            pts = np.empty((n, 3))
            for i in range(n):
                p = tri.Node(i + 1).Transformed(trsf)
                pts[i] = (p.X(), p.Y(), p.Z())
            m = tri.NbTriangles()
            idx = np.empty((m, 3), dtype=np.int64)
            for i in range(m):
                idx[i] = tri.Triangle(i + 1).Get()
            idx -= 1
            if face.Orientation() == TopAbs_REVERSED:
                idx = idx[:, ::-1]
            verts.append(pts)
            faces.append(idx + offset)
            offset += n
        exp.Next()
    if not faces:
        raise MeshError("the shape has no faces to mesh")
    # on the stated grid (numfmt.GRID_MM) BEFORE welding: the last bits of OCP's nodes move with the
    # CPU and the releases; a vertex pair the grid merges is welded here and its collapsed faces dropped
    mesh = trimesh.Trimesh(numfmt.on_grid(np.vstack(verts)), np.vstack(faces), process=True)
    return clean(mesh)


def clean(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Drop degenerate and duplicate faces and unused vertices, make winding/normals consistent."""
    mesh = mesh.copy()
    mesh.merge_vertices()
    _mend_slivers(mesh)
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.update_faces(mesh.unique_faces())
    mesh.remove_unreferenced_vertices()
    trimesh.repair.fix_normals(mesh)
    return mesh


def _mend_slivers(mesh: trimesh.Trimesh, rounds: int = 4) -> None:
    """Split, in place, each face across the long edge of a sliver: a zero-area face with three
    distinct corners, one of them (m) on the line between the other two (a, c).

    OCC's mesher leaves such a face now and then where a face's boundary has a node between two
    of its neighbour's (a T-junction), and the grid rounding above makes a near-sliver exact (the
    knee at frame.height 107.14). Dropping it alone leaves a crack: its edges a-m and m-c and the
    neighbour's a-c each have one face, and the STL is not watertight. With the neighbour (a, c, d)
    split into (a, m, d) and (m, c, d), same winding, the sliver is dropped as any degenerate face
    is, and the surface stays closed. A sliver whose long edge borders another sliver is mended in
    the next round."""
    for _ in range(rounds):
        faces = mesh.faces.copy()
        distinct = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
        slivers = np.flatnonzero(distinct & ~mesh.nondegenerate_faces())
        added = []
        for s in slivers:
            tri = faces[s]
            ends = mesh.vertices[np.roll(tri, -1)] - mesh.vertices[np.roll(tri, -2)]  # edge opposite each corner
            m = int(np.argmax(np.einsum("ij,ij->i", ends, ends)))  # the middle corner faces the longest edge
            mid, a, c = int(tri[m]), int(tri[(m + 1) % 3]), int(tri[(m + 2) % 3])
            across = np.flatnonzero((faces == a).any(axis=1) & (faces == c).any(axis=1) & ~(faces == mid).any(axis=1))
            if not len(across):
                continue
            f = faces[across[0]]
            r = next(r for r in range(3) if {int(f[r]), int(f[(r + 1) % 3])} == {a, c})
            g0, g1, g2 = int(f[r]), int(f[(r + 1) % 3]), int(f[(r + 2) % 3])
            faces[across[0]] = (g0, mid, g2)
            added.append((mid, g1, g2))
        if not added:
            return
        mesh.faces = np.vstack([faces, np.asarray(added, dtype=faces.dtype)])


def stl_bytes(mesh: trimesh.Trimesh) -> bytes:
    """Binary STL with a fixed header: identical meshes give identical bytes, and vertices and
    normals at the stated precision (numfmt.GRID_MM, numfmt.NORMAL_DIGITS), so meshes that differ
    only in last bits do too."""
    tris = numfmt.on_grid(mesh.triangles)  # at the stated precision (numfmt): mm on a 1e-4 grid
    normals = numfmt.unit_normals(mesh.face_normals)
    rec = np.zeros(len(tris), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["n"] = normals
    rec["v"] = tris
    buf = io.BytesIO()
    buf.write(STL_HEADER)
    buf.write(np.uint32(len(tris)).tobytes())
    buf.write(rec.tobytes())
    return buf.getvalue()


def load_stl(path: str | Path) -> trimesh.Trimesh:
    """Read an STL and weld it (the way a slicer sees it)."""
    return trimesh.load(str(path), file_type="stl", force="mesh", process=True)


def write_stl(shape_or_mesh, path: str | Path, tol: float = LINEAR_TOL, angular: float = ANGULAR_TOL,
              name: str = "part") -> trimesh.Trimesh:
    """Tessellate (unless given a Trimesh), write a binary STL, re-read it and assert it is closed.

    Returns the re-read mesh. Raises MeshError naming `name` if the file is not watertight or not a
    positive volume.
    """
    mesh = shape_or_mesh if isinstance(shape_or_mesh, trimesh.Trimesh) else tessellate(shape_or_mesh, tol, angular)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(stl_bytes(mesh))
    back = load_stl(path)
    if not back.is_watertight:
        raise MeshError(f"{name}: the STL written to {path} is not watertight")
    if not back.is_volume or back.volume <= 0:
        raise MeshError(f"{name}: the STL written to {path} is not a positive closed volume")
    return back


def _occ(shape):
    if hasattr(shape, "val") and callable(shape.val):  # cq.Workplane
        shape = shape.val()
    return getattr(shape, "wrapped", shape)


# -- measurements ----------------------------------------------------------------------------

def area_split(mesh: trimesh.Trimesh, threshold: float = 0.7) -> tuple[float, float]:
    """(horizontal area, vertical area) in mm^2: faces with |n_z| > threshold count as horizontal."""
    nz = np.abs(mesh.face_normals[:, 2])
    a = mesh.area_faces
    return float(a[nz > threshold].sum()), float(a[nz <= threshold].sum())


def bed_faces(mesh: trimesh.Trimesh, z_tol: float = 1e-3) -> np.ndarray:
    """Mask of faces lying on the bed: every vertex at z ~ min z, facing down."""
    z0 = mesh.bounds[0, 2]
    on = np.all(mesh.vertices[mesh.faces][:, :, 2] < z0 + z_tol, axis=1)
    return on & (mesh.face_normals[:, 2] < -0.99)


def footprint_area(mesh: trimesh.Trimesh) -> float:
    """Area of the convex hull of the part's xy projection, mm^2."""
    from scipy.spatial import ConvexHull

    return float(ConvexHull(mesh.vertices[:, :2]).volume)


def flat_contact_ratio(mesh: trimesh.Trimesh) -> float:
    """Bed contact area (faces at the lowest z facing down) / footprint area."""
    return float(mesh.area_faces[bed_faces(mesh)].sum()) / footprint_area(mesh)


def _moller_trumbore(tris: np.ndarray, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Distances t (n_rays x n_tris) along each ray to each triangle; inf where missed."""
    v0, v1, v2 = tris[:, 0], tris[:, 1], tris[:, 2]
    e1, e2 = v1 - v0, v2 - v0
    out = np.full((len(origins), len(tris)), np.inf)
    for i, (o, d) in enumerate(zip(origins, dirs)):
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = o - v0
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        v = (q @ d) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
        out[i, hit] = t[hit]
    return out


def ray_first_hit(mesh: trimesh.Trimesh, origins, dirs) -> np.ndarray:
    """Distance from each origin along its (unit) direction to the first surface; inf if none."""
    origins = np.atleast_2d(np.asarray(origins, float))
    dirs = np.atleast_2d(np.asarray(dirs, float))
    dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    return _moller_trumbore(np.asarray(mesh.triangles), origins, dirs).min(axis=1)


def contains(mesh: trimesh.Trimesh, points) -> np.ndarray:
    """Point-in-solid by ray parity (a slightly skewed ray so it never runs along an edge)."""
    points = np.atleast_2d(np.asarray(points, float))
    d = np.array([0.0123, 0.0371, 1.0])
    d /= np.linalg.norm(d)
    t = _moller_trumbore(np.asarray(mesh.triangles), points, np.tile(d, (len(points), 1)))
    return (np.isfinite(t).sum(axis=1) % 2) == 1


def overhangs(mesh: trimesh.Trimesh, max_angle_deg: float = 45.0, bridge_max: float = 6.0,
              tol: float = 0.01) -> dict:
    """Downward-facing surface steeper than `max_angle_deg` from vertical that would need support.

    A face overhangs when its normal points down and the surface is tilted more than
    `max_angle_deg` from vertical (n_z < -sin(max_angle) - tol). Faces on the bed do not count.
    Overhanging faces are grouped into connected patches; a patch is excused as a BRIDGE when it is
    at most `bridge_max` wide (narrowest xy extent) and material flanks it on both sides of that
    width (probes just outside it, a little below, are inside the solid): the ceiling of a hole or
    slot. A cantilevered lip fails the flank test and counts.

    Returns {"area": unsupported mm^2, "down_area": all downward-facing mm^2 off the bed,
    "fraction": area / down_area, "patches": [(area, width, excused), ...]}.
    """
    n = mesh.face_normals
    a = mesh.area_faces
    on_bed = bed_faces(mesh)
    down = (n[:, 2] < -1e-6) & ~on_bed
    steep = down & (n[:, 2] < -math.sin(math.radians(max_angle_deg)) - tol)
    down_area = float(a[down].sum())
    idx = np.nonzero(steep)[0]
    patches = []
    bad = 0.0
    if len(idx):
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        pos = -np.ones(len(mesh.faces), dtype=np.int64)
        pos[idx] = np.arange(len(idx))
        adj = mesh.face_adjacency
        keep = steep[adj[:, 0]] & steep[adj[:, 1]]
        e = pos[adj[keep]]
        g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(len(idx), len(idx)))
        ncomp, labels = connected_components(g, directed=False)
        angles = np.radians(np.arange(0, 180, 2.0))
        dirs2 = np.column_stack([np.cos(angles), np.sin(angles)])
        for c in range(ncomp):
            fi = idx[labels == c]
            area = float(a[fi].sum())
            pts = mesh.vertices[np.unique(mesh.faces[fi])]
            proj = pts[:, :2] @ dirs2.T
            ext = proj.max(axis=0) - proj.min(axis=0)
            k = int(np.argmin(ext))
            width = float(ext[k])
            excused = False
            centre = mesh.triangles_center[fi]
            c_xy = np.average(centre[:, :2], axis=0, weights=a[fi])
            probe_z = float(np.average(centre[:, 2], weights=a[fi])) - 0.1
            # Try the narrowest direction, then the one across it (a short hole through a thin
            # wall is narrowest along its own axis but bridges across it).
            for kk in (k, (k + len(angles) // 2) % len(angles)):
                if ext[kk] > bridge_max:
                    continue
                mid = (proj[:, kk].max() + proj[:, kk].min()) / 2
                along = c_xy - (c_xy @ dirs2[kk]) * dirs2[kk]
                probes = [np.r_[along + (mid + sg * (ext[kk] / 2 + 0.3)) * dirs2[kk], probe_z] for sg in (-1, 1)]
                if np.all(contains(mesh, probes)):
                    excused = True
                    break
            if not excused:
                bad += area
            patches.append((area, width, excused))
    return {"area": bad, "down_area": down_area, "fraction": bad / down_area if down_area > 0 else 0.0,
            "patches": patches}


def manifold_of(mesh: trimesh.Trimesh):
    """manifold3d.Manifold of a closed trimesh (for exact-ish boolean volumes)."""
    import manifold3d

    m = manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(mesh.vertices, np.float32),
                                            tri_verts=np.asarray(mesh.faces, np.uint32)))
    if m.status() != manifold3d.Error.NoError:
        raise MeshError(f"manifold3d rejects the mesh: {m.status()}")
    return m


def intersection_volume(a: trimesh.Trimesh, b: trimesh.Trimesh) -> float:
    """Volume of a ∩ b, mm^3 (manifold3d boolean)."""
    return float((manifold_of(a) ^ manifold_of(b)).volume())
