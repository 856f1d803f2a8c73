"""cogniframe's Python API: the same designs, checks and builds as the CLI, from Python.

    import cogniframe as cf

    d = cf.load("params/carbon.yaml")              # Design (validated like `cogniframe check`)
    d2 = d.with_values({"rods.diameter": 4.0})     # a new Design; d is unchanged
    r = d2.check()                                 # CheckResult: verdict, mass_g, k_n_per_m, ...
    r.to_dict() == json.loads(`check --json`)      # the CLI's JSON, key for key
    d2.build("out/carbon-4mm")                     # BuildResult, under the CLI's output-folder rules
    d2                                             # in Jupyter: the 3D view (the report's viewer)
    cf.sweep("examples/sweeps/carbon.yaml")        # pandas DataFrame, one row per design

Bad input raises `ParamsError` (a `UserError`) whose message is the paragraph the CLI prints for
the same file: it names the file, the key with its line, and the fix. A design made by
`with_values` keeps its YAML text with the values edited in place (comments and order kept,
`yamledit`), so its messages name the user's file and the line the key has in what `save` would
write. The CLI's `check` and `build` commands call this module. docs/api.md has the reference.
"""

from __future__ import annotations

import os
import re
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import UserError

from .results import BuildResult, CheckResult

if TYPE_CHECKING:  # pragma: no cover
    import pandas

    from .. import design as design_mod
    from ..spec import Spec

__all__ = ["BuildResult", "CheckResult", "Design", "ParamsError", "load", "sweep"]


class ParamsError(UserError):
    """A params value cogniframe refuses. `str(err)` is the CLI's paragraph (file, key with its
    line, fix); `key` is the first dotted key it names (None when it names none)."""

    def __init__(self, message: str, key: str | None = None, located: bool = True):
        super().__init__(message, key=key, located=located)


def _params_error(err: UserError, source: str) -> ParamsError:
    if isinstance(err, ParamsError):
        return err
    return ParamsError(str(err), err.key or key_named(str(err), source), True)


_KEY = re.compile(r"([A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z0-9_]+)*)(?: \(|:)")


def key_named(message: str, source: str) -> str | None:
    """The dotted key a message names right after its file (`FILE: rods.diameter (line 17): ...`)."""
    first = message.split("\n", 1)[0]
    prefix = f"{source}: "
    if not first.startswith(prefix):
        return None
    m = _KEY.match(first[len(prefix):])
    return m.group(1) if m else None


# -- Design -----------------------------------------------------------------------------------

