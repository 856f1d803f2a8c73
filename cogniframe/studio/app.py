"""The studio's web app: Starlette routes and one WebSocket per page, served by uvicorn on 127.0.0.1.

    GET  /                    the page: the form (from the schema), figures, 3D view, Save and Build
    GET  /static/<file>       studio.js, studio.css (cogniframe/studio/static/)
    GET  /viewer/<file>       three.js, OrbitControls and viewer.js (cogniframe/report/viewer/, as vendored)
    GET  /scene/<key>.json    the 3D view's items (the viewer's packed scene)
    GET  /files/<path>        a file of the last build, when its manifest lists it (plates' 3MF, report)
    WS   /ws?token=<token>    edits, save, build, compare in; figures, messages, progress out (session.py)

Every asset is in the package: the page makes no request off this server. The server binds
127.0.0.1 only; it answers only requests whose Host is 127.0.0.1 or localhost (a page of another
site reached through DNS rebinding is refused), and a WebSocket only from its own pages, since
the socket can write the params file and start builds: the Origin must be this server and the
socket's address must carry the token of this server's pages (random per server, in the page,
which another site's page cannot read). No page of another site may frame the studio's pages
(`X-Frame-Options: DENY`, CSP `frame-ancestors 'none'` on every response), so none can click
Save in an invisible frame. One message holds at most MAX_MESSAGE_BYTES and MAX_KEYS values;
anything else is refused with a plain message, and the errors of the server go to its log.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import hmac
import html
import json
import logging
import secrets
from importlib import resources
from pathlib import Path

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.responses import FileResponse, HTMLResponse, JSONResponse, Response
from starlette.routing import Route, WebSocketRoute
from starlette.websockets import WebSocket, WebSocketDisconnect

from .compare import COMPARE_ROWS
from .messages import MAX_MESSAGE_BYTES, Refused, shorten, text_hash
from .session import Page, Session

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
SECURITY_HEADERS = [(b"x-frame-options", b"DENY"), (b"content-security-policy", b"frame-ancestors 'none'"),
                    (b"x-content-type-options", b"nosniff"), (b"referrer-policy", b"no-referrer")]
log = logging.getLogger("cogniframe.studio")


def page(session: Session, token: str) -> str:
    e = html.escape
    d = session.refresh()  # a page that loads starts from the file as it is now
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
<body data-params="{e(str(session.path))}" data-base="{e(text_hash(d.text))}" data-token="{e(token)}"
      data-compare-rows="{e(json.dumps(COMPARE_ROWS))}">
<header>
  <h1>cogniframe studio <span class="design">{e(d.name)}</span> <span class="file">{e(str(session.path))}</span></h1>
  <div class="actions">
    <span id="status" role="status"></span>
    <button type="button" id="undo" disabled title="undo the last edit (Ctrl+Z outside a field)">Undo</button>
    <button type="button" id="redo" disabled title="redo (Ctrl+Shift+Z outside a field)">Redo</button>
    <button type="button" id="save" disabled title="write the edited values into {e(str(session.path))} (comments kept)">Save</button>
    <button type="button" id="build" title="cogniframe build into out/{e(d.name)}">Build</button>
  </div>
<div id="notice" class="notice" role="alert" {'' if session.disk_error else 'hidden'}><p class="notice-text">{e(session.disk_error or '')}</p>
  <button type="button" id="rebase" hidden>Take the saved file under my edits</button>
  <button type="button" id="dismiss" title="close this message">Dismiss</button></div>
</header>
<main>
<section id="form-pane" aria-label="parameters">
{session.form_html(d)}
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
  <details id="snapshots-box" open><summary>snapshots and compare</summary>
    <p class="note">A snapshot keeps the design as it is now (in this browser, for this file). Tick two or more
      (or "now") and Compare shows them side by side.</p>
    <form id="snapshot-form" onsubmit="return false"><input type="text" id="snapshot-name" placeholder="name, e.g. 4 mm rods"
      maxlength="80" spellcheck="false"> <button type="button" id="snapshot-take">Take a snapshot</button></form>
    <ul id="snapshots"></ul>
    <button type="button" id="compare-go">Compare</button>
    <div id="compare"></div></details>
  <div id="build-box" hidden><h2>build</h2><div id="build-progress" class="progress"><progress max="1" value="0"></progress> <span></span></div>
    <ul id="downloads"></ul></div>
</section>
</main>
</body></html>"""


def _secured(app):
    """ASGI middleware: the frame protection and a few safe defaults on every HTTP response."""

    async def wrapped(scope, receive, send):
        if scope["type"] != "http":
            return await app(scope, receive, send)

        async def send_secured(message):
            if message["type"] == "http.response.start":
                names = {k.lower() for k, _ in message.get("headers", [])}
                message = {**message, "headers": [*message.get("headers", []),
                                                  *[(k, v) for k, v in SECURITY_HEADERS if k not in names]]}
            await send(message)

        return await app(scope, receive, send_secured)

    return wrapped


