"""`cogniframe optimize`: optuna over the sweep file's vary box, candidates evaluated on Dask.

Ask/tell in rounds: each round asks optuna for (workers x batch) candidates (TPE with the
constant liar for one objective, NSGA-II for several), evaluates them in batches on the same Dask
cluster as `sweep` (same evaluate_batch, same rows), and tells the values back. A trial is
feasible when its verdict is PASS and every `--constraint` holds; optuna gets the violations
through `constraints_func`. INVALID, TIMEOUT and ERROR trials are told as failed.

    DIR/trials.parquet   every trial: number, the design's row (keys, outputs, verdict, worker, ...)
    DIR/best.yaml        the base params file with only the changed values edited (comments kept)
    DIR/optimize.md      objectives, constraints, the best design against the base, the Pareto set
    DIR/cad.json         with --cad N: the N best designs built and verified on the cluster

Joint models. Like `sweep`, optimize evaluates with the solid FE's surrogate by default
(milliseconds per design, within a few per cent of the FE: docs/stiffness-model.md), so its best
design needs no re-check for the model's sake; `--verify N` still re-checks the N best with the
base file's own model. A sweep file that screens with the closed-form joints (`set:
model.stiffness_model: analytic`) is verified by default (4 designs): the closed forms and the FE
disagree by up to tens of per cent, so the best design is the best of those that still pass under
the base file's model. best.yaml keeps the base file's model.
"""

from __future__ import annotations

import json
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import UserError
from . import evaluate as ev
from . import run as run_mod
from .sample import DECIMALS
from .sweepfile import Sweep

_CONSTRAINT = re.compile(r"^\s*([A-Za-z_][\w.]*)\s*(>=|<=)\s*([-+]?(\d+(\.\d*)?|\.\d+)([eE][-+]?\d+)?)\s*$")


@dataclass(frozen=True)
class Objective:
    name: str
    direction: str  # "minimize" | "maximize"


@dataclass(frozen=True)
class Constraint:
    name: str
    op: str  # ">=" | "<="
    value: float

    def violation(self, row: dict) -> float:
        """<= 0 when the constraint holds (optuna's convention); +inf without a value."""
        v = row.get(self.name)
        if v is None or not isinstance(v, (int, float)) or not math.isfinite(v):
            return math.inf
        return (self.value - v) if self.op == ">=" else (v - self.value)

    def __str__(self) -> str:
        return f"{self.name} {self.op} {self.value:g}"


def _check_output(name: str, option: str) -> str:
    if name in ev.OUTPUTS or "." in name:  # dotted: a section another stage adds (stiffness.*, flight.*)
        return name
    raise UserError(f"Option {option} names {name!r}, which is not an output. Fix: use one of {', '.join(ev.OUTPUTS)}, "
                    "or a dotted output of another section such as stiffness.k_lateral_n_per_m.")


def parse_objectives(minimize: list[str], maximize: list[str]) -> list[Objective]:
    objs = [Objective(_check_output(n, "--minimize"), "minimize") for n in minimize]
    objs += [Objective(_check_output(n, "--maximize"), "maximize") for n in maximize]
    if not objs:
        raise UserError("Give at least one objective: --minimize OUT or --maximize OUT (e.g. --minimize mass_g).")
    return objs


def parse_constraint(text: str) -> Constraint:
    m = _CONSTRAINT.match(text)
    if not m:
        raise UserError(f"Option --constraint is {text!r}; write \"OUT >= VALUE\" or \"OUT <= VALUE\", "
                        "e.g. --constraint \"max_safe_drop_cm >= 120\".")
    return Constraint(_check_output(m.group(1), "--constraint"), m.group(2), float(m.group(3)))


