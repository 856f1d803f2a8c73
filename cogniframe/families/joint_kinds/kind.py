"""What a joint kind is: the hooks every kind of TPU joint answers (`JointKind`), one short
subclass per kind in this package, one tuple of them in `kinds.py`.

A kind joins one kind of frame node (`node`: corner_top, corner_bottom, knee, core_link; the frame
makes the nodes) in one way (`variant`: the core link's bolted tab, its flat tab on level arms, its
pegs). The joint family (families/joint.py) places a part per node kind and asks the kind:

- plan: `plans(spec)` (whether this design makes its node this way), `claims(params, sockets)`
  (whether a planned part is this kind: the registry asks each kind in turn), `params` and
  `hardware` (what the part record carries), `refuse` (a design it cannot make: a UserError
  naming the params key);
- closed form: `estimate(spec, sockets, params)`, the volume and areas of the solid it builds;
- print: `print_from_local(part)` (pure numpy, no CAD kernel) and `solid(part)` (CadQuery,
  imported only when asked for; built in print orientation from parts/joint_solid.py's pieces);
- stiffness: `has_body` (its super-element holds a support body at the joint centre), `hinged`
  (one socket hangs on a living hinge), `closed_form_stiffness` (the analytic joint model has a
  closed form for it), `support_faces(part, m, tol, curvature)` (the FE's support tie: which mesh
  faces the support body holds), `surrogate_family`, `surrogate_features(part)`,
  `surrogate_reads(param)` and `surrogate_reads_wall` (which fit of the joint surrogate it belongs
  to, and what of it the fit's features read);
- the core's side (core links): `plate_bolts(spec)` (the plate's link holes) and
  `peg_axes(part)` (the pegs the plate's tubes hold);
- assembly words (the core links): `fitted` (how the link goes on: "bolted", "pressed in"),
  `fixing_words` (how to fix it to the plate) and `stacking_words` (how the plate, spacer and
  holder stack where the link changes that).
"""

from __future__ import annotations

import numpy as np

from ...parts.joint_plan import PSocket, map_sockets
from ...parts.record import Estimate, HardwareLine, PartSpec


class JointKind:
    """The defaults are a joint with no support body, no hinge, a closed-form stiffness, no
    params or hardware of its own."""

    node: str = ""  # the frame node kind it joins
    variant: str = ""  # how, among the kinds of one node ("" for the only one)
    has_body = False
    hinged = False
    closed_form_stiffness = True
    chiral = False  # always a part for fl/rr and its mirror image for fr/rl, whatever the box
    fitted = "glued"  # how it goes on (the assembly steps' words for the core links)

    @property
    def label(self) -> str:
        """The kind's name: its node, and its variant where the node has several."""
        return f"{self.node}_{self.variant}" if self.variant else self.node

    @property
    def surrogate_family(self) -> str:
        """The joint surrogate's fit this kind's parts belong to (analysis/joints/surrogate.py)."""
        return self.node

    def __repr__(self) -> str:
        return f"<joint kind {self.label}>"

    # -- plan ------------------------------------------------------------------------------------

    def plans(self, spec) -> bool:
        """Whether this design makes its node this way."""
        return True

    def claims(self, params: dict, sockets) -> bool:
        """Whether a part of its node, with these params and sockets, is this kind."""
        return True

    def params(self, spec, frame, corner: str, origin: np.ndarray, sockets) -> list[tuple[str, object]]:
        """The part's params of this kind (after the common hinge thickness, kind and mirror)."""
        return []

    def hardware(self, spec, frame) -> tuple[HardwareLine, ...]:
        return ()

    def refuse(self, spec, sockets, params: dict) -> None:
        """Raise the spec's error when the design asks for a joint this kind cannot make."""

    # -- closed form, print, solid -------------------------------------------------------------

    def estimate(self, spec, sockets, params: dict) -> Estimate:
        raise NotImplementedError

    def print_from_local(self, part: PartSpec) -> np.ndarray:
        raise NotImplementedError

    def solid(self, part: PartSpec):
        """The solid in print orientation (a cq shape); `kinds.solid` wraps it in a `Built`."""
        raise NotImplementedError

    def in_print(self, part: PartSpec) -> tuple[np.ndarray, list[PSocket], float]:
        """(the print <- local transform, the sockets in print, the sleeves' radius)."""
        m = self.print_from_local(part)
        return m, map_sockets(part, m), (part.sockets[0].bore + 2 * part.wall) / 2

    # -- stiffness -------------------------------------------------------------------------------

    def support_faces(self, part: PartSpec, m: np.ndarray, tol: float, curvature: int):
        """``select(centroids, normals)`` of the mesh faces (print coordinates, `m` the print <-
        local transform; `tol` the bores' tolerance, `curvature` the mesh's elements per circle)
        the joint FE's support body holds; None without a support body."""
        return None

    def surrogate_features(self, part: PartSpec) -> tuple[list[str], list[float]]:
        """Shape features of its own the surrogate fits on, after the sockets'."""
        return [], []

    # -- the core's side (core links) --------------------------------------------------------------

    def plate_bolts(self, spec) -> list[tuple[float, float]]:
        """The bolts that fix it to the core plate, (x, y) from the plate's centre: the plate's
        link holes, the spacer's nut traps."""
        return []

    def peg_axes(self, part: PartSpec) -> tuple:
        """The axes of the pegs it presses into the core (parts/peg_plan.py `PegAxis`), in its own
        frame: the core plate's tubes follow them."""
        return ()

    # -- assembly words ----------------------------------------------------------------------------

    def fixing_words(self, which: str, spacer: str | None) -> str:
        """The assembly step's sentence fixing this joint (`which`: the mirrored parts' note)."""
        return ""

    def stacking_words(self, spacer: str | None) -> str | None:
        """How the core's plate, spacer and holder stack with this joint, where it changes that;
        None: the usual stack."""
        return None

    # -- the surrogate's features ------------------------------------------------------------------

    surrogate_reads_wall = True  # joints.wall is a feature (the pegged link's columns have their own)

    def surrogate_reads(self, param: str) -> bool:
        """Whether the surrogate's features include this part param (the solid reads it)."""
        return param != "hinge_thickness"
