"""Stiffness of each printed joint from its own geometry: solid FE (default) or closed forms.

A joint is reduced to a *super-element*: a 6n x 6n stiffness over n rigid reference bodies in
the part's local frame -- every rod in its socket, referenced at the socket mouth, plus for
some joints a support body at the joint centre (the foot pad on the floor, the core link's
bolted tab). The frame model (`stiffness`) connects each rod's free span (mouth to mouth) to it.

Two ways to get it (`method`):

``"fe"``  (default) the part's CAD solid (`parts/joint.py`, exactly what is printed: D-section
          sleeves, hub, foot pad, the knee's slotted living hinge) meshed with gmsh and solved
          with scikit-fem quadratic tetrahedra (`joint_fe`). Each rod is a rigid body tied to
          its bore wall and socket bottom through an elastic interface layer; the support body
          is tied to the pad (floor) or the bolt hole and tab underside (core plate).
``"analytic"`` per socket, closed forms: the rod as a beam on an elastic (Winkler) foundation
          over the socket depth (Hetenyi's finite beam, `bef_end_flexibility`), in series with
          the sleeve as a TPU cantilever from the joint centre to the mouth (the knee's hinged
          leg: through the living-hinge web), axial grip by interface shear and bearing on the
          socket bottom, torsion likewise. Microseconds; for sweeps and as a cross-check.

Material: printed TPU at ``TPU_PRINTED_MODULUS_FACTOR`` times its datasheet E and G -- the one
calibration number of the whole stiffness model (docs/stiffness-model.md). The rod-bore
interface layer is ``h_i = max(fit_clearance, 0) / 2 + printer.layer_height / 2`` thick: the
radial clearance plus the printed hole's surface roughness (layer steps about one layer height
peak to valley), with normal stiffness E / h_i and shear stiffness G / h_i per unit area. A
looser fit is a thicker, softer interface; an interference fit is the roughness alone.

Results are cached by a hash of the joint's geometry and material (`cache.load_json`).

Mirrored joints. A part flagged ``mirror`` (``core_link_mirrored``, the fr/rl core link) is the
exact mirror image of its original (``core_link``). When both are in the set ``solve_missing``
is given, the mirror's super-element is not solved again: it is the original's, reflected
(`reflection`, `reflect_unit`), and cached under the mirror's own geometry key.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

# ------------------------------------------------------------------------------------------
# THE calibration: effective modulus of printed TPU (100 % infill, 0.2 mm layers) relative to
# its datasheet value (Ultimaker TPU 95A, E = 26 MPa). Set ONCE so that the carbon preset's
# payload stiffness k from the FE joint model equals the paper's static 7040 N/m
# (`calibrate_tpu_factor`); never per preset, load case or method. Printed TPU is softer than
# moulded test bars (voids between extrusion lines, weak inter-layer bond, anisotropy).
# Re-set from 0.250 when the core link's tab tie was made to take its whole underside (it took a
# mesh-dependent half: facet normals of either sign), which stiffened carbon k by 4.7 %.
TPU_PRINTED_MODULUS_FACTOR = 0.238
# ------------------------------------------------------------------------------------------

TPU_NU = 0.48  # Poisson's ratio of TPU 95A (nearly incompressible elastomer)
TPU_ELONGATION_AT_BREAK = 5.8  # Ultimaker TPU 95A TDS: 580 % elongation at break (ISO 527)
FE_CURVATURE = 8  # elements per full circle on curved faces (bores)
FE_MESH_MM = 1.5  # tetrahedron size in the joint FE (converged to < 2 %: tests/test_joint_fe.py)
_TIE_STIFF = 1.0e4  # support ties (floor, bolt): per unit area, x E, effectively rigid
_CACHE_VERSION = "joint-1"
# Progress of the solid FE (a new joint geometry costs ~1-2 s): the CLI prints these records on
# stderr; nothing is printed when no handler is attached (library use, tests).
progress_log = logging.getLogger("cogniframe.progress")


@dataclass(frozen=True)
class JointStiffness:
    """Condensed stiffness of one distinct joint, in the part's local frame (mm, N)."""

    name: str
    method: str
    labels: tuple[str, ...]  # rod names of the prototype instance, and "body" for the support
    refs: tuple[tuple[float, float, float], ...]  # reference point of each body (mouths, centre)
    K: tuple[tuple[float, ...], ...]  # 6n x 6n, N/mm, N, N mm
    n_dofs: int = 0
    seconds: float = 0.0

    @property
    def matrix(self) -> np.ndarray:
        return np.array(self.K, dtype=float)

    def to_json(self) -> dict:
        return {"name": self.name, "method": self.method, "labels": list(self.labels), "refs": [list(r) for r in self.refs],
                "K": [list(r) for r in self.K], "n_dofs": self.n_dofs, "seconds": self.seconds}

    @staticmethod
    def from_json(d: dict) -> "JointStiffness":
        return JointStiffness(d["name"], d["method"], tuple(d["labels"]), tuple(tuple(r) for r in d["refs"]),
                              tuple(tuple(r) for r in d["K"]), int(d.get("n_dofs", 0)), float(d.get("seconds", 0.0)))

    def socket_rotational_stiffness(self, label: str) -> float:
        """Smallest rotational stiffness (N mm/rad) of one rod about an axis across it, about its
        mouth, with every other body of the joint held: the end restraint used for buckling."""
        K = self.matrix
        i = self.labels.index(label)
        block = K[6 * i + 3:6 * i + 6, 6 * i + 3:6 * i + 6]
        w = np.linalg.eigvalsh(block)
        return float(w[1])  # the two across-axis ones are the smaller (torsion about the rod is stiffer)


