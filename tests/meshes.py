"""Meshes the plate, slicer and report tests lay out: boxes and cylinders with their lowest
corner at the origin, as a part's STL sits in its print orientation."""

from __future__ import annotations

import trimesh


def box(x: float, y: float, z: float) -> trimesh.Trimesh:
    m = trimesh.creation.box((x, y, z))
    m.apply_translation(-m.bounds[0])
    return m


def cylinder(r: float, h: float, sections: int = 32) -> trimesh.Trimesh:
    m = trimesh.creation.cylinder(radius=r, height=h, sections=sections)
    m.apply_translation(-m.bounds[0])
    return m