class Design:
    """One validated design: its params (`spec`), the YAML text they come from, and where that
    text lives. Immutable: `with_values` returns a new Design."""

    def __init__(self, spec: Spec, text: str, source: str, path: Path | None, design: design_mod.Derived | None = None):
        self._spec = spec
        self._text = text
        self._source = source
        self._path = path
        self._design = design

    # what it is
    @property
    def spec(self) -> Spec:
        """The validated params (`cogniframe.spec.Spec`, a frozen pydantic model)."""
        return self._spec

    @property
    def name(self) -> str:
        return self._spec.name

    @property
    def text(self) -> str:
        """The params file's YAML text, with any `with_values` edits."""
        return self._text

    @property
    def path(self) -> Path | None:
        """The params file this design was loaded from (None for text)."""
        return self._path

    @property
    def source(self) -> str:
        """How messages name the params file (the path as given to `load`)."""
        return self._source

    @property
    def derived(self) -> design_mod.Derived:
        """Frame graph, part list and cut list (`design_mod.Derived`): what the checks and the CAD use."""
        if self._design is None:
            from .. import design as design_mod

            try:
                with self._spec.blamed():
                    self._design = design_mod.design(self._spec)
            except UserError as e:
                raise _params_error(e, self._source) from None
        return self._design

    def validate(self) -> Design:
        """Check that the frame and its parts can exist (a part that fits no bed, a propeller that
        hits the cage): ParamsError otherwise. `load` and `with_values` do it."""
        self.derived  # noqa: B018 (made on first use, which validates)
        return self

    @property
    def modified(self) -> bool:
        """Whether `text` differs from the file on disk (unsaved `with_values` edits)."""
        if self._path is None:
            return True
        try:
            return self._path.read_bytes().decode("utf-8-sig") != self._text
        except (OSError, UnicodeDecodeError):
            return True

    def get(self, key: str) -> Any:
        """The value of a dotted key as validated (defaults and printer presets applied)."""
        node: Any = self._spec.model_dump(mode="json")
        for part in key.split("."):
            if isinstance(node, list) and part.isdigit() and int(part) < len(node):
                node = node[int(part)]
            elif isinstance(node, dict) and part in node:
                node = node[part]
            else:
                raise KeyError(key)
        return node

    def __repr__(self) -> str:
        return f"<cogniframe.Design {self.name!r} from {self._source}{' (edited)' if self.modified else ''}>"

    # changing it
    def with_values(self, values: Mapping[str, Any]) -> Design:
        """A new Design with the dotted keys set (`{"rods.diameter": 4.0, "joints.wall": 1.6}`),
        validated as `cogniframe check` validates the file that `save` would write (the schema,
        the cross-field rules and the frame and part geometry). The original is unchanged.
        Raises ParamsError with the CLI's paragraph for that file."""
        from . import yamledit

        try:
            text = yamledit.set_values(self._text, dict(values))
        except KeyError as e:
            key = next(iter(values), "")
            raise ParamsError(f"{self._source}: {key}: {e.args[0] if e.args else e}. Fix: give a dotted key of the params "
                              f"file, e.g. rods.diameter (`cogniframe schema` lists them).", key) from None
        return from_text(text, self._source, self._path)

    def save(self, path: str | Path | None = None) -> Path:
        """Write the YAML text (comments and order kept) to `path`, by default the file it was
        loaded from. A different `path` must not exist yet (cogniframe never writes over a file it
        did not write). The file is replaced atomically. Returns the path written."""
        target = Path(path) if path is not None else self._path
        if target is None:
            raise UserError("this design was not loaded from a file. Fix: give save() a path.")
        if path is not None and (self._path is None or target.resolve() != self._path.resolve()) and os.path.lexists(target):
            raise UserError(f"{target} already exists; cogniframe never writes over a file it did not write. "
                            f"Fix: give save() a new file name, or save to {self._path or 'the file it came from'}.")
        write_text_atomic(target, self._text)
        return target

    # using it
    def check(self) -> CheckResult:
        """Mass budget, stiffness, crash model, flight and PASS/FAIL: `cogniframe check`. The first
        check of a new joint geometry runs its solid FE (seconds; cached after)."""
        from ..analysis import verdict
        from ..analysis.drop import Session
        from ..analysis.joints import needs_fe
        from ..analysis.numerics import one_blas_thread

        from ..runtime.pools import joint_fe_workers

        d = self.derived
        try:
            with self._spec.blamed(), one_blas_thread():  # as `build` computes it: same numbers
                session = Session(self._spec, d.frame, d.parts)  # this check's frame model
                outside = session.outside if self._spec.model.stiffness_model == "surrogate" else None
                if needs_fe(self._spec, d.parts, outside):  # new joint geometries: their FE on worker processes first
                    from ..analysis.joints import solve_fe

                    with joint_fe_workers() as submit:
                        solve_fe(self._spec, d.parts, submit)
                result = verdict.check(self._spec, design_=d, session=session)
        except UserError as e:
            raise _params_error(e, self._source) from None
        return CheckResult(result)

    def needs_fe(self) -> bool:
        """Whether `check` would solve a joint's finite-element model first (a joint geometry not in
        the cache yet, with `model.stiffness_model: fe`, or outside the surrogate's training box
        with `surrogate`): seconds instead of a tenth of one."""
        from ..analysis.joints import needs_fe

        return needs_fe(self._spec, self.derived.parts)

    def with_fast_model(self) -> Design:
        """This design with `model.stiffness_model: analytic` (the joints' closed forms, milliseconds):
        the screening model the studio shows while a joint's FE is solved. A pegged core link
        (core.link: pegs) has no closed form: its fast model is the FE's surrogate (milliseconds too,
        the FE itself for a joint outside its training box)."""
        from .. import spec as spec_mod
        from ..families.joint_kinds.kinds import closed_forms_cover

        data = self._spec.model_dump(mode="json", exclude_unset=False)
        data["model"]["stiffness_model"] = "analytic" if closed_forms_cover(self._spec) else "surrogate"
        fast = spec_mod.from_dict(data, source=self._source, text=self._text)
        return Design(fast, self._text, self._source, self._path, self._design)

    def build(self, out: str | Path | None = None, *, jobs: int | None = None, use_cache: bool = True,
              gcode: bool = False, server: bool | None = None, console=None, early=None) -> BuildResult:
        """`cogniframe build`: every part, plate, the assembly, the report, into `out` (default
        out/<name>). The CLI's rules hold: only a folder cogniframe made is replaced, whole, and
        only when the build succeeded. `server`: CAD workers from the CAD server (None: the CLI's
        default, COGNIFRAME_CAD_SERVER). `console`: a rich Console for the progress lines
        (default: stderr)."""
        from ..pipeline import run_build
        from ..runtime import cad_server

        out_path = Path(out) if out is not None else None
        use_server = cad_server.wanted(server)
        if not use_server:
            _refuse_unguarded_build(server)
        try:
            with self._params_file() as params_path:
                result = run_build(self._spec, params_path, out_path, jobs=jobs, use_cache=use_cache, console=console,
                                   gcode=gcode, server=use_server, early=early)
        except UserError as e:
            if e.key is not None or str(e).startswith(f"{self._source}: "):
                raise _params_error(e, self._source) from None
            raise
        return BuildResult(result)

    def _params_file(self):
        """A context giving the params file whose bytes are this design's text: the file it was
        loaded from when unchanged, else a temporary copy with the same file name."""
        import contextlib

        if not self.modified and self._path is not None:
            return contextlib.nullcontext(self._path)

        @contextlib.contextmanager
        def temp():
            with tempfile.TemporaryDirectory(prefix="cogniframe-params-") as folder:
                p = Path(folder) / (Path(self._source).name if self._source.endswith((".yaml", ".yml")) else f"{self.name}.yaml")
                p.write_text(self._text, encoding="utf-8")
                yield p

        return temp()

    def fly(self, out: str | Path | None = None) -> Path:
        """`cogniframe fly`: the flight-controller setup and simulator models (INAV, Betaflight,
        ArduPilot SITL, PX4 SIH and airframe, Gazebo, rotorpy) and the resonance check, from the
        part list's estimates, into `out` (default out/<name>-flight). Only a folder cogniframe
        made is replaced, whole. Returns the folder."""
        import json

        from .. import flight, outdir
        from ..cache import file_sha256

        final = Path(out) if out is not None else Path("out") / f"{self._spec.name}-flight"
        result = self.check().result
        try:
            with self._spec.blamed():
                v = flight.make_vehicle(self._spec, result)
        except UserError as e:
            raise _params_error(e, self._source) from None
        final.parent.mkdir(parents=True, exist_ok=True)
        with outdir.writing(final) as tmp:
            files = flight.write(v, tmp)
            listed = [{"path": f, "size": (tmp / f).stat().st_size, "sha256": file_sha256(tmp / f)} for f in sorted(files)]
            (tmp / outdir.MANIFEST).write_text(json.dumps({"generator": outdir.GENERATOR, "files": listed}, indent=2) + "\n",
                                               encoding="utf-8")
        return final

    def view_html(self) -> str:
        """The 3D view (the report's three.js viewer) as one self-contained HTML fragment: three.js,
        the viewer and the geometry inline, no network. The parts are built through the build
        graph and its cache (seconds the first time, a cache copy after)."""
        from . import view

        return view.design_html(self)

    def _repr_html_(self) -> str:
        try:
            return self.view_html()
        except UserError as e:
            import html

            return f"<pre>{html.escape(str(e))}</pre>"


