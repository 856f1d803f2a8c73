"""The studio's state and its background work, independent of the web server.

One `Session` per `cogniframe studio PARAMS`. The design a page shows lives in that page (and in
its address): the file's text it started from (`base`, the SHA-256 of that text) and the values
it changed (dotted key -> what was typed). Every message of a page carries both, so the server
holds no design state that one page could change under another: a page that connects, reloads
or edits never touches what another page shows. The server keeps the file texts pages started
from (`bases`), the newest evaluation of each page (to check it again once a joint's FE is
solved) and the 3D views. Events (`Page.send(event)`, a JSON-able dict):

    figures   the `check --json` object of the page's design (`model`: "fe", or the fast model's, "analytic" or "surrogate", while
              a new joint geometry's FE is solved: `pending_fe` true), `seq` of the edit, `ms`
              (from the message to the figures) and `cpu_ms` (the check's own CPU time)
    invalid   the CLI's message for the edited file, the key it names and the field edited
    refused   a message the studio does not take (too large, too many keys, an unknown key)
    scene     a new 3D view is ready at `url` (the viewer's items, packed); every page, by `key`.
              `provisional` true: a view of the new frame drawn at once, before its changed parts
              are made (rods and unchanged parts exact; the `changed` parts their previous
              shapes at their new places, pale; the `missing` ones never made, left out); the
              exact view of the same `key` follows and replaces it
    progress  background work: `task` ("view", "fe", "build"), `done`/`total`, `text`
    saved     the params file now holds the page's design (read back); `base` its new text's hash
    save-error  nothing was written, and why (changed on disk, a value refused)
    file-saved  (to the other pages) the file was saved from another page: their Save now
              refuses until they take the saved file under their edits (`rebase`)
    compared  the figures of several designs side by side

Work, by thread: `evaluator` validates and checks the newest edit of each page (older edits of a
page that queued up meanwhile are skipped), in about a tenth of a second when no joint needs its
FE; `geometry` publishes a provisional view of the newest geometry at once (from the parts an
earlier view made), makes its parts through the build graph (and the joints' FE with them), then
publishes the exact view and, after a FE, checks the waiting pages again; `build`
runs `cogniframe build` into out/<name>. Nothing is written but the params file (Save), the build
folder (Build) and the studio's log; the parts of the 3D view go to a temporary folder, removed
on exit.

Beside it: what a message may hold (`messages.py`), the compare table's figures (`compare.py`)
and the workers' mailboxes (`mailbox.py`).
"""

from __future__ import annotations

import collections
import itertools
import json
import logging
import shutil
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import api
from ..api.view import geometry_key
from ..errors import UserError
from . import form
from .compare import compare_figures
from .mailbox import Latest, PerPage
from .messages import Refused, compare_items, parse_values, shorten, text_hash

Event = dict
log = logging.getLogger("cogniframe.studio")
BASES_KEPT = 32  # file texts that pages started from

@dataclass
class Page:
    """One connected page: where its events go, and the newest design it asked for."""

    id: int
    send: Callable[[Event], None]
    seq: int = 0  # the page's number of its newest edit
    job: tuple | None = None  # (base, overrides, edited): the newest edit, to check again after a FE
    pending_fe: bool = False  # its figures are the fast model's, waiting for a joint's FE
    geometry: str | None = None  # the geometry key of its newest valid design
    closed: bool = False


