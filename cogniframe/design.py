"""The design: everything the params give without CAD: the validated spec,
its frame graph, the printed parts and the rod cut list (`design(spec)`; a design that cannot
exist is refused here with the key to change).
"""

from __future__ import annotations

from dataclasses import dataclass

from . import cutlist as cutlist_mod
from . import frame as frame_mod
from . import partlist as partlist_mod
from .spec import Spec


@dataclass(frozen=True)
class Derived:
    """Everything derived from the params without CAD."""

    spec: Spec
    frame: frame_mod.Frame
    parts: tuple[partlist_mod.PartSpec, ...]
    cut: cutlist_mod.CutList


def design(spec: Spec) -> Derived:
    frame = frame_mod.frame_of(spec)
    parts = partlist_mod.part_list(spec, frame)
    _check_printer_fit(spec, parts)
    cut = cutlist_mod.cut_list(spec, frame)
    return Derived(spec, frame, parts, cut)


def _check_printer_fit(spec: Spec, parts) -> None:
    """Every printed part's print-orientation envelope must fit the bed (it may turn on the bed)."""
    bx, by, bz = spec.printer.bed
    for p in parts:
        ex, ey, ez = p.estimate.envelope
        if max(ex, ey) > max(bx, by) or min(ex, ey) > min(bx, by) or ez > bz:
            raise spec.error(
                "printer.bed",
                f"the {p.name} ({ex:.0f} x {ey:.0f} x {ez:.0f} mm as printed) does not fit the "
                f"{bx:g} x {by:g} x {bz:g} mm bed", "set printer.bed to your printer's build volume, "
                "or shrink the part (for the battery holder: core.battery; for the core plate: core.plate_size)")