@dataclass(frozen=True)
class Interface:
    e: float  # effective TPU E, MPa
    g: float
    h: float  # interface layer thickness, mm


def tpu_moduli(spec, factor: float | None = None) -> tuple[float, float]:
    """(E, G) of the printed joint material in MPa: datasheet times the calibration factor."""
    f = TPU_PRINTED_MODULUS_FACTOR if factor is None else float(factor)
    mat = spec.material(spec.joints.material)
    return f * mat.e_mpa, f * mat.g_mpa


def interface(spec, factor: float | None = None) -> Interface:
    e, g = tpu_moduli(spec, factor)
    return Interface(e, g, max(spec.fit_clearance, 0.0) / 2 + spec.printer.layer_height / 2)


def _nu(e: float, g: float) -> float:
    return float(min(max(e / (2 * g) - 1, 0.0), 0.499))


# -- closed forms ----------------------------------------------------------------------------

def bef_end_flexibility(length: float, ei: float, k_found: float) -> np.ndarray:
    """Hetenyi: 2x2 flexibility [[w/P, w/M], [phi/P, phi/M]] at one end of a free-free beam of
    `length` (mm) and bending stiffness `ei` (N mm^2) on a Winkler foundation of modulus
    `k_found` (N/mm per mm), loaded at that end by a force P and a moment M (w and phi the end's
    deflection and slope, same sense as the load). lambda = (k / 4 EI)^(1/4).

        w/P   = 2 lam / k      (sinh L cosh L - sin L cos L) / (sinh^2 L - sin^2 L)
        w/M   = 2 lam^2 / k    (sinh^2 L + sin^2 L)          / (sinh^2 L - sin^2 L)
        phi/M = 4 lam^3 / k    (sinh L cosh L + sin L cos L) / (sinh^2 L - sin^2 L)

    with L standing for lam * length (Hetenyi, Beams on Elastic Foundation, 1946, ch. 5).
    """
    lam = (k_found / (4 * ei)) ** 0.25
    x = lam * length
    if x < 1e-3:  # rigid limit (series to avoid 0/0): 4/(kL), 6/(kL^2), 12/(kL^3)
        L = length
        return np.array([[4 / (k_found * L), 6 / (k_found * L**2)], [6 / (k_found * L**2), 12 / (k_found * L**3)]])
    sh, ch, s, c = math.sinh(x), math.cosh(x), math.sin(x), math.cos(x)
    den = sh * sh - s * s
    f_wp = 2 * lam / k_found * (sh * ch - s * c) / den
    f_wm = 2 * lam**2 / k_found * (sh * sh + s * s) / den
    f_pm = 4 * lam**3 / k_found * (sh * ch + s * c) / den
    return np.array([[f_wp, f_wm], [f_wm, f_pm]])


def cantilever_flexibility(segments: list[tuple[float, float]], e: float) -> np.ndarray:
    """2x2 end flexibility [[w/P, w/M], [phi/P, phi/M]] at the free end of a clamped beam made
    of `segments` (length, I) from the clamp outwards (unit-load integrals, exact)."""
    total = sum(l for l, _ in segments)
    f = np.zeros((2, 2))
    s0 = 0.0
    for l, i in segments:
        a, b = total - s0 - l, total - s0  # distance from the free end, at segment's ends
        f[0, 0] += (b**3 - a**3) / 3 / (e * i)
        f[0, 1] += (b**2 - a**2) / 2 / (e * i)
        f[1, 1] += l / (e * i)
        s0 += l
    f[1, 0] = f[0, 1]
    return f


