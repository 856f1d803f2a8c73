"""Clash check: does anything in the aircraft occupy the same space, or sit in a propeller's way?

A pure function over named solids (trimesh meshes with a 4x4 world transform each):

* every pair of solids may overlap by less than `tolerance_mm3` (0.5 mm^3: tessellation noise).
  A rod in its socket is no exception unless the socket is a declared press fit (`allowed`: the
  pair's designed interference volume, a hole narrower than its rod); a socket that clears its
  rod overlaps it by ~0 like any other pair;
* every propeller disc (a body with `disc` set) must clear every other body by `prop_margin` mm,
  except the bodies named in `ignore` (its own motor, on whose shaft it sits);
* every keep-out volume (analysis/fit_check.keepouts: a screw's or nut's driver, the battery's
  slide path) overlaps no body fitted by its stage (`Body.stage`, fasteners.STAGES) but those it
  exempts by less than the tolerance.

Booleans and gaps are manifold3d's (`^` intersection volume, `min_gap`), after an axis-aligned
bounding-box prefilter (grown by the margin for the discs), so only neighbours are tested.

A pair with a rod is intersected in a frame turned so that the rod runs along z
(`_turn_to_z`): manifold3d classifies vertices by vertical rays, and a slanted rod's long facets
have bounding boxes that every ray through the part meets, so turned pairs are tens of times
faster (docs/measurements.md). The volume is the same solid's; only the rounding differs, so a real overlap comes out the
same to ~1e-12, and so does an empty one (0.0). What moves is the noise of touching faces (a
rod end on its socket floor: ~1e-6 mm^3 either way, printed as 0.000). The carbon and bamboo
checks give the same clash.json, largest overlap included, as the world-frame booleans.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, MutableMapping, Sequence

import numpy as np

TOLERANCE_MM3 = 0.5


@dataclass(frozen=True, eq=False)
class Body:
    name: str
    kind: str  # part | rod | vitamin | propeller
    mesh: object  # trimesh.Trimesh in its own frame
    transform: np.ndarray | None = None  # 4x4 world <- mesh; None = identity
    disc: bool = False  # a propeller disc: tested for clearance, not only overlap
    stage: str = ""  # when it is fitted (fasteners.STAGES; "" = the first): a keep-out sees it from then on


@dataclass(frozen=True)
class Clash:
    a: str
    b: str
    kind: str  # "overlap" | "prop_margin" | a keep-out's rule: "driver" | "battery_path" (a: the keep-out)
    volume_mm3: float  # overlap volume (0 for a margin clash that does not touch)
    gap_mm: float | None = None  # propeller clearance found (margin clashes)

    def message(self, margin: float) -> str:
        if self.kind == "overlap":
            return f"clash: {self.a} and {self.b} overlap by {self.volume_mm3:.2f} mm^3"
        if self.kind == "driver":
            return (f"fit: {self.a.removeprefix('driver_')} cannot be turned: its driver (along the screw's axis, from "
                    f"outside) hits {self.b} ({self.volume_mm3:.2f} mm^3)")
        if self.kind == "battery_path":
            return (f"fit: {self.b} sits in the battery's slide path ({self.volume_mm3:.2f} mm^3 of it): the pack cannot "
                    "slide from the holder's open end to its seat")
        return (f"clash: propeller {self.a} comes within {self.gap_mm:.1f} mm of {self.b} "
                f"(needs {margin:g} mm, requirements.prop_margin); overlap {self.volume_mm3:.2f} mm^3")


@dataclass(frozen=True)
class ClashResult:
    clashes: tuple[Clash, ...]
    bodies: int
    pairs_total: int
    pairs_tested: int  # survived the bounding-box prefilter
    tolerance_mm3: float
    prop_margin_mm: float
    max_overlap: tuple[str, str, float] = ("", "", 0.0)  # largest overlap seen (a clash or not)
    prop_gaps: tuple[tuple[str, str, float], ...] = field(default=())  # each disc's nearest body and gap
    keepouts: int = 0  # keep-out volumes tested (drivers, the battery's slide path)

    @property
    def ok(self) -> bool:
        return not self.clashes

    def messages(self) -> list[str]:
        return [c.message(self.prop_margin_mm) for c in self.clashes]

    def to_dict(self) -> dict:
        return {"ok": self.ok, "bodies": self.bodies, "pairs_total": self.pairs_total, "pairs_tested": self.pairs_tested,
                "tolerance_mm3": self.tolerance_mm3, "prop_margin_mm": self.prop_margin_mm,
                "max_overlap": {"a": self.max_overlap[0], "b": self.max_overlap[1], "volume_mm3": round(self.max_overlap[2], 3)},
                "prop_gaps": [{"propeller": p, "nearest": n, "gap_mm": round(g, 2)} for p, n, g in self.prop_gaps],
                "keepouts": self.keepouts,
                "clashes": [{"a": c.a, "b": c.b, "kind": c.kind, "volume_mm3": round(c.volume_mm3, 3),
                             "gap_mm": None if c.gap_mm is None else round(c.gap_mm, 2)} for c in self.clashes]}


def from_dict(d: dict) -> ClashResult:
    """The inverse of ClashResult.to_dict (for the build cache)."""
    mo = d["max_overlap"]
    return ClashResult(tuple(Clash(c["a"], c["b"], c["kind"], c["volume_mm3"], c["gap_mm"]) for c in d["clashes"]), d["bodies"],
                       d["pairs_total"], d["pairs_tested"], d["tolerance_mm3"], d["prop_margin_mm"],
                       (mo["a"], mo["b"], mo["volume_mm3"]), tuple((g["propeller"], g["nearest"], g["gap_mm"]) for g in d["prop_gaps"]),
                       d.get("keepouts", 0))


def _mesh_manifold(mesh):
    """A mesh as a manifold3d solid, in its own frame."""
    import manifold3d as m3

    return m3.Manifold(m3.Mesh(np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32)))


def _manifold(body: Body, base=None):
    """The body as a manifold3d solid in the world frame; `base`: its mesh's Manifold, if made."""
    if base is None:
        base = _mesh_manifold(body.mesh)
    if body.transform is not None:
        return base.transform(np.asarray(body.transform, float)[:3, :4])
    return base