def load(path: str | Path) -> Design:
    """Read and validate a params file as `cogniframe check` does. Raises ParamsError."""
    return _load(path, validate=True)


def _load(path: str | Path, validate: bool = True) -> Design:
    """`load`; `validate=False` leaves the frame and part geometry to the first use (the CLI's
    `build` validates them itself, as before)."""
    from .. import spec as spec_mod

    source = str(path)
    try:
        spec = spec_mod.load(path)
    except UserError as e:
        raise _params_error(e, source) from None
    text = spec_mod.decode(Path(path).read_bytes(), Path(path))
    d = Design(spec, text, source, Path(path))
    if validate:
        d.validate()
    return d


def build_file(path: str | Path, out: str | Path | None = None, *, jobs: int | None = None, use_cache: bool = True,
               gcode: bool = False, server: bool | None = None, console=None) -> BuildResult:
    """`cogniframe build PATH`: `load(path).build(...)`, with the CAD server (when wanted) started
    before the params are read, so that its seconds of imports overlap this process's own and
    the validation; the server is let go again when the build did not connect to it (bad
    params, nothing to build, Ctrl-C)."""
    from ..runtime import cad_server

    use_server = cad_server.wanted(server)
    early = None
    if use_server:
        from ..stack import versions

        early = cad_server.prestart(versions())
    try:
        from ..runtime.heap import imports_frozen

        with imports_frozen():
            from .. import pipeline  # noqa: F401  (its imports, frozen with the others)

        design = _load(path, validate=False)  # the build validates the frame and parts before any folder is touched
        return design.build(out, jobs=jobs, use_cache=use_cache, gcode=gcode, server=use_server, console=console,
                            early=early)
    finally:
        if early is not None:
            early.release()


