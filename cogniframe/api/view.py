"""The 3D view of a design outside a build: its parts made through the build graph, drawn by
the report's viewer (cogniframe/report/viewer/).

`build_parts` runs the build graph's part steps (`part:{material}/{part}`, the same steps,
keys and cache as `cogniframe build`, so a part the studio or a notebook made is a cache copy
for the next build and the other way round), optionally with the `estimate` step (the joints'
FE, on the same CAD workers as the build does it). `scene` turns the part files into the
viewer's item list (printed parts, rods and the bought parts) and packs it; `design_html`
inlines three.js, the viewer and the geometry into one HTML fragment with ids of its own, so
several views can sit in one notebook and none fetches anything. For the studio:
`geometry_key` (what a view shows, so an edit that changes none of it keeps the view) and
`provisional_items` (a new frame's view at once, from the parts an earlier view made).
"""

from __future__ import annotations

import base64
import hashlib
import html
import json
import secrets
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any


def build_parts(spec, design, out: Path, *, fe: bool = False, server: bool | None = None,
                on_step: Callable[..., None] | None = None,
                log: Callable[[str], None] | None = None, stop=None) -> dict[str, dict]:
    """Make every printed part's STL and STEP in `out` through the build graph (cached steps);
    with `fe`, also solve the joints' FE (the `estimate` step). Returns each part step's value
    (its file names, volume, `print_from_local`, ...) by part name. `on_step(task, done, total,
    part_values)` after each step; `part_values()` gives the values once every part step is done
    (the files are in `out` then, while the FE may still run). `stop` (a threading.Event): once set,
    the work ends early with `pipeline.graph.Stopped` (the caller no longer wants it)."""
    from .. import pipeline
    from ..runtime import cad_server

    only = ("part:*", "estimate") if fe else ("part:*",)
    total = len(design.parts) + (1 if fe else 0)
    done = [0]

    def finished(record, ctx) -> None:
        done[0] += 1
        if on_step is not None:
            on_step(record.task, done[0], total, lambda: {p.name: ctx.part_value(p.name) for p in design.parts})

    ctx, _ = pipeline.run(spec, design, out, only=only, server=cad_server.wanted(server), log=log, on_step=finished,
                          stop=stop)
    return {p.name: ctx.part_value(p.name) for p in design.parts}


def items(spec, design, out: Path, values: dict[str, dict], meshes: dict | None = None) -> list:
    """The viewer's items: every copy of every printed part (grams from the mass model with the
    CAD volumes), every rod and the bought parts. `meshes`: the parts' meshes when the caller
    has read them (else read from the STLs in `out`)."""
    import numpy as np

    from ..report.renders import vitamin_viewer_items
    from ..report.viewer import design_items, read_stl

    mass = _budget(spec, design, values)
    if meshes is None:
        meshes = {p.name: read_stl(out / values[p.name]["stl"]) for p in design.parts}
    found = design_items(design, meshes, {p.name: np.asarray(values[p.name]["print_from_local"], float) for p in design.parts},
                         mass, ())
    return found + vitamin_viewer_items(spec, design.frame, mass)


def _budget(spec, design, values: dict[str, dict]):
    """The mass budget with the CAD volumes of the parts in `values` (the others estimated)."""
    from ..analysis.mass import PartGeometry, budget

    geometry = {name: PartGeometry(v["volume_mm3"], v["area_h_mm2"], v["area_v_mm2"], "cad") for name, v in values.items()}
    return budget(spec, design.frame, design.cut, design.parts, geometry)


@dataclass(frozen=True)
class MadePart:
    """A part as a view made it: what its shape was made from (`geometry_digest`), its mesh in
    print orientation, print <- local, and its part step's value (volumes)."""

    digest: str
    mesh: Any
    print_from_local: Any
    value: dict


def provisional_items(spec, design, made: dict[str, MadePart]) -> tuple[list, tuple[str, ...], tuple[str, ...]]:
    """The viewer's items of `design` at once, before its changed parts are made: (items, the
    parts drawn provisionally, the parts left out). A part whose shape is unchanged is its mesh
    as made; a changed part is its previous mesh at its NEW placements, drawn pale and noted as
    updating (its grams the mass model's estimate, not the CAD's); a part never made is left
    out. The rods (from the frame graph) and the bought parts are the new design's own."""
    import numpy as np

    from ..parts.shapes import geometry_digest
    from ..report.renders import vitamin_viewer_items
    from ..report.viewer import design_items

    changed, missing = [], []
    meshes, pfl, values = {}, {}, {}
    for p in design.parts:
        m = made.get(p.name)
        if m is None:
            missing.append(p.name)
            continue
        meshes[p.name], pfl[p.name] = m.mesh, np.asarray(m.print_from_local, float)
        if m.digest == geometry_digest(p):
            values[p.name] = m.value
        else:
            changed.append(p.name)
    mass = _budget(spec, design, values)
    found = design_items(design, meshes, pfl, mass, (), provisional=changed)
    return found + vitamin_viewer_items(spec, design.frame, mass), tuple(changed), tuple(missing)