@dataclass(frozen=True)
class OptimizeResult:
    out_dir: Path
    objectives: tuple[Objective, ...]
    constraints: tuple[Constraint, ...]
    trials: int
    feasible: int
    best: dict | None  # the best feasible row
    pareto: tuple[dict, ...]
    base: dict
    seconds: float
    scheduler: str
    workers: int
    cad: tuple[dict, ...] = field(default_factory=tuple)
    note: str = ""
    verified: tuple[dict, ...] = field(default_factory=tuple)  # finalists re-checked with the base's model
    fidelity: tuple[str, str] | None = None  # (screening, verifying) stiffness models, None: one model
    correction: dict = field(default_factory=dict)  # constraint -> factor on its screened values (`screen_correction`)

    def as_dict(self) -> dict:
        def clean(r):
            return None if r is None else {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in r.items()}

        return {"trials": self.trials, "feasible": self.feasible, "best": clean(self.best),
                "best_yaml": str(self.out_dir / "best.yaml") if self.best is not None else None,
                "pareto": [clean(r) for r in self.pareto], "base": clean(self.base),
                "objectives": [f"{o.direction} {o.name}" for o in self.objectives],
                "constraints": [str(c) for c in self.constraints], "seconds": round(self.seconds, 3),
                "scheduler": self.scheduler, "workers": self.workers, "cad": list(self.cad), "note": self.note,
                "verified": [clean(r) for r in self.verified],
                "fidelity": {"screening": self.fidelity[0], "verified_with": self.fidelity[1],
                             "correction": self.correction} if self.fidelity else None,
                "out_dir": str(self.out_dir)}

    def text(self) -> str:
        lines = [f"{self.trials} trials, {self.feasible} feasible, {self.seconds:.1f} s on {self.workers} workers"]
        if self.fidelity and self.verified:
            ok = sum(1 for r in self.verified if r.get("feasible"))
            lines.append(f"screened with {self.fidelity[0]} joints; {len(self.verified)} best re-checked with "
                         f"{self.fidelity[1]} joints, {ok} still feasible")
        elif self.fidelity:
            lines.append(f"screened with {self.fidelity[0]} joints; no design came near enough to feasible to re-check "
                         f"with {self.fidelity[1]} joints")
        if self.best is None:
            lines.append(f"no feasible design. {self.note}")
        else:
            parts = ", ".join(f"{o.name} {self.best[o.name]:.4g} (base {_num(self.base.get(o.name))})" for o in self.objectives)
            lines.append(f"best {self.best['design_id']}: {parts}; wrote {self.out_dir / 'best.yaml'}")
        for c in self.cad:
            lines.append(f"CAD {c['design_id']}: {'OK' if c['ok'] else 'FAILED'} ({c['parts']} parts, {c['seconds']:.1f} s"
                         + (f"; {'; '.join(c['failures'])}" if c["failures"] else "") + ")")
        return "\n".join(lines)


def _num(v) -> str:
    return f"{v:.4g}" if isinstance(v, (int, float)) and v is not None else "-"


def _distributions(sweep: Sweep) -> dict:
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    out = {}
    step = 10.0 ** -DECIMALS
    for k in sweep.keys:
        if k.is_choice:
            out[k.name] = CategoricalDistribution(list(k.choices))
        elif k.integer:
            out[k.name] = IntDistribution(math.ceil(k.lo), math.floor(k.hi))
        else:
            span = (k.hi - k.lo) / step
            on_grid = abs(span - round(span)) < 1e-6 and abs(k.lo / step - round(k.lo / step)) < 1e-6
            out[k.name] = FloatDistribution(k.lo, k.hi, step=step if on_grid else None)
    return out


def _overrides(sweep: Sweep, params: dict) -> dict:
    out = {}
    for k in sweep.keys:
        v = params[k.name]
        out[k.name] = v if k.is_choice or k.integer else round(float(v), DECIMALS)
    return out


def _feasible(row: dict, objectives, constraints, slack: float = 0.0) -> bool:
    """PASS, finite objectives, and every constraint holding -- within `slack` x |bound| if given."""
    if row.get("verdict") != "PASS":
        return False
    if any(not isinstance(row.get(o.name), (int, float)) or not math.isfinite(row[o.name]) for o in objectives):
        return False
    return all(c.violation(row) <= slack * abs(c.value) for c in constraints)


def _dominates(a: dict, b: dict, objectives) -> bool:
    sign = {"minimize": 1.0, "maximize": -1.0}
    av = [sign[o.direction] * a[o.name] for o in objectives]
    bv = [sign[o.direction] * b[o.name] for o in objectives]
    return all(x <= y for x, y in zip(av, bv)) and any(x < y for x, y in zip(av, bv))