def from_text(text: str, source: str = "<params>", path: Path | None = None) -> Design:
    """A Design from YAML text; messages name `source` (e.g. the file the text will be saved to)."""
    from .. import spec as spec_mod

    try:
        data = spec_mod.parse_yaml(text, source)
        if data is None:
            data = {}
        if not isinstance(data, dict):
            raise UserError(f"{source}: the file must be a mapping of sections (frame:, rods:, joints: ...), not a "
                            f"{type(data).__name__}. Fix: start from a preset such as params/carbon.yaml (`cogniframe schema` lists every key).")
        data.setdefault("name", spec_mod.slug(Path(source).stem))
        spec = spec_mod.from_dict(data, source=source, text=text)
    except UserError as e:
        raise _params_error(e, source) from None
    d = Design(spec, text, source, path)
    d.validate()  # the frame and parts must exist (a part that does not fit the bed, ...)
    return d


def write_text_atomic(path: Path, text: str) -> None:
    """Replace `path` with `text` whole (a temp file beside it, renamed over it; its mode kept)."""
    path = Path(path)
    mode = path.stat().st_mode & 0o7777 if path.exists() else None
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".cogniframe-tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
            f.write(text)
        if mode is not None:
            os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _refuse_unguarded_build(server: bool | None) -> None:
    """A build without the CAD server makes its parts on forkserver / spawn worker processes, and
    those run the main script again: from a script's unguarded top level it would start the build
    once more in each of them (they fail on the output folder's lock). Say so instead. With the
    server (the default on Linux) the workers are forks of the server, which runs no script."""
    import sys

    from ..runtime.mainguard import unguarded_main_script

    where = unguarded_main_script()
    if where is None:
        return
    why = ("server=False" if server is False else "COGNIFRAME_CAD_SERVER=0" if sys.platform.startswith("linux")
           else "there is no CAD server off Linux")
    raise UserError(f"{where[0]}, line {where[1]}: this build runs at the script's top level, not under "
                    f'`if __name__ == "__main__":`, and without the CAD server ({why}) its CAD worker processes would '
                    f"run the script again. Fix: put the script's code under that line"
                    + (", or build with the CAD server (leave COGNIFRAME_CAD_SERVER unset, or server=True)."
                       if sys.platform.startswith("linux") else "."))


