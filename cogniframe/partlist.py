"""Stage 3: Frame -> the printed parts: which distinct parts, how many, and where their sockets are.

Pure numpy, no CAD. Every part quantity and every socket comes from the frame graph, so the CAD,
the cut list, the mass budget and the stiffness model agree. The part list is every registered
family's plan (families/registry.py), in the registry's order. Each part carries an analytic
estimate of its volume and surface (used by `cogniframe check`, which must not import CadQuery;
the build replaces it with the CAD volume) and the BOM lines of the hardware it implies.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace

from .families import registry
from .frame import Frame
from .parts.record import PartSpec  # noqa: F401  (the part record: the later stages import it from here)
from .spec import Spec


def part_list(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    """All distinct printed parts of the design, in a stable order (the registry's, then each plan's)."""
    planned: list[PartSpec] = []
    for family in registry.FAMILIES:
        if getattr(family, "PLANS_FROM_EARLIER", False):  # placed from earlier families' parts (registry.py)
            planned += family.plan(spec, frame, tuple(planned))
        else:
            planned += family.plan(spec, frame)
    return tuple(_with_digest(p) for p in planned)


def infill_by_material(parts) -> dict[str, float]:
    """The infill each material prints at (the slicer profile is per material): the densest of its
    parts' (the joints and motor mounts solid, the core parts at `core.infill`)."""
    out: dict[str, float] = {}
    for p in parts:
        out[p.material] = max(out.get(p.material, 0.0), p.infill)
    return dict(sorted(out.items()))


def _with_digest(p: PartSpec) -> PartSpec:
    payload = json.dumps([p.name, p.family, p.material, p.infill, [s.__dict__ for s in p.sockets], p.wall,
                          [list(map(str, kv)) for kv in p.params]], sort_keys=True, default=str)
    return replace(p, digest=hashlib.sha256(payload.encode()).hexdigest()[:16])
