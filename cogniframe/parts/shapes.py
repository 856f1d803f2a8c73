"""What a printed part's CAD is made from, and its shape shared between the part build and the joint FE.

`geometry_digest(part)` hashes every PartSpec field the CAD reads; `CAD_VERSION` and the source
files in `PART_CODE` are the rest of what a part's shape depends on. A joint's part build stores
the shape's BREP text under `shape_key(part)` (`shared_brep`), so that the joint FE meshes the
same shape instead of building the CAD again.
"""

from __future__ import annotations

import os
from pathlib import Path

from .record import PartSpec


# Bump when any part's CAD changes shape: it is part of every cache key.
CAD_VERSION = "cad-2025.3"

# Everything the part CAD and its files are made by: editing any of these invalidates the part cache.
PART_CODE = ("parts/*.py", "families/*.py", "families/joint_kinds/*.py", "export/part_files.py", "export/mesh.py",
             "export/step.py", "partlist.py", "numfmt.py")


# PartSpec fields the CAD does not read (where copies go, the mass model's inputs, the BOM): a change
# to them must not rebuild the part. Every other field, including any added later, is in the key.
NOT_CAD = ("placements", "estimate", "hardware", "group", "infill", "digest")


def geometry_digest(part: PartSpec) -> str:
    """Hash of every PartSpec field the part's CAD and file names can depend on."""
    import dataclasses

    from .. import cache

    return cache.key({f.name: getattr(part, f.name) for f in dataclasses.fields(part) if f.name not in NOT_CAD})


SHAPE_KIND = "shapes"  # cache folder of the shared BREP texts


def shape_key(part: PartSpec) -> str:
    """Key of the shape `registry.solid(part)` makes (before any turn on the bed): the part's CAD
    inputs, the CAD code and CadQuery's and OpenCascade's versions."""
    from .. import cache
    from ..stack import installed

    stack = installed()  # looked up once per process
    return cache.key([geometry_digest(part), CAD_VERSION], PART_CODE, f"{stack['cadquery']}/{stack['cadquery-ocp']}")


def brep_text(shape) -> str:
    """The shape as OpenCascade BREP text (CadQuery's `exportBrep`)."""
    import tempfile

    fd, path = tempfile.mkstemp(suffix=".brep")
    os.close(fd)
    try:
        shape.exportBrep(path)
        return Path(path).read_text()
    finally:
        os.unlink(path)


def shared_brep(part: PartSpec) -> str | None:
    """The BREP text of `part`'s shape when a part build of this build (or an earlier one) stored
    it (`build_part_files(share_shape=True)`), else None. The joint FE meshes it instead of
    building the same CAD again (0.1-0.35 s a joint): the text is what building it here gives,
    so the mesh and the stiffness are the same bits either way (tested)."""
    from ..cache import load_text

    return load_text(SHAPE_KIND, shape_key(part), ".brep")
