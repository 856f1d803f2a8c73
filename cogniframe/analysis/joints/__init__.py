"""The stiffness of each printed joint from its own geometry: the super-element the frame model
(`analysis.stiffness`) connects each rod's free span to, cached by a hash of the joint's
geometry and material.

A joint is reduced to a 6n x 6n stiffness over n rigid reference bodies (`model.JointStiffness`)
in one of two ways (`method`):

``"fe"``  (default) the solid FE of the part's CAD (`fe`, which meshes with `meshing` and
          condenses with `solid_fe`). Seconds per new geometry, so solved once and cached.
``"analytic"`` the closed forms (`closed_forms`). Microseconds; a cross-check, for trends only.
``"surrogate"`` the solid FE's fit over the joint geometry (`surrogate`, trained offline by
          tools/train_joint_surrogate.py): milliseconds, within a few per cent of the FE inside its
          training box; outside it the joint is solved by FE (`surrogate_models` says which and why).

This module is the entry point: `joint_stiffness` (one joint, from the cache or solved here),
`solve_missing` (every joint of a design not cached yet, on the caller's worker processes, with
mirrored joints reflected from their originals: `mirror`), `has_unsolved` and `geometry_key`.
Every FE stiffness is proportional to the TPU calibration factor, so the cache holds the FE at
factor 1 and `joint_stiffness` scales it on use.
"""

from __future__ import annotations

import logging
import time

from .closed_forms import analytic_joint
from .fe import FE_CURVATURE, FE_MESH_MM, fe_joint
from .mirror import _originals, is_mirror, mirror_original, reflect_unit
from .model import (TPU_ELONGATION_AT_BREAK, TPU_PRINTED_MODULUS_FACTOR, JointStiffness, hinge_geometry,
                    hinged_socket, interface, joint_kind)

# the entry points, and what the frame model, the load cases and the build read from the joints
__all__ = ["FE_MESH_MM", "TPU_ELONGATION_AT_BREAK", "TPU_PRINTED_MODULUS_FACTOR", "JointStiffness", "analytic_joint",
           "fe_joint", "geometry_key", "has_unsolved", "hinge_geometry", "hinged_socket", "interface", "is_mirror",
           "joint_stiffness", "mirror_original", "solve_missing", "surrogate_models", "surrogate_notes"]

_CACHE_VERSION = "joint-1"
# Progress of the solid FE (a new joint geometry costs ~1-2 s): the CLI prints these records on
# stderr; nothing is printed when no handler is attached (library use, tests).
progress_log = logging.getLogger("cogniframe.progress")


def geometry_key(spec, part, method: str, factor: float | None, mesh_mm: float) -> str:
    """Hash of everything the joint model reads: the part's geometry digest (sockets, wall, params),
    the interface (clearance, layer height), materials, method, and this package's source."""
    itf = interface(spec, factor)
    # the FE takes the rods as rigid: their modulus does not enter (the closed forms are not cached)
    from ... import cache

    data = [_CACHE_VERSION, part.digest, method, itf.e, itf.g, itf.h, spec.rods.diameter, mesh_mm, FE_CURVATURE]
    # parts/joint_plan.py and peg_plan.py: the plan the CAD builds on (the knee's and the core
    # link's pieces in plan); families/joint_kinds/: each kind's print orientation, solid and support
    return cache.key(data, ("analysis/joints/*.py", "parts/joint_solid.py", "parts/joint_plan.py", "parts/peg_plan.py",
                            "families/joint.py", "families/joint_kinds/*.py"))


