"""The socket-fit coupon: what `cogniframe coupon` does, from Python.

    c = coupon_file("params/carbon.yaml", "out/carbon-coupon.stl")   # Coupon: the STL, the clearances

One row of sockets stepping the fit clearance, each labelled, printed in the joints' material:
the loosest blind socket that still grips a rod is the `joints.fit_clearance` of that material,
the tightest sleeve a rod slides through the `joints.sleeve_clearance`. The STL is written only
where no file is, or over a file cogniframe wrote.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import UserError


@dataclass(frozen=True)
class Coupon:
    path: Path  # the STL written
    clearances_mm: tuple[float, ...]  # one socket each, rod-to-hole, in the order printed
    material: str  # the joints' material, which the fit keys are named by (joints.fit_clearance.<material>)


def coupon_file(params: str | Path, out: str | Path | None = None) -> Coupon:
    """Write the coupon of the params file `params` to `out` (default out/<name>-coupon.stl).
    The params are read as `build` reads them before it starts (the schema and its rules; the
    coupon does not need the frame to exist). Raises UserError naming the file and the fix."""
    from ..export.coupon import write_coupon
    from ..outdir import claim_file
    from . import _load, _params_error

    design = _load(params, validate=False)
    spec = design.spec
    path = Path(out) if out is not None else Path("out") / f"{spec.name}-coupon.stl"
    claim_file(path)
    try:
        with spec.blamed():
            written, clearances = write_coupon(spec, path)
    except UserError as e:
        if e.key is None:
            raise
        raise _params_error(e, design.source) from None
    return Coupon(written, tuple(clearances), spec.joints.material)
