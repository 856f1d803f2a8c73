"""The studio's state and its background work, independent of the web server.

One `Session` per `cogniframe studio PARAMS`. The browser sends the values it changed (dotted
key -> what was typed) and gets events back (`publish(event)`: a JSON-able dict):

    figures   the `check --json` object of the edited design (`model`: "fe", or "analytic" while a
              new joint geometry's FE is solved: `pending_fe` true), `seq` of the edit, `ms`
    invalid   the CLI's message for the edited file, the key it names and the field edited
    scene     a new 3D view is ready at `url` (the viewer's items, packed)
    progress  background work: `task` ("view", "fe", "build"), `done`/`total`, `text`
    saved     the params file was written; built / build-error: the build's outcome

Work, by thread: `evaluator` validates and checks the newest edit (older edits that queued up
meanwhile are skipped: only the last one counts), in about a tenth of a second when no joint
needs its FE; `geometry` makes the parts of the newest geometry through the build graph (and the
joints' FE with them), then publishes the view and, after a FE, checks the current design again;
`build` runs `cogniframe build` into out/<name>. Nothing is written but the params file (Save)
and the build folder (Build); the parts of the 3D view go to a temporary folder, removed on exit.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import tempfile
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .. import api
from ..errors import UserError
from . import form

Event = dict


class _Latest:
    """A one-slot mailbox: `put` replaces what is waiting; `take` waits for something."""

    def __init__(self):
        self._cond = threading.Condition()
        self._item = None
        self._closed = False

    def put(self, item) -> None:
        with self._cond:
            self._item = item
            self._cond.notify_all()

    def offer(self, item) -> None:
        """`put`, unless something newer is already waiting."""
        with self._cond:
            if self._item is None:
                self._item = item
                self._cond.notify_all()

    def take(self):
        with self._cond:
            while self._item is None and not self._closed:
                self._cond.wait()
            item, self._item = self._item, None
            return item

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()


class Session:
    def __init__(self, params: str | Path, publish: Callable[[Event], None] | None = None,
                 server: bool | None = None, out_root: Path | None = None, view: bool = True):
        self.path = Path(params)
        self.view = view  # False: no 3D view (no CAD); the joints' FE is still solved for the figures
        self.base = api.load(self.path)  # ParamsError: the CLI says so and exits 2
        self.server = server
        self.out_root = out_root  # None: out/<name>, as the CLI's build
        self.publish_fn = publish or (lambda event: None)
        self.lock = threading.RLock()
        self.overrides: dict[str, Any] = {}
        self.seq = 0
        self.client = 0
        self.current: api.Design = self.base  # the newest valid design
        self.invalid: Event | None = None
        self.last: dict[str, Event] = {}  # the newest event of each type, for a page that connects later
        self.scenes: dict[str, tuple[dict, bytes]] = {}
        self.scene_key: str | None = None  # the geometry the newest scene shows
        self.requested_key: str | None = None  # the geometry the 3D view is being made for
        self.build_dir: Path | None = None
        self.building = False
        self.schema = None
        self.tmp = Path(tempfile.mkdtemp(prefix="cogniframe-studio-"))
        self._edits = _Latest()
        self._geometry = _Latest()
        self._closed = False
        self._threads = [threading.Thread(target=self._evaluator, name="studio-evaluate", daemon=True),
                         threading.Thread(target=self._geometry_worker, name="studio-geometry", daemon=True)]
        for t in self._threads:
            t.start()

    # -- the form -------------------------------------------------------------------------------
    def form_groups(self):
        from .. import spec as spec_mod

        if self.schema is None:
            self.schema = spec_mod.json_schema()
        return form.build(self.schema, self.base.spec.model_dump(mode="json"))

    def form_html(self) -> str:
        groups = self.form_groups()
        self.fields = form.fields(groups)
        return form.render(groups, self.base.spec.model_dump(mode="json"))

    def field(self, key: str) -> form.Field | None:
        if not hasattr(self, "fields"):
            self.fields = form.fields(self.form_groups())
        return self.fields.get(key)

    # -- events ---------------------------------------------------------------------------------
    def publish(self, event: Event) -> None:
        with self.lock:
            self.last[event["type"]] = event
            if event["type"] == "figures":
                self.last.pop("invalid", None)
            elif event["type"] == "invalid":
                self.last.pop("figures-stale", None)
        try:
            self.publish_fn(event)
        except Exception:  # noqa: BLE001 - a page that went away must not stop the work
            traceback.print_exc()

    def replay(self) -> list[Event]:
        """What a page that connects now needs to show the current state."""
        with self.lock:
            order = ("figures", "invalid", "scene", "progress", "saved", "built", "build-error")
            return [self.last[t] for t in order if t in self.last]

    # -- edits ----------------------------------------------------------------------------------
    def start(self) -> None:
        """The first figures and view, for the file as loaded."""
        self.edit({}, replace=True)

    def edit(self, changes: dict[str, Any], replace: bool = False, client: int = 0, edited: str | None = None) -> int:
        """Queue an edit: `changes` (dotted key -> what the browser sent) on top of the earlier
        ones (`replace`: instead of them). `client`: the page's number for the edit, sent back
        with its events. Returns the edit's sequence number here."""
        with self.lock:
            parsed = {}
            for key, raw in changes.items():
                f = self.field(key)
                parsed[key] = f.parse(raw) if f is not None else raw
            self.overrides = dict(parsed) if replace else {**self.overrides, **parsed}
            self.seq += 1
            self.client = client
            job = (self.seq, client, dict(self.overrides), edited or next(reversed(changes), None), time.perf_counter(), False)
        self._edits.put(job)
        return job[0]

    def _evaluator(self) -> None:
        while True:
            job = self._edits.take()
            if job is None:
                return
            try:
                self._evaluate(*job)
            except Exception as e:  # noqa: BLE001 - a bug: say so on the page, keep serving
                traceback.print_exc()
                self.publish({"type": "invalid", "seq": job[0], "client": job[1], "key": None, "edited": job[3],
                              "message": f"internal error: {type(e).__name__}: {e} (a bug in cogniframe, not in your input)"})

    def _evaluate(self, seq: int, client: int, overrides: dict, edited: str | None, t0: float, after_fe: bool) -> None:
        try:
            d = self.base.with_values(overrides) if overrides else self.base
        except api.ParamsError as e:
            with self.lock:
                self.invalid = {"type": "invalid", "seq": seq, "client": client, "key": e.key, "edited": edited, "message": str(e)}
            self.publish(dict(self.invalid, ms=round(1000 * (time.perf_counter() - t0), 1)))
            return
        pending_fe = d.needs_fe()
        shown = d.with_fast_model() if pending_fe else d
        try:
            result = shown.check()
        except api.ParamsError as e:
            self.publish({"type": "invalid", "seq": seq, "client": client, "key": e.key, "edited": edited, "message": str(e)})
            return
        with self.lock:
            if seq < self.seq and not after_fe:
                return  # a newer edit is queued: it will show its own figures
            self.current, self.invalid = d, None
        self.publish({"type": "figures", "seq": seq, "client": client, "check": result.to_dict(), "model": result.stiffness_model,
                      "pending_fe": pending_fe, "after_fe": after_fe, "modified": d.modified,
                      "ms": round(1000 * (time.perf_counter() - t0), 1)})
        key = geometry_key(d)
        with self.lock:
            wanted = pending_fe or key not in (self.scene_key, self.requested_key)
            if wanted:
                self.requested_key = key
        if wanted:
            self._geometry.put((seq, d, key, pending_fe))

    # -- geometry: parts, 3D view, joint FE --------------------------------------------------------
    def _geometry_worker(self) -> None:
        from ..api import view
        from ..report.viewer import pack

        n = 0
        while True:
            job = self._geometry.take()
            if job is None:
                return
            seq, d, key, fe = job
            if not self.view:
                if fe:
                    self._solve_fe(d)
                continue
            n += 1
            out = self.tmp / f"view-{n}"
            t0 = time.perf_counter()
            self.publish({"type": "progress", "task": "view", "done": 0, "total": 1, "fe": fe,
                          "text": "making the parts" + (" and solving the joints' FE" if fe else "")})
            n_parts = len(d.derived.parts)
            parts_done: list[str] = []
            shown: list[threading.Thread] = []

            def show_view(values: dict, d=d, out=out, key=key, seq=seq, t0=t0) -> None:
                """The 3D view as soon as the parts are made (the joints' FE may still run)."""
                try:
                    packed = pack(view.items(d.spec, d.derived, out, values))
                except Exception as e:  # noqa: BLE001
                    traceback.print_exc()
                    self._view_failed(key)
                    self.publish({"type": "progress", "task": "view", "done": 1, "total": 1, "text": f"the 3D view failed: {e}",
                                  "error": f"{type(e).__name__}: {e}"})
                    return
                with self.lock:
                    self.scenes = {key: packed}  # only the newest is kept
                    self.scene_key = key
                    current = geometry_key(self.current) == key
                if current:
                    self.publish({"type": "scene", "seq": seq, "url": f"/scene/{key}.json", "key": key,
                                  "objects": len(packed[0]["objects"]), "seconds": round(time.perf_counter() - t0, 2)})

            def step(task: str, done: int, total: int, part_values=None, parts_done=parts_done, n_parts=n_parts,
                     fe=fe, shown=shown, show_view=show_view) -> None:
                is_part = task.startswith("part:")
                if is_part:
                    parts_done.append(task)
                all_parts = is_part and len(parts_done) == n_parts
                what = f"made the {task.rsplit('/', 1)[-1]}" if is_part else "solved the joints' FE"
                if fe and all_parts:
                    what += "; solving the joints' FE"
                self.publish({"type": "progress", "task": "view", "done": done, "total": total, "fe": fe,
                              "text": f"{what} ({done}/{total})"})
                if all_parts and part_values is not None:
                    t = threading.Thread(target=show_view, args=(part_values(),), name="studio-view", daemon=True)
                    shown.append(t)
                    t.start()

            try:
                view.build_parts(d.spec, d.derived, out, fe=fe, server=self.server, on_step=step)
            except UserError as e:
                self._view_failed(key)
                self.publish({"type": "progress", "task": "view", "done": 1, "total": 1, "error": str(e), "text": str(e)})
                if fe:  # the figures wait for the FE: solve it on its own, or say why it cannot be
                    self._solve_fe(d)
                continue
            except Exception as e:  # noqa: BLE001
                traceback.print_exc()
                self._view_failed(key)
                self.publish({"type": "progress", "task": "view", "done": 1, "total": 1, "text": f"the 3D view failed: {e}",
                              "error": f"{type(e).__name__}: {e}"})
                if fe:
                    self._solve_fe(d)
                continue
            finally:
                for t in shown:
                    t.join()
                shutil.rmtree(out, ignore_errors=True)
            self.publish({"type": "progress", "task": "view", "done": 1, "total": 1, "text": "", "fe": False})
            if fe:  # the joints are in the cache now: the figures of the current design, FE this time
                self._after_fe()

    def _solve_fe(self, d: api.Design) -> None:
        self.publish({"type": "progress", "task": "fe", "done": 0, "total": 1, "text": "solving the joints' FE"})
        try:
            d.check()  # solves the new joints into the cache
        except Exception as e:  # noqa: BLE001
            self.publish({"type": "progress", "task": "fe", "done": 1, "total": 1, "text": "", "error": f"{type(e).__name__}: {e}"})
            return
        self.publish({"type": "progress", "task": "fe", "done": 1, "total": 1, "text": ""})
        self._after_fe()

    def _after_fe(self) -> None:
        with self.lock:
            job = (self.seq, self.client, dict(self.overrides), None, time.perf_counter(), True)
        self._edits.offer(job)  # a queued edit already stands for the current design

    def _view_failed(self, key: str) -> None:
        with self.lock:
            if self.requested_key == key:
                self.requested_key = None  # the next edit tries again

    def scene(self, key: str) -> tuple[dict, bytes] | None:
        with self.lock:
            return self.scenes.get(key)

    # -- save and build ---------------------------------------------------------------------------
    def save(self) -> Event:
        """Write the edited params to the file (comments and order kept). Refused while the newest
        edit is invalid, or when the file changed on disk since the studio read it."""
        with self.lock:
            if self.invalid is not None:
                return {"type": "save-error", "message": "not saved: " + self.invalid["message"]}
            d = self.current
            try:
                on_disk = self.path.read_bytes().decode("utf-8-sig")
            except (OSError, UnicodeDecodeError) as e:
                return {"type": "save-error", "message": f"not saved: {self.path} cannot be read ({e})."}
            if on_disk != self.base.text:
                return {"type": "save-error", "message": f"not saved: {self.path} changed on disk since the studio read it; "
                                                          f"nothing was written. Restart the studio to edit the new version."}
            d.save()
            self.base = api.load(self.path)
            self.overrides = {}
            self.current = self.base
        event = {"type": "saved", "path": str(self.path)}
        self.publish(event)
        return event

    def build(self) -> Event:
        """Start `cogniframe build` of the current design into out/<name> (a thread)."""
        with self.lock:
            if self.invalid is not None:
                return {"type": "build-error", "message": "not built: " + self.invalid["message"]}
            if self.building:
                return {"type": "build-error", "message": "a build is already running"}
            self.building = True
            d = self.current
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
            self.publish({"type": "build-error", "message": str(e)})
        except Exception as e:  # noqa: BLE001
            traceback.print_exc()
            self.publish({"type": "build-error", "message": f"internal error: {type(e).__name__}: {e} (a bug in cogniframe)"})
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

    def close(self) -> None:
        self._closed = True
        self._edits.close()
        self._geometry.close()
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


def geometry_key(d: api.Design) -> str:
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
