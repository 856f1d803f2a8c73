"""Print plates as OrcaSlicer / Bambu Studio 3MF files: each object with its filament and print settings.

OrcaSlicer and Bambu Studio read a 3MF with their own loader (`bbs_3mf.cpp`), which takes per-object
settings only from `Metadata/model_settings.config`: one `<object id=N>` per object of
`3D/3dmodel.model` (the ids must match), whose `<metadata key=K value=V/>` lines become that object's
settings (`name` names it; any other key must be one of their print settings, or the load fails),
and `<part id=M>` lines name the mesh objects it is made of. A PrusaSlicer 3MF carries its settings
in `Metadata/Slic3r_PE.config` instead, which these loaders do not read: they open it as "geometry
data only" and slice the TPU joints at the default infill.

What the loader is told, and why:
- `Application` is `cogniframe`. OrcaSlicer sends any 3MF whose Application names PrusaSlicer to its
  PrusaSlicer loader (which ignores model_settings.config); only an Application starting with
  `BambuStudio-` makes them load `Metadata/project_settings.config` as well, and then their GUI wants
  a complete Bambu vendor printer config. cogniframe does not pretend to be Bambu Studio, so it
  writes no project_settings.config: the printer, filament and process are the user's presets in
  the slicer, and every object's own settings (below) override the process preset where it matters.
- `BambuStudio:3mfVersion` is 1: the version of Bambu Studio's 3MF layout these files follow
  (OrcaSlicer then reads the objects as its own and keeps each one where it is).
- Each copy is its own object (one build item, one instance) made of one component, the shape's mesh
  object; copies of a shape share that mesh. One instance per object matters: for a file the
  loader does not take as its own it splits objects with several instances into new objects
  that lose their settings.
- Per object: `extruder` (the filament slot: 1, as every plate holds one material),
  `sparse_infill_density` (100 % for the TPU joints, `core.infill` for the rigid parts),
  `sparse_infill_pattern` (grid, as the PrusaSlicer profile; not set at 100 %, where the slicers
  fill solid with their solid-infill pattern), `wall_loops`, `top_shell_layers`,
  `bottom_shell_layers` and `layer_height` from `printer:`. These are the keys' names in both
  slicers' print settings. The plate block lists every object on plate 1.

Byte-stable like the PrusaSlicer files: no UUIDs or dates, zip entries with a fixed date.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

from .plates import _CONTENT_TYPES, _RELS, Plate, _instances, _num, _transform, _zip

if TYPE_CHECKING:
    import trimesh

    from ..spec import Spec

APPLICATION = "cogniframe"
BBS_3MF_VERSION = "1"  # Bambu Studio's 3MF layout version (`BambuStudio:3mfVersion`)
MODEL_SETTINGS = "Metadata/model_settings.config"
EXTRUDER = 1  # every plate holds one material: filament slot 1


def object_settings(spec: Spec, material: str, infill: float) -> tuple[tuple[str, str], ...]:
    """The per-object settings (OrcaSlicer / Bambu Studio key names) of every object of a material's
    plates: filament slot, infill and shells as `slicer.profile_ini` gives PrusaSlicer."""
    pr = spec.printer
    out = [("extruder", str(EXTRUDER)),
           ("sparse_infill_density", f"{round(100 * infill, 2):g}%")]
    if infill < 0.999:
        out.append(("sparse_infill_pattern", "grid"))
    out += [("wall_loops", str(pr.perimeters)),
            ("top_shell_layers", str(pr.top_bottom_layers)),
            ("bottom_shell_layers", str(pr.top_bottom_layers)),
            ("layer_height", f"{pr.layer_height:g}")]
    return tuple(out)


def settings_text(settings: Sequence[tuple[str, str]]) -> str:
    """The settings as text (what the build's plate step keys its work on)."""
    return "orca/bambu 3mf\n" + "".join(f"{k} = {v}\n" for k, v in settings)


def plate_3mf(plate: Plate, settings: Sequence[tuple[str, str]]
              ) -> tuple[bytes, tuple[tuple[str, trimesh.Trimesh, np.ndarray], ...]]:
    """The plate as an OrcaSlicer / Bambu Studio 3MF, with `settings` (`object_settings`) on every object.

    Returns (bytes, items) as `plates.plate_3mf` does: items are what `plates.read_3mf_items` reads
    back from the bytes (name, shared mesh, item transform)."""
    import trimesh
    from xml.sax.saxutils import quoteattr

    groups = _instances(plate)
    meshes, copies_xml, items, read = [], [], [], []
    config = []
    plate_objects = []
    shape_meshes = []
    for sid, (verts, faces, copies) in enumerate(groups, start=1):
        text = [_num(x) for x in verts.ravel().tolist()]
        it = iter(text)
        vx = "".join(f'<vertex x="{x}" y="{y}" z="{z}"/>' for x, y, z in zip(it, it, it))
        tr = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in faces.tolist())
        meshes.append(f'<object id="{sid}" name={quoteattr(copies[0].part)} type="model">'
                      f'<mesh><vertices>{vx}</vertices><triangles>{tr}</triangles></mesh></object>')
        # the mesh read_3mf_items builds from this text
        shape_meshes.append(trimesh.Trimesh(np.array([float(x) for x in text], float).reshape(-1, 3),
                                            np.array(faces, np.int64).reshape(-1, 3), process=False))
    oid = len(groups)
    for sid, (_, _, copies) in enumerate(groups, start=1):
        for c in copies:
            oid += 1
            copies_xml.append(f'<object id="{oid}" name={quoteattr(c.name)} type="model">'
                              f'<components><component objectid="{sid}"/></components></object>')
            transform = f"1 0 0 0 1 0 0 0 1 {_num(c.x)} {_num(c.y)} 0"
            items.append(f'<item objectid="{oid}" transform="{transform}" partnumber={quoteattr(c.name)} printable="1"/>')
            read.append((c.name, shape_meshes[sid - 1], _transform(transform)))
            lines = [f'  <object id="{oid}">', f'    <metadata key="name" value={quoteattr(c.name)}/>']
            lines += [f'    <metadata key="{k}" value={quoteattr(v)}/>' for k, v in settings]
            lines += [f'    <part id="{sid}" subtype="normal_part">',
                      f'      <metadata key="name" value={quoteattr(c.part)}/>', '    </part>', '  </object>']
            config.append("\n".join(lines) + "\n")
            plate_objects.append(oid)
    model = ('<?xml version="1.0" encoding="UTF-8"?>\n'
             '<model unit="millimeter" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" '
             'xmlns:BambuStudio="http://schemas.bambulab.com/package/2021">\n'
             f' <metadata name="Application">{APPLICATION}</metadata>\n'
             f' <metadata name="BambuStudio:3mfVersion">{BBS_3MF_VERSION}</metadata>\n'
             f' <metadata name="Title">{plate.name}</metadata>\n'
             ' <resources>\n  ' + "\n  ".join(meshes + copies_xml) + '\n </resources>\n'
             ' <build>\n  ' + "\n  ".join(items) + '\n </build>\n</model>\n')
    instances = "".join(f'    <model_instance>\n      <metadata key="object_id" value="{o}"/>\n'
                        f'      <metadata key="instance_id" value="0"/>\n'
                        f'      <metadata key="identify_id" value="{o}"/>\n    </model_instance>\n'
                        for o in plate_objects)
    settings_xml = ('<?xml version="1.0" encoding="UTF-8"?>\n<config>\n' + "".join(config)
                    + '  <plate>\n    <metadata key="plater_id" value="1"/>\n    <metadata key="locked" value="false"/>\n'
                    + instances + '  </plate>\n</config>\n')
    entries = {"[Content_Types].xml": _CONTENT_TYPES, "_rels/.rels": _RELS, "3D/3dmodel.model": model,
               MODEL_SETTINGS: settings_xml}
    return _zip({k: v.encode("utf-8") for k, v in entries.items()}), tuple(read)


def read_object_settings(threemf: bytes | str) -> dict[int, dict[str, str]]:
    """`Metadata/model_settings.config` of a 3MF read back: object id -> {key: value} (the object's
    own metadata lines, not its parts'). For tests and for users checking a file."""
    import io
    import zipfile
    from xml.etree import ElementTree

    src = io.BytesIO(threemf) if isinstance(threemf, (bytes, bytearray)) else threemf
    with zipfile.ZipFile(src) as z:
        root = ElementTree.fromstring(z.read(MODEL_SETTINGS))
    out: dict[int, dict[str, str]] = {}
    for obj in root.findall("object"):
        out[int(obj.get("id"))] = {m.get("key"): m.get("value") for m in obj.findall("metadata")}
    return out

