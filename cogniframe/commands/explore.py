"""`cogniframe sweep` and `cogniframe optimize`: explore the design space on Dask.

Thin wrappers over the API (api.sweep, api.optimize, api.sweep_schema); `register(app)` adds both commands. Bad sweep files and
options raise UserError (exit 2); a finished sweep exits 0 whatever its designs' verdicts.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Optional

import typer

SweepArg = Annotated[Path, typer.Argument(help="sweep YAML file, e.g. examples/sweeps/carbon.yaml", show_default=False)]
OutOpt = Annotated[Optional[Path], typer.Option("-o", "--out", help="output folder (default out/sweeps/<sweep file name>)")]
SchedulerOpt = Annotated[Optional[str], typer.Option("--scheduler", help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (default: local worker processes)")]
WorkersOpt = Annotated[Optional[int], typer.Option("--workers", min=1, help="local worker processes (default: all cores); with --scheduler: wait for this many workers")]


def sweep(sweep_file: SweepArg, out: OutOpt = None, scheduler: SchedulerOpt = None, workers: WorkersOpt = None,
          json_out: Annotated[bool, typer.Option("--json", help="print one JSON object: designs, pass, fail, invalid, seconds, scheduler, workers")] = False) -> None:
    """Check every design of a sweep file on Dask: results.parquet, pareto.png, sensitivity.png, summary.md."""
    from cogniframe import api

    table = api.sweep(sweep_file, scheduler, out=out, workers=workers, progress=api.sweep_progress())
    c = table.attrs["summary"]
    if json_out:
        sys.stdout.write(json.dumps(c) + "\n")
    else:
        from rich.console import Console

        Console().print(f"wrote {table.attrs['out_dir']}: {c['designs']} designs ({c['pass']} PASS, {c['fail']} FAIL, "
                        f"{c['invalid']} INVALID, {c['timeout']} TIMEOUT, {c['error']} ERROR; {c['skipped']} reused) "
                        f"in {c['seconds']:.1f} s on {c['workers']} workers", highlight=False)


def optimize(sweep_file: SweepArg,
             minimize: Annotated[Optional[list[str]], typer.Option("--minimize", help="output to minimise, e.g. mass_g (repeat for several objectives)")] = None,
             maximize: Annotated[Optional[list[str]], typer.Option("--maximize", help="output to maximise, e.g. max_safe_drop_cm")] = None,
             constraint: Annotated[Optional[list[str]], typer.Option("--constraint", help="\"OUT >= V\" or \"OUT <= V\", e.g. \"max_safe_drop_cm >= 120\" (repeatable)")] = None,
             trials: Annotated[Optional[int], typer.Option("--trials", min=1, help="designs to try (default: the sweep file's samples)")] = None,
             out: OutOpt = None, scheduler: SchedulerOpt = None, workers: WorkersOpt = None,
             cad: Annotated[int, typer.Option("--cad", min=0, help="build and verify the CAD of the N best designs on the cluster")] = 0,
             verify: Annotated[Optional[int], typer.Option("--verify", min=0, help="re-check the N best with the base file's joint model when the sweep evaluates with another (0: off; default: 4 when screening with the closed forms, none with the surrogate)")] = None,
             json_out: Annotated[bool, typer.Option("--json", help="print one JSON object with the best design and the run's numbers")] = False) -> None:
    """Optimise over the sweep file's vary box with optuna on Dask: trials.parquet and best.yaml (passes `check`)."""
    from cogniframe import api

    result = api.optimize(sweep_file, minimize=minimize or (), maximize=maximize or (), constraints=constraint or (),
                          trials=trials, out=out, scheduler=scheduler, workers=workers, cad=cad, verify=verify,
                          progress=api.sweep_progress())
    if json_out:
        sys.stdout.write(json.dumps(result.as_dict()) + "\n")
    else:
        from rich.console import Console

        Console().print(result.text(), highlight=False)
    raise typer.Exit(0 if result.best is not None else 1)


def sweep_schema() -> None:
    """Print the JSON Schema of a sweep file (for editor autocompletion)."""
    from cogniframe import api

    sys.stdout.write(json.dumps(api.sweep_schema(), indent=2) + "\n")


def register(app: typer.Typer) -> None:
    app.command("sweep")(sweep)
    app.command("optimize")(optimize)
    app.command("sweep-schema")(sweep_schema)
