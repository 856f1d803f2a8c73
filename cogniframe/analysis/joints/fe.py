"""The solid-FE joint super-element (``method="fe"``, the default): the part's own CAD solid,
meshed and condensed onto its rods and support.

The solid is exactly what is printed (its kind's `solid`, families/joint_kinds/: D-section
sleeves, hub, foot pad, the knee's slotted living hinge); `meshing` turns it into gmsh tetrahedra
and `solid_fe` condenses scikit-fem quadratic elasticity onto rigid bodies. This module picks those
bodies' surfaces: each rod is tied to its bore wall and socket bottom through the elastic
interface layer (`model.interface`); the support body is tied stiffly to the faces its kind's
`support_faces` picks: the pad (floor), the bolt hole and the tab's underside where it lies on
the plate (the tab core link; `contact.py` measures what tying it both ways overstates under
thrust), or the pegs' sides and inner ends (the pegged core link, whose pegs the core's ABS bores
hold). It also holds the mesh settings, which are part of the joint cache key.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .model import JointStiffness, _block_rot, interface, joint_kind

FE_CURVATURE = 8  # elements per full circle on curved faces (bores)
FE_MESH_MM = 1.5  # tetrahedron size in the joint FE (converged to < 2 %: tests/test_joint_fe.py)
_TIE_STIFF = 1.0e4  # support ties (floor, bolt): per unit area, x E, effectively rigid


def _nu(e: float, g: float) -> float:
    return float(min(max(e / (2 * g) - 1, 0.0), 0.499))


def fe_joint(spec, part, factor: float | None = None, mesh_mm: float | None = None) -> JointStiffness:
    """Super-element from the solid FE of the part's CAD (see the module docstring).

    With one BLAS thread wherever it runs (a pool worker, a fork, this process): the thread count
    changes the order of the dense sums, and the cached numbers must be the same bits whichever
    path solved them."""
    from ..numerics import one_blas_thread

    with one_blas_thread():
        return _fe_joint(spec, part, factor, mesh_mm)


def _fe_joint(spec, part, factor: float | None, mesh_mm: float | None) -> JointStiffness:
    from . import solid_fe

    t0 = time.perf_counter()
    pb = joint_problem(spec, part, factor, mesh_mm)
    c = solid_fe.condense(pb.points, pb.tets, pb.e, pb.nu, list(pb.ties))
    # back to the part's local frame: u_print = R u_local
    T = np.kron(np.eye(len(pb.ties)), _block_rot(pb.rotation))
    K = T.T @ c.K @ T
    K = 0.5 * (K + K.T)
    return JointStiffness(part.name, "fe", pb.labels, pb.refs, tuple(map(tuple, K.tolist())), c.n_dofs,
                          time.perf_counter() - t0)


def socket_faces(bottom: np.ndarray, d: np.ndarray, rb: float, depth: float, tol: float):
    """``select(centroids, normals)`` of a socket's bore wall (radius ``rb``, ``depth`` deep from
    ``bottom`` along the unit vector ``d``) and its floor: the surface a rod's tie holds."""

    def sel(c, n):
        rel = c - bottom[:, None]
        t = d @ rel
        radial = np.linalg.norm(rel - np.outer(d, t), axis=0)
        wall = (t > -tol) & (t < depth + tol) & (np.abs(radial - rb) < tol)
        floor = (np.abs(t) < tol) & (radial < rb + tol) & (np.abs(d @ n) > 0.9)
        return wall | floor

    return sel


@dataclass(frozen=True)
class JointProblem:
    """A joint's solid FE before condensation: the mesh (print coordinates), the material and
    the ties, with the print-from-local rotation and offset and the ties' labels and reference
    points in the part's local frame."""

    points: np.ndarray
    tets: np.ndarray
    e: float
    nu: float
    ties: tuple
    rotation: np.ndarray
    offset: np.ndarray
    labels: tuple[str, ...]
    refs: tuple


def joint_problem(spec, part, factor: float | None = None, mesh_mm: float | None = None) -> JointProblem:
    """Mesh the part's CAD and pick the tied surfaces (see the module docstring)."""
    from . import meshing, solid_fe
    from ...families.joint_kinds.kinds import print_from_local, solid
    from ...parts.joint_solid import CHAMFER
    from ...parts.shapes import brep_text, shared_brep

    mesh_mm = FE_MESH_MM if mesh_mm is None else mesh_mm
    itf = interface(spec, factor)
    m = print_from_local(part)
    # the shape the build's part step stored (the same text), else built here
    shared = shared_brep(part)
    try:
        pts, tets = meshing.mesh_brep_text(shared or brep_text(solid(part).shape), mesh_mm, FE_CURVATURE)
    except RuntimeError:
        if shared is None:
            raise
        # a damaged cache file is a miss, never an error
        pts, tets = meshing.mesh_brep_text(brep_text(solid(part).shape), mesh_mm, FE_CURVATURE)
    R, o = m[:3, :3], m[:3, 3]
    ties = []
    refs_local = []
    # facet centroids of the faceted bore lie up to the sagitta inside the true cylinder
    tol = 0.1 + 0.5 * part.sockets[0].bore * (1 - math.cos(math.pi / FE_CURVATURE))
    for s in part.sockets:
        d = R @ np.asarray(s.direction, float)
        bottom = R @ np.asarray(s.bottom(), float) + o
        mouth_l = np.asarray(s.mouth(), float)
        refs_local.append(tuple(float(v) for v in mouth_l))
        sel = socket_faces(bottom, d, s.bore / 2, s.depth - CHAMFER, tol)
        ties.append(solid_fe.Tie(s.rod, sel, tuple(R @ mouth_l + o), itf.e / itf.h, itf.g / itf.h))
    labels = tuple(s.rod for s in part.sockets)
    kind = joint_kind(part)
    support = kind.support_faces(part, m, tol, FE_CURVATURE)  # the floor, the plate's bolt and top, the core's bores
    if support is not None:
        ties.append(solid_fe.Tie("body", support, tuple(o), _TIE_STIFF * itf.e, _TIE_STIFF * itf.e))
    if kind.has_body:
        labels += ("body",)
    refs = refs_local + ([(0.0, 0.0, 0.0)] if kind.has_body else [])
    return JointProblem(pts, tets, itf.e, _nu(itf.e, itf.g), tuple(ties), R, o, labels, tuple(refs))
