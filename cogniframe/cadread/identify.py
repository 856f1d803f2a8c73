"""Names for unnamed solids, from reference part files (an assembly saved as one compound, like
the authors' `CogniFly-Flex.FCStd`: 82 solids, no names).

Each solid and each reference part (STL or STEP) gets a signature that does not depend on where
the part sits or how it is turned (or mirrored): its volume and its three radii of gyration about
its centroid. A solid takes the name of the reference whose signature is closest, when that is
within `TOL` (relative) and clearly closer than the second best; copies are numbered in the
order they come (`Flex_Foot4_Shorter_1`, `_2`, ...). An STL's signature is its mesh's, so it is
off by the tessellation (well under 1 % for the authors' files).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .load import NamedSolid

TOL = 0.02


@dataclass(frozen=True)
class Signature:
    volume: float
    gyration: tuple[float, float, float]  # sorted, mm

    def error(self, other: "Signature") -> float:
        ev = abs(self.volume - other.volume) / max(other.volume, 1e-9)
        eg = max(abs(a - b) / max(b, 1e-9) for a, b in zip(self.gyration, other.gyration))
        return max(ev, eg)


def _sig(volume: float, inertia: np.ndarray) -> Signature:
    ev = np.clip(np.linalg.eigvalsh(np.asarray(inertia, float)), 0, None)
    # principal moments I1 = V (b2 + c2) etc. -> second moments along the principal axes
    tot = ev.sum() / 2
    sec = np.clip(tot - ev, 0, None) / max(volume, 1e-12)
    return Signature(float(volume), tuple(float(x) for x in np.sort(np.sqrt(sec))))


def solid_signature(solid) -> Signature:
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    g = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid.wrapped, g)
    m = g.MatrixOfInertia()
    inertia = np.array([[m.Value(i, j) for j in (1, 2, 3)] for i in (1, 2, 3)])
    return _sig(abs(g.Mass()), inertia)


def file_signature(path: str | Path) -> Signature:
    """An STL's (its mesh) or a STEP's (its largest solid) signature."""
    p = Path(path)
    if p.suffix.lower() == ".stl":
        import trimesh

        m = trimesh.load(str(p), force="mesh")
        return _sig(abs(float(m.volume)), np.asarray(m.moment_inertia) * (1 if m.volume >= 0 else -1))
    from .load import load_solids

    sols = load_solids(p)
    return solid_signature(max(sols, key=lambda s: abs(s.solid.Volume())).solid)


def best_match(solid, references: dict[str, Signature]) -> tuple[str, float] | None:
    """The closest reference and its error, matched or not (for a report)."""
    s = solid_signature(solid)
    return min(((name, s.error(ref)) for name, ref in references.items()), key=lambda x: x[1], default=None)


def identify(solids: list[NamedSolid], references: dict[str, Signature], tol: float = TOL) -> tuple[list[NamedSolid], dict[str, str]]:
    """(the solids renamed where a reference matches, {new name: old name})."""
    count: dict[str, int] = {}
    picks = []
    for ns in solids:
        s = solid_signature(ns.solid)
        ranked = sorted((s.error(ref), name) for name, ref in references.items())
        # a close second that is the same shape (an STL and a STEP of one part, a mirrored pair)
        # does not make the pick ambiguous
        ok = bool(ranked) and ranked[0][0] <= tol and (
            len(ranked) < 2 or ranked[1][0] > 2 * ranked[0][0]
            or references[ranked[1][1]].error(references[ranked[0][1]]) <= tol)
        picks.append(ranked[0][1] if ok else None)
        if ok:
            count[ranked[0][1]] = count.get(ranked[0][1], 0) + 1
    seen: dict[str, int] = {}
    out, renamed = [], {}
    for ns, pick in zip(solids, picks):
        if pick is None:
            out.append(ns)
            continue
        seen[pick] = seen.get(pick, 0) + 1
        name = pick if count[pick] == 1 else f"{pick}_{seen[pick]}"
        renamed[name] = ns.name
        out.append(NamedSolid(name, ns.solid))
    return out, renamed
