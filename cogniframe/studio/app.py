"""The studio's web app: Starlette routes and one WebSocket per page, served by uvicorn on 127.0.0.1.

    GET  /                    the page: the form (from the schema), figures, 3D view, Save and Build
    GET  /static/<file>       studio.js, studio.css (cogniframe/studio/static/)
    GET  /viewer/<file>       three.js, OrbitControls and viewer.js (cogniframe/report/viewer/, as vendored)
    GET  /scene/<key>.json    the 3D view's items (the viewer's packed scene)
    GET  /files/<path>        a file of the last build, when its manifest lists it (plates' 3MF, report)
    WS   /ws                  edits, save, build in; figures, messages, progress out (session.py)

Every asset is in the package: the page makes no request off this server. The server binds
127.0.0.1 only; it answers only requests whose Host is 127.0.0.1 or localhost (a page of another
site reached through DNS rebinding is refused), and a WebSocket only from its own pages (the
Origin must be this server), since the socket can write the params file and start builds.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import html
import json
from importlib import resources
from pathlib import Path

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.responses import FileResponse, HTMLResponse, JSONResponse, Response
from starlette.routing import Route, WebSocketRoute
from starlette.websockets import WebSocket, WebSocketDisconnect

from .session import Session

VIEWER_FILES = {"three.module.min.js", "OrbitControls.js", "viewer.js"}
STATIC_FILES = {"studio.js": "text/javascript", "studio.css": "text/css"}

# the figures: label, dotted path in `check --json`, digits, unit
FIGURES = (
    ("all-up weight", "mass.total_g", 1, "g"),
    ("margin to the limit", "mass.margin_g", 1, "g"),
    ("stiffness k", "stiffness.k_n_per_m", 0, "N/m"),
    ("max safe drop", "drop.max_safe_height_cm", 1, "cm"),
    ("peak at the design drop", "peak_g.heights.design.peak_g", 0, "G"),
    ("hover time", "flight.hover_time_min", 1, "min"),
    ("thrust / weight", "flight.thrust_to_weight", 2, ""),
    ("wall impact speed", "stiffness.wall.max_wall_speed_m_s", 1, "m/s"),
)
GROUPS = ("exoskeleton", "core", "electronics", "battery")


def page(session: Session) -> str:
    e = html.escape
    d = session.base
    from ..report.viewer import CSS

    figures = "".join(
        f'<div class="fig"><dt>{e(label)}</dt><dd><span class="value" data-metric="{e(path)}" data-digits="{digits}">–</span>'
        f'<span class="unit">{e(unit)}</span></dd></div>' for label, path, digits, unit in FIGURES)
    groups = "".join(f'<tr><td>{g}</td><td class="num"><span data-metric="mass.groups.{g}" data-digits="1">–</span> g</td></tr>'
                     for g in GROUPS)
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<title>cogniframe studio: {e(d.name)}</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<link rel="icon" href="data:,">
<link rel="stylesheet" href="/static/studio.css">
<style>{CSS}</style>
<script type="importmap">{{"imports": {{"three": "/viewer/three.module.min.js"}}}}</script>
<script type="module" src="/static/studio.js"></script>
</head>
<body data-params="{e(str(session.path))}">
<header>
  <h1>cogniframe studio <span class="design">{e(d.name)}</span> <span class="file">{e(str(session.path))}</span></h1>
  <div class="actions">
    <span id="status" role="status"></span>
    <button type="button" id="save" disabled title="write the edited values into {e(str(session.path))} (comments kept)">Save</button>
    <button type="button" id="build" title="cogniframe build into out/{e(d.name)}">Build</button>
  </div>
</header>
<main>
<section id="form-pane" aria-label="parameters">
{session.form_html()}
</section>
<section id="result-pane" aria-label="results">
  <div id="verdict-box"><span class="verdict" data-metric="verdict">…</span>
    <span id="model" class="model" data-model=""></span></div>
  <p id="error-banner" class="error" role="alert" hidden></p>
  <dl id="figures" class="figures">{figures}</dl>
  <ul id="problems" class="problems"></ul>
  <table class="groups"><caption>mass budget</caption>{groups}
    <tr class="total"><td>all-up</td><td class="num"><span data-metric="mass.total_g" data-digits="1">–</span> g
      of <span data-metric="mass.limit_g" data-digits="0">–</span> g</td></tr></table>
  <p id="timing" class="timing"></p>
  <div id="view-box"><div id="view-progress" class="progress" hidden><progress max="1" value="0"></progress> <span></span></div>
    <div id="view-slot"><p class="note">making the 3D view…</p></div></div>
  <div id="build-box" hidden><h2>build</h2><div id="build-progress" class="progress"><progress max="1" value="0"></progress> <span></span></div>
    <ul id="downloads"></ul></div>
</section>
</main>
</body></html>"""