def scene(spec, design, *, server: bool | None = None, on_step=None, log=None) -> tuple[dict, bytes]:
    """(metadata, geometry buffer) of the viewer for this design: its parts built in a temporary
    folder (removed after), from the cache when they were made before."""
    from ..report.viewer import pack

    with tempfile.TemporaryDirectory(prefix="cogniframe-view-") as tmp:
        out = Path(tmp)
        values = build_parts(spec, design, out, server=server, on_step=on_step, log=log)
        return pack(items(spec, design, out, values))


def design_html(d) -> str:
    """The design's 3D view as one self-contained HTML fragment (for Jupyter's `_repr_html_`)."""
    meta, buf = scene(d.spec, d.derived)
    return inline_html(meta, buf, title=f"{d.name}: 3D view")




def _view_id(name: str) -> str:
    """The fragment's ids of the viewer's text scripts, after its uid."""
    return json.dumps("viewer-js" if name == "viewer" else name)


def inline_html(meta: dict, buf: bytes, title: str = "3D view") -> str:
    """The viewer with three.js, OrbitControls, viewer.js and the scene inline, under ids made
    for this fragment (the report's section uses fixed ids: one per page)."""
    from ..report.viewer import CSS, THREE_VERSION, _read, _script_text, module_loader

    uid = "cfv-" + secrets.token_hex(6)
    code = {n: _script_text(_read(n), n) for n in ("three.module.min.js", "OrbitControls.js", "viewer.js")}
    data = json.dumps(meta, separators=(",", ":"), sort_keys=True).replace("</", "<\\/")
    counts = {k: sum(1 for o in meta["objects"] if o["kind"] == k) for k in ("part", "rod", "vitamin")}
    toggles = "".join(f'<label><input type="checkbox" data-kind="{k}" checked> {k}s ({counts[k]})</label>'
                      for k in ("rod", "vitamin"))
    b64 = base64.b64encode(buf).decode("ascii")
    return "\n".join([
        f'<div class="cf-view-wrap" data-viewer="{uid}">',
        f"<style>{CSS}</style>",
        f'<div id="{uid}" class="cf-viewer" data-objects="{len(meta["objects"])}">',
        f'<canvas width="960" height="560" aria-label="{html.escape(title)}"></canvas>',
        f'<div class="cf-bar">{toggles}<button type="button" class="cf-reset">reset view</button></div>',
        '<div class="cf-info">The 3D view needs JavaScript and WebGL (in Jupyter: a trusted notebook).</div>',
        "</div>",
        (f'<p class="cf-help">{html.escape(title)}: drag to rotate, scroll to zoom, right-drag to pan; click a part. '
         f'{counts["part"]} part copies, {counts["rod"]} rods, {counts["vitamin"]} bought parts. '
         f'three.js r{THREE_VERSION.split(".")[1]} (MIT licence) is embedded.</p>'),
        f'<script type="text/plain" id="{uid}-three">{code["three.module.min.js"]}</script>',
        f'<script type="text/plain" id="{uid}-orbit">{code["OrbitControls.js"]}</script>',
        f'<script type="text/plain" id="{uid}-viewer-js">{code["viewer.js"]}</script>',
        f'<script type="application/json" id="{uid}-scene">{data}</script>',
        f'<script type="text/plain" id="{uid}-geometry">{b64}</script>',
        f'<script type="module">{module_loader(_view_id, "uid", uid=json.dumps(uid))}</script>',
        "</div>",
    ])


def geometry_key(d) -> str:
    """What the 3D view shows: each part's CAD inputs and placements, the rods, the bought parts'
    shapes and the bed. A change elsewhere needs no new view (which would also reset its camera):
    grams, a motor's KV, the battery's cells and capacity (they are only in the click panel's
    text, which follows at the next change of shape)."""
    from ..parts.shapes import geometry_digest

    pd = d.derived
    spec = d.spec
    parts = [[p.name, geometry_digest(p), [[list(map(float, pl.origin)), pl.rotation_deg] for pl in p.placements]] for p in pd.parts]
    rods = [[r.name, [float(x) for x in r.start], [float(x) for x in r.end], float(r.diameter)] for r in pd.frame.rods.values()]
    battery = spec.core.battery
    vitamins = [spec.motors.model_dump(mode="json", exclude={"kv", "mass", "max_thrust_g", "prop_mass"}),
                [c.vitamin for c in spec.components],  # not their grams
                [battery.length, battery.width, battery.height, battery.connector], spec.core.stack_pattern,
                spec.core.model_dump(mode="json", include={"camera", "flow_sensor", "computer"})]
    payload = [parts, rods, vitamins, [float(b) for b in spec.printer.bed]]
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:20]
