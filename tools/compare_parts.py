#!/usr/bin/env python3
"""Measure printed parts side by side: a folder of the authors' STL files against a cogniframe build.

    python tools/compare_parts.py AUTHORS_DIR BUILD_DIR [--markdown]

AUTHORS_DIR holds the authors' published parts (thecognifly/CogniFly-STL,
`CogniFly_v8_Crash_Tests/*.stl`: fetch them yourself, cogniframe does not ship them); BUILD_DIR is
`out/<name>` of `cogniframe build`. For every STL the script prints its solid volume, the mass at
100 % of the material's density (TPU for parts whose name starts with `Flex_` or lives under
`stl/tpu_95a/`, else ABS), its bounding box and the round holes it finds: each closed interior loop
of planar sections taken along the three axes, reported as the diameter of the circle of the same
area (rounded to 0.05 mm), most frequent first. A hole that runs obliquely to every axis shows as
an ellipse and reads too large; the sections are meant for bores, sockets and screw holes that run
along an axis of the part's print orientation, which is how both sets of files are laid out.

docs/authors-parts.md is this script's output with the reasons for each difference.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

import numpy as np

DENSITY = {"tpu_95a": 1.22, "abs": 1.10}  # g/cm^3, cogniframe/materials.py


def _manifold(mesh):
    import manifold3d as m3

    return m3.Manifold(m3.Mesh(vert_properties=np.asarray(mesh.vertices, np.float32),
                               tri_verts=np.asarray(mesh.faces, np.uint32)))


# Rotations taking each axis to z, each with determinant +1 (a reflection turns the mesh inside out).
_TO_Z = {0: np.array([[0.0, 1, 0, 0], [0, 0, 1, 0], [1, 0, 0, 0]]),
         1: np.array([[0.0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 0]]),
         2: np.eye(3, 4)}


def holes(mesh, slices: int = 9) -> list[tuple[float, int]]:
    """(diameter mm, how many section loops had it), most frequent first."""
    solid = _manifold(mesh)
    lo, hi = mesh.bounds
    found: Counter = Counter()
    for axis, rot in _TO_Z.items():
        turned = solid.transform(rot)
        for f in np.linspace(0.05, 0.95, slices):
            z = lo[axis] + f * (hi[axis] - lo[axis])
            for loop in turned.slice(float(z)).to_polygons():
                p = np.asarray(loop)
                area = 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))
                if area < 0 and abs(area) > 0.5:  # interior loops wind clockwise
                    d = 2 * np.sqrt(-area / np.pi)
                    if d < 12.0:
                        found[round(d * 20) / 20] += 1
    return found.most_common(6)


def measure(path: Path, material: str) -> dict:
    import trimesh

    mesh = trimesh.load(path, force="mesh")
    vol = float(mesh.volume) / 1000.0
    return {"part": path.stem, "material": material, "volume_cm3": round(vol, 2),
            "mass_g_solid": round(vol * DENSITY[material], 2),
            "bbox_mm": tuple(round(float(x), 1) for x in sorted(mesh.extents, reverse=True)),
            "holes_mm": holes(mesh), "watertight": bool(mesh.is_watertight)}


def authors(folder: Path) -> list[dict]:
    return [measure(p, "tpu_95a" if p.name.startswith("Flex_") else "abs") for p in sorted(folder.glob("*.stl"))]


def ours(build: Path) -> list[dict]:
    return [measure(p, p.parent.name if p.parent.name in DENSITY else "abs") for p in sorted((build / "stl").glob("*/*.stl"))]


def table(rows: list[dict]) -> str:
    out = ["| part | material | volume cm^3 | mass g (solid) | box mm | holes mm (count) |", "|---|---|---|---|---|---|"]
    for r in rows:
        hs = ", ".join(f"{d:g} ({n})" for d, n in r["holes_mm"])
        out.append(f"| {r['part']} | {r['material']} | {r['volume_cm3']} | {r['mass_g_solid']} | "
                   f"{' x '.join(f'{x:g}' for x in r['bbox_mm'])} | {hs} |")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("authors", type=Path)
    ap.add_argument("build", type=Path)
    a = ap.parse_args(argv)
    print("## The authors' parts\n")
    print(table(authors(a.authors)))
    print("\n## cogniframe's parts\n")
    print(table(ours(a.build)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