def _socket_local_k(spec, sock, itf: Interface, hinge: tuple[float, float, float] | None,
                    rod_e: float, rod_d: float, wall: float) -> np.ndarray:
    """6x6 stiffness of one socket at its mouth, in the socket frame (x out along the rod).

    In bending the joint body behind the socket bottom (hub, neighbouring sleeves) and the sleeve
    wall are taken as rigid; axially the sleeve and the seat carry the load back to the centre.
    The rod bears on the sleeve over the socket depth through a Winkler foundation, the
    interface layer: k_f = E d / h_i (N/mm per mm: the rod's projected width d pressing a layer
    h_i thick). (A pad of h_i + wall was tried: it makes a thicker wall softer in bending, the
    wrong trend, because the real wall is not backed by anything rigid.) Lateral/rotation: Hetenyi's
    finite beam (the rod, EI of the rod) on that foundation; axial: interface shear over the
    bore wall and bearing on the socket bottom; torsion: interface shear. The knee's hinged leg
    adds the living-hinge web (a strip bending about the fold axis) in series.
    """
    L = sock.depth
    i_rod = math.pi * rod_d**4 / 64
    e, g = itf.e, itf.g
    k_found = e * rod_d / itf.h
    f = bef_end_flexibility(L, rod_e * i_rod, k_found)
    if hinge is not None:  # the leg hangs on the living-hinge web
        l_web, width, t = hinge
        f_web = cantilever_flexibility([(l_web, width * t**3 / 12)], e)
        lever = sock.seat + L  # the web's end flexibility seen at the mouth through the rigid sleeve
        tr = np.array([[1.0, lever], [0.0, 1.0]])
        f = f + tr @ f_web @ tr.T
    k_lat = np.linalg.inv(f)
    # axial: grip (interface + wall shear over the bore, bearing on the bottom) in series with the
    # sleeve carrying it back to the bottom (a tube over half the depth on average) and the solid
    # seat between the socket bottom and the joint centre
    bore, od = sock.bore, sock.bore + 2 * wall
    k_grip = g * math.pi * rod_d * L / (itf.h + wall) + e * math.pi * rod_d**2 / 4 / (itf.h + wall)
    a_tube, a_disc = math.pi * (od**2 - bore**2) / 4, math.pi * od**2 / 4
    k_ax = 1.0 / (1.0 / k_grip + (L / 2) / (e * a_tube) + max(sock.seat, 1e-6) / (e * a_disc))
    k_tor = g * math.pi * rod_d * L * (rod_d / 2) ** 2 / (itf.h + wall)
    if hinge is not None:
        l_web, width, t = hinge
        j_web = width * t**3 / 3 * (1 - 0.63 * t / width)
        k_ax = 1.0 / (1.0 / k_ax + l_web / (e * width * t))
        k_tor = 1.0 / (1.0 / k_tor + l_web / (g * j_web))
    K = np.zeros((6, 6))
    K[0, 0] = k_ax
    K[3, 3] = k_tor
    # x-y plane: v (1), rz (5); a lateral force +y at the mouth tilts it with +rz
    K[np.ix_([1, 5], [1, 5])] = k_lat
    # x-z plane: w (2), ry (4); ry = -dw/dx
    K[np.ix_([2, 4], [2, 4])] = k_lat * np.array([[1, -1], [-1, 1]])
    return K


