"""What a printed joint is to the stiffness model: the terms the closed forms, the solid FE
and the mirroring share.

- the printed TPU: ``TPU_PRINTED_MODULUS_FACTOR`` times its datasheet E and G -- the one
  calibration number of the whole stiffness model (docs/stiffness-model.md) -- and its
  elongation at break;
- the rod-bore interface layer (`interface`), ``h_i = max(fit_clearance, 0) / 2 +
  printer.layer_height / 2`` thick: the radial clearance plus the printed hole's surface
  roughness (layer steps about one layer height peak to valley), with normal stiffness E / h_i
  and shear stiffness G / h_i per unit area. A looser fit is a thicker, softer interface; an
  interference fit is the roughness alone;
- what kind a joint part is (`joint_kind`: its kind in families/joint_kinds/, which says whether
  it has a support body and a living hinge), which socket of a knee hangs on the hinge and the
  hinge's size;
- the super-element every method produces (`JointStiffness`, with its cache JSON): a 6n x 6n
  stiffness over n rigid reference bodies in the part's local frame -- every rod in its socket,
  referenced at the socket mouth, plus for some joints a support body at the joint centre (the
  foot pad on the floor, the core link's bolted tab).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ...families.joint_kinds.kinds import kind_of

# ------------------------------------------------------------------------------------------
# THE calibration: effective modulus of printed TPU (100 % infill, 0.2 mm layers) relative to
# its datasheet value (Ultimaker TPU 95A, E = 26 MPa). Set ONCE, on the frame the paper measured:
# the authors' own CogniFly (thecognifly/CogniFly-STL, CogniFly_v8_Crash_Tests, CogniFly-Flex.FCStd)
# read by `cogniframe analyse`, each of its printed joints' solid FE condensed at its sockets,
# gives the paper's static 7040 N/m at this factor (`exoframe.calibrate`; `tools/authors_frame.py
# --analyse`). It does not move when cogniframe's joints change: the presets' k are predictions.
# Printed TPU is softer than moulded test bars (voids between extrusion lines, weak inter-layer
# bond, anisotropy).
# The derivation and the history of the earlier per-preset fits (0.238-0.3349) are in
# docs/stiffness-model.md, "The calibration from the authors' frame".
TPU_PRINTED_MODULUS_FACTOR = 0.4881
# ------------------------------------------------------------------------------------------

TPU_NU = 0.48  # Poisson's ratio of TPU 95A (nearly incompressible elastomer)
TPU_ELONGATION_AT_BREAK = 5.8  # Ultimaker TPU 95A TDS: 580 % elongation at break (ISO 527)


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

    @cached_property
    def matrix(self) -> np.ndarray:
        """K as an array, made once per object (the frame model reads it for every build) and
        read-only, so no caller can change what the next one reads."""
        m = np.array(self.K, dtype=float)
        m.setflags(write=False)
        return m

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


# -- joint kinds --------------------------------------------------------------------------------

def joint_kind(part):
    """What a joint part is, whatever it is called (`core_link_mirrored` is a core link): its kind
    (families/joint_kinds/)."""
    return kind_of(part)


def _has_body(part) -> bool:
    return joint_kind(part).has_body


def hinged_socket(part) -> int | None:
    """Index of the knee's hinged (upper-leg) socket: the leg making the larger angle with the arms
    (any knee part: `knee_mirrored`, a rectangle's fr/rl knee, is hinged too)."""
    if not joint_kind(part).hinged:
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
    """(web length, web width, thickness) of the knee's living hinge, mm (as parts/joint_plan.py plans it and parts/joint_solid.py draws it)."""
    from ...parts.joint_plan import knee_hinge

    h = knee_hinge(part)
    return float(np.linalg.norm(h.end - h.start)), float(h.height), float(h.thickness)


def _block_rot(r: np.ndarray) -> np.ndarray:
    """6 x 6 rotation of one body's (displacement, rotation) by the 3 x 3 `r`."""
    t = np.zeros((6, 6))
    t[:3, :3] = t[3:, 3:] = r
    return t

