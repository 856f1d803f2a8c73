"""The build's slice step (pipeline.plate_steps.make_slice) slices each plate on its own key: when one
plate of a material changes, the material's other plates keep their sliced numbers (no
PrusaSlicer run), and the numbers are those of a fresh slice. PrusaSlicer is replaced by a
recorder here; the real slicer runs in test_slicer.py and test_steps_build.py."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest
import trimesh

from cogniframe import spec as spec_mod
from cogniframe import design as design_mod
from cogniframe.pipeline import context as steps
from cogniframe.export import plates as pl
from cogniframe.export import slicer
from cogniframe.pipeline.plate_steps import make_slice

ROOT = Path(__file__).resolve().parents[1]


def _plate(index: int, size: float) -> pl.Plate:
    mesh = trimesh.creation.box(extents=(size, size, 5.0))
    mesh.apply_translation(-mesh.bounds[0] + [10.0, 10.0, 0.0])
    copy = pl.PlacedCopy("knee_1", "knee", 10.0, 10.0, (size, size, 5.0), 0.0, mesh)
    return pl.Plate("tpu_95a", index, (120.0, 120.0, 120.0), 4.0, (copy,))


def _ctx(out: Path, plates: list[pl.Plate], use_cache: bool = True):
    spec = spec_mod.load(ROOT / "params" / "carbon.yaml")
    (out / "plates").mkdir(parents=True, exist_ok=True)
    value = []
    for p in plates:
        f = out / "plates" / f"{p.name}.3mf"
        f.write_bytes(pl.plate_3mf_bytes(p))
        value.append({"name": p.name, "threemf": f"plates/{f.name}", "sha256": hashlib.sha256(f.read_bytes()).hexdigest()})

    class FakeSlicer:
        def get(self):
            return ("prusa-slicer", "PrusaSlicer-test")

    ctx = steps.BuildContext(out, steps.Inputs(spec, design_mod.design(spec), slicer=FakeSlicer()), use_cache=use_cache)
    ctx.values["plates:tpu_95a"] = value
    return ctx


@pytest.fixture
def recorder(monkeypatch, tmp_path):
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    calls = []

    def fake_slice(plate, profile, bed, exe=None, gcode=None, timeout_s=0, items=None, started=None, cpu=0):
        plate = Path(plate)
        objs = slicer.check_plate(plate, bed, items=items)
        calls.append(plate.stem)
        vol = sum(o.volume_mm3 for o in objs)
        return slicer.PlateSlice(plate.stem, "tpu_95a", plate, Path(gcode), vol * 1.22e-3, vol / 10.0,
                                 tuple((o.name, o.volume_mm3) for o in objs), 0.0)

    monkeypatch.setattr(slicer, "slice_plate", fake_slice)
    return calls


def test_only_the_changed_plate_is_sliced_again(tmp_path, recorder):
    first = make_slice(_ctx(tmp_path / "a", [_plate(1, 20.0), _plate(2, 30.0)]), "tpu_95a")
    assert recorder == ["tpu_95a_1", "tpu_95a_2"]
    recorder.clear()
    second = make_slice(_ctx(tmp_path / "b", [_plate(1, 20.0), _plate(2, 32.0)]), "tpu_95a")
    assert recorder == ["tpu_95a_2"]  # plate 1's bytes did not change
    p1, p2 = second.value["plates"]
    assert p1 == first.value["plates"][0]
    assert p2["grams"] == pytest.approx(32.0 * 32.0 * 5.0 * 1.22e-3)  # the recorder's "grams": volume x density
    recorder.clear()
    cold = make_slice(_ctx(tmp_path / "c", [_plate(1, 20.0), _plate(2, 32.0)], use_cache=False), "tpu_95a")
    assert recorder == ["tpu_95a_1", "tpu_95a_2"] and cold.value == second.value  # no cache: every plate, same numbers
