"""Fly it before you print it: the flight-controller setup and simulator models of a design.

    check result (mass budget, modes) -> mass properties (analysis/massprops.py) -> rotors
      (analysis/rotors.py) -> the frame's modes against the motors (analysis/resonance.py)
      -> Vehicle (vehicle.py) -> one file per format: inav.py, betaflight.py, ardupilot.py,
         px4.py, gazebo.py, rotorpy_params.py, resonance.json / resonance.png (campbell.py)

`cogniframe fly PARAMS` writes them from the part list's estimates; `build` from the CAD solids
into out/<name>/flight/. Every writer is a pure function of the frozen `Vehicle`: same params,
same bytes. Importing this package loads numpy only.
"""

from __future__ import annotations

import json
from pathlib import Path

FILES = ("inav.txt", "betaflight.txt", "ardupilot/frame.json", "ardupilot/params.parm", "px4/sih.params", "px4/10090_sihsim_cogniframe",
         "gazebo/model.sdf", "gazebo/model.config", "rotorpy.json", "resonance.json", "resonance.png")


def make_vehicle(spec, result, solids=None, shapes: bool = True):
    """The Vehicle of a checked design (`verdict.Findings`): mass properties from the CAD
    solids when `solids` ({part: (massprops.SolidProps as printed, print-from-local 4 x 4)}) is
    given, else from the estimates; the modes' flight-controller participation from their shapes
    when `shapes`."""
    from ..analysis import massprops, resonance, rotors
    from .vehicle import vehicle_of

    d, budget = result.design, result.mass
    mp = massprops.from_solids(spec, d, budget, solids) if solids is not None else massprops.estimate(spec, d, budget)
    rm = rotors.model(spec, mp.mass_kg, len(d.frame.motors))
    hz = list((result.stiffness or {}).get("modes_hz") or [])
    part = None
    if shapes and result.stiffness is not None:
        hz, part = resonance.mode_shapes(spec, d, budget.total_g, len(hz) or None)
    res = resonance.assess(hz, rm.hover_rotor_hz, rm.max_rotor_hz, part)
    return vehicle_of(spec, d, budget, mp, res)


def texts(v) -> dict[str, str]:
    """Every text file, by its path under the flight folder."""
    from . import ardupilot, betaflight, gazebo, inav, px4, rotorpy_params

    res = {"generator": "cogniframe", "name": v.name, "mass": v.mass.to_dict(), "rotor": v.rotor.to_dict(),
           **v.resonance.to_dict()}
    return {"inav.txt": inav.text(v), "betaflight.txt": betaflight.text(v),
            "ardupilot/frame.json": ardupilot.frame_json(v), "ardupilot/params.parm": ardupilot.params_parm(v),
            "px4/sih.params": px4.sih_params(v), px4.AIRFRAME_FILE: px4.airframe(v),
            "gazebo/model.sdf": gazebo.model_sdf(v), "gazebo/model.config": gazebo.model_config(v),
            "rotorpy.json": rotorpy_params.text(v), "resonance.json": json.dumps(res, indent=2) + "\n"}


def write(v, folder: Path) -> tuple[str, ...]:
    """Write every flight file into `folder` (made if missing); the paths written, relative to it."""
    from .campbell import plot

    folder = Path(folder)
    for rel, text in texts(v).items():
        p = folder / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text, encoding="utf-8")
    plot(v.resonance, folder / "resonance.png", v.name)
    return FILES