def _socket_frame(direction) -> np.ndarray:
    """Rows: socket x (out along the rod), y, z in the part frame."""
    x = np.asarray(direction, float)
    x = x / np.linalg.norm(x)
    ref = np.array([0.0, 0.0, 1.0]) if abs(x[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    y = np.cross(ref, x)
    y /= np.linalg.norm(y)
    return np.vstack([x, y, np.cross(x, y)])


def _block_rot(r: np.ndarray) -> np.ndarray:
    t = np.zeros((6, 6))
    t[:3, :3] = t[3:, 3:] = r
    return t


def hinged_socket(part) -> int | None:
    """Index of the knee's hinged (upper-leg) socket: the leg making the larger angle with the arms
    (any knee part: `knee_mirrored`, a rectangle's fr/rl knee, is hinged too)."""
    if joint_kind(part) != "knee":
        return None
    dirs = [np.asarray(s.direction, float) for s in part.sockets]
    arm = None
    for i in range(len(dirs)):
        for k in range(i + 1, len(dirs)):
            if dirs[i] @ dirs[k] > 1 - 1e-4:
                arm = dirs[i]
    legs = [i for i, d in enumerate(dirs) if arm is None or d @ arm < 1 - 1e-4]
    return min(legs, key=lambda i: float(dirs[i] @ arm)) if arm is not None else None


def hinge_geometry(part) -> tuple[float, float, float]:
    """(web length, web width, thickness) of the knee's living hinge, mm (as parts/joint.py draws it)."""
    from ..parts.joint import knee_hinge  # pure numpy (CadQuery only inside its CAD functions)

    h = knee_hinge(part)
    return float(np.linalg.norm(h.end - h.start)), float(h.height), float(h.thickness)


def joint_kind(part) -> str:
    """What a joint part is, whatever it is called: `core_link_mirrored` is a `core_link`."""
    return str(dict(part.params).get("kind", part.name))


def _has_body(part) -> bool:
    return joint_kind(part) in ("corner_bottom", "core_link")


def analytic_joint(spec, part, factor: float | None = None) -> JointStiffness:
    """Super-element from closed forms: per socket a 6x6 spring mouth <-> joint centre, the
    centre kept as the "body" (condensed out when the joint has no support)."""
    t0 = time.perf_counter()
    itf = interface(spec, factor)
    rod = spec.material(spec.rods.material)
    hi = hinged_socket(part)
    hinge = hinge_geometry(part) if hi is not None else None
    n = len(part.sockets)
    N = 6 * (n + 1)
    K = np.zeros((N, N))
    refs = []
    for i, s in enumerate(part.sockets):
        kl = _socket_local_k(spec, s, itf, hinge if i == hi else None, rod.e_mpa, spec.rods.diameter, part.wall)
        R = _block_rot(_socket_frame(s.direction))
        kg = R.T @ kl @ R  # part frame, at the mouth
        mouth = np.asarray(s.port, float) + np.asarray(s.direction, float) * (s.seat + s.depth)
        refs.append(tuple(float(v) for v in mouth))
        # spring between the rod body (at the mouth) and the centre body: the centre's motion
        # seen at the mouth is T u_c.
        from .framefe import rigid_transfer

        T = rigid_transfer(np.zeros(3), mouth)
        B = np.hstack([np.eye(6), -T])  # relative motion at the mouth
        ks = B.T @ kg @ B
        idx = np.r_[6 * i:6 * i + 6, 6 * n:6 * n + 6]
        K[np.ix_(idx, idx)] += ks
    labels = tuple(s.rod for s in part.sockets)
    if _has_body(part):
        labels += ("body",)
        refs.append((0.0, 0.0, 0.0))
    else:  # condense the centre out
        a, b = slice(0, 6 * n), slice(6 * n, N)
        K = K[a, a] - K[a, b] @ np.linalg.solve(K[b, b], K[b, a])
    K = 0.5 * (K + K.T)
    return JointStiffness(part.name, "analytic", labels, tuple(refs), tuple(map(tuple, K.tolist())), N,
                          time.perf_counter() - t0)


# -- solid FE ----------------------------------------------------------------------------------

def fe_joint(spec, part, factor: float | None = None, mesh_mm: float | None = None) -> JointStiffness:
    """Super-element from the solid FE of the part's CAD (see the module docstring).

    With one BLAS thread wherever it runs (a pool worker, a fork, this process): the thread count
    changes the order of the dense sums, and the cached numbers must be the same bits whichever
    path solved them."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return _fe_joint(spec, part, factor, mesh_mm)


def _fe_joint(spec, part, factor: float | None, mesh_mm: float | None) -> JointStiffness:
    from . import joint_fe
    from ..parts.shapes import brep_text, shared_brep
    from ..parts import joint as joint_cad

    t0 = time.perf_counter()
    mesh_mm = FE_MESH_MM if mesh_mm is None else mesh_mm
    itf = interface(spec, factor)
    m = joint_cad.print_from_local(part)
    # the shape the build's part step stored (the same text), else built here
    shared = shared_brep(part)
    try:
        pts, tets = joint_fe.mesh_brep_text(shared or brep_text(joint_cad.build(part).shape), mesh_mm, FE_CURVATURE)
    except RuntimeError:
        if shared is None:
            raise
        # a damaged cache file is a miss, never an error
        pts, tets = joint_fe.mesh_brep_text(brep_text(joint_cad.build(part).shape), mesh_mm, FE_CURVATURE)
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
        rb = s.bore / 2
        depth = s.depth - joint_cad.CHAMFER

        def sel(c, n, d=d, bottom=bottom, rb=rb, depth=depth):
            rel = c - bottom[:, None]
            t = d @ rel
            radial = np.linalg.norm(rel - np.outer(d, t), axis=0)
            wall = (t > -tol) & (t < depth + tol) & (np.abs(radial - rb) < tol)
            floor = (np.abs(t) < tol) & (radial < rb + tol) & (np.abs(d @ n) > 0.9)
            return wall | floor

        ties.append(joint_fe.Tie(s.rod, sel, tuple(R @ mouth_l + o), itf.e / itf.h, itf.g / itf.h))
    labels = tuple(s.rod for s in part.sockets)
    if joint_kind(part) == "corner_bottom":
        ties.append(joint_fe.Tie("body", lambda c, n: (c[2] < 1e-3) & (np.abs(n[2]) > 0.99), tuple(o),
                                 _TIE_STIFF * itf.e, _TIE_STIFF * itf.e))
    elif joint_kind(part) == "core_link":
        bolt = R @ np.asarray(part.param("bolt_hole"), float) + o
        axis = R @ np.array([0.0, 0.0, 1.0])
        r_hole = float(part.param("screw_clearance")) / 2
        z0 = float(part.param("plate_top_z"))

        def sel_bolt(c, n, bolt=bolt, axis=axis):
            rel = c - bolt[:, None]
            t = axis @ rel
            radial = np.linalg.norm(rel - np.outer(axis, t), axis=0)
            hole = np.abs(radial - r_hole) < tol
            # the tab's underside on the plate: local z = plate_top_z, facing down (local -z)
            zl = axis @ (c - o[:, None])
            under = (np.abs(zl - z0) < 1e-3) & ((axis @ n) < -0.99)
            return hole | under

        ties.append(joint_fe.Tie("body", sel_bolt, tuple(o), _TIE_STIFF * itf.e, _TIE_STIFF * itf.e))
    if _has_body(part):
        labels += ("body",)
    c = joint_fe.condense(pts, tets, itf.e, _nu(itf.e, itf.g), ties)
    # back to the part's local frame: u_print = R u_local
    T = np.kron(np.eye(len(ties)), _block_rot(R))
    K = T.T @ c.K @ T
    refs = refs_local + ([(0.0, 0.0, 0.0)] if _has_body(part) else [])
    K = 0.5 * (K + K.T)
    return JointStiffness(part.name, "fe", labels, tuple(refs), tuple(map(tuple, K.tolist())), c.n_dofs,
                          time.perf_counter() - t0)


# -- mirrored joints ------------------------------------------------------------------------------

MIRROR_TOL = 1e-4  # mm (and unit vectors): sockets are stored rounded to 1e-6 mm (`partlist._t`)


def is_mirror(part) -> bool:
    """A joint whose print is the mirror image of another part's (`partlist._joint`, param ``mirror``)."""
    return bool(dict(part.params).get("mirror"))


def _kabsch_reflection(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The orthogonal 3x3 P with det(P) = -1 that best maps the columns of `a` onto those of `b`
    (least squares, SVD of b a^T: Kabsch's solution with the determinant's sign forced)."""
    u, _, vt = np.linalg.svd(b @ a.T)
    s = -1.0 if np.linalg.det(u @ vt) > 0 else 1.0
    return u @ np.diag([1.0, 1.0, s]) @ vt


def reflection(original, part) -> tuple[np.ndarray, tuple[int, ...]]:
    """(P, order): the reflection P (3x3, det -1) with part's local geometry = P x original's, and
    order[j] = the original's socket whose mirror image is the part's socket j.

    The sockets carry different rod names (and come in another order: the mirror swaps the two
    arms), so they are matched by geometry: every assignment of the part's sockets to the
    original's with the same seat, depth and bore gets its best reflection (Kabsch, over the
    ports, mouths and directions), and the one whose images land within `MIRROR_TOL` of the
    part's sockets wins (smallest error, first in order on a tie). Raises ValueError (the caller
    solves the FE instead) unless everything the CAD and the FE ties read maps too: the other
    params equal, the bolt hole the image of the original's, P keeps the vertical (the plate
    top, the tab and the bed are horizontal), and the two print orientations differ by a
    reflection that keeps the bed, so the print-safe construction of `parts/joint.py` (built
    against the bed) is the mirror image of the original's."""
    import itertools

    from ..parts.joint import print_from_local

    if joint_kind(part) != joint_kind(original) or len(part.sockets) != len(original.sockets):
        raise ValueError(f"{part.name} and {original.name} are not the same kind of joint")
    if part.wall != original.wall:
        raise ValueError(f"walls differ ({part.wall} / {original.wall} mm)")
    skip = ("mirror", "kind", "bolt_hole")
    p_par = {k: v for k, v in part.params if k not in skip}
    o_par = {k: v for k, v in original.params if k not in skip}
    if p_par != o_par:
        raise ValueError(f"params differ: {sorted(set(p_par.items()) ^ set(o_par.items()), key=str)}")

    def cloud(socks) -> np.ndarray:  # 3 x 3n: ports, mouths, directions (scaled to the socket length)
        cols = []
        for s in socks:
            cols += [np.asarray(s.port, float), s.mouth(), np.asarray(s.direction, float) * (s.seat + s.depth)]
        return np.array(cols).T

    b = cloud(part.sockets)
    sv = np.linalg.svd(b, compute_uv=False)
    if sv[-1] < 1e-6 * sv[0]:
        raise ValueError("the sockets lie in one plane: the reflection is not determined by them")
    best = None
    for order in itertools.permutations(range(len(part.sockets))):
        so = [original.sockets[i] for i in order]
        if any((x.seat, x.depth, x.bore) != (y.seat, y.depth, y.bore) for x, y in zip(so, part.sockets)):
            continue
        a = cloud(so)
        P = _kabsch_reflection(a, b)
        err = float(np.abs(P @ a - b).max())
        if best is None or err < best[0]:
            best = (err, P, tuple(order))
    if best is None or best[0] > MIRROR_TOL:
        worst = f" (best: {best[0]:.3g} mm)" if best else ""
        raise ValueError(f"no reflection maps the sockets onto each other{worst}")
    _, P, order = best
    snapped = np.round(P)
    if np.abs(P - snapped).max() < 1e-9:  # a mirror across a coordinate plane: exact signs, no round-off
        P = snapped + 0.0
    ez = np.array([0.0, 0.0, 1.0])
    if np.abs(P @ ez - ez).max() > 1e-9:
        raise ValueError("the mirror plane is not vertical")
    holes = [dict(x.params).get("bolt_hole") for x in (original, part)]
    if holes != [None, None]:
        if None in holes or np.abs(P @ np.asarray(holes[0], float) - np.asarray(holes[1], float)).max() > MIRROR_TOL:
            raise ValueError("the bolt hole is not the mirror image of the original's")
    mo, mp = print_from_local(original), print_from_local(part)
    Q = mp[:3, :3] @ P @ mo[:3, :3].T  # print(part) = Q print(original)
    keeps_bed = np.abs(Q[:, 2] - ez).max() < 1e-9 and np.abs(Q[2, :] - ez).max() < 1e-9
    if not keeps_bed or np.abs(mp[:3, 3] - mo[:3, 3]).max() > MIRROR_TOL:
        raise ValueError("the print orientations are not mirror images on the bed")
    return P, order


