"""Check a 3MF the way a third party reads it: lib3mf (the 3MF Consortium's reference library) loads it,
every mesh is manifold and consistently oriented, object ids are unique, and every build item and
component points at an object that exists."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path
from xml.etree import ElementTree

NS = "{http://schemas.microsoft.com/3dmanufacturing/core/2015/02}"
# lib3mf's warning for an attribute outside the core namespace: the `printable` attribute that
# PrusaSlicer's, OrcaSlicer's and Bambu Studio's loaders read on build items (one per item)
LIB3MF_INVALID_ATTRIBUTE = 32935


def check_3mf(src: Path | bytes) -> dict:
    """Load with lib3mf and check; returns counts (meshes, components objects, build items, warnings)."""
    import lib3mf

    data = src if isinstance(src, (bytes, bytearray)) else Path(src).read_bytes()
    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    reader = model.QueryReader("3mf")
    reader.ReadFromBuffer(bytearray(data))  # raises on a file lib3mf cannot load
    warnings = [reader.GetWarning(i) for i in range(reader.GetWarningCount())]

    ids = []
    meshes = 0
    it = model.GetMeshObjects()
    while it.MoveNext():
        mesh = it.GetCurrentMeshObject()
        ids.append(mesh.GetResourceID())
        meshes += 1
        assert mesh.GetTriangleCount() > 0, f"mesh object {mesh.GetName()} is empty"
        assert mesh.IsManifoldAndOriented(), f"mesh object {mesh.GetName()} is not manifold and oriented"
    comps = 0
    it = model.GetComponentsObjects()
    while it.MoveNext():
        obj = it.GetCurrentComponentsObject()
        ids.append(obj.GetResourceID())
        comps += 1
        for k in range(obj.GetComponentCount()):
            assert obj.GetComponent(k).GetObjectResource() is not None
    assert len(ids) == len(set(ids)), f"duplicate object ids {sorted(ids)}"
    items = 0
    it = model.GetBuildItems()
    while it.MoveNext():
        assert it.GetCurrent().GetObjectResourceID() in ids
        items += 1

    # the ids as written (lib3mf renumbers nothing it reads, but check the text itself too)
    with zipfile.ZipFile(io.BytesIO(bytes(data))) as z:
        root = ElementTree.fromstring(z.read("3D/3dmodel.model"))
    written = [o.get("id") for o in root.iter(f"{NS}object")]
    assert len(written) == len(set(written)), f"duplicate object ids in 3D/3dmodel.model: {written}"
    assert sorted(int(i) for i in written) == sorted(ids)
    assert all(code == LIB3MF_INVALID_ATTRIBUTE for code, _ in warnings), warnings
    assert len(warnings) <= items, warnings  # at most the build items' `printable`
    return {"meshes": meshes, "components": comps, "items": items, "warnings": len(warnings)}
