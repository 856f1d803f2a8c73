"""`cogniframe coupon`: write the socket-fit test print (see parts/coupon_solid.py for the geometry)."""

from __future__ import annotations

from pathlib import Path

from ..spec import Spec


def write_coupon(spec: Spec, path: str | Path) -> tuple[Path, tuple[float, ...]]:
    """Write the coupon STL to `path` (watertight, deterministic). Returns (path, clearances in mm)."""
    from ..parts import coupon_solid
    from .mesh import tessellate, write_stl

    path = Path(path)
    built = coupon_solid.solid(spec)
    mesh = tessellate(built.shape)  # measured before writing: a coupon refused for the bed leaves no file
    bed = spec.printer.bed
    if any(e > b + 1e-6 for e, b in zip(mesh.extents, bed)):
        from ..errors import UserError

        raise UserError(f"coupon: {mesh.extents[0]:.0f} x {mesh.extents[1]:.0f} x {mesh.extents[2]:.0f} mm does not fit the "
                        f"{bed[0]:g} x {bed[1]:g} x {bed[2]:g} mm bed. Fix: set printer.bed or reduce joints.socket_depth.", key="printer.bed")
    write_stl(mesh, path, name="coupon")
    return path, coupon_solid.CLEARANCES