def reflect_unit(unit: JointStiffness, part, P: np.ndarray, order: tuple[int, ...], original_rods) -> JointStiffness:
    """The mirror part's super-element from its original's (`unit`, the original's sockets' rods
    `original_rods` in its socket order) and `reflection`'s (P, order).

    A displacement maps as u' = P u, a rotation (a pseudo-vector) as theta' = det(P) P theta,
    and forces and moments alike, so with T = blockdiag(P, det(P) P) per body (permuted to the
    part's socket order) K' = T K T^T: orthogonal, so the same eigenvalues. The reference points
    map with P; the part's own mouths are recorded (checked to be the images within
    `MIRROR_TOL`), exactly what a direct solve records."""
    t0 = time.perf_counter()
    n = len(part.sockets)
    if tuple(unit.labels[:n]) != tuple(original_rods) or len(unit.labels) not in (n, n + 1):
        raise ValueError(f"{unit.name}: labels {unit.labels} do not follow the original's sockets")
    body = len(unit.labels) == n + 1
    idx = list(order) + ([n] if body else [])
    rows = np.concatenate([np.arange(6 * i, 6 * i + 6) for i in idx])
    Ko = unit.matrix[np.ix_(rows, rows)]
    tb = np.zeros((6, 6))
    tb[:3, :3] = P
    tb[3:, 3:] = float(np.sign(np.linalg.det(P))) * P  # pseudo-vectors: det(P) P, det exactly -1
    T = np.kron(np.eye(len(idx)), tb)
    K = T @ Ko @ T.T
    K = 0.5 * (K + K.T)
    refs = []
    for j, s in enumerate(part.sockets):
        own = s.mouth()
        if np.abs(P @ np.asarray(unit.refs[order[j]], float) - own).max() > MIRROR_TOL:
            raise ValueError(f"{part.name}: the mouth of {s.rod} is not the image of the original's")
        refs.append(tuple(float(v) for v in own))
    if body:
        refs.append(tuple(float(v) for v in P @ np.asarray(unit.refs[n], float)))
    labels = tuple(s.rod for s in part.sockets) + (("body",) if body else ())
    return JointStiffness(part.name, unit.method, labels, tuple(refs), tuple(map(tuple, K.tolist())), unit.n_dofs,
                          time.perf_counter() - t0)