def _long_axis(man) -> np.ndarray:
    """Unit direction of a solid's largest extent (a rod's axis): principal axis of its vertices."""
    v = np.asarray(man.to_mesh().vert_properties, float)[:, :3]
    return np.linalg.svd(v - v.mean(axis=0), full_matrices=False)[2][0]


def _turn_to_z(d: np.ndarray) -> np.ndarray:
    """3x4 rotation taking unit vector d to +z (Rodrigues; the identity if d is already along z)."""
    z = np.array([0.0, 0.0, 1.0])
    c = np.cross(d, z)
    s = float(np.linalg.norm(c))
    if s < 1e-12:
        R = np.eye(3) if d[2] > 0 else np.diag([1.0, -1.0, -1.0])
    else:
        k = c / s
        K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
        R = np.eye(3) + s * K + (1.0 - float(d @ z)) * (K @ K)
    return np.c_[R, np.zeros(3)]


def body_key(body: Body, mesh_hash: str | None = None) -> str:
    """sha256 of what a pair test reads of a body: its mesh, transform and whether it is a disc
    (`mesh_hash`: the mesh's hash when already known, as for the copies of one part)."""
    import hashlib

    h = hashlib.sha256((mesh_hash or _mesh_hash(body.mesh)).encode())
    if body.transform is not None:
        h.update(np.ascontiguousarray(body.transform, np.float64).tobytes())
    h.update(b"disc" if body.disc else b"solid")
    return h.hexdigest()


def _mesh_hash(mesh) -> str:
    import hashlib

    h = hashlib.sha256(np.ascontiguousarray(mesh.vertices, np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, np.int64).tobytes())
    return h.hexdigest()


def _pair_key(ka: str, kb: str, margin: float | None) -> str:
    from .. import cache

    return cache.key([ka, kb, margin])


