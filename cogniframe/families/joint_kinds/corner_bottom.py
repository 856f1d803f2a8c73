"""The bottom corner (corner_bottom): a `Corner` with a foot pad on the ground side (the bottom
corners are the feet); in the joint FE the floor holds the pad (its support body)."""

from __future__ import annotations

import numpy as np

from .corner import Corner


class CornerBottom(Corner):
    node = "corner_bottom"
    has_body = True

    def params(self, spec, frame, corner, origin, sockets) -> list[tuple[str, object]]:
        return [("foot", True)]  # the flat pad on the ground side

    def support_faces(self, part, m, tol, curvature):
        """The pad's underside, on the bed in print."""
        return lambda c, n: (c[2] < 1e-3) & (np.abs(n[2]) > 0.99)

