"""Read a rod-and-joint exoskeleton from its CAD (issue 43, the reading half).

    from cogniframe.cadread import read_exoskeleton
    exo = read_exoskeleton("frame.step")          # or a FreeCAD .FCStd
    exo.rods, exo.joints, exo.sockets, exo.warnings

Modules, one idea each: `load` (STEP / FCStd -> named solids in one frame), `rods` (the rod
finder), `sockets` (rod ends and sleeves in the joints), `materials` (part name -> material,
`--materials` YAML), `identify` (names for unnamed solids from reference part files), `read`
(the whole pipeline), `model` (the frozen result), `toframe` (the mapping onto cogniframe's frame).
"""

from .model import Contact, Exoskeleton, Joint, Rod, Socket, as_dict
from .read import exoskeleton_of, read_exoskeleton

__all__ = ["Contact", "Exoskeleton", "Joint", "Rod", "Socket", "as_dict", "exoskeleton_of", "read_exoskeleton"]
