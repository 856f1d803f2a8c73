"""Random params files across the schema's bounds, for the property tests and tools/design_space.py.

`bounded_keys()` reads every numeric key with both bounds from the params schema (the `materials`
table aside: it holds whole material definitions). `random_design(rnd)` starts from a preset and
either edits the box and a few keys as a person does (`"edit"`), anywhere in their bounds, or
draws every bounded key at once (`"anywhere"`: mostly designs the validation must refuse).
Boxes are square or not, at random; a third of the designs fly another motor of the catalogue
(materials.MOTOR_PRESETS), so the fit check meets every hole pattern.
"""

from __future__ import annotations

import copy
import json
import random
from functools import lru_cache
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ("carbon", "bamboo")
# The box a maker draws: the schema allows more (and the anywhere mode draws from all of it).
BOX = {"frame.width": (150.0, 320.0), "frame.depth": (150.0, 320.0), "frame.height": (80.0, 180.0)}


@lru_cache(maxsize=1)
def bounded_keys() -> tuple[tuple[str, float, float, str], ...]:
    """(dotted key, minimum, maximum, "number" | "integer") for every bounded key of the schema."""
    schema = json.loads((ROOT / "cogniframe" / "data" / "params.schema.json").read_text())
    defs = schema.get("$defs", {})
    out = []

    def walk(node, path):
        if "$ref" in node:
            return walk(defs[node["$ref"].split("/")[-1]], path)
        for alt in node.get("anyOf", []):
            if alt.get("type") != "null":
                return walk(alt, path)
        kind = node.get("type")
        if kind == "object" and "properties" in node:
            for key, sub in node["properties"].items():
                walk(sub, path + [key])
        elif kind in ("number", "integer") and path[0] != "materials":
            lo = node.get("minimum", node.get("exclusiveMinimum"))
            hi = node.get("maximum", node.get("exclusiveMaximum"))
            if lo is not None and hi is not None:
                out.append((".".join(path), float(lo), float(hi), kind))

    walk(schema, [])
    return tuple(out)


def preset(name: str) -> dict:
    return yaml.safe_load((ROOT / "params" / f"{name}.yaml").read_text())


def put(doc: dict, dotted: str, value) -> bool:
    """Set a key; False (and nothing set) when a section on its way is absent or null."""
    node = doc
    *path, last = dotted.split(".")
    for key in path:
        node = node.get(key) if isinstance(node, dict) else None
        if not isinstance(node, dict):
            return False
    node[last] = value
    return True


def follow_the_box(doc: dict, side: float) -> None:
    """Move the motors with the box, as a maker who resizes it does: the preset's radius for its
    box (smaller side `side`) scaled by the new box's smaller side, and smaller propellers in a
    smaller box."""
    f, m = doc["frame"], doc["motors"]
    ratio = min(f["width"], f["depth"]) / side
    m["radius"] = round(m["radius"] * ratio, 1)
    m["prop_diameter"] = round(m["prop_diameter"] * min(1.0, ratio), 1)


def _value(rnd: random.Random, lo: float, hi: float, kind: str):
    if kind == "integer":
        return rnd.randint(int(lo), int(hi))
    return round(rnd.uniform(lo, hi), 3)


def random_design(rnd: random.Random, mode: str | None = None) -> dict:
    """A params document (the preset's name kept: the file name carries the design's number)."""
    doc = copy.deepcopy(preset(rnd.choice(PRESETS)))
    mode = mode or rnd.choice(("edit", "edit", "edit", "anywhere"))
    keys = bounded_keys()
    if mode == "anywhere":
        for key, lo, hi, kind in keys:
            put(doc, key, _value(rnd, lo, hi, kind))
    else:
        side = min(doc["frame"]["width"], doc["frame"]["depth"])
        width = round(rnd.uniform(*BOX["frame.width"]), 1)
        put(doc, "frame.width", width)
        put(doc, "frame.depth", width if rnd.random() < 0.4 else round(rnd.uniform(*BOX["frame.depth"]), 1))
        put(doc, "frame.height", round(rnd.uniform(*BOX["frame.height"]), 1))
        follow_the_box(doc, side)
        for key, lo, hi, kind in rnd.sample(keys, k=rnd.randint(0, 3)):
            put(doc, key, _value(rnd, lo, hi, kind))
    put(doc, "frame.struts", rnd.random() < 0.8)
    if rnd.random() < 1 / 3:
        from cogniframe.materials import MOTOR_PRESETS

        put(doc, "motors.model", rnd.choice(sorted(MOTOR_PRESETS)))
    return doc


def write(doc: dict, path: Path) -> Path:
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path
