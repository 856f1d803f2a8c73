"""`cogniframe analyse ASSEMBLY`: the frame stiffness, thrust case and drop model of any
rod-and-joint exoskeleton read from a STEP assembly or a FreeCAD document (issue 43).

The work is the API's (`api.analyse.analyse`); this module parses the arguments and prints.
``register(app)`` adds the command to a Typer app. User-fixable problems raise UserError.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Optional

import typer


def analyse_cmd(
    assembly: Annotated[Path, typer.Argument(help="STEP assembly (.step/.stp) or FreeCAD document (.FCStd)", show_default=False)],
    materials: Annotated[Optional[Path], typer.Option("--materials", help="YAML of part-name patterns -> material")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print the results as JSON")] = False,
    down: Annotated[str, typer.Option("--down", help="which way the ground is: -z (+z up, cogniframe's STEP) or +z "
                                                      "(the authors' FreeCAD document)")] = "-z",
    rod_diameter: Annotated[Optional[float], typer.Option("--rod-diameter", help="the rods' real diameter, mm, for the "
                                                          "beams and the fits (default: as drawn)")] = None,
    factor: Annotated[Optional[float], typer.Option("--tpu-factor", help="printed / datasheet TPU modulus (default: "
                                                    "the package's calibration)")] = None,
    mass_kg: Annotated[float, typer.Option("--mass-kg", help="payload mass of the drop model")] = 0.241,
    c: Annotated[float, typer.Option("--c", help="damping of the drop model, N s/m")] = 46.0,
    clearance: Annotated[float, typer.Option("--clearance-mm", help="battery holder's clearance above the ground")] = 16.0,
    thrust_g: Annotated[float, typer.Option("--max-thrust-g", help="full thrust per motor, g")] = 175.0,
    prop_diameter: Annotated[float, typer.Option("--prop-diameter", help="propeller diameter, mm, for the wall case "
                                                 "(a disc centred on each motor mount)")] = 76.2,
) -> None:
    """Frame stiffness k, thrust case, wall case and safe drop height of an exoskeleton read from CAD."""
    from cogniframe.errors import UserError

    if down not in ("+z", "-z"):
        raise UserError(f"--down {down!r}: give +z (the ground is towards +z, like the authors' FreeCAD document) or -z "
                        f"(+z up, like cogniframe's own STEP)")
    if rod_diameter is not None and not rod_diameter > 0:
        raise UserError(f"--rod-diameter {rod_diameter!r}: give the rods' diameter in mm, a positive number")
    if factor is not None and not factor > 0:
        raise UserError(f"--tpu-factor {factor!r}: give a positive number (1.0 = the datasheet modulus)")
    import sys

    from cogniframe.api.analyse import analyse, summary

    a = analyse(assembly, materials=materials, down=down, rod_diameter=rod_diameter, factor=factor, mass_kg=mass_kg,
                c_n_s_per_m=c, clearance_mm=clearance, max_thrust_g=thrust_g, prop_diameter_mm=prop_diameter,
                progress=None if as_json else (lambda msg: print(msg, file=sys.stderr, flush=True)))
    if as_json:
        print(json.dumps(a.to_dict(), indent=2, default=float))
    else:
        print("\n".join(summary(a)))


def register(app: typer.Typer) -> None:
    app.command("analyse")(analyse_cmd)