def ranked(rows: list[dict], objectives, constraints) -> tuple[list[dict], list[dict]]:
    """(feasible rows best first by the first objective, the feasible Pareto set)."""
    ok = [r for r in rows if _feasible(r, objectives, constraints)]
    first = objectives[0]
    ok.sort(key=lambda r: (r[first.name] if first.direction == "minimize" else -r[first.name], r["design_id"]))
    unique = list({r["design_id"]: r for r in reversed(ok)}.values())[::-1]
    pareto = [r for r in unique if not any(_dominates(o, r, objectives) for o in unique)]
    return unique, pareto


def run_optimize(sweep: Sweep, objectives: list[Objective], constraints: list[Constraint], out_dir: Path | None = None,
                 trials: int | None = None, scheduler: str | None = None, workers: int | None = None, cad: int = 0,
                 verify: int | None = None,
                 progress: Callable | None = None, batch: int | None = None) -> OptimizeResult:
    from ..outdir import lock

    out_dir = Path(out_dir) if out_dir is not None else Path("out") / "sweeps" / f"{sweep.stem}-optimize"
    run_mod.claim_folder(out_dir, "optimize", sweep, write=False)
    with lock(out_dir):  # one optimize per folder at a time
        return _run_optimize(sweep, objectives, constraints, out_dir, trials, scheduler, workers, cad, progress, batch,
                             verify)


