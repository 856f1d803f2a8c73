"""Command line: thin wrappers over the Python API (api/). Exit codes: 0 ok/PASS, 1 FAIL, 2 bad input."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import sys
import threading
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.console import Console

from .errors import UserError, bug_message

app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="CogniFly exoskeleton generator: params file in; parts, cut list, mass and crash margin out. "
                       "Exit codes: 0 PASS, 1 FAIL, 2 bad input, 3 a bug in cogniframe, 130 interrupted. "
                       "--debug (or COGNIFRAME_DEBUG=1) prints the traceback of a bug.")

ParamsArg = Annotated[Path, typer.Argument(help="params YAML file, e.g. params/bamboo.yaml", show_default=False)]


@app.command()
def check(params: ParamsArg,
          json_out: Annotated[bool, typer.Option("--json", help="print one JSON object instead of tables")] = False,
          plots: Annotated[Optional[Path], typer.Option(help="also write the drop-model plots into this folder")] = None) -> None:
    """Mass budget, cut list, crash margin and PASS/FAIL in well under a second (no CAD)."""
    from . import check_cache

    console = Console()
    key = None if plots is not None else check_cache.key(params, check_cache.variant(json_out, console))
    hit = check_cache.load(key)
    if hit is not None:  # same params, same code: the stored answer (imports neither pydantic nor numpy)
        sys.stdout.write(hit[0])
        raise typer.Exit(hit[1])
    from . import api

    design = api.load(params)
    # a new joint geometry's solid FE takes seconds: say what it is doing
    with _progress_to_stderr():
        checked = design.check()  # blamed, one BLAS thread: as `build` computes it, same numbers
    if plots is not None:
        checked.write_drop_plots(plots)
    text = json.dumps(checked.to_dict(), indent=2) + "\n" if json_out else checked.tables(console)
    sys.stdout.write(text)
    code = 0 if checked.verdict == "PASS" else 1
    check_cache.store(key, text, code)
    raise typer.Exit(code)


@contextlib.contextmanager
def _progress_to_stderr():
    """Plain stderr lines for the `cogniframe.progress` log (the joint FE's), one per record, for
    the duration of one command: the handler, level and propagation are put back afterwards (a
    handler left behind wrote to a closed stream and hid the records from later callers in the
    same process, such as a script or a test)."""
    import logging

    log = logging.getLogger("cogniframe.progress")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(message)s"))
    before = (log.level, log.propagate)
    log.addHandler(handler)
    log.setLevel(logging.INFO)
    log.propagate = False
    try:
        yield
    finally:
        log.removeHandler(handler)
        log.setLevel(before[0])
        log.propagate = before[1]


@app.command("build")
def build_command(params: ParamsArg,
                  out: Annotated[Optional[Path], typer.Option("-o", "--out", help="output folder (default out/<name>)")] = None,
                  jobs: Annotated[Optional[int], typer.Option("--jobs", "-j", min=1, help="parallel part builds (default: all cores)")] = None,
                  no_cache: Annotated[bool, typer.Option("--no-cache", help="rebuild every part from scratch")] = False,
                  gcode: Annotated[bool, typer.Option("--gcode", help="also keep the sliced G-code per plate (plates/*.gcode; not byte-stable)")] = False,
                  server: Annotated[Optional[bool], typer.Option("--server/--no-server", help="CAD workers from a server kept between builds (default; COGNIFRAME_CAD_SERVER=0: off)")] = None) -> None:
    """Build every printable part (STL, STEP), the assembly, cut list, mass budget and manifest."""
    from . import api

    result = api.build_file(params, out, jobs=jobs, use_cache=not no_cache, gcode=gcode, server=server,
                            console=Console(stderr=True))
    Console().print(f"wrote {result.out_dir} ({len(result.files)} files); verdict {result.verdict}")
    raise typer.Exit(0 if result.verdict == "PASS" else 1)


@app.command()
def coupon(params: ParamsArg,
           out: Annotated[Optional[Path], typer.Option("-o", "--out", help="STL path (default out/<name>-coupon.stl)")] = None) -> None:
    """Write a socket-fit test print: a row of sockets stepping the fit clearance, each labelled."""
    from .api.coupons import coupon_file

    c = coupon_file(params, out)
    Console().print(f"wrote {c.path}: sockets for clearances {', '.join(f'{x:+.2f}' for x in c.clearances_mm)} mm. "
                    f"Print it in {c.material}, push a rod into each, and set "
                    f"joints.fit_clearance.{c.material} to the loosest hole that still grips (blind sockets), "
                    f"and joints.sleeve_clearance to the tightest one a rod slides through (motor mount sleeves).")


@app.command()
def fly(params: ParamsArg,
        out: Annotated[Optional[Path], typer.Option("-o", "--out", help="output folder (default out/<name>-flight)")] = None) -> None:
    """Flight-controller setup (INAV, Betaflight, ArduPilot, PX4), simulator models (ArduPilot SITL,
    PX4 SIH, Gazebo, rotorpy) and the frame's vibration against the motors, from the estimates."""
    from . import api

    design = api.load(params)
    with _progress_to_stderr():
        folder = design.fly(out)
    Console().print(f"wrote {folder}: INAV and Betaflight CLI, ArduPilot SITL frame and params, PX4 SIH and airframe, "
                    f"Gazebo model, rotorpy.json, resonance.json and resonance.png")


@app.command()
def schema() -> None:
    """Print the JSON Schema of a params file (for editor autocompletion)."""
    from .api.presets import params_schema

    sys.stdout.write(json.dumps(params_schema(), indent=2) + "\n")


def _register_commands() -> None:
    from .commands import drop_fit, exoskeleton, explore, fab, maker, server_control, studio

    exoskeleton.register(app)
    drop_fit.register(app)
    fab.register(app)
    maker.register(app)
    explore.register(app)
    server_control.register(app)
    studio.register(app)


_register_commands()


BUG_EXIT = 3  # cogniframe itself failed (not the user's input)
INTERRUPTED_EXIT = 130  # Ctrl-C, as shells report SIGINT


def main(argv: list[str] | None = None) -> int:
    """Entry point: runs the app and turns UserError into a one-paragraph message and exit code 2.

    Ctrl-C is exit 130 (any temp folder removed, previous output untouched); any other exception
    is a bug: one plain paragraph saying so, exit 3, the traceback only with --debug or
    COGNIFRAME_DEBUG=1.
    """
    err = Console(stderr=True, highlight=False, soft_wrap=True)
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv or os.environ.get("COGNIFRAME_DEBUG", "") not in ("", "0")
    argv = [a for a in argv if a != "--debug"]
    sigint: list[int] = []

    def on_sigint(signum, frame):
        sigint.append(signum)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, on_sigint) if threading.current_thread() is threading.main_thread() else None
    try:
        rv = app(args=argv, standalone_mode=False)
    except UserError as e:
        err.print(f"error: {e}", markup=False)
        return e.exit_code
    except KeyboardInterrupt:
        return _interrupted(err)
    except typer.Exit as e:  # typer turns Ctrl-C into Exit(130)
        return _interrupted(err) if e.exit_code == INTERRUPTED_EXIT or sigint else e.exit_code
    except typer.Abort:
        return _interrupted(err) if sigint else 1
    except typer.TyperException as e:  # usage errors: unknown option, missing argument
        e.show()
        return getattr(e, "exit_code", 2)
    except Exception as e:  # noqa: BLE001 -- a bug: say so plainly
        if sigint:  # Ctrl-C inside C code (an import, OCC) can surface as any exception
            return _interrupted(err)
        if debug:
            import traceback

            traceback.print_exc()
        err.print(bug_message(e, "cogniframe " + " ".join(argv)), markup=False)
        return BUG_EXIT
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    if sigint or rv == INTERRUPTED_EXIT:  # non-standalone typer returns Ctrl-C as the value 130
        return _interrupted(err)
    return rv if isinstance(rv, int) else 0


def _interrupted(err: Console) -> int:
    err.print("interrupted: nothing was written; any previous output is as it was.", markup=False)
    return INTERRUPTED_EXIT


def entry() -> None:
    from .check_cache import quick

    code = quick(sys.argv[1:])  # a repeated `check` answered from the cache, before typer parses anything
    _leave(main() if code is None else code)


def _leave(code: int) -> None:
    """End the `cogniframe` process. Once the command has returned and no other thread runs, the
    exit handlers run and the process ends without the interpreter's teardown of every module and
    object (VTK, matplotlib, the meshes: 0.25-0.5 s after a build, for nothing: every file is
    written and closed by then). A daemon thread left waiting (the reaper of a CAD server this build
    started) does not count: the interpreter would not wait for it either. A thread that is not a
    daemon may still be writing: a normal exit, which waits for it."""
    import atexit

    main = threading.main_thread()
    if any(t is not main and not t.daemon for t in threading.enumerate()):
        sys.exit(code)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a reader that went away (`| head`) or a closed stream
            pass
    os._exit(int(code or 0))