def mirror_original(part, parts):
    """(original, P, order) for a mirrored joint whose original is among `parts`, else None.
    Raises ValueError (with the reason) when the flagged original is not its mirror image."""
    if not is_mirror(part):
        return None
    reasons = []
    for o in _originals(part, parts):
        try:
            P, order = reflection(o, part)
        except ValueError as exc:
            reasons.append(f"{o.name}: {exc}")
            continue
        return o, P, order
    if reasons:
        raise ValueError("; ".join(reasons))
    return None


def _originals(part, parts) -> list:
    """The parts a mirrored joint may be the image of: joints of its kind that are not mirrors."""
    return [p for p in parts if p.family == "joint" and not is_mirror(p) and joint_kind(p) == joint_kind(part)]


# -- cache ---------------------------------------------------------------------------------------

def geometry_key(spec, part, method: str, factor: float | None, mesh_mm: float) -> str:
    """Hash of everything the joint model reads: the part's geometry digest (sockets, wall, params),
    the interface (clearance, layer height), materials, method, and this module's source."""
    itf = interface(spec, factor)
    # the FE takes the rods as rigid: their modulus does not enter (the closed forms are not cached)
    from .. import cache

    data = [_CACHE_VERSION, part.digest, method, itf.e, itf.g, itf.h, spec.rods.diameter, mesh_mm, FE_CURVATURE]
    return cache.key(data, ("analysis/joint_stiffness.py", "analysis/joint_fe.py", "parts/joint.py"))


