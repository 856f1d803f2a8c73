"""A preset with some keys changed, as the part tests build it: `preset_spec("carbon",
frame__arm_spacing=25)` reads params/carbon.yaml and sets frame.arm_spacing (a double underscore
between the section and the key, so the changes are keyword arguments)."""

from __future__ import annotations

from pathlib import Path

import yaml

from cogniframe import spec as spec_mod

ROOT = Path(__file__).resolve().parents[1]


def preset_doc(name: str, **changes) -> dict:
    doc = yaml.safe_load((ROOT / "params" / f"{name}.yaml").read_text(encoding="utf-8"))
    for key, value in changes.items():
        *path, last = key.split("__")
        node = doc
        for k in path:
            node = node[k]
        node[last] = value
    return doc


def preset_spec(name: str = "carbon", **changes) -> spec_mod.Spec:
    return spec_mod.from_dict(preset_doc(name, **changes), f"{name}.yaml")


def link_for(spacing: float) -> dict:
    """The core link for a test at `spacing` mm between the arm rods: the presets' pegs, or the tab
    below 14 mm, where the pegged link's strut sleeve has no room between its columns (refused,
    naming core.link): tests of the mount or the knee at narrow pairs build them on the tab."""
    return {"core__link": "tab"} if spacing < 14.0 else {}


# The carbon preset before it took the authors' dimensions where they carry load (the calibration
# from the authors' frame, docs/stiffness-model.md): the figures some tests quote were measured on it.
FORMER_CARBON = dict(joints__fit_clearance={"tpu_95a": -0.15}, frame__width=210.0, frame__depth=210.0,
                     frame__height=120.0, frame__knee_inset=12.0, core__plate_thickness=3.0)
