"""The registered joint kinds, one tuple (`KINDS`), and the lookups everything else asks: which
kind a joint part is (`kind_of`), which kind a design makes at a node (`planned`), the print
transform and the solid of a joint part. Adding a joint kind: its module (a `kind.JointKind`
subclass) and one line in `KINDS`; a kind claims a part before the kinds after it."""

from __future__ import annotations

import numpy as np

from ...parts.record import PartSpec
from .core_link_flat import CoreLinkFlat
from .core_link_pegs import CoreLinkPegs
from .core_link_tab import CoreLinkTab
from .corner_bottom import CornerBottom
from .corner_top import CornerTop
from .kind import JointKind
from .knee import Knee

KINDS: tuple[JointKind, ...] = (CornerTop(), CornerBottom(), Knee(), CoreLinkTab(), CoreLinkFlat(), CoreLinkPegs())
# The frame's nodes a joint part is planned for, in the part list's order (frame.frame_of makes them).
NODES = ("corner_top", "corner_bottom", "knee", "core_link")


def node_of(part: PartSpec) -> str:
    """The node kind a joint part joins, whatever it is called: `core_link_mirrored` joins core links."""
    return str(dict(part.params).get("kind", part.name))


def resolve(node: str, params: dict, sockets) -> JointKind:
    """The kind of a joint at a `node` with these params and sockets: the first registered kind of
    that node that claims it. ValueError naming the nodes when none does."""
    for k in KINDS:
        if k.node == node and k.claims(params, sockets):
            return k
    raise ValueError(f"unknown joint {node!r}; valid: {', '.join(NODES)}")


def kind_of(part: PartSpec) -> JointKind:
    """The kind of a joint part."""
    return resolve(node_of(part), dict(part.params), part.sockets)


def planned(spec, node: str) -> JointKind:
    """The kind this design makes at its `node` joints: the first registered kind of that node that plans it."""
    for k in KINDS:
        if k.node == node and k.plans(spec):
            return k
    raise ValueError(f"no joint kind plans the {node} of this design")


def core_link(spec) -> JointKind:
    """The core link's kind in this design (core.link)."""
    return planned(spec, "core_link")


def closed_forms_cover(spec) -> bool:
    """Whether the analytic joint model has a closed form for every joint this design makes (the
    pegged link has none: its fast model is the FE's surrogate)."""
    return all(planned(spec, node).closed_form_stiffness for node in NODES)


def labels() -> tuple[str, ...]:
    return tuple(k.label for k in KINDS)


def print_from_local(part: PartSpec) -> np.ndarray:
    """The joint's 4x4 print <- local transform (bed at z = 0): pure numpy, no CAD kernel."""
    return kind_of(part).print_from_local(part)


def solid(part: PartSpec):
    """The joint's solid in print orientation (a `parts.joint_solid.Built`)."""
    from ...parts.joint_solid import Built

    k = kind_of(part)
    return Built(k.solid(part), k.print_from_local(part))
