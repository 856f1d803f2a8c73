"""`cogniframe build`: the whole fabrication folder, built in a temp dir and moved into place whole.

The work is the graph of cached steps in pipeline/steps.py (part CAD, check with CAD volumes, plates,
slicer, assembly, plots, previews, renders, BOM, report; docs/build.md), then the manifest.
Nothing appears in the output folder unless every step succeeded, and a folder
cogniframe did not make is never touched (outdir.py: lock, ownership check, atomic swap).
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from .. import outdir, stack
from .. import design as design_mod
from ..analysis import verdict
from ..cache import file_sha256
from ..spec import Spec


@dataclass(frozen=True)
class Outcome:
    out_dir: Path
    files: int
    verdict: str
    check: verdict.Findings | None  # None when the folder was already up to date
    built: tuple
    steps: tuple = ()  # (step, "ran" | "cached" | "always") in the order they finished; () when up to date


def run_build(spec: Spec, params_path: Path, out: Path | None, jobs: int | None = None, use_cache: bool = True,
              console: Console | None = None, gcode: bool = False, server: bool = False, early=None) -> Outcome:
    """Build `spec` into `out`. `server`: CAD workers from the CAD server that outlives this build
    (`runtime.cad_server`; the CLI's default) instead of a process pool of its own. `early`: the
    server the CLI started before it validated the params (`runtime.cad_server.prestart`); the caller
    releases it (`Early.release`) when the build did not connect to it."""
    console = console or Console(stderr=True)
    with spec.blamed():
        design = design_mod.design(spec)  # a design that cannot exist is refused before any folder is touched
    final = outdir.output_dir(spec, out)
    key = build_key(spec, params_path) + ("+gcode" if gcode else "")  # a --gcode build differs
    if use_cache and _up_to_date(final, key):
        verdict = json.loads((final / "check.json").read_text())["verdict"]
        console.print(f"{final} is up to date (same params, same cogniframe): nothing rebuilt", markup=False)
        files = len(json.loads((final / "manifest.json").read_text())["files"]) + 1
        return Outcome(final, files, verdict, None, ())
    with outdir.writing(final) as tmp, spec.blamed():
        result = _build_into(spec, params_path, tmp, jobs, use_cache, console, key, gcode=gcode, design=design,
                             server=server, early=early)
    return Outcome(final, result[0], result[1].verdict, result[1], result[2], result[3])


def build_key(spec: Spec, params_path: Path) -> str:
    """Everything a build's bytes depend on: the params, the installed stack and cogniframe's code."""
    from .. import cache

    return cache.key([file_sha256(Path(params_path)), spec.digest()], ("**/*.py",), json.dumps(stack.installed(), sort_keys=True))


def _up_to_date(final: Path, key: str) -> bool:
    """True when `final` was built with this key and every file it lists is still as written."""
    try:
        manifest = json.loads((final / "manifest.json").read_text())
    except (OSError, ValueError):
        return False
    if manifest.get("build_key") != key:
        return False
    listed = {f["path"] for f in manifest["files"]}
    present = {p.relative_to(final).as_posix() for p in final.rglob("*") if p.is_file()} - {"manifest.json"}
    return listed == present and all(file_sha256(final / f["path"]) == f["sha256"] for f in manifest["files"])


def _build_into(spec: Spec, params_path: Path, out: Path, jobs: int | None, use_cache: bool, console: Console,
                key: str, gcode: bool = False, design: design_mod.Derived | None = None, server: bool = False,
                early=None):
    """Run the build graph (steps.py) into `out`, then write the manifest. `gcode`: keep the
    sliced G-code per plate (`build --gcode`; read by pipeline.plate_steps.make_slice).

    Returns (files, check result, built parts, ((step, "ran" | "cached" | "always"), ...))."""
    design = design_mod.design(spec) if design is None else design
    log = lambda m: console.print(m, markup=False, highlight=False)  # noqa: E731
    from . import graph, steps

    total = len(graph.expand(steps.STEPS, steps.rows(design)))
    with _StepProgress(console, total, spec.name) as progress:
        ctx, records = run(spec, design, out, jobs=jobs, server=server, early=early, use_cache=use_cache, log=log,
                           gcode=gcode, on_start=progress.start,
                           on_step=lambda record, ctx: progress.done(record))
    n = _write_manifest(spec, params_path, out, key)
    return n, ctx["check"], ctx.built_parts(), tuple((r.task, r.status) for r in records)


def run(spec: Spec, design: design_mod.Derived, out: Path, *, only: tuple[str, ...] | None = None,
        jobs: int | None = None, server: bool = False, early=None, use_cache: bool = True, log=None,
        gcode: bool = False, on_start=None, on_step=None, stop=None):
    """Run the build graph's steps for `design` into the folder `out`: the one place that wires
    the steps, their inputs and the CAD runtime (the CLI's build, the API's and the studio's 3D
    view all come here). `only`: task-name patterns (e.g. `("part:*", "estimate")`) to run a
    part of the graph; None runs all of it. `on_start(task)` before and `on_step(record, ctx)` after
    each task (`ctx.part_value` reads a finished part's files). `stop` (a threading.Event): once set,
    the CAD jobs are dropped and `graph.Stopped` is raised when the steps under way end. Returns
    (the context, with every task's value, and the records in finishing order)."""
    import fnmatch

    from . import graph, steps
    from .context import BuildContext, Inputs, NoWarmup, Slicer, needs_joint_fe
    from .. import stack
    from ..runtime import BuildRuntime

    log = log or (lambda message: None)
    tasks = graph.expand(steps.STEPS, steps.rows(design))
    if only is not None:
        tasks = [t for t in tasks if any(fnmatch.fnmatchcase(t.name, p) for p in only)]
    whole = only is None
    if whole:
        from ..report.renders import ensure_headless

        ensure_headless()  # before any thread starts: the environment is not changed while one starts a process
    slicer = Slicer(log) if whole else None
    fe = any(t.name == "estimate" for t in tasks) and needs_joint_fe(spec, design)
    versions = stack.versions()
    out.mkdir(parents=True, exist_ok=True)
    with BuildRuntime(jobs or os.cpu_count() or 1, fe=fe, server=server, stack=versions, log=log, early=early,
                      warm_before=slicer.get if slicer else None) as rt:
        ctx = BuildContext(out, Inputs(spec, design, rt.cad, rt.warm if whole else NoWarmup(), log, slicer, gcode),
                           stack=versions, use_cache=use_cache)
        if rt.cad.fe or any(graph.will_run(t, ctx) for t in tasks if t.name.startswith("part:")):
            rt.cad.start_server()  # now, beside the set-up below, not when the first part step submits
        records = graph.run(tasks, ctx, on_start=on_start, on_error=rt.cancel,
                            on_done=None if on_step is None else (lambda record: on_step(record, ctx)),
                            main_lock=rt.main_lock if whole else None, stop=stop)
    return ctx, records


class _StepProgress:
    """One line per step as it finishes (cached ones marked); on a terminal also a live bar."""

    def __init__(self, console: Console, total: int, name: str):
        self.console, self.total, self.name = console, total, name
        self.n = 0
        self.counts: dict[str, int] = {}
        self.progress = None

    def __enter__(self):
        self.t0 = time.perf_counter()
        if self.console.is_terminal:
            self.progress = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                                     TimeElapsedColumn(), console=self.console, transient=True)
            self.progress.__enter__()
            self.bar = self.progress.add_task(f"building {self.name}", total=self.total)
        return self

    def start(self, task: str) -> None:
        if self.progress is not None:
            self.progress.update(self.bar, description=f"building {self.name}: {task}")

    def done(self, rec) -> None:
        self.n += 1
        self.counts[rec.status] = self.counts.get(rec.status, 0) + 1
        # ran: how long it took and when it ended (seconds into the build), so a slow build shows its critical path
        took = "cached" if rec.status == "cached" else f"{rec.seconds:5.1f} s, done at {time.perf_counter() - self.t0:.1f} s"
        text = f"[{self.n:>{len(str(self.total))}}/{self.total}] {rec.task:<28} {took}"
        if self.progress is not None:
            self.progress.console.print(text, style="dim" if rec.status == "cached" else None, markup=False,
                                        highlight=False)
            self.progress.update(self.bar, advance=1)
        else:
            self.console.print(text, markup=False, highlight=False, soft_wrap=True)

    def __exit__(self, *exc):
        if self.progress is not None:
            self.progress.__exit__(*exc)
        if exc[0] is None:
            ran = self.counts.get("ran", 0) + self.counts.get("always", 0)
            self.console.print(f"{self.n} steps: {ran} ran, {self.counts.get('cached', 0)} cached", markup=False,
                               highlight=False)
        return False


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")


def _write_manifest(spec: Spec, params_path: Path, out: Path, key: str) -> int:
    files = sorted(p for p in out.rglob("*") if p.is_file() and p.name != outdir.TEMP_MARK)
    manifest = {
        "generator": outdir.GENERATOR,
        "name": spec.name,
        "build_key": key,
        "params_file": Path(params_path).name,
        "params_sha256": file_sha256(Path(params_path)),
        "spec_sha256": spec.digest(),
        "versions": stack.installed(),
        "files": [{"path": p.relative_to(out).as_posix(), "size": p.stat().st_size, "sha256": file_sha256(p)} for p in files],
        # outside the identical-rebuild promise: `build --gcode`'s G-code has a timestamp and threaded path order
        "not_reproducible": [p.relative_to(out).as_posix() for p in files if p.suffix == ".gcode"],
    }
    _write(out / "manifest.json", json.dumps(manifest, indent=2) + "\n")
    return len(files) + 1
