"""Fabrication package step of `build` (issue 6): plates, slicer check, BOM, renders, report.

Filled in as those modules land; until then it writes nothing.
"""

from __future__ import annotations


def write_fabrication(spec, check, built, out, console) -> None:
    return None
