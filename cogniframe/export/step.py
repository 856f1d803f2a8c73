"""Per-part STEP files that are byte-identical for identical geometry.

OpenCASCADE's STEP writer stamps the file with the wall-clock time (FILE_NAME) and names each
product "Open CASCADE STEP translator 7.9 N" with N counting the files written by the process;
both are rewritten here (a fixed timestamp, the part's name), so the same params give the same
bytes whatever order or process the parts were built in.
"""

from __future__ import annotations

import re
from pathlib import Path

FIXED_TIME = "2000-01-01T00:00:00"
_TIME = re.compile(r"(FILE_NAME\([^;]*?,\s*')\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(')", re.S)
_PRODUCT = re.compile(r"Open CASCADE STEP translator [\d.]+ \d+")


def normalize(text: str, name: str) -> str:
    """Strip the run-dependent parts of a STEP file's text."""
    safe = re.sub(r"[^A-Za-z0-9_.-]", "_", name)
    text = _TIME.sub(lambda m: m.group(1) + FIXED_TIME + m.group(2), text, count=1)
    return _PRODUCT.sub(safe, text)


def write_step(shape, path: str | Path, name: str) -> Path:
    """Write `shape` (cq.Shape/Workplane) as STEP (AP214) with a deterministic header."""
    import cadquery as cq

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    cq.exporters.export(shape, str(tmp), exportType="STEP")
    text = tmp.read_text(encoding="latin-1")
    tmp.unlink()
    path.write_text(normalize(text, name), encoding="latin-1", newline="\n")
    return path


def normalize_file(path: str | Path, name: str) -> None:
    path = Path(path)
    path.write_text(normalize(path.read_text(encoding="latin-1"), name), encoding="latin-1", newline="\n")
