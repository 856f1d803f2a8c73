"""What the build's steps share: the inputs they read (`Inputs`: the params, the design, the CAD
workers), the memos of one build (`BuildContext`: meshes, plate items, the part plotter) and
PrusaSlicer's path, looked up once per build."""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any, Callable

from . import graph


class NoWarmup:
    """Idle-time imports (matplotlib, pyvista, trimesh) serve main-thread steps; a run of the part
    steps alone needs none of them."""

    def start(self) -> None:
        pass


@dataclass(frozen=True)
class Inputs:
    """What every step of one build reads besides the values of the steps before it."""

    spec: Any  # spec.Spec
    design: Any  # design.Derived
    cad: Any = None  # runtime.BuildRuntime.cad: the CAD workers
    warm: Any = field(default_factory=NoWarmup)  # runtime.warm's idle-time imports
    log: Callable[[str], None] = lambda message: None
    slicer: Any = None  # Slicer, or None when the run slices nothing
    gcode: bool = False  # `build --gcode`: keep each plate's G-code


@dataclass
class BuildContext(graph.Context):
    """graph.Context plus what many steps look up: parts by name, their step values and meshes.
    The memos are per build: one off-screen plotter for the part renders, each part's mesh read
    once, and the plate items the plates step read back."""

    part_plotter: Any = field(default=None, init=False)
    _vitamins: Any = field(default=None, init=False)
    _vitamins_lock: Any = field(default_factory=threading.Lock, init=False)
    _meshes: dict = field(default_factory=dict, init=False)
    _plate_items: dict = field(default_factory=dict, init=False)

    spec = property(lambda self: self.inputs.spec)
    design = property(lambda self: self.inputs.design)
    cad = property(lambda self: self.inputs.cad)
    warm = property(lambda self: self.inputs.warm)
    log = property(lambda self: self.inputs.log)
    slicer = property(lambda self: self.inputs.slicer)
    gcode = property(lambda self: self.inputs.gcode)

    @property
    def bed(self) -> tuple[float, float, float]:
        return tuple(float(b) for b in self.spec.printer.bed)

    def part(self, name: str):
        return next(p for p in self.design.parts if p.name == name)

    def parts_of(self, material: str):
        return [p for p in self.design.parts if p.material == material]

    def part_value(self, name: str) -> dict:
        (value,) = self.each(f"part:*/{name}").values()
        return value

    def built_parts(self):
        """BuiltPart per part, in the design's order, from the part steps' values."""
        from ..export.part_files import _built

        return tuple(_built(p, self.part_value(p.name)) for p in self.design.parts)

    def vitamins(self) -> tuple:
        """The bought parts (`vitamins.vitamins`), made once per build from the design's part list:
        the keys of the clash check, assembly, GLB, renders, 3D view and flight files and three of
        those steps read them, and made without the part list each costs a part list (0.1-0.3 s
        with the pegged core link). The key functions of waiting steps run in threads: a lock."""
        with self._vitamins_lock:
            if self._vitamins is None:
                from ..vitamins import vitamins

                self._vitamins = vitamins(self.spec, self.design.frame, self.design.parts)
            return self._vitamins

    def vitamin_key(self) -> list:
        """What a step's key reads of the bought parts (`export.assembly._vitamin_key`)."""
        from ..export.assembly import _vitamin_key

        return _vitamin_key(self.spec, self.design.frame, self.vitamins())

    def warm_imports(self) -> None:
        """Start importing the main thread's libraries while it waits for the CAD workers
        (`runtime.warm`): called by the first part step that runs, since a rebuilt part means the
        plates, previews and renders run too."""
        self.warm.start()

    def plate_items(self, plate: dict):
        """What reading a plate's 3MF back gives (`plates.read_3mf_items`), when the plates step
        wrote it in this build (`plates.plate_3mf` returns it with the bytes); None for a plate
        that came from the cache (its readers read the file). `plate`: a plates step's entry."""
        return self._plate_items.get(plate.get("model_sha256"))

    def keep_plate_items(self, model_sha256: str, items) -> None:
        self._plate_items[model_sha256] = items

    def mesh(self, name: str):
        """The part's STL as a trimesh, read once per build (plates, part renders and assembly
        renders all read it; they copy before they move it)."""
        import trimesh

        v = self.part_value(name)
        memo = self._meshes
        key = (name, v["stl_sha256"])
        if key not in memo:
            memo[key] = trimesh.load(self.out / v["stl"], force="mesh")
        return memo[key]

class Slicer:
    """PrusaSlicer's path and version, looked up once per build (None when it is not installed)."""

    def __init__(self, log):
        self.log = log
        self._found = None
        self._lock = threading.Lock()

    def get(self) -> tuple[str, str] | None:
        with self._lock:
            if self._found is None:
                from ..export import slicer

                exe = slicer.find_slicer()
                self._found = (exe, slicer.known_version(exe)) if exe else ()
                if not exe:
                    self.log(f"{slicer.SLICER} not found on PATH: skipping the slicer check "
                             f"(install it with `apt-get install prusa-slicer` to get grams and print times).")
            return self._found or None

def needs_joint_fe(spec, design) -> bool:
    """Whether this build meshes and solves a joint (analysis.joints.needs_fe, the question
    `check` asks too): the runtime then prepares worker processes for the FE."""
    from ..analysis.joints import needs_fe

    return needs_fe(spec, design.parts)