def _run_optimize(sweep, objectives, constraints, out_dir: Path, trials, scheduler, workers, cad, progress, batch,
                  verify: int | None = None) -> OptimizeResult:
    import optuna
    from optuna.trial import TrialState

    n_trials = trials or sweep.settings.samples
    t0 = time.perf_counter()
    optuna.logging.set_verbosity(optuna.logging.WARNING)

    # optuna >= 5 reads constraints set on the trial; older versions need a constraints_func
    native = hasattr(optuna.trial.Trial, "set_constraint")
    extra = {} if native else {"constraints_func": lambda trial: trial.user_attrs.get("constraints", [1.0])}
    seed = sweep.settings.seed
    if len(objectives) == 1:
        sampler = optuna.samplers.TPESampler(seed=seed, multivariate=True, constant_liar=True,
                                             n_startup_trials=min(10, max(2, n_trials // 4)), **extra)
    else:
        sampler = optuna.samplers.NSGAIISampler(seed=seed, population_size=max(4, min(50, n_trials // 4)), **extra)
    study = optuna.create_study(directions=[o.direction for o in objectives], sampler=sampler)
    dists = _distributions(sweep)
    rows: list[dict] = []
    if verify is None:
        verify = default_verify(sweep)
    fidelity = two_fidelities(sweep) if verify > 0 else None
    with run_mod.dask_client(scheduler, workers) as (client, scheduler_addr, n_workers):
        run_mod.claim_folder(out_dir, "optimize", sweep)
        base = None
        correction: dict[str, float] = {}
        if fidelity:  # the base design under both models, before the search: it anchors the screen
            base, screened_base = run_mod.evaluate_all(
                client, sweep.base_data, [{FIDELITY_KEY: fidelity[1]}, {}], max(sweep.settings.timeout_s, 600.0), 1,
                n_workers, text=sweep.base_text, base_name=sweep.base_label)
            correction = screen_correction(screened_base, base, constraints)
        size = batch or sweep.settings.batch or 4
        per_round = max(1, n_workers * size)
        done = 0
        tb = written = time.perf_counter()
        while done < n_trials:
            k = min(per_round, n_trials - done)
            asked = [study.ask(dists) for _ in range(k)]
            overrides = [_overrides(sweep, t.params) for t in asked]
            got = run_mod.evaluate_all(client, sweep.base_data, overrides, sweep.settings.timeout_s, size, n_workers,
                                       text=sweep.base_text, base_name=sweep.base_label)
            for t, row in zip(asked, got):
                row = {"trial": t.number, **row}
                rows.append(row)
                values = [row.get(o.name) for o in objectives]
                if row["verdict"] in ("PASS", "FAIL") and all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
                    # a FAIL outweighs any miss of a constraint (cm, g, ...): the sampler is steered to
                    # PASS designs first (with 1, a heavy FAIL that met a drop bound ranked above a
                    # light PASS 10 cm short of it, and the search drifted over the mass limit)
                    cons = {"verdict PASS": 0.0 if row["verdict"] == "PASS" else FAIL_VIOLATION}
                    seen = corrected(row, correction)
                    cons.update({str(c): min(c.violation(seen), 1e9) for c in constraints})
                    if native:
                        for name, v in cons.items():
                            t.set_constraint(name, v)
                    else:
                        t.set_user_attr("constraints", list(cons.values()))
                    study.tell(t, values)
                else:
                    study.tell(t, state=TrialState.FAIL)
            done += k
            if time.perf_counter() - written >= TRIALS_WRITE_S:  # for a reader watching the run; the last write follows the loop
                _write_trials(out_dir, rows)
                written = time.perf_counter()
            if progress:
                progress(run_mod.BatchDone(tuple(got), got[0]["worker"] if got else "", done, n_trials, time.perf_counter() - tb, "round"))
        if rows:  # every trial: the same bytes however often the loop wrote them before
            _write_trials(out_dir, rows)
        best_rows, pareto = ranked(rows, objectives, constraints)
        # the closed forms' finalists include designs up to SCREEN_TOLERANCE short of a bound (they
        # may pass under the FE); the surrogate's are its feasible designs, best first
        tol = SCREEN_TOLERANCE if fidelity and fidelity[0] == "analytic" else 0.0
        finalists = near_feasible(rows, objectives, constraints, tol, correction)[:verify] if fidelity else []
        verified: list[dict] = []
        if finalists:
            verified = verify_rows(client, sweep, finalists, objectives, constraints, n_workers, fidelity[1])
            (out_dir / "verified.json").write_text(json.dumps(verified, indent=2, default=_py) + "\n")
            best_rows = sorted((r for r in verified if r["feasible"]), key=lambda r: _objective_key(r, objectives))
        cad_rows: tuple[dict, ...] = ()
        if cad and best_rows:
            cad_rows = build_cad(client, sweep, best_rows[:cad])
            (out_dir / "cad.json").write_text(json.dumps(list(cad_rows), indent=2) + "\n")
    if base is None:
        base = ev.evaluate_one(sweep.base_data, {}, sweep.settings.timeout_s, "client", sweep.base_text, sweep.base_label)
    best = best_rows[0] if best_rows else None
    note = ""
    if best is None:
        note = why_none(rows, objectives, constraints)
        if fidelity and verified:
            note += (f" The {len(verified)} best screened designs ({fidelity[0]} joints) all fail under the base file's "
                     f"{fidelity[1]} joints: see verified.json.")
    if best is not None:
        write_best_yaml(sweep, best, out_dir / "best.yaml", keep_model=fidelity is not None)
    result = OptimizeResult(out_dir, tuple(objectives), tuple(constraints), len(rows), len(best_rows), best, tuple(pareto),
                            base, time.perf_counter() - t0, scheduler_addr, n_workers, cad_rows, note, tuple(verified),
                            fidelity, correction)
    _write_summary(sweep, result)
    return result


FIDELITY_KEY = "model.stiffness_model"
DEFAULT_VERIFY = 4  # finalists re-checked when screening with the closed forms
FAIL_VIOLATION = 1e3  # a FAIL trial's constraint violation for the sampler (see _run_optimize)
# trials.parquet is rewritten during the run at most this often (seconds), and once at its end: a
# rewrite converts and writes every row so far, so one per round cost O(rounds x trials)
TRIALS_WRITE_S = 5.0
# How far a screened (closed-form joints) constraint value may miss and the design still be worth
# re-checking with the FE: the two joint models' max_safe_drop_cm differ by up to ~20 % in either
# direction on the carbon designs compared (docs/sweeps.md).
SCREEN_TOLERANCE = 0.2


def screen_correction(screened_base: dict, base: dict, constraints) -> dict[str, float]:
    """Per constraint, the factor that takes the screening model's value to the full model's at the
    base design (base / screened): a multiplicative correction of the cheap model anchored at the
    one design evaluated with both, as in multi-fidelity optimisation. The closed-form joints are
    biased, not random, near the base: on the carbon example they put the base's safe drop at
    121.8 cm where the FE says 137.9, so an uncorrected screen steered the search away from the lightest
    designs the FE accepts. 1.0 where either value is missing, zero or not finite."""
    out = {}
    for c in constraints:
        a, b = screened_base.get(c.name), base.get(c.name)
        ok = all(isinstance(v, (int, float)) and math.isfinite(v) and v != 0 for v in (a, b))
        out[c.name] = float(b) / float(a) if ok else 1.0
    return out


def corrected(row: dict, correction: dict[str, float]) -> dict:
    """`row` with its constraint outputs multiplied by their screen correction (the row itself
    when there is none)."""
    if not correction:
        return row
    out = dict(row)
    for name, f in correction.items():
        v = row.get(name)
        if isinstance(v, (int, float)) and math.isfinite(v):
            out[name] = v * f
    return out


def near_feasible(rows: list[dict], objectives, constraints, tolerance: float,
                  correction: dict[str, float] | None = None) -> list[dict]:
    """Screened PASS rows whose every constraint holds within `tolerance` (relative to its bound),
    their values multiplied by `correction` first (`screen_correction`), best objective first:
    the candidates worth the full model (the rows as screened)."""
    ok = [r for r in rows if _feasible(corrected(r, correction or {}), objectives, constraints, slack=tolerance)]
    return sorted(ok, key=lambda r: _objective_key(r, objectives))


def two_fidelities(sweep: Sweep) -> tuple[str, str] | None:
    """(screening, full) joint models when the sweep file's `set:` changes the base file's one."""
    import yaml

    if FIDELITY_KEY not in sweep.fixed:
        return None
    own = ((yaml.safe_load(sweep.base_text) or {}).get("model") or {}).get("stiffness_model", "fe")
    screen = report_get(sweep.base_data, FIDELITY_KEY)
    return (screen, own) if screen != own else None


def default_verify(sweep: Sweep) -> int:
    """Finalists re-checked with the base file's model when `--verify` is not given: none when the
    sweep evaluates with the FE's surrogate (it agrees with the FE within a few per cent), 4 when it
    screens with the closed forms."""
    fid = two_fidelities(sweep)
    return 0 if fid is None or fid[0] == "surrogate" else DEFAULT_VERIFY


def _objective_key(row: dict, objectives) -> tuple:
    return tuple(row[o.name] if o.direction == "minimize" else -row[o.name] for o in objectives)


def verify_rows(client, sweep: Sweep, rows: list[dict], objectives, constraints, n_workers: int, model: str) -> list[dict]:
    """Re-check the screened finalists on the cluster with the base file's joint model, one design
    per task (each costs seconds of FE). A row gains `feasible` and `screened` (its screening values)."""
    overrides = [{**{k.name: _py(r[k.name]) for k in sweep.keys}, FIDELITY_KEY: model} for r in rows]
    timeout = max(sweep.settings.timeout_s, 600.0)  # a new joint geometry is seconds of FE per joint
    got = run_mod.evaluate_all(client, sweep.base_data, overrides, timeout, 1, n_workers, text=sweep.base_text,
                               base_name=sweep.base_label)
    out = []
    names = list(dict.fromkeys([o.name for o in objectives] + [c.name for c in constraints]))
    for screened, row in zip(rows, got):
        row = {k: v for k, v in row.items() if k != FIDELITY_KEY}
        row["trial"] = screened.get("trial")
        row["feasible"] = bool(_feasible(row, objectives, constraints))
        row["screened"] = {n: screened.get(n) for n in names + ["verdict"]}
        out.append(row)
    return out


def _write_trials(out_dir: Path, rows: list[dict]) -> None:
    import os

    tmp = out_dir / f".trials.parquet.{os.getpid()}.tmp"
    run_mod._frame(rows).to_parquet(tmp, engine="pyarrow", index=False)
    tmp.replace(out_dir / "trials.parquet")


def why_none(rows: list[dict], objectives, constraints) -> str:
    """From the trials: what kept every design out (the most common blocking reason, the closest miss)."""
    if not rows:
        return "No trials ran."
    counts: dict[str, int] = {}
    for r in rows:
        if r["verdict"] != "PASS":
            key = f"verdict {r['verdict']}"
        else:
            broken = [str(c) for c in constraints if c.violation(r) > 0]
            key = "violates " + " and ".join(broken) if broken else "objective missing"
        counts[key] = counts.get(key, 0) + 1
    parts = ", ".join(f"{n} {k}" for k, n in sorted(counts.items(), key=lambda kv: -kv[1]))
    passing = [r for r in rows if r["verdict"] == "PASS"]
    closest = ""
    if passing and constraints:
        c0 = constraints[0]
        r = min(passing, key=lambda r: c0.violation(r))
        closest = f" Closest PASS to {c0}: {r['design_id']} with {c0.name} = {_num(r.get(c0.name))}."
    return f"Of {len(rows)} trials: {parts}.{closest}"


def write_best_yaml(sweep: Sweep, row: dict, path: Path, keep_model: bool = False) -> list[str]:
    """The base file with the changed values edited in place (ruamel round trip: comments and order kept).
    keep_model: the sweep's screening joint model is not written (the design was verified with the
    base file's own)."""
    import io

    from ruamel.yaml import YAML
    from ruamel.yaml.comments import CommentedMap, CommentedSeq

    yaml = YAML()  # round trip: comments, key order, quoting
    yaml.preserve_quotes = True
    yaml.indent(mapping=2, sequence=4, offset=2)  # the presets' style: "  - item" under a key
    yaml.width = 4096  # never re-wrap a long line
    yaml.representer.add_representer(type(None), lambda r, _: r.represent_scalar("tag:yaml.org,2002:null", "null"))
    doc = yaml.load(sweep.base_text)
    if doc is None:
        doc = CommentedMap()
    targets = {f: report_get(sweep.base_data, f) for f in sweep.fixed  # the sweep file's set: values
               if not (keep_model and f == FIDELITY_KEY) and f not in sweep.defaults}
    for k in sweep.keys:
        v = _py(row[k.name])  # numpy scalar -> Python
        targets[k.name] = int(round(v)) if k.integer and isinstance(v, float) else v
    changed = []
    for name, new in targets.items():
        node = doc
        parts = name.split(".")
        for p in parts[:-1]:
            if node.get(p) is None:
                node[p] = CommentedMap()
            node = node[p]
        if parts[-1] not in node or node[parts[-1]] != new:
            old = node.get(parts[-1])
            if isinstance(new, (list, tuple)):  # keep a flow-style list ([50, 100]) in flow style
                seq = CommentedSeq(new)
                if getattr(old, "fa", None) is not None and old.fa.flow_style():
                    seq.fa.set_flow_style()
                new = seq
            node[parts[-1]] = new
            changed.append(name)
    buf = io.StringIO()
    yaml.dump(doc, buf)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(buf.getvalue(), encoding="utf-8")
    tmp.replace(path)
    return changed


def report_get(data: dict, dotted: str):
    from .report import _get

    return _get(data, dotted)


def build_cad(client, sweep: Sweep, rows: list[dict]) -> tuple[dict, ...]:
    """Build the CAD of each design on the cluster (one task each) and verify it."""
    futures = [client.submit(cad_check, ev.apply_overrides(sweep.base_data, {k.name: _py(r[k.name]) for k in sweep.keys}),
                             r["design_id"], pure=False) for r in rows]
    return tuple(f.result() for f in futures)


def _py(v):
    return v.item() if hasattr(v, "item") else v


def cad_check(params: dict, design_id: str) -> dict:
    """A Dask task: every printed part of one design built into a temporary folder and verified:
    watertight single shells, a fit on printer.bed, and the build's clash check (parts, rods,
    vitamins, propeller margins: analysis/clash.py)."""
    import tempfile

    from .. import design as design_mod
    from .. import spec as spec_mod
    from ..export.assembly import check_clashes
    from ..export.part_files import build_parts, fits

    t0 = time.perf_counter()
    spec = spec_mod.from_dict(params, source=f"design {design_id}")
    d = design_mod.design(spec)
    with tempfile.TemporaryDirectory(prefix="cogniframe-cad-") as tmp:
        built = build_parts(spec, d.frame, d.parts, tmp)
        clash = check_clashes(spec, d.frame, d.parts, built, tmp)
    bed = tuple(float(b) for b in spec.printer.bed)
    failures = []
    for b in built:
        if not b.watertight:
            failures.append(f"{b.name} is not watertight")
        if b.shells != 1:
            failures.append(f"{b.name} has {b.shells} shells")
        if not fits(b.bbox_mm, bed):
            failures.append(f"{b.name} ({' x '.join(f'{v:.1f}' for v in b.bbox_mm)} mm) does not fit the bed")
    failures += clash.messages()
    return {"design_id": design_id, "ok": not failures, "parts": len(built), "failures": failures,
            "volume_mm3": round(sum(b.volume_mm3 * b.qty for b in built), 1),
            "clash": {"ok": clash.ok, "bodies": clash.bodies, "pairs_tested": clash.pairs_tested},
            "worker": ev._worker_address(), "seconds": round(time.perf_counter() - t0, 3)}


def _write_summary(sweep: Sweep, result: OptimizeResult) -> None:
    from .report import _md_table

    keys = [k.name for k in sweep.keys]
    outs = list(dict.fromkeys([o.name for o in result.objectives] + [c.name for c in result.constraints]
                              + ["mass_g", "max_safe_drop_cm", "k_n_per_m", "prop_margin_mm"]))
    lines = [f"# Optimize {sweep.stem}", "",
             "Objectives: " + ", ".join(f"{o.direction} `{o.name}`" for o in result.objectives) + "; constraints: "
             + (", ".join(f"`{c}`" for c in result.constraints) or "none") + " (and verdict PASS).", "",
             f"{result.trials} trials ({result.feasible} feasible) in {result.seconds:.1f} s on {result.workers} Dask workers.", ""]
    if result.fidelity and not result.verified:
        lines += [f"Screened with {result.fidelity[0]} joints (the sweep file's set:); no design passed within "
                  f"{100 * SCREEN_TOLERANCE:.0f} % of the constraints, so none was re-checked with the base file's "
                  f"{result.fidelity[1]} joints.", ""]
    if result.fidelity and result.verified:
        outs_v = list(dict.fromkeys([o.name for o in result.objectives] + [c.name for c in result.constraints]))
        lines += [f"## Finalists re-checked with {result.fidelity[1]} joints", "",
                  f"The trials were screened with {result.fidelity[0]} joints (the sweep file's set:), their "
                  "constraint values corrected by the base design's ratio of the two models ("
                  + ", ".join(f"`{n}` x {f:.3f}" for n, f in result.correction.items()) + "); the "
                  f"{len(result.verified)} best feasible were checked again with the base file's {result.fidelity[1]} "
                  "joints, and the best design is the best of those still feasible.", "",
                  *_md_table(["trial", *[f"{o} ({result.fidelity[0]})" for o in outs_v], *[f"{o} ({result.fidelity[1]})" for o in outs_v],
                              "verdict", "feasible"],
                             [[r.get("trial"), *[r["screened"].get(o) for o in outs_v], *[r.get(o) for o in outs_v],
                               r.get("verdict"), r["feasible"]] for r in result.verified]), ""]
    if result.best is None:
        lines += ["No feasible design. " + result.note, ""]
    else:
        b = result.best
        lines += ["## Best design (best.yaml)", "",
                  *_md_table(["key", "base", "best"], [[k, report_get(sweep.base_data, k), _py(b[k])] for k in keys]
                             + [[o, result.base.get(o), b.get(o)] for o in outs]), ""]
        if len(result.objectives) > 1:
            lines += ["## Pareto set", "", *_md_table(["design_id", *keys, *[o.name for o in result.objectives]],
                                                     [[r["design_id"], *[_py(r[k]) for k in keys], *[r[o.name] for o in result.objectives]]
                                                      for r in result.pareto]), ""]
    if result.cad:
        lines += ["## CAD of the best designs", "", *_md_table(["design_id", "ok", "parts", "failures", "seconds"],
                                                              [[c["design_id"], c["ok"], c["parts"], "; ".join(c["failures"]) or "-", c["seconds"]]
                                                               for c in result.cad]), "",
                  "Each design's parts are built, checked watertight and on the bed, and clash-checked with its rods, "
                  "vitamins and propeller discs (`analysis/clash.py`, as in `cogniframe build`).", ""]
    (result.out_dir / "optimize.md").write_text("\n".join(lines))