def joint_stiffness(spec, part, method: str = "fe", factor: float | None = None,
                    mesh_mm: float | None = None, use_cache: bool = True) -> JointStiffness:
    """The super-element of one distinct joint, cached by geometry hash."""
    from ... import cache

    mesh_mm = FE_MESH_MM if mesh_mm is None else mesh_mm
    if method not in ("fe", "analytic", "surrogate"):
        raise ValueError(f"joint stiffness method must be 'fe', 'analytic' or 'surrogate', got {method!r}")
    if method == "analytic":
        return analytic_joint(spec, part, factor)
    if method == "surrogate":
        from .surrogate import predict

        unit, _ = predict(spec, part, factor)
        if unit is not None:
            return unit
        method = "fe"  # outside the training box: the reference model
    # Every stiffness in the FE (TPU E and G, the interface E/h_i and G/h_i, the support ties)
    # is proportional to the TPU factor, so the condensed matrix is too: solve and cache at
    # factor 1, scale on use.
    key = geometry_key(spec, part, method, 1.0, mesh_mm)
    hit = cache.load_json("joint", key) if use_cache else None
    if hit is not None:
        unit = JointStiffness.from_json(hit)
    else:
        unit = fe_joint(spec, part, 1.0, mesh_mm)
        # A mirrored joint's cache entry is its original's reflected (`solve_missing`), so that
        # its numbers are the same bits whatever was solved before: a direct solve is not stored.
        if use_cache and not is_mirror(part):
            cache.store_json("joint", key, unit.to_json())
    f = TPU_PRINTED_MODULUS_FACTOR if factor is None else float(factor)
    return JointStiffness(unit.name, unit.method, unit.labels, unit.refs,
                          tuple(map(tuple, (f * unit.matrix).tolist())), unit.n_dofs, unit.seconds)


def _fe_unit(spec, part, mesh_mm: float) -> tuple[str, dict | None, str | None]:
    """A worker's task: the FE super-element at factor 1, as cache JSON (or the mesher's error)."""
    try:
        return part.name, fe_joint(spec, part, 1.0, mesh_mm).to_json(), None
    except RuntimeError as exc:
        return part.name, None, str(exc)


def fe_joints(spec, parts, outside: dict[str, str] | None = None) -> list:
    """The joints of ``parts`` whose super-element the solid FE gives under
    `model.stiffness_model`: all of them (fe), those outside the surrogate's training box
    (surrogate, milliseconds: the surrogate's box test; ``outside``: `surrogate.outside_reasons`
    of these parts when the caller has it), none (analytic)."""
    method = spec.model.stiffness_model
    if method == "fe":
        return list(parts)
    if method == "surrogate":
        if outside is None:
            from .surrogate import outside_reasons

            outside = outside_reasons(spec, parts)
        return [p for p in parts if p.name in outside]
    return []


def has_unsolved(spec, parts, mesh_mm: float | None = None) -> bool:
    """Whether a joint in ``parts`` has no FE super-element in the joint cache yet (the test
    `solve_missing` makes; milliseconds: the keys are hashes of the parts' inputs)."""
    from ... import cache

    mesh_mm = FE_MESH_MM if mesh_mm is None else mesh_mm
    return any(cache.load_json("joint", geometry_key(spec, p, "fe", 1.0, mesh_mm)) is None for p in parts)