class Session:
    def __init__(self, params: str | Path, publish: Callable[[Event], None] | None = None,
                 server: bool | None = None, out_root: Path | None = None, view: bool = True):
        self.path = Path(params)
        self.view = view  # False: no 3D view (no CAD); the joints' FE is still solved for the figures
        self.base = api.load(self.path)  # ParamsError: the CLI says so and exits 2
        self.server = server
        self.out_root = out_root  # None: out/<name>, as the CLI's build
        self.broadcast_fn = publish or (lambda event: None)  # events for every page (and the tests)
        self.lock = threading.RLock()
        self.save_lock = threading.Lock()
        self.bases: collections.OrderedDict[str, api.Design] = collections.OrderedDict()
        self._keep_base(self.base)
        self.pages: dict[int, Page] = {}
        self._ids = itertools.count(1)
        self.disk_error: str | None = None  # the file on disk no longer loads: why
        self.last: dict[str, Event] = {}  # the newest shared events (scene, build), for a page that connects later
        self.scenes: collections.OrderedDict[str, tuple[dict, bytes]] = collections.OrderedDict()
        self.provisional: dict[str, Event] = {}  # geometry key -> its provisional scene event, until the exact one
        self.made: dict[str, Any] = {}  # part name -> view.MadePart: the newest exact view's parts, for the provisional ones
        self.requested_key: str | None = None  # the geometry the 3D view is being made for
        self.build_dir: Path | None = None
        self.building = False
        self.schema = None
        self.tmp = Path(tempfile.mkdtemp(prefix="cogniframe-studio-"))
        self._edits = PerPage()
        self._geometry = Latest()
        self._stop = threading.Event()  # set by close: the work under way ends early, none starts
        self._threads = [threading.Thread(target=self._evaluator, name="studio-evaluate", daemon=True),
                         threading.Thread(target=self._geometry_worker, name="studio-geometry", daemon=True)]
        for t in self._threads:
            t.start()

    # -- the file ---------------------------------------------------------------------------------
    def _keep_base(self, d: api.Design) -> str:
        key = text_hash(d.text)
        with self.lock:
            self.bases[key] = d
            self.bases.move_to_end(key)
            while len(self.bases) > BASES_KEPT:
                self.bases.popitem(last=False)
        return key

    @property
    def base_hash(self) -> str:
        return text_hash(self.base.text)

    def refresh(self) -> api.Design:
        """The file as it is on disk now, for a page that loads: a new valid version becomes the
        base of new pages; one that no longer loads leaves the last good one (and `disk_error`)."""
        try:
            text = self.path.read_bytes().decode("utf-8-sig")
        except (OSError, UnicodeDecodeError) as e:
            with self.lock:
                self.disk_error = f"{self.path} cannot be read now ({e}); the page shows the version the studio read last."
            return self.base
        if text == self.base.text:
            with self.lock:
                self.disk_error = None
            return self.base
        try:
            d = api.load(self.path)
        except api.ParamsError as e:
            with self.lock:
                self.disk_error = (f"{self.path} changed on disk and does not load now; the page shows the version the "
                                   f"studio read last (Save refuses until the file loads again).\n{shorten(str(e))}")
            return self.base
        with self.lock:
            self.base, self.disk_error = d, None
        self._keep_base(d)
        return d

    def base_of(self, key: Any) -> api.Design:
        with self.lock:
            d = self.bases.get(key) if isinstance(key, str) else None
        if d is None:
            raise Refused("this page started from a version of the file the studio no longer holds; reload the page "
                          "(its edits are kept in the address).")
        return d

    def field_values(self, d: api.Design) -> dict[str, str]:
        """What each input of the form shows for design `d` (text; a checkbox: "true"/"false")."""
        values = d.spec.model_dump(mode="json")
        return {key: form.shown(form.value_at(values, key)) for key in self._fields()}

    # -- the form ---------------------------------------------------------------------------------
    def form_groups(self, d: api.Design | None = None):
        from .. import spec as spec_mod

        if self.schema is None:
            self.schema = spec_mod.json_schema()
        return form.groups_of(self.schema, (d or self.base).spec.model_dump(mode="json"))

    def form_html(self, d: api.Design | None = None) -> str:
        d = d or self.base
        groups = self.form_groups(d)
        fields = form.fields(groups)
        with self.lock:
            self.fields = {**getattr(self, "fields", {}), **fields}
        return form.render(groups, d.spec.model_dump(mode="json"))

    def _fields(self) -> dict[str, form.Field]:
        with self.lock:
            if not hasattr(self, "fields"):
                self.fields = form.fields(self.form_groups())
            return self.fields

    def field(self, key: str) -> form.Field | None:
        return self._fields().get(key)

    def parse_values(self, values: Any) -> dict[str, Any]:
        """The values a page sent, as the YAML values to write (`messages.parse_values`)."""
        return parse_values(values, self._fields())

    # -- pages ------------------------------------------------------------------------------------
    def connect(self, send: Callable[[Event], None]) -> Page:
        page = Page(next(self._ids), send)
        with self.lock:
            self.pages[page.id] = page
            replay = [self.last[t] for t in ("progress-build", "built", "build-error") if t in self.last]
        for event in replay:
            page.send(event)
        return page

    def disconnect(self, page: Page) -> None:
        with self.lock:
            page.closed = True
            self.pages.pop(page.id, None)

    def _send(self, page: Page | None, event: Event) -> None:
        if page is None or page.closed:
            return
        try:
            page.send(event)
        except Exception:  # noqa: BLE001 - a page that went away must not stop the work
            log.exception("sending an event to page %s", page.id)

    def publish(self, event: Event) -> None:
        """An event for every page."""
        with self.lock:
            pages = list(self.pages.values())
            if event["type"] in ("built", "build-error"):
                self.last[event["type"]] = event
                self.last.pop("build-error" if event["type"] == "built" else "built", None)
            elif event["type"] == "progress" and event.get("task") == "build":
                self.last["progress-build"] = event
        try:
            self.broadcast_fn(event)
        except Exception:  # noqa: BLE001
            log.exception("publishing an event")
        for p in pages:
            self._send(p, event)

    # -- edits ------------------------------------------------------------------------------------
    def start(self) -> None:
        """The file's 3D view (and its joints' FE) made before the first page asks for it."""

        def warm():
            try:
                d = self.base
                key, fe = geometry_key(d), d.needs_fe()
            except Exception:  # noqa: BLE001 - the first page's edit tries again and says why
                log.exception("the first view")
                return
            with self.lock:
                if self.requested_key is not None or key in self.scenes:
                    return
                self.requested_key = key
            self._geometry.put((d, key, fe))

        t = threading.Thread(target=warm, name="studio-warm", daemon=True)
        with self.lock:
            self._threads.append(t)  # close waits for it
        t.start()

    def edit(self, page: Page, values: Any, base: Any, seq: int = 0, edited: str | None = None) -> None:
        """Queue a check of the page's design: `values` (what the page changed) on the file text
        `base`. Refused: see `parse_values`."""
        d0 = self.base_of(base)
        overrides = self.parse_values(values)
        with self.lock:
            page.seq = seq
            page.job = (d0, overrides, edited if isinstance(edited, str) and edited in overrides else None)
        self._edits.put(page.id, (page, seq, d0, overrides, page.job[2], time.perf_counter(), False))

    def _evaluator(self) -> None:
        while True:
            job = self._edits.take()
            if job is None:
                return
            page, seq = job[0], job[1]
            try:
                self._evaluate(*job)
            except Exception as e:  # noqa: BLE001 - a bug: say so on the page, keep serving
                log.exception("checking an edit")
                self._send(page, {"type": "invalid", "seq": seq, "key": None, "edited": job[4],
                                  "message": f"internal error: {type(e).__name__}: {shorten(str(e))} (a bug in cogniframe, "
                                             f"not in your input; the studio's log has the details)"})

    def _evaluate(self, page: Page, seq: int, d0: api.Design, overrides: dict, edited: str | None, t0: float,
                  after_fe: bool) -> None:
        if page.closed or (seq < page.seq and not after_fe):
            return
        cpu0 = time.thread_time()  # the check's own work, whatever else the machine runs
        try:
            d = d0.with_values(overrides) if overrides else d0
        except api.ParamsError as e:
            self._send(page, {"type": "invalid", "seq": seq, "key": e.key, "edited": edited, "message": shorten(str(e), 4000),
                              "ms": round(1000 * (time.perf_counter() - t0), 1)})
            return
        pending_fe = d.needs_fe()
        shown = d.with_fast_model() if pending_fe else d
        try:
            result = shown.check()
        except api.ParamsError as e:
            self._send(page, {"type": "invalid", "seq": seq, "key": e.key, "edited": edited, "message": shorten(str(e), 4000)})
            return
        key = geometry_key(d)
        with self.lock:
            if seq < page.seq and not after_fe:
                return  # a newer edit of this page is queued: it will show its own figures
            page.pending_fe, page.geometry = pending_fe, key
        self._send(page, {"type": "figures", "seq": seq, "check": result.to_dict(), "model": result.stiffness_model,
                          "pending_fe": pending_fe, "after_fe": after_fe, "geometry": key,
                          "ms": round(1000 * (time.perf_counter() - t0), 1),
                          "cpu_ms": round(1000 * (time.thread_time() - cpu0), 1)})
        with self.lock:
            ready = self.scenes.get(key)
            wanted = pending_fe or (ready is None and key != self.requested_key)
            if wanted:
                self.requested_key = key
            stand_in = self.provisional.get(key) if ready is None else None
        if ready is not None:
            self._send(page, {"type": "scene", "url": f"/scene/{key}.json", "key": key, "objects": len(ready[0]["objects"])})
        elif stand_in is not None:
            self._send(page, stand_in)
        if wanted:
            self._geometry.put((d, key, pending_fe))

    # -- geometry: parts, 3D view, joint FE ---------------------------------------------------------
    def _geometry_worker(self) -> None:
        n = 0
        while True:
            job = self._geometry.take()
            if job is None:
                return
            d, key, fe = job
            if not self.view:
                if fe:
                    self._solve_fe(d)
                continue
            n += 1
            try:
                self._make_view(d, key, fe, self.tmp / f"view-{n}")
            except Exception:  # noqa: BLE001 - logged; the next edit tries again
                log.exception("making the 3D view")

    def _keep_scene(self, key: str, packed: tuple[dict, bytes]) -> None:
        with self.lock:
            self.scenes[key] = packed
            self.scenes.move_to_end(key)
            while len(self.scenes) > 4:  # the pages' newest views
                old, _ = self.scenes.popitem(last=False)
                if old.endswith("-provisional"):  # its event no longer points at a view
                    self.provisional.pop(old.removesuffix("-provisional"), None)

    def _show_provisional(self, d: api.Design, key: str, t0: float) -> None:
        """A view of the new frame at once, while its changed parts are made (a second, more on a
        busy machine): the rods and the bought parts of the new design, the unchanged parts as
        made, each changed part its previous mesh at its new placements, pale. Nothing when no
        view was made before, or when every part is as made (the exact view follows at once)."""
        from ..api import view
        from ..report.viewer import pack

        with self.lock:
            made = dict(self.made)
            if not made or key in self.scenes:
                return
        try:
            items, changed, missing = view.provisional_items(d.spec, d.derived, made)
            if not changed and not missing:
                return
            packed = pack(items)
        except Exception:  # noqa: BLE001 - the exact view still comes
            log.exception("the provisional 3D view")
            return
        event = {"type": "scene", "url": f"/scene/{key}-provisional.json", "key": key, "provisional": True,
                 "changed": list(changed), "missing": list(missing), "objects": len(packed[0]["objects"]),
                 "seconds": round(time.perf_counter() - t0, 2)}
        with self.lock:
            if key in self.scenes:  # the exact view is there already
                return
            self._keep_scene(f"{key}-provisional", packed)
            self.provisional[key] = event
        self.publish(event)

    def _make_view(self, d: api.Design, key: str, fe: bool, out: Path) -> None:
        from ..api import view
        from ..parts.shapes import geometry_digest
        from ..report.viewer import pack, read_stl

        t0 = time.perf_counter()
        self.publish({"type": "progress", "task": "view", "key": key, "done": 0, "total": 1, "fe": fe,
                      "text": "making the parts" + (" and solving the joints' FE" if fe else "")})
        # the provisional view is made while the CAD server makes the changed parts (another
        # process); the exact view waits for it, so a page never gets the provisional one after it
        stand_in = threading.Thread(target=self._show_provisional, args=(d, key, t0), name="studio-provisional", daemon=True)
        stand_in.start()
        n_parts = len(d.derived.parts)
        parts_done: list[str] = []
        shown: list[threading.Thread] = []

        def show_view(values: dict) -> None:
            """The 3D view as soon as the parts are made (the joints' FE may still run)."""
            try:
                meshes = {p.name: read_stl(out / values[p.name]["stl"]) for p in d.derived.parts}
                packed = pack(view.items(d.spec, d.derived, out, values, meshes))
                made = {p.name: view.MadePart(geometry_digest(p), meshes[p.name], values[p.name]["print_from_local"],
                                              values[p.name]) for p in d.derived.parts}
            except Exception as e:  # noqa: BLE001
                log.exception("packing the 3D view")
                stand_in.join()
                self._view_failed(key)
                self.publish({"type": "progress", "task": "view", "key": key, "done": 1, "total": 1,
                              "text": f"the 3D view failed: {shorten(str(e))}", "error": f"{type(e).__name__}: {shorten(str(e))}"})
                return
            stand_in.join()
            with self.lock:
                self.made.update(made)
                self.provisional.pop(key, None)  # no page is sent it now
                self._keep_scene(key, packed)
                if f"{key}-provisional" in self.scenes:  # a page told of it may still fetch it: the next view drops it
                    self.scenes.move_to_end(f"{key}-provisional", last=False)
            self.publish({"type": "scene", "url": f"/scene/{key}.json", "key": key,
                          "objects": len(packed[0]["objects"]), "seconds": round(time.perf_counter() - t0, 2)})

        def step(task: str, done: int, total: int, part_values=None) -> None:
            is_part = task.startswith("part:")
            if is_part:
                parts_done.append(task)
            all_parts = is_part and len(parts_done) == n_parts
            what = f"made the {task.rsplit('/', 1)[-1]}" if is_part else "solved the joints' FE"
            if fe and all_parts:
                what += "; solving the joints' FE"
            self.publish({"type": "progress", "task": "view", "key": key, "done": done, "total": total, "fe": fe,
                          "text": f"{what} ({done}/{total})"})
            if all_parts and part_values is not None:
                t = threading.Thread(target=show_view, args=(part_values(),), name="studio-view", daemon=True)
                shown.append(t)
                t.start()

        try:
            view.build_parts(d.spec, d.derived, out, fe=fe, server=self.server, on_step=step, stop=self._stop)
        except Exception as e:  # noqa: BLE001
            stand_in.join()
            if self._stop.is_set():  # the session closes: no page waits for this view or its FE now
                return
            if not isinstance(e, UserError):
                log.exception("making the parts of the 3D view")
            self._view_failed(key)
            text = str(e) if isinstance(e, UserError) else f"the 3D view failed: {type(e).__name__}: {e}"
            self.publish({"type": "progress", "task": "view", "key": key, "done": 1, "total": 1,
                          "error": shorten(text), "text": shorten(text)})
            if fe:  # the figures wait for the FE: solve it on its own, or say why it cannot be
                self._solve_fe(d)
            return
        finally:
            for t in shown:
                t.join()
            shutil.rmtree(out, ignore_errors=True)
        self.publish({"type": "progress", "task": "view", "key": key, "done": 1, "total": 1, "text": "", "fe": False})
        if fe:  # the joints are in the cache now: the figures of the waiting pages, FE this time
            self._after_fe()

    def _solve_fe(self, d: api.Design) -> None:
        self.publish({"type": "progress", "task": "fe", "done": 0, "total": 1, "text": "solving the joints' FE"})
        try:
            d.check()  # solves the new joints into the cache
        except Exception as e:  # noqa: BLE001
            if not isinstance(e, UserError):
                log.exception("solving the joints' FE")
            self.publish({"type": "progress", "task": "fe", "done": 1, "total": 1, "text": "",
                          "error": shorten(f"{type(e).__name__}: {e}")})
            return
        self.publish({"type": "progress", "task": "fe", "done": 1, "total": 1, "text": ""})
        self._after_fe()

    def _after_fe(self) -> None:
        with self.lock:
            waiting = [p for p in self.pages.values() if p.pending_fe and p.job is not None]
        for p in waiting:  # a queued edit of the page already stands for its current design
            d0, overrides, edited = p.job
            self._edits.put(p.id, (p, p.seq, d0, overrides, None, time.perf_counter(), True), replace=False)

    def _view_failed(self, key: str) -> None:
        with self.lock:
            if self.requested_key == key:
                self.requested_key = None  # the next edit tries again
            self.provisional.pop(key, None)  # no exact view follows it now

    def scene(self, key: str) -> tuple[dict, bytes] | None:
        with self.lock:
            return self.scenes.get(key)

    # -- save and build ---------------------------------------------------------------------------
    def save(self, values: Any, base: Any, page: Page | None = None) -> Event:
        """Write the page's design (`values` on the file text `base`) to the file, comments and order
        kept, and read it back. Refused, with nothing written, when a value is refused or when the
        file on disk is no longer the text the page started from (another page saved, an editor):
        a Save never writes over what it has not shown."""
        try:
            d0 = self.base_of(base)
            overrides = self.parse_values(values)
        except Refused as e:
            return {"type": "save-error", "message": "not saved: " + str(e)}
        with self.save_lock:
            try:
                on_disk = self.path.read_bytes().decode("utf-8-sig")
            except (OSError, UnicodeDecodeError) as e:
                return {"type": "save-error", "message": f"not saved: {self.path} cannot be read ({e}); nothing was written."}
            if on_disk != d0.text:
                return {"type": "save-error", "reason": "changed-on-disk",
                        "message": f"not saved: {self.path} changed on disk since this page loaded it (a Save from "
                                   f"another page, or an editor); nothing was written. Your edits are kept here: "
                                   f"\"Take the saved file\" puts them on the file as it is now, then Save again."}
            try:
                d = d0.with_values(overrides) if overrides else d0
            except api.ParamsError as e:
                return {"type": "save-error", "message": "not saved: " + shorten(str(e), 4000)}
            try:
                d.save()
                written = self.path.read_bytes().decode("utf-8-sig")
            except (OSError, UnicodeDecodeError, UserError) as e:
                return {"type": "save-error", "message": f"not saved: writing {self.path} failed ({shorten(str(e))})."}
            if written != d.text:
                return {"type": "save-error", "message": f"not saved: {self.path} does not hold what this page shows after "
                                                          f"writing it (another program wrote it at the same moment?)."}
            with self.lock:
                self.base = d
            key = self._keep_base(d)
        event = {"type": "saved", "path": str(self.path), "base": key}
        with self.lock:
            others = [p for p in self.pages.values() if p is not page]
        for p in others:
            self._send(p, {"type": "file-saved", "path": str(self.path), "base": key})
        return event

    def rebase(self) -> Event:
        """The file as it is on disk now, for a page that takes it under its edits: its hash and
        what every input shows for it."""
        d = self.refresh()
        with self.lock:
            problem = self.disk_error
        if problem:
            return {"type": "rebase-error", "message": problem}
        return {"type": "rebased", "base": text_hash(d.text), "values": self.field_values(d)}

    def start_build(self, values: Any, base: Any) -> Event:
        """Start `cogniframe build` of the page's design into out/<name> (a thread)."""
        try:
            d0 = self.base_of(base)
            overrides = self.parse_values(values)
            d = d0.with_values(overrides) if overrides else d0
        except Refused as e:
            return {"type": "build-error", "message": "not built: " + str(e)}
        except api.ParamsError as e:
            return {"type": "build-error", "message": "not built: " + shorten(str(e), 4000)}
        with self.lock:
            if self.building:
                return {"type": "build-error", "message": "a build is already running"}
            self.building = True
        threading.Thread(target=self._build, args=(d,), name="studio-build", daemon=True).start()
        return {"type": "build-started", "name": d.name}

    def _build(self, d: api.Design) -> None:
        from rich.console import Console

        out = (self.out_root / d.name) if self.out_root is not None else None
        lines = _Lines(lambda line: self._build_line(line))
        try:
            self.publish({"type": "progress", "task": "build", "done": 0, "total": 1, "text": f"building {d.name}"})
            result = d.build(out, console=Console(file=lines, force_terminal=False, width=160, highlight=False),
                             server=self.server)
            with self.lock:
                self.build_dir = result.out_dir
            files = [{"name": p.relative_to(result.out_dir).as_posix(), "url": f"/files/{p.relative_to(result.out_dir).as_posix()}"}
                     for p in [*result.plates, *([result.report] if result.report else [])]]
            self.publish({"type": "built", "out_dir": str(result.out_dir), "verdict": result.verdict, "files": files,
                          "up_to_date": result.up_to_date, "count": len(result.files)})
        except UserError as e:
            self.publish({"type": "build-error", "message": shorten(str(e), 4000)})
        except Exception as e:  # noqa: BLE001
            log.exception("building")
            self.publish({"type": "build-error", "message": f"internal error: {type(e).__name__}: {shorten(str(e))} "
                                                            f"(a bug in cogniframe; the studio's log has the details)"})
        finally:
            with self.lock:
                self.building = False
            self.publish({"type": "progress", "task": "build", "done": 1, "total": 1, "text": ""})

    def _build_line(self, line: str) -> None:
        import re

        m = re.match(r"\[\s*(\d+)/(\d+)\]\s+(\S+)", line)
        if m:
            self.publish({"type": "progress", "task": "build", "done": int(m.group(1)), "total": int(m.group(2)),
                          "text": f"{m.group(3)} ({m.group(1)}/{m.group(2)})"})

    def build_file(self, rel: str) -> Path | None:
        """A file of the last build, when its manifest lists it (nothing else is served)."""
        with self.lock:
            folder = self.build_dir
        if folder is None:
            return None
        try:
            manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        listed = {f["path"] for f in manifest.get("files", [])}
        return folder / rel if rel in listed and (folder / rel).is_file() else None

    # -- compare ----------------------------------------------------------------------------------
    def compare(self, designs: Any) -> Event:
        """The compare table's figures of each design ({"name", "base", "values"}); a design that
        does not validate gets its message instead. Each is checked as `cogniframe check` checks it
        (a joint geometry never solved: its FE first, seconds)."""
        prepared = [(name, self.base_of(base), self.parse_values(values)) for name, base, values in compare_items(designs)]
        columns = []
        for name, d0, overrides in prepared:
            try:
                d = d0.with_values(overrides) if overrides else d0
                columns.append({"name": name, "figures": compare_figures(d.check().to_dict())})
            except api.ParamsError as e:
                columns.append({"name": name, "error": shorten(str(e), 2000)})
        return {"type": "compared", "columns": columns}

    def close(self) -> None:
        """End the session's work, and return once it has ended: the edits and views still queued
        are dropped, a 3D view being made drops its CAD jobs (a joint FE solved in this process
        ends first), so no thread of it runs on into what follows or writes into the folder
        removed here. A Build runs on (it ends with the process)."""
        self._stop.set()
        self._edits.close()
        self._geometry.close()
        with self.lock:
            threads = list(self._threads)
        for t in threads:
            t.join()
        shutil.rmtree(self.tmp, ignore_errors=True)


class _Lines:
    """A text stream that hands each complete line to a callback (the build's progress lines)."""

    def __init__(self, on_line: Callable[[str], None]):
        self.on_line = on_line
        self.buf = ""

    def write(self, text: str) -> int:
        self.buf += text
        while "\n" in self.buf:
            line, self.buf = self.buf.split("\n", 1)
            self.on_line(line)
        return len(text)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False
