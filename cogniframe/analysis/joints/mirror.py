"""Mirrored joints: a mirror part's super-element as its original's, reflected.

A part flagged ``mirror`` (``core_link_mirrored``, the fr/rl core link) is the exact mirror image
of its original (``core_link``). Rather than meshing it again, `reflection` finds the reflection
that maps the original's sockets onto the part's (matched by geometry, not by name or order) and
checks that everything the CAD and the FE ties read maps too; `reflect_unit` then transforms the
original's super-element. The package's `solve_missing` caches the result under the mirror's own
geometry key, so the mirror's numbers are the same bits whichever was solved first.
"""

from __future__ import annotations

import functools
import time

import numpy as np

from .model import JointStiffness, joint_kind

MIRROR_TOL = 1e-4  # mm (and unit vectors): sockets are stored rounded to 1e-6 mm (`families.base.rounded`)


def is_mirror(part) -> bool:
    """A joint whose print is the mirror image of another part's (`families.joint._joint`, param ``mirror``)."""
    return bool(dict(part.params).get("mirror"))


def _kabsch_reflection(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The orthogonal 3x3 P with det(P) = -1 that best maps the columns of `a` onto those of `b`
    (least squares, SVD of b a^T: Kabsch's solution with the determinant's sign forced)."""
    u, _, vt = np.linalg.svd(b @ a.T)
    s = -1.0 if np.linalg.det(u @ vt) > 0 else 1.0
    return u @ np.diag([1.0, 1.0, s]) @ vt


def reflection(original, part) -> tuple[np.ndarray, tuple[int, ...]]:
    """`_reflection` of the two parts, kept by their content (PartSpec is frozen and hashable): a
    check asks for it up to three times per mirrored joint (the FE test, the box test, the
    reflection itself), and an edit that moves no joint asks again for the same parts. P is a new
    array each time (the caller may change it)."""
    rows, order = _reflection_kept(original, part)
    return np.array(rows), order


@functools.lru_cache(maxsize=64)
def _reflection_kept(original, part) -> tuple[tuple, tuple[int, ...]]:
    P, order = _reflection(original, part)
    return tuple(map(tuple, P.tolist())), order


def _reflection(original, part) -> tuple[np.ndarray, tuple[int, ...]]:
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
    reflection that keeps the bed, so the print-safe construction of `parts/joint_solid.py` (built
    against the bed) is the mirror image of the original's."""
    import itertools

    from ...families.joint_kinds.kinds import print_from_local

    if joint_kind(part) != joint_kind(original) or len(part.sockets) != len(original.sockets):
        raise ValueError(f"{part.name} and {original.name} are not the same kind of joint")
    if part.wall != original.wall:
        raise ValueError(f"walls differ ({part.wall} / {original.wall} mm)")
    skip = ("mirror", "kind", "bolt_hole", "plate_corner", "esc_keepout")
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
    for key in ("bolt_hole", "plate_corner", "esc_keepout"):
        holes = [dict(x.params).get(key) for x in (original, part)]
        if holes != [None, None]:
            if None in holes or np.abs(P @ np.asarray(holes[0], float) - np.asarray(holes[1], float)).max() > MIRROR_TOL:
                raise ValueError(f"the {key.replace('_', ' ')} is not the mirror image of the original's")
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