def solve_missing(spec, parts, mesh_mm: float | None = None, submit=None) -> dict[str, str]:
    """Solve and cache the FE of every joint in ``parts`` whose geometry is not cached yet: on the
    caller's worker processes (``submit(fn, *args) -> Future``: `runtime.pools.joint_fe_workers`
    for `check`, the CAD workers in a build), or here one after another when ``submit`` is None
    (in a Dask worker, whose cores the cluster schedules) or the workers fail. Returns
    {part name: error} of the joints the mesher or the tie selection could not handle (nothing
    cached for them).

    A mirrored joint whose original is in ``parts`` is not solved: once the original is solved
    (or found in the cache) its super-element is reflected (`reflection`, `reflect_unit`) and
    cached under the mirror's key -- always from the original, never the reverse, so the bits
    are the same whatever the order or the cache held. If the two are not exact mirror images,
    or the original fails, the mirror is solved by FE like any other joint. A mirror without its
    original in ``parts`` is not solved here (nor cached by `joint_stiffness`)."""
    from ... import cache

    mesh_mm = FE_MESH_MM if mesh_mm is None else mesh_mm
    todo, seen = [], set()
    derive = []  # (mirror part, its key, original part, original key, P, order)
    for p in parts:
        key = geometry_key(spec, p, "fe", 1.0, mesh_mm)
        if key not in seen and cache.load_json("joint", key) is None:
            try:
                found = mirror_original(p, parts)
            except ValueError as exc:
                progress_log.info("joint FE: %s is not an exact mirror image (%s); solving it", p.name, exc)
                found = None
            if found is not None:
                o, P, order = found
                derive.append((p, key, o, geometry_key(spec, o, "fe", 1.0, mesh_mm), P, order))
            elif is_mirror(p) and not _originals(p, parts):
                # a hand-picked subset (a design's part list always has both): its own FE is not
                # cached, so the cache never depends on which subset came first; joint_stiffness
                # solves it when used
                progress_log.info("joint FE: %s left to joint_stiffness (its original is not in this set)", p.name)
            else:
                todo.append((p, key))
        seen.add(key)
    if not todo and not derive:
        return {}
    failed = _solve(spec, todo, mesh_mm, submit)
    # the mirrors, after their originals (solved above or cached before)
    for p, key, o, okey, P, order in derive:
        hit = cache.load_json("joint", okey)
        if hit is not None:
            try:
                unit = reflect_unit(JointStiffness.from_json(hit), p, P, order, [s.rod for s in o.sockets])
            except ValueError as exc:
                progress_log.info("joint FE: %s not derived (%s); solving it", p.name, exc)
            else:
                cache.store_json("joint", key, unit.to_json())
                progress_log.info("joint FE: %s derived by reflection from %s", p.name, o.name)
                continue
        # the original failed (or its unit did not fit): solve the mirror itself
        failed.update(_solve(spec, [(p, key)], mesh_mm))
    return failed


def needs_fe(spec, parts, outside: dict[str, str] | None = None) -> bool:
    """Whether checking a design with these printed parts solves a joint's FE first: the FE model
    (or the surrogate outside its box) and a joint geometry not in the cache yet (milliseconds:
    the cache keys are hashes of the parts' inputs). `check` and `build` both ask here.
    ``outside``: `surrogate.outside_reasons` of the joints when the caller has it."""
    if spec.model.stiffness_model == "analytic":
        return False
    return has_unsolved(spec, fe_joints(spec, _joints(parts), outside))


def solve_fe(spec, parts, submit) -> None:
    """Solve and cache the FE of every joint of these printed parts that the cache lacks, on
    `submit(fn, *args)` (the caller's worker processes): the one preparation `check` and the
    build's `estimate` step share; the stiffness model then reads every joint from the cache."""
    if spec.model.stiffness_model == "analytic":
        return
    todo = fe_joints(spec, _joints(parts))  # with the surrogate: those outside its box
    if todo:
        solve_missing(spec, todo, submit=submit)


def _joints(parts) -> list:
    """The printed parts that are joints (as stiffness.joint_parts; here so that this package
    does not import the stiffness model, which imports it)."""
    return [p for p in parts if p.family == "joint"]


