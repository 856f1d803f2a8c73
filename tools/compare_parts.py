#!/usr/bin/env python3
"""Measure printed parts side by side: a folder of the authors' STL files against a cogniframe build.

    python tools/compare_parts.py AUTHORS_DIR BUILD_DIR

AUTHORS_DIR holds the authors' published parts (thecognifly/CogniFly-STL,
`CogniFly_v8_Crash_Tests/*.stl`: fetch them yourself, cogniframe does not ship them); BUILD_DIR is
`out/<name>` of `cogniframe build`. For every STL the script prints its solid volume, the mass at
100 % of the material's density (TPU for parts whose name starts with `Flex_` or lives under
`stl/tpu_95a/`, else ABS), its bounding box and its round holes, then a table of every hole.

Each hole is measured across its own axis. Sections along the part's x, y and z axes read a
socket that runs at a slant as an ellipse: a 2.69 mm socket tilted 25 deg reads 2.83 (the circle of
the ellipse's area: 2.69 / sqrt(cos 25 deg)), and the authors' sockets run at slants. So the script
first finds each hole's wall in the mesh (a ring of concave faces whose normals all lie
perpendicular to one direction, its axis), then cuts the part perpendicular to that axis half-way
along the wall and reads there the bore (the diameter of the circle of the loop's area) and the
wall (the least distance from the bore to the part's outside or another hole); the depth is the
round wall's length along the axis. `holes` documents each figure.

docs/authors-parts.md is this script's output with the reasons for each difference.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

DENSITY = {"tpu_95a": 1.22, "abs": 1.10}  # g/cm^3, cogniframe/materials.py


def _manifold(mesh):
    import manifold3d as m3

    return m3.Manifold(m3.Mesh(vert_properties=np.asarray(mesh.vertices, np.float32),
                               tri_verts=np.asarray(mesh.faces, np.uint32)))


def _section(solid, centre, axis) -> list[np.ndarray]:
    """The solid's section by the plane through `centre` perpendicular to `axis`: its loops in that
    plane's coordinates, the origin at `centre` (outer boundaries anticlockwise, holes clockwise)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    u = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
    u /= np.linalg.norm(u)
    rot = np.array([u, np.cross(a, u), a])  # rows u, v, a: determinant +1 (a reflection turns the mesh inside out)
    return [np.asarray(p, float) for p in solid.transform(np.c_[rot, -rot @ np.asarray(centre, float)]).slice(0.0).to_polygons()]


def _area(p: np.ndarray) -> float:
    return 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def _winding(p: np.ndarray, q=(0.0, 0.0)) -> int:
    """How many times the closed loop `p` winds anticlockwise round the point `q`."""
    d = p - np.asarray(q)
    ang = np.arctan2(d[:, 1], d[:, 0])
    return int(round(float(np.sum((np.roll(ang, -1) - ang + np.pi) % (2 * np.pi) - np.pi)) / (2 * np.pi)))


def _gap(a: np.ndarray, b: np.ndarray) -> float:
    """The smallest distance between two closed polylines (every vertex of each to every edge of the other)."""

    def one_way(pts, loop):
        s0, s1 = loop, np.roll(loop, -1, axis=0)
        e = s1 - s0
        t = np.clip(np.einsum("pij,ij->pi", pts[:, None, :] - s0[None], e) / np.maximum((e * e).sum(1), 1e-30), 0, 1)
        return float(np.min(np.linalg.norm(pts[:, None, :] - (s0[None] + t[..., None] * e[None]), axis=2)))

    return min(one_way(a, b), one_way(b, a))


