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