# -- sweeps -----------------------------------------------------------------------------------

def sweep(sweep_file_or_dict: str | Path | Mapping[str, Any], scheduler: str | None = None, *,
          out: str | Path | None = None, workers: int | None = None,
          progress: Callable[[Any], None] | None = None) -> pandas.DataFrame:
    """`cogniframe sweep` from Python: every design of the sweep checked on Dask; one row per
    design (the columns of results.parquet, docs/sweeps.md). A sweep file writes its folder as
    the CLI does (`out`, default out/sweeps/<file name>: results.parquet, plots, summary; resumable).
    A dict (the sweep file's keys; `base` may be a path or a Design) runs in a temporary folder
    unless `out` is given. `scheduler`: a Dask scheduler's address (default: local processes)."""
    import pandas as pd

    from ..sweep import run as sweep_run
    from ..sweep import sweepfile

    with tempfile.TemporaryDirectory(prefix="cogniframe-sweep-") as tmp:
        if isinstance(sweep_file_or_dict, Mapping):
            data = dict(sweep_file_or_dict)
            if isinstance(data.get("base"), Design):
                base: Design = data["base"]
                p = Path(tmp) / "params" / f"{base.name}.yaml"
                p.parent.mkdir()
                p.write_text(base.text, encoding="utf-8")
                data["base"] = str(p)
            sw = sweepfile.from_dict(data, source="<sweep>", text=None, folder=Path.cwd())
            folder = Path(out) if out is not None else Path(tmp) / "sweep"
            reports = out is not None
        else:
            sw = sweepfile.load(sweep_file_or_dict)
            folder = Path(out) if out is not None else sweep_run.default_out(sw)
            reports = True
        result = sweep_run.run_sweep(sw, folder, scheduler=scheduler, workers=workers, progress=progress, reports=reports)
        table = result.out_dir / sweep_run.RESULTS
        df = pd.read_parquet(table) if table.is_file() else pd.DataFrame()
    df.attrs["out_dir"] = str(result.out_dir) if out is not None or not isinstance(sweep_file_or_dict, Mapping) else None
    df.attrs["summary"] = result.as_dict()
    return df


def optimize(sweep_file: str | Path, *, minimize=(), maximize=(), constraints=(), trials: int | None = None,
             out: str | Path | None = None, scheduler: str | None = None, workers: int | None = None, cad: int = 0,
             verify: int | None = None, progress: Callable[[Any], None] | None = None):
    """`cogniframe optimize` from Python: optuna over the sweep file's vary box on Dask, into `out`
    (default out/sweeps/<file name>: trials.parquet, best.yaml). `minimize`/`maximize`: output
    names (e.g. "mass_g"); `constraints`: "OUT >= V" / "OUT <= V". Returns the run's result
    (`best`, `as_dict()`, `text()`)."""
    from ..sweep import optimize as opt
    from ..sweep import sweepfile

    sw = sweepfile.load(sweep_file)
    objectives = opt.parse_objectives(list(minimize), list(maximize))
    parsed = [opt.parse_constraint(c) for c in constraints]
    return opt.run_optimize(sw, objectives, parsed, out_dir=Path(out) if out is not None else None, trials=trials,
                            scheduler=scheduler, workers=workers, cad=cad, verify=verify, progress=progress)


def sweep_progress() -> Callable[[Any], None]:
    """The command line's progress display for `sweep` and `optimize`: a bar on a terminal, one
    line per batch otherwise (on stderr)."""
    from ..sweep import run as sweep_run

    return sweep_run.progress_printer()


def sweep_schema() -> dict:
    """The JSON Schema of a sweep file (for editor autocompletion)."""
    from ..sweep import sweepfile

    return sweepfile.json_schema()