def _cylinders(mesh, max_bend_deg: float = 30.0, min_faces: int = 8):
    """Each concave, closed round surface of the mesh: (axis, a point on it, radius, its faces).

    The wall of a round hole is a ring of faces joined by concave (or coplanar) edges that bend
    little; each such connected patch is a candidate. Every normal of a cylinder's wall is
    perpendicular to its axis, so the axis is the least-eigenvalue direction of the patch's
    area-weighted normal scatter matrix (the other two eigenvalues near 1/2 each: a flat patch has
    one near 1, a part-round fillet two unequal). The patch is a hole when its vertices, seen along
    that axis, lie on a circle (least squares) all round (no gap wider than 60 deg) and its
    normals point at the axis (a boss's point away)."""
    from trimesh import graph

    bend = np.degrees(mesh.face_adjacency_angles)
    joined = (bend < 0.5) | ((bend < max_bend_deg) & (mesh.face_adjacency_projections > 0))
    patches = graph.connected_components(mesh.face_adjacency[joined], nodes=np.arange(len(mesh.faces)),
                                         min_len=min_faces)
    normals, areas, verts = mesh.face_normals, mesh.area_faces, mesh.vertices
    found = []
    for faces in patches:
        n, w = normals[faces], areas[faces]
        ev, vec = np.linalg.eigh((n * w[:, None]).T @ n / w.sum())
        if ev[0] > 0.01 or ev[1] < 0.35:
            continue
        axis = vec[:, 0]
        u, v = vec[:, 2], np.cross(axis, vec[:, 2])
        idx = np.unique(mesh.faces[faces])
        xy = np.c_[verts[idx] @ u, verts[idx] @ v]
        sol = np.linalg.lstsq(np.c_[2 * xy, np.ones(len(xy))], (xy ** 2).sum(1), rcond=None)[0]
        c = sol[:2]
        r = float(np.sqrt(sol[2] + c @ c))
        rad = np.linalg.norm(xy - c, axis=1)
        if not 0.3 < r < 6.0 or np.max(np.abs(rad - r)) > 0.03 * r + 0.01:
            continue
        az = np.sort(np.arctan2(xy[:, 1] - c[1], xy[:, 0] - c[0]))
        if np.degrees(np.max(np.diff(np.r_[az, az[0] + 2 * np.pi]))) > 60:
            continue
        centres = mesh.triangles_center[faces]
        out = np.c_[centres @ u, centres @ v] - c
        if np.sum((np.c_[n @ u, n @ v] * out).sum(1) * w) >= 0:  # normals pointing away from the axis: a boss
            continue
        found.append((axis, c[0] * u + c[1] * v, r, np.asarray(faces)))
    # A wall that other features cut into patches is one hole: coaxial, the same radius, overlapping
    # along the axis (two bores in line, one each side of a part, stay two).
    merged: list = []
    along = lambda faces, axis: mesh.vertices[mesh.faces[faces]].reshape(-1, 3) @ axis  # noqa: E731
    for axis, point, r, faces in found:
        for k, (a2, p2, r2, f2) in enumerate(merged):
            off, t1, t2 = point - p2, along(faces, a2), along(f2, a2)
            if (abs(axis @ a2) > np.cos(np.radians(2)) and np.linalg.norm(off - (off @ a2) * a2) < 0.2
                    and abs(r - r2) < 0.05 and t1.min() < t2.max() + 0.5 and t2.min() < t1.max() + 0.5):
                merged[k] = (a2, p2, r2, np.union1d(f2, faces))
                break
        else:
            merged.append((axis, point, r, faces))
    return merged


def _in_material(loops: list[np.ndarray]) -> bool:
    return sum(_winding(p) for p in loops) > 0


def holes(mesh, solid=None) -> list[dict]:
    """Every round hole of the mesh (`_cylinders`), each measured across its own axis.

    depth: the length of the hole's round wall along its axis, each end the mean over the angle
    round the axis (so a mouth cut at a slant counts at the axis; a chamfer at the mouth is not
    round wall and not counted). diameter: that of the circle with the area of the loop round the
    axis in the section perpendicular to the axis half-way along the wall. wall: the least distance
    in that section from that loop to any other boundary, the part's outside or another hole.
    kind: `blind` when the axis runs into material within 1 mm past one end (the axis then points
    out of the mouth), `through` when past neither (its largest component then positive). Where
    that section has no loop round the axis alone (the hole opens sideways there) the diameter is
    the circle fitted to the wall's vertices and the wall NaN. Sorted by diameter, then depth."""
    import trimesh

    solid = _manifold(mesh) if solid is None else solid
    out = []
    for axis, point, r, faces in _cylinders(mesh):
        # The wall's two ends: the vertices on its boundary edges (edges of one wall face only),
        # split at the middle of its length, each end's position along the axis averaged with the
        # angle round the axis each vertex stands for as its weight.
        edges = np.sort(mesh.faces[faces][:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        rim = mesh.vertices[np.unique(edges[trimesh.grouping.group_rows(edges, require_count=1)])] - point
        t = rim @ axis
        u = np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0, 1.0, 0])
        az = np.arctan2(rim @ np.cross(axis, u), rim @ u)
        half = 0.5 * (t.min() + t.max())

        def mean_end(sel):
            o = np.argsort(az[sel])
            a, tt = az[sel][o], t[sel][o]
            w = (np.roll(a, -1) - np.roll(a, 1)) % (2 * np.pi) if len(a) > 2 else np.ones(len(a))
            return float(np.sum(w * tt) / np.sum(w))

        lo, hi = mean_end(t < half), mean_end(t >= half)
        centre = point + 0.5 * (lo + hi) * axis
        loops = _section(solid, centre, axis)
        round_the_axis = [q for q in loops if _area(q) < 0 and _winding(q) != 0]
        bore = min(round_the_axis, key=lambda q: -_area(q)) if round_the_axis else None
        if bore is not None and abs(2 * np.sqrt(-_area(bore) / np.pi) - 2 * r) < 0.05 * 2 * r:
            diameter = 2 * np.sqrt(-_area(bore) / np.pi)
            wall = min((_gap(bore, q) for q in loops if q is not bore), default=float("nan"))
        else:
            diameter, wall = 2 * r, float("nan")
        closed = [any(_in_material(_section(solid, point + (at + sign * step) * axis, axis)) for step in (0.3, 0.6, 1.0))
                  for at, sign in ((lo, -1), (hi, 1))]
        direction = -axis if (closed[1] and not closed[0]) else axis.copy()
        if closed[0] == closed[1] and direction[np.argmax(np.abs(direction))] < 0:
            direction = -direction
        out.append({"kind": "blind" if closed[0] != closed[1] else ("through" if not any(closed) else "closed"),
                    "diameter": float(diameter), "axis": direction + 0.0, "depth": hi - lo, "wall": float(wall),
                    "centre": centre})
    return sorted(out, key=lambda h: (h["diameter"], h["depth"]))


