"""Per-part STEP files that are byte-identical for identical geometry.

OpenCASCADE's STEP writer stamps the file with the wall-clock time (FILE_NAME), names each
product "Open CASCADE STEP translator 7.9 N" with N counting the files written by the process, and
numbers assembly occurrences with a process-wide counter; all are rewritten here (a fixed timestamp, the part's name), so the same params give the same
bytes whatever order or process the parts were built in.
"""

from __future__ import annotations

import re
from pathlib import Path

FIXED_TIME = "2000-01-01T00:00:00"
_TIME = re.compile(r"(FILE_NAME\([^;]*?,\s*')\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(')", re.S)
_PRODUCT = re.compile(r"Open CASCADE STEP translator [\d.]+ \d+")
_NAUO = re.compile(r"NEXT_ASSEMBLY_USAGE_OCCURRENCE\('\d+'")


def normalize(text: str, name: str) -> str:
    """Strip the run-dependent parts of a STEP file's text."""
    safe = re.sub(r"[^A-Za-z0-9_.-]", "_", name)
    # One entity per line: the writer's line wrapping depends on the lengths of the numbers below.
    text = re.sub(r"\n[ \t]+", "", text)
    text = _TIME.sub(lambda m: m.group(1) + FIXED_TIME + m.group(2), text, count=1)
    text = _PRODUCT.sub(safe, text)
    # Assembly occurrences are numbered by a process-wide counter: renumber them in file order.
    counter = iter(range(1, 1 << 30))
    text = _NAUO.sub(lambda m: f"NEXT_ASSEMBLY_USAGE_OCCURRENCE('{next(counter)}'", text)
    return _canonical_styles(text)


_LINE = re.compile(r"^#(\d+) = (.*)$")
_REF = re.compile(r"#(\d+)")


def _canonical_styles(text: str) -> str:
    """Put the colour (presentation style) block in a canonical order.

    XCAF writes one style group per coloured shape, in the order of an address-keyed map, and
    defines each COLOUR_RGB in the first group that uses it: the same assembly comes out with the
    groups shuffled. Sort the colours by value and the groups by the shape they style, then
    renumber the block's entities in that order. Left alone if anything outside the block refers
    into it.
    """
    lines = text.split("\n")
    start = next((i for i, ln in enumerate(lines) if "MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION" in ln), None)
    if start is None:
        return text
    end = next(i for i in range(start, len(lines)) if lines[i].startswith("ENDSEC"))
    parsed = [_LINE.match(ln) for ln in lines[start:end]]
    if not all(parsed):
        return text
    ids = {int(m.group(1)) for m in parsed}
    for ln in lines[:start] + lines[end:]:
        if any(int(r) in ids for r in _REF.findall(ln.split(" = ", 1)[-1])):
            return text
    colours, groups = [], []
    for m in parsed:
        body = m.group(2)
        if body.startswith("COLOUR_RGB"):
            colours.append(m)
        elif body.startswith("MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION"):
            groups.append([m])
        else:
            groups[-1].append(m)

    def key(group):
        styled = next((g.group(2) for g in group if g.group(2).startswith("STYLED_ITEM")), "")
        refs = [int(r) for r in _REF.findall(styled)] + [int(r) for r in _REF.findall(group[0].group(2))]
        return refs[-1:] + refs

    order = sorted(colours, key=lambda m: m.group(2)) + [m for g in sorted(groups, key=key) for m in g]
    first = min(ids)
    new = {int(m.group(1)): first + k for k, m in enumerate(order)}

    def ren(body: str) -> str:
        return _REF.sub(lambda r: f"#{new.get(int(r.group(1)), int(r.group(1)))}", body)

    block = [f"#{new[int(m.group(1))]} = {ren(m.group(2))}" for m in order]
    return "\n".join(lines[:start] + block + lines[end:])


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