def joint_stiffness(spec, part, method: str = "fe", factor: float | None = None,
                    mesh_mm: float | None = None, use_cache: bool = True) -> JointStiffness:
    """The super-element of one distinct joint, cached by geometry hash."""
    from .. import cache

    mesh_mm = FE_MESH_MM if mesh_mm is None else mesh_mm
    if method not in ("fe", "analytic"):
        raise ValueError(f"joint stiffness method must be 'fe' or 'analytic', got {method!r}")
    if method == "analytic":
        return analytic_joint(spec, part, factor)
    # Every stiffness in the FE (TPU E and G, the interface E/h_i and G/h_i, the support ties)
    # is proportional to the TPU factor, so the condensed matrix is too: solve and cache at
    # factor 1, scale on use.
    key = geometry_key(spec, part, method, 1.0, mesh_mm)
    hit = cache.load_json("joint", key) if use_cache else None
    if hit is not None:
        unit = JointStiffness.from_json(hit)
    else:
        unit = fe_joint(spec, part, 1.0, mesh_mm)
        # A mirrored joint's cache entry is its original's reflected (`solve_missing`), so that
        # its numbers are the same bits whatever was solved before: a direct solve is not stored.
        if use_cache and not is_mirror(part):
            cache.store_json("joint", key, unit.to_json())
    f = TPU_PRINTED_MODULUS_FACTOR if factor is None else float(factor)
    return JointStiffness(unit.name, unit.method, unit.labels, unit.refs,
                          tuple(map(tuple, (f * unit.matrix).tolist())), unit.n_dofs, unit.seconds)


def _fe_unit(spec, part, mesh_mm: float) -> tuple[str, dict | None, str | None]:
    """A worker's task: the FE super-element at factor 1, as cache JSON (or the mesher's error)."""
    try:
        return part.name, fe_joint(spec, part, 1.0, mesh_mm).to_json(), None
    except RuntimeError as exc:
        return part.name, None, str(exc)


def has_unsolved(spec, parts, mesh_mm: float | None = None) -> bool:
    """Whether a joint in ``parts`` has no FE super-element in the joint cache yet (the test
    `solve_missing` makes; milliseconds: the keys are hashes of the parts' inputs)."""
    from .. import cache

    mesh_mm = FE_MESH_MM if mesh_mm is None else mesh_mm
    return any(cache.load_json("joint", geometry_key(spec, p, "fe", 1.0, mesh_mm)) is None for p in parts)


