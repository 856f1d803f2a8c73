"""Read a rod-and-joint exoskeleton from its CAD (issue 43, the reading half).

    from cogniframe.cadread import read_exoskeleton
    exo = read_exoskeleton("frame.step")          # or a FreeCAD .FCStd
    exo.rods, exo.joints, exo.sockets, exo.warnings

Modules, one idea each: `load` (STEP / FCStd -> named solids in one frame), `rods` (the rod
finder), `sockets` (rod ends and sleeves in the joints), `materials` (part name -> material,
`--materials` YAML), `identify` (names for unnamed solids from reference part files), `read`
(the whole pipeline), `model` (the frozen result, `as_dict` for JSON), `toframe` (the mapping onto
cogniframe's frame: `frame.Rod`/`RodEnd`/`Node`, `parts.record.Socket`), `geometry` (B-rep facts:
cylinders, B-spline cylinders included, cones, boxes, contacts). `python -m cogniframe.cadread.summary
ASSEMBLY [--materials FILE] [--json]` prints what it finds.

Checked: cogniframe's own `assembly.step` (carbon and bamboo presets) reads back as the frame's 28
rods (lengths to 1e-10 mm), 56 sockets (rod ends, directions, depths, bores to 1e-6) and the 8
motor-mount sleeves (`tools/cadread_roundtrip.py`); the authors' `CogniFly-Flex.FCStd`: 28 rods,
56 rod ends all in sockets, 8 sleeves (`tools/authors_frame.py`).
"""

from .found import Contact, Exoskeleton, Joint, Rod, Socket, as_dict
from .read import exoskeleton_of, read_exoskeleton

__all__ = ["Contact", "Exoskeleton", "Joint", "Rod", "Socket", "as_dict", "exoskeleton_of", "read_exoskeleton"]