def measure(path: Path, material: str) -> dict:
    import trimesh

    mesh = trimesh.load(path, force="mesh")
    vol = float(mesh.volume) / 1000.0
    return {"part": path.stem, "material": material, "volume_cm3": round(vol, 2),
            "mass_g_solid": round(vol * DENSITY[material], 2),
            "bbox_mm": tuple(round(float(x), 1) for x in sorted(mesh.extents, reverse=True)),
            "holes": holes(mesh), "watertight": bool(mesh.is_watertight)}


def authors(folder: Path) -> list[dict]:
    return [measure(p, "tpu_95a" if p.name.startswith("Flex_") else "abs") for p in sorted(folder.glob("*.stl"))]


def ours(build: Path) -> list[dict]:
    return [measure(p, p.parent.name if p.parent.name in DENSITY else "abs") for p in sorted((build / "stl").glob("*/*.stl"))]


def _axis(v) -> str:
    return "(" + ", ".join(f"{x:.2f}".replace("-0.00", "0.00") for x in v) + ")"


def _hole_kinds(hs: list[dict]) -> str:
    """The holes grouped by kind, diameter (0.01 mm), depth (0.1) and wall (0.05), with counts."""
    kinds: dict = {}
    for h in hs:
        wall = "" if np.isnan(h["wall"]) else f", wall {round(h['wall'] * 20) / 20:.2f}"
        key = f"{h['kind']} {h['diameter']:.2f} x {h['depth']:.1f}{wall}"
        kinds[key] = kinds.get(key, 0) + 1
    return "; ".join(f"{k} ({n})" for k, n in kinds.items())


def table(rows: list[dict]) -> str:
    out = ["| part | material | volume cm^3 | mass g (solid) | box mm | holes: kind, bore mm x depth mm, wall mm (count) |",
           "|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['part']} | {r['material']} | {r['volume_cm3']} | {r['mass_g_solid']} | "
                   f"{' x '.join(f'{x:g}' for x in r['bbox_mm'])} | {_hole_kinds(r['holes'])} |")
    return "\n".join(out)


def hole_table(rows: list[dict]) -> str:
    """One line a hole: its kind, bore, axis (out of the mouth of a blind hole), depth and wall."""
    out = ["| part | kind | bore mm | axis | depth mm | wall mm |", "|---|---|---|---|---|---|"]
    for r in rows:
        for h in r["holes"]:
            out.append(f"| {r['part']} | {h['kind']} | {h['diameter']:.2f} | {_axis(h['axis'])} | {h['depth']:.2f} | "
                       f"{'open' if np.isnan(h['wall']) else format(h['wall'], '.2f')} |")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("authors", type=Path)
    ap.add_argument("build", type=Path)
    a = ap.parse_args(argv)
    theirs, mine = authors(a.authors), ours(a.build)
    print("## The authors' parts\n")
    print(table(theirs))
    print("\n## cogniframe's parts\n")
    print(table(mine))
    print("\n## Every hole\n")
    print(hole_table(theirs + mine))
    return 0


if __name__ == "__main__":
    sys.exit(main())
