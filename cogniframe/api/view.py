"""The 3D view of a design outside a build: its parts made through the build graph, drawn by
the report's viewer (cogniframe/report/viewer/).

`build_parts` runs the build graph's part steps (`part:{material}/{part}`, the same steps,
keys and cache as `cogniframe build`, so a part the studio or a notebook made is a cache copy
for the next build and the other way round), optionally with the `estimate` step (the joints'
FE, on the same CAD workers as the build does it). `scene` turns the part files into the
viewer's item list (printed parts, rods and the bought parts) and packs it; `design_html`
inlines three.js, the viewer and the geometry into one HTML fragment with ids of its own, so
several views can sit in one notebook and none fetches anything.
"""

from __future__ import annotations

import base64
import html
import json
import secrets
import tempfile
from collections.abc import Callable
from pathlib import Path


def build_parts(spec, design, out: Path, *, fe: bool = False, server: bool | None = None,
                on_step: Callable[..., None] | None = None,
                log: Callable[[str], None] | None = None) -> dict[str, dict]:
    """Make every printed part's STL and STEP in `out` through the build graph (cached steps);
    with `fe`, also solve the joints' FE (the `estimate` step). Returns each part step's value
    (its file names, volume, `print_from_local`, ...) by part name. `on_step(task, done, total,
    part_values)` after each step; `part_values()` gives the values once every part step is done
    (the files are in `out` then, while the FE may still run)."""
    from .. import pipeline
    from ..runtime import cad_server

    only = ("part:*", "estimate") if fe else ("part:*",)
    total = len(design.parts) + (1 if fe else 0)
    done = [0]

    def finished(record, ctx) -> None:
        done[0] += 1
        if on_step is not None:
            on_step(record.task, done[0], total, lambda: {p.name: ctx.part_value(p.name) for p in design.parts})

    ctx, _ = pipeline.run(spec, design, out, only=only, server=cad_server.wanted(server), log=log, on_step=finished)
    return {p.name: ctx.part_value(p.name) for p in design.parts}


def items(spec, design, out: Path, values: dict[str, dict]) -> list:
    """The viewer's items: every copy of every printed part (grams from the mass model with the
    CAD volumes), every rod and the bought parts."""
    import numpy as np

    from ..analysis.mass import PartGeometry, budget
    from ..report.renders import vitamin_viewer_items
    from ..report.viewer import design_items, read_stl

    geometry = {name: PartGeometry(v["volume_mm3"], v["area_h_mm2"], v["area_v_mm2"], "cad") for name, v in values.items()}
    mass = budget(spec, design.frame, design.cut, design.parts, geometry)
    meshes = {p.name: read_stl(out / values[p.name]["stl"]) for p in design.parts}
    found = design_items(design, meshes, {p.name: np.asarray(values[p.name]["print_from_local"], float) for p in design.parts},
                         mass, ())
    return found + vitamin_viewer_items(spec, design.frame, mass)


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