def _solve(spec, todo, mesh_mm: float, submit=None) -> dict[str, str]:
    """The FE of `todo` [(part, key)], cached; {part name: error} of those that failed.
    `submit(fn, *args) -> Future`: the caller's worker processes; None: here, one after another."""
    from ... import cache

    if not todo:
        return {}
    keys = {p.name: key for p, key in todo}
    t0 = time.perf_counter()
    done = 0
    failed: dict[str, str] = {}

    def finished(name: str, unit: dict | None, err: str | None) -> None:
        nonlocal done
        done += 1
        if unit is not None:
            cache.store_json("joint", keys[name], unit)
            progress_log.info("joint FE %d/%d: %s (%s DOF), %.1f s", done, len(todo), name, unit.get("n_dofs"),
                              time.perf_counter() - t0)
        else:  # joint_models falls back to the closed forms for this joint
            failed[name] = str(err)
            progress_log.info("joint FE %d/%d: %s failed (%s)", done, len(todo), name, err)

    pending = list(todo)
    if submit is not None:
        from concurrent.futures import BrokenExecutor, as_completed

        progress_log.info("joint FE: %d new joint geometries on the caller's worker processes", len(todo))
        try:
            # the biggest first (by the closed-form volume: the mesh is of a fixed size, so its
            # DOFs and the factorization grow with it), so that the last job to start is a small
            # one and the workers end together (longest-processing-time-first)
            biggest_first = sorted(todo, key=lambda t: -t[0].estimate.volume)
            futures = {submit(_fe_unit, spec, p, mesh_mm): p.name for p, _ in biggest_first}
            for fut in as_completed(futures):
                finished(*fut.result())
                pending = [x for x in pending if x[0].name != futures[fut]]
        except BrokenExecutor:
            # a worker could not start or died: the rest is solved here, one after another
            progress_log.info("joint FE: worker processes failed; solving %d joint(s) in this process", len(pending))
    for p, _ in pending:
        finished(*_fe_unit(spec, p, mesh_mm))
    return failed


def _surrogate_split(spec, parts, factor: float | None = None, outside: dict[str, str] | None = None,
                     tests: dict | None = None):
    """({part name: surrogate super-element}, {part name: why it is outside the training box}):
    originals predicted, mirrored joints reflected from their predicted original (as the FE path
    reflects them); which joints are outside is `surrogate.outside_reasons` (``outside``: its
    answer for these parts when the caller has it; ``tests``: their `surrogate.box_tests`)."""
    from .surrogate import box_tests, outside_reasons, predict

    tests = box_tests(spec, parts) if tests is None else tests
    outside = outside_reasons(spec, parts, tests) if outside is None else outside
    inside = {}
    for p in parts:
        if not is_mirror(p) and p.name not in outside:
            inside[p.name], _ = predict(spec, p, factor, tested=tests[p.name])
    for p in parts:
        if is_mirror(p) and p.name not in outside:
            o, P, order = mirror_original(p, parts)
            inside[p.name] = reflect_unit(inside[o.name], p, P, order, [s.rod for s in o.sockets])
    return inside, outside


def surrogate_models(spec, parts, factor: float | None = None, submit=None, outside: dict[str, str] | None = None,
                     tests: dict | None = None) -> dict:
    """Every joint's super-element from the surrogate; the joints outside its training box from the
    solid FE (cached; `solve_missing` on `submit`'s workers), those the FE cannot mesh from the
    closed forms, as `stiffness.joint_models` does for the FE. ``outside``: `surrogate.outside_reasons`
    for these parts when the caller has it; ``tests``: their `surrogate.box_tests`."""
    inside, outside = _surrogate_split(spec, parts, factor, outside, tests)
    out = dict(inside)
    if outside:
        rest = [p for p in parts if p.name in outside]
        for name, why in outside.items():
            progress_log.info("joint surrogate: %s outside its training box (%s); solid FE", name, why)
        failed = solve_missing(spec, rest, submit=submit)
        for p in rest:
            if p.name not in failed:
                try:
                    out[p.name] = joint_stiffness(spec, p, "fe", factor)
                    continue
                except RuntimeError:
                    pass
            out[p.name] = joint_stiffness(spec, p, "analytic", factor)
    return {p.name: out[p.name] for p in parts}


def surrogate_notes(spec, parts, outside: dict[str, str] | None = None) -> list[str]:
    """One line per joint outside the surrogate's training box (what `check` reports as a note and
    a sweep as its `joints_outside_box` column); empty when every joint is inside. Milliseconds:
    the features and the box, no fit evaluated (``outside``: `surrogate.outside_reasons` for these
    parts when the caller has it)."""
    from .surrogate import outside_reasons

    outside = outside_reasons(spec, parts) if outside is None else outside
    return [f"joint {name}: outside the surrogate's training box ({why}); its stiffness is from the solid FE"
            for name, why in outside.items()]