def solve_missing(spec, parts, mesh_mm: float | None = None, submit=None) -> dict[str, str]:
    """Solve and cache the FE of every joint in ``parts`` whose geometry is not cached yet: on the
    caller's worker processes (``submit(fn, *args) -> Future``: `runtime.pools.joint_fe_workers`
    for `check`, the CAD workers in a build), or here one after another when ``submit`` is None
    (in a Dask worker, whose cores the cluster schedules) or the workers fail. Returns
    {part name: error} of the joints the mesher or the tie selection could not handle (nothing
    cached for them).

    A mirrored joint whose original is in ``parts`` is not solved: once the original is solved
    (or found in the cache) its super-element is reflected (`reflection`, `reflect_unit`) and
    cached under the mirror's key -- always from the original, never the reverse, so the bits
    are the same whatever the order or the cache held. If the two are not exact mirror images,
    or the original fails, the mirror is solved by FE like any other joint. A mirror without its
    original in ``parts`` is not solved here (nor cached by `joint_stiffness`)."""
    from .. import cache

    mesh_mm = FE_MESH_MM if mesh_mm is None else mesh_mm
    todo, seen = [], set()
    derive = []  # (mirror part, its key, original part, original key, P, order)
    for p in parts:
        key = geometry_key(spec, p, "fe", 1.0, mesh_mm)
        if key not in seen and cache.load_json("joint", key) is None:
            try:
                found = mirror_original(p, parts)
            except ValueError as exc:
                progress_log.info("joint FE: %s is not an exact mirror image (%s); solving it", p.name, exc)
                found = None
            if found is not None:
                o, P, order = found
                derive.append((p, key, o, geometry_key(spec, o, "fe", 1.0, mesh_mm), P, order))
            elif is_mirror(p) and not _originals(p, parts):
                # a hand-picked subset (a design's part list always has both): its own FE is not
                # cached, so the cache never depends on which subset came first; joint_stiffness
                # solves it when used
                progress_log.info("joint FE: %s left to joint_stiffness (its original is not in this set)", p.name)
            else:
                todo.append((p, key))
        seen.add(key)
    if not todo and not derive:
        return {}
    failed = _solve(spec, todo, mesh_mm, submit)
    # the mirrors, after their originals (solved above or cached before)
    for p, key, o, okey, P, order in derive:
        hit = cache.load_json("joint", okey)
        if hit is not None:
            try:
                unit = reflect_unit(JointStiffness.from_json(hit), p, P, order, [s.rod for s in o.sockets])
            except ValueError as exc:
                progress_log.info("joint FE: %s not derived (%s); solving it", p.name, exc)
            else:
                cache.store_json("joint", key, unit.to_json())
                progress_log.info("joint FE: %s derived by reflection from %s", p.name, o.name)
                continue
        # the original failed (or its unit did not fit): solve the mirror itself
        failed.update(_solve(spec, [(p, key)], mesh_mm))
    return failed


def _solve(spec, todo, mesh_mm: float, submit=None) -> dict[str, str]:
    """The FE of `todo` [(part, key)], cached; {part name: error} of those that failed.
    `submit(fn, *args) -> Future`: the caller's worker processes; None: here, one after another."""
    from .. import cache

    if not todo:
        return {}
    keys = {p.name: key for p, key in todo}
    t0 = time.perf_counter()
    done = 0
    failed: dict[str, str] = {}

    def finished(name: str, unit: dict | None, err: str | None) -> None:
        nonlocal done
        done += 1
        if unit is not None:
            cache.store_json("joint", keys[name], unit)
            progress_log.info("joint FE %d/%d: %s (%s DOF), %.1f s", done, len(todo), name, unit.get("n_dofs"),
                              time.perf_counter() - t0)
        else:  # joint_models falls back to the closed forms for this joint
            failed[name] = str(err)
            progress_log.info("joint FE %d/%d: %s failed (%s)", done, len(todo), name, err)

    pending = list(todo)
    if submit is not None:
        from concurrent.futures import BrokenExecutor, as_completed

        progress_log.info("joint FE: %d new joint geometries on the caller's worker processes", len(todo))
        try:
            # the biggest first (by the closed-form volume: the mesh is of a fixed size, so its
            # DOFs and the factorization grow with it), so that the last job to start is a small
            # one and the workers end together (longest-processing-time-first)
            biggest_first = sorted(todo, key=lambda t: -t[0].estimate.volume)
            futures = {submit(_fe_unit, spec, p, mesh_mm): p.name for p, _ in biggest_first}
            for fut in as_completed(futures):
                finished(*fut.result())
                pending = [x for x in pending if x[0].name != futures[fut]]
        except BrokenExecutor:
            # a worker could not start or died: the rest is solved here, one after another
            progress_log.info("joint FE: worker processes failed; solving %d joint(s) in this process", len(pending))
    for p, _ in pending:
        finished(*_fe_unit(spec, p, mesh_mm))
    return failed