def check(bodies: Sequence[Body], tolerance_mm3: float = TOLERANCE_MM3, prop_margin: float = 5.0,
          ignore: frozenset[frozenset[str]] = frozenset(), memo: MutableMapping[str, list] | None = None,
          allowed: Mapping[frozenset[str], float] | None = None, keepouts: Sequence = ()) -> ClashResult:
    """Test every pair of `bodies`; `ignore` holds name pairs not tested at all (a disc and its motor);
    `allowed` the pairs that overlap by design (a rod pressed into a narrower socket) and by how
    much, mm^3: such a pair clashes only past that volume plus the tolerance.

    `memo`: pair results from earlier checks (key -> [overlap mm^3, gap mm or None]), read and
    filled here; the key is the hash of both bodies' meshes and transforms (`body_key`) and, for a
    disc, the margin. A rebuild after one part changed only re-tests the pairs that hold a copy of
    it; the result is the same as testing every pair again.

    `keepouts`: analysis/fit_check.Keepout volumes, each tested against the bodies fitted by its
    stage that it does not exempt (not memoised: a few dozen small cylinders)."""
    names = [b.name for b in bodies]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise ValueError(f"clash check: duplicate body names {dup}")
    bases: dict[int, object] = {}  # the copies of a part share one mesh: one Manifold of it
    mans = []
    for b in bodies:
        if id(b.mesh) not in bases:
            bases[id(b.mesh)] = _mesh_manifold(b.mesh)
        mans.append(_manifold(b, bases[id(b.mesh)]))
    turns: dict[int, object] = {}  # a rod's turn to z: (3x4, the rod turned)
    bb = np.array([m.bounding_box() for m in mans], float).reshape(-1, 6)
    lo, hi = bb[:, :3], bb[:, 3:]
    # apart[g][i, k]: i's box starts past k's (grown by g), on some axis; a pair is skipped when
    # either starts past the other
    apart = {g: (lo[:, None, :] - g > hi[None, :, :]).any(axis=2) for g in (0.0, prop_margin)}
    keys: list[str | None] = [None] * len(bodies)
    if memo is not None:
        meshes: dict[int, str] = {}  # the copies of a part share one mesh: hash it once
        for i, b in enumerate(bodies):
            if id(b.mesh) not in meshes:
                meshes[id(b.mesh)] = _mesh_hash(b.mesh)
            keys[i] = body_key(b, meshes[id(b.mesh)])
    clashes: list[Clash] = []
    tested = 0
    worst = ("", "", 0.0)
    gaps: dict[str, tuple[str, float]] = {}
    n = len(bodies)
    for i in range(n):
        for k in range(i + 1, n):
            a, b = bodies[i], bodies[k]
            if frozenset((a.name, b.name)) in ignore:
                continue
            disc = a if a.disc else b if b.disc else None
            grow = prop_margin if disc is not None else 0.0
            if apart[grow][i, k] or apart[grow][k, i]:
                continue
            tested += 1
            pk = None if memo is None else _pair_key(keys[i], keys[k], prop_margin if disc is not None else None)
            known = memo.get(pk) if pk is not None else None
            if known is not None:
                vol, gap = float(known[0]), known[1]
            else:
                rod = i if a.kind == "rod" else k if b.kind == "rod" else None
                if rod is None:
                    vol = float((mans[i] ^ mans[k]).volume())
                else:
                    if rod not in turns:
                        turn = _turn_to_z(_long_axis(mans[rod]))
                        turns[rod] = (turn, mans[rod].transform(turn))
                    turn, turned = turns[rod]
                    other = mans[k if rod == i else i].transform(turn)
                    vol = float((turned ^ other).volume())
                gap = None
                if disc is not None:
                    gap = 0.0 if vol > 0 else float(mans[i].min_gap(mans[k], prop_margin + 20.0))
                if pk is not None:
                    memo[pk] = [vol, gap]
            # compared at the precision clash.json states (0.001 mm3, 0.01 mm), ties by name: mirror-image
            # pairs overlap by the same volume up to the last bits, which differ between machines
            if vol > 0 and (-round(vol, 3), a.name, b.name) < (-round(worst[2], 3), worst[0], worst[1]):
                worst = (a.name, b.name, vol)
            if disc is not None:
                other = b if disc is a else a
                if disc.name not in gaps or (round(gap, 2), other.name) < (round(gaps[disc.name][1], 2), gaps[disc.name][0]):
                    gaps[disc.name] = (other.name, gap)
                if gap < prop_margin:
                    clashes.append(Clash(disc.name, other.name, "prop_margin", vol, gap))
            elif vol >= tolerance_mm3 + (allowed or {}).get(frozenset((a.name, b.name)), 0.0):
                clashes.append(Clash(a.name, b.name, "overlap", vol))
    clashes += _keepout_clashes(bodies, mans, lo, hi, keepouts, tolerance_mm3)
    clashes.sort(key=lambda c: (-round(c.volume_mm3, 3), c.a, c.b))
    return ClashResult(tuple(clashes), n, n * (n - 1) // 2, tested, tolerance_mm3, prop_margin, worst,
                       tuple((p, o, g) for p, (o, g) in sorted(gaps.items())), len(keepouts))


def _keepout_clashes(bodies, mans, lo, hi, keepouts, tolerance_mm3: float) -> list[Clash]:
    """Each keep-out against the bodies fitted by its stage (bounding boxes first)."""
    if not keepouts:
        return []
    from ..fasteners import STAGES
    from ..vitamins import _prims_manifold

    rank = {s: i for i, s in enumerate(STAGES)}
    out = []
    for ko in keepouts:
        man = _prims_manifold(ko.prims, 48)
        kb = np.asarray(man.bounding_box(), float)
        klo, khi = kb[:3], kb[3:]
        for i, b in enumerate(bodies):
            if b.name in ko.exempt or rank.get(b.stage, 0) > rank[ko.stage]:
                continue
            if (klo > hi[i]).any() or (lo[i] > khi).any():
                continue
            vol = float((man ^ mans[i]).volume())
            if vol >= tolerance_mm3:
                out.append(Clash(ko.name, b.name, ko.rule, vol))
    return out