def create_app(session: Session, loop_holder: dict | None = None) -> Starlette:
    clients: set[asyncio.Queue] = set()
    state = loop_holder if loop_holder is not None else {}

    def publish(event: dict) -> None:  # from any thread
        loop = state.get("loop")
        if loop is None or loop.is_closed():
            return
        for q in list(clients):
            loop.call_soon_threadsafe(q.put_nowait, event)

    session.publish_fn = publish

    async def index(request):
        return HTMLResponse(page(session), headers={"Cache-Control": "no-store"})

    async def static(request):
        name = request.path_params["name"]
        if name not in STATIC_FILES:
            return Response("not found", 404)
        text = resources.files(__package__).joinpath("static", name).read_bytes()
        return Response(text, media_type=STATIC_FILES[name], headers={"Cache-Control": "no-store"})

    async def viewer(request):
        name = request.path_params["name"]
        if name not in VIEWER_FILES:
            return Response("not found", 404)
        data = resources.files("cogniframe.report.viewer").joinpath(name).read_bytes()
        return Response(data, media_type="text/javascript")

    async def scene(request):
        found = session.scene(request.path_params["key"])
        if found is None:
            return Response("no such scene (a newer one replaced it)", 404)
        meta, buf = found
        return JSONResponse({"meta": meta, "geometry": base64.b64encode(buf).decode("ascii")})

    async def files(request):
        path = session.build_file(request.path_params["path"])
        if path is None:
            return Response("not a file of the last build", 404)
        return FileResponse(path, filename=Path(path).name)

    async def ws(socket: WebSocket):
        origin = socket.headers.get("origin")
        host = socket.headers.get("host", "")
        if origin is not None and origin not in (f"http://{host}",):
            await socket.close(code=1008)
            return
        await socket.accept()
        state["loop"] = asyncio.get_running_loop()
        queue: asyncio.Queue = asyncio.Queue()
        for event in session.replay():
            queue.put_nowait(event)
        clients.add(queue)
        if session.overrides:  # a page (re)loaded shows the file: edits live in the page until saved
            session.edit({}, replace=True)

        async def sender():
            while True:
                event = await queue.get()
                await socket.send_text(json.dumps(event))

        task = asyncio.create_task(sender())
        try:
            while True:
                msg = json.loads(await socket.receive_text())
                kind = msg.get("type")
                if kind == "edit":
                    values = msg.get("values") or {}
                    session.edit(values, replace=bool(msg.get("replace", True)), client=int(msg.get("seq") or 0),
                                 edited=msg.get("edited"))
                elif kind == "save":
                    reply = await asyncio.to_thread(session.save)
                    if reply["type"] != "saved":
                        queue.put_nowait(reply)
                elif kind == "build":
                    reply = session.build()
                    queue.put_nowait(reply)
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            clients.discard(queue)
            task.cancel()

    @contextlib.asynccontextmanager
    async def lifespan(app):
        state["loop"] = asyncio.get_running_loop()
        session.start()
        yield

    routes = [Route("/", index), Route("/static/{name}", static), Route("/viewer/{name}", viewer),
              Route("/scene/{key}.json", scene), Route("/files/{path:path}", files), WebSocketRoute("/ws", ws)]
    return Starlette(routes=routes, lifespan=lifespan,
                     middleware=[Middleware(TrustedHostMiddleware, allowed_hosts=["127.0.0.1", "localhost"])])