def create_app(session: Session, token: str | None = None):
    token = token or secrets.token_urlsafe(32)

    async def index(request):
        text = await asyncio.to_thread(page, session, token)  # reads (and may validate) the file: off the event loop
        return HTMLResponse(text, headers={"Cache-Control": "no-store"})

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
        if path.suffix == ".html":  # the report opens in the browser, not as a download
            return FileResponse(path, media_type="text/html; charset=utf-8", filename=path.name,
                                content_disposition_type="inline")
        return FileResponse(path, filename=Path(path).name)

    async def ws(socket: WebSocket):
        origin = socket.headers.get("origin")
        host = socket.headers.get("host", "")
        given = socket.query_params.get("token", "")
        if (origin is not None and origin != f"http://{host}") or not hmac.compare_digest(given.encode(), token.encode()):
            await socket.close(code=1008)
            return
        await socket.accept()
        loop = asyncio.get_running_loop()
        queue: asyncio.Queue = asyncio.Queue()

        def send(event: dict) -> None:  # from any thread
            loop.call_soon_threadsafe(queue.put_nowait, event)

        page_ = session.connect(send)

        async def sender():
            while True:
                event = await queue.get()
                await socket.send_text(json.dumps(event))

        async def reply_later(fn, *args, request_id=None):
            try:
                reply = await asyncio.to_thread(fn, *args)
            except Refused as e:
                reply = {"type": "refused", "message": str(e)}
            except Exception as e:  # noqa: BLE001 - logged; the page gets a plain line
                log.exception("answering a message")
                reply = {"type": "refused", "message": f"internal error: {type(e).__name__} (a bug in cogniframe; "
                                                       f"the studio's log has the details)"}
            if request_id is not None:
                reply["id"] = request_id
            queue.put_nowait(reply)

        task = asyncio.create_task(sender())
        pending: set[asyncio.Task] = set()
        try:
            while True:
                message = await socket.receive()
                if message["type"] == "websocket.disconnect":
                    break
                reply = await _handle(session, page_, message, reply_later, pending)
                if reply is not None:
                    queue.put_nowait(reply)
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            session.disconnect(page_)
            task.cancel()
            for t in pending:
                t.cancel()

    @contextlib.asynccontextmanager
    async def lifespan(app):
        session.start()
        yield

    routes = [Route("/", index), Route("/static/{name}", static), Route("/viewer/{name}", viewer),
              Route("/scene/{key}.json", scene), Route("/files/{path:path}", files), WebSocketRoute("/ws", ws)]
    app = Starlette(routes=routes, lifespan=lifespan,
                    middleware=[Middleware(TrustedHostMiddleware, allowed_hosts=["127.0.0.1", "localhost"])])
    return _secured(app)


def _int(value, default: int = 0) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) and abs(value) < 2**53 else default


async def _handle(session: Session, page_: Page, message: dict, reply_later, pending: set) -> dict | None:
    """One message of a page: the event to send back at once (a refusal), or None."""
    text = message.get("text")
    if text is None:
        return {"type": "refused", "message": "refused: the studio takes text messages (JSON), not binary ones."}
    size = len(text) if len(text) * 4 <= MAX_MESSAGE_BYTES else len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_MESSAGE_BYTES:
        return {"type": "refused", "message": f"refused: a message of {size} bytes; the studio takes at most "
                                              f"{MAX_MESSAGE_BYTES // 1024} KiB per message. Nothing was changed."}
    try:
        msg = json.loads(text)
    except (ValueError, RecursionError):  # RecursionError: JSON nested thousands deep
        return {"type": "refused", "message": "refused: a message that is not JSON (or is nested too deep). Nothing was changed."}
    if not isinstance(msg, dict):
        return {"type": "refused", "message": "refused: a message is a JSON object with a `type`. Nothing was changed."}
    kind = msg.get("type")
    request_id = _int(msg.get("id"), None) if "id" in msg else None
    try:
        if kind == "edit":
            edited = msg.get("edited")
            session.edit(page_, msg.get("values"), msg.get("base"), seq=_int(msg.get("seq")),
                         edited=edited if isinstance(edited, str) else None)
            return None
        if kind in ("save", "rebase", "compare"):
            if kind == "compare" and any(t.get_name() == "compare" for t in pending):
                return {"type": "refused", "message": "refused: a compare of this page is still running; wait for it."}
            if kind == "save":
                args = (session.save, msg.get("values"), msg.get("base"), page_)
            elif kind == "rebase":
                args = (session.rebase,)
            else:
                args = (session.compare, msg.get("designs"))
            t = asyncio.create_task(reply_later(*args, request_id=request_id), name=kind)
            pending.add(t)
            t.add_done_callback(pending.discard)
            return None
        if kind == "build":
            return session.start_build(msg.get("values"), msg.get("base"))
    except Refused as e:
        return {"type": "refused", "message": str(e), "seq": _int(msg.get("seq"))}
    except Exception as e:  # noqa: BLE001 - logged, never a traceback on the terminal
        log.exception("a message of type %r", shorten(str(kind), 40))
        return {"type": "refused", "message": f"internal error: {type(e).__name__} (a bug in cogniframe; the studio's log "
                                              f"has the details). Nothing was changed."}
    return {"type": "refused", "message": f"refused: no message type {shorten(repr(kind), 40)} (edit, save, rebase, "
                                          f"build, compare). Nothing was changed."}
