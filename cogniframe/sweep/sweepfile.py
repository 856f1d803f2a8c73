"""The sweep file: which params file to start from and which keys to vary over what box.

```yaml
base: params/carbon.yaml     # every design starts from this file
samples: 300
sampler: lhs                 # grid | lhs | sobol | random
seed: 3
vary:
  rods.diameter: [2.5, 4.0]          # a range: lo, hi
  rods.material: {choices: [carbon_rod, bamboo]}
```

`load(path) -> Sweep` validates the file (unknown keys, types), resolves every `vary` key to a
params key, checks each range end and choice against the params schema's bounds, and loads the
base params file. Every problem is a `UserError` naming the sweep file, the key (with its line)
and the fix. `base` is read relative to the sweep file's folder, else to the current folder.
"""

from __future__ import annotations

import difflib
import os
import hashlib
import json
import typing
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError

from .. import spec as params_spec
from ..errors import UserError


class _M(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Choices(_M):
    choices: Annotated[list[Any], Field(min_length=1, description="the values to pick from (e.g. materials)")]


class SweepFile(_M):
    """A design-space sweep (`cogniframe sweep`) or optimisation box (`cogniframe optimize`)."""

    base: str = Field(description="params file every design starts from (relative to this file's folder, else to the current folder)")
    samples: Annotated[int, Field(ge=1, le=1_000_000, description="designs to draw (sobol: base sample N, giving N * (keys + 2) designs; grid: ignored, see levels); optimize: trials")] = 100
    sampler: Literal["grid", "lhs", "sobol", "random"] = Field("lhs", description="grid (levels per range key) | lhs (Latin hypercube) | sobol (Saltelli design, Sobol indices) | random")
    seed: Annotated[int, Field(ge=0, le=2**32 - 1, description="random seed: same file, same designs")] = 0
    levels: Annotated[int, Field(ge=2, le=1000, description="grid sampler: values per range key, ends included")] = 5
    batch: Annotated[int, Field(ge=1, le=10_000, description="designs per Dask task; null = automatic")] | None = None
    timeout_s: Annotated[float, Field(gt=0, le=86_400, description="per-design time limit, s; a design over it is recorded as TIMEOUT")] = 60.0
    vary: Annotated[dict[str, tuple[float, float] | Choices], Field(min_length=1, description="dotted params key -> [lo, hi] or {choices: [...]}")]
    set: dict[str, Any] = Field(default_factory=dict, description="dotted params key -> value, applied to every design (and to the base it is compared with), e.g. a faster stiffness model")


@dataclass(frozen=True)
class VaryKey:
    name: str  # dotted params key
    lo: float | None = None
    hi: float | None = None
    choices: tuple | None = None
    integer: bool = False

    @property
    def is_choice(self) -> bool:
        return self.choices is not None


@dataclass(frozen=True)
class Sweep:
    path: str  # the sweep file as given
    settings: SweepFile
    keys: tuple[VaryKey, ...]
    base_path: str
    base_text: str  # the base params file's text (travels to the workers; they never read a disk)
    base_data: dict  # parsed base (name filled in as spec.load does) with the `set:` values applied
    fixed: tuple[str, ...] = ()  # the `set:` keys, and the sweep defaults applied (`defaults`)
    defaults: tuple[str, ...] = ()  # keys set by the sweep's defaults, not by the file (`SWEEP_DEFAULTS`)

    @property
    def base_label(self) -> str:
        """How messages name the base params file ("carbon.yaml")."""
        return Path(self.base_path).name

    @property
    def stem(self) -> str:
        return Path(self.path).stem

    def digest(self) -> str:
        """Hash of what decides the design list: base params, keys, sampler settings."""
        payload = {"base": self.base_data, "settings": self.settings.model_dump(mode="json", exclude={"base"})}
        return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()[:16]


# What a sweep sets unless its file sets or varies it: the joints from the solid FE's surrogate
# (milliseconds per design, within a few per cent of the FE; the FE for a joint outside its
# training box), in place of the base file's solid FE (seconds per new joint geometry).
SWEEP_DEFAULTS = {"model.stiffness_model": ("fe", "surrogate")}  # key: (base value it replaces, sweep value)


def json_schema() -> dict:
    return SweepFile.model_json_schema()


def load(path: str | Path) -> Sweep:
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: no such sweep file. Give the path of a sweep YAML file such as examples/sweeps/carbon.yaml.")
    text = path.read_text(encoding="utf-8")
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise UserError(f"{path}: not valid YAML{where} ({getattr(e, 'problem', e)}). Fix the indentation or quoting there.") from None
    if not isinstance(data, dict):
        raise UserError(f"{path}: a sweep file is a mapping with base:, vary: and optional samples:, sampler:, seed:; "
                        f"got a {type(data).__name__}. Fix: start from examples/sweeps/carbon.yaml.")
    return from_dict(data, source=str(path), text=text, folder=path.parent)


def from_dict(data: dict, source: str = "<sweep>", text: str | None = None, folder: Path | None = None) -> Sweep:
    try:
        settings = SweepFile.model_validate(data)
    except ValidationError as e:
        raise UserError(_explain(e, source, text)) from None
    base_path = _find_base(settings.base, source, text, folder)
    try:
        base_spec = params_spec.load(base_path)
    except UserError as e:
        raise UserError(f"{source}: base{_line(text, ('base',))}: the base params file {base_path} does not load: {e} "
                        f"Fix that file, or point base at a params file that `cogniframe check` accepts.") from None
    base_text = Path(base_path).read_text(encoding="utf-8")
    base_data = yaml.safe_load(base_text) or {}
    base_data.setdefault("name", Path(base_path).stem)
    fixed = {}
    for name, v in settings.set.items():
        _check_value(name, v, base_spec, f"{source}: set.{name}{_line(text, ('set', name))}", containers=True)
        fixed[name] = v
    defaults = []
    for name, (slow, fast) in SWEEP_DEFAULTS.items():
        if name not in fixed and name not in settings.vary and _get(base_data, name, slow) == slow:
            fixed[name] = fast
            defaults.append(name)
    if fixed:
        from .evaluate import apply_overrides

        base_data = apply_overrides(base_data, fixed)
        try:
            base_spec = params_spec.from_dict(base_data, source=f"{base_path} with {source}'s set:")
        except UserError as e:
            raise UserError(f"{source}: set{_line(text, ('set',))}: the base with these values does not validate: {e} "
                            "Fix: change the values under set.") from None
    keys = tuple(_vary_key(name, rng, base_spec, source, text) for name, rng in settings.vary.items())
    if settings.sampler == "sobol" and len(keys) < 2:
        raise UserError(f"{source}: sampler{_line(text, ('sampler',))}: Sobol indices need at least two keys under vary. "
                        "Fix: add a key to vary, or use sampler: lhs.")
    return Sweep(str(source), settings, keys, str(base_path), base_text, base_data, tuple(fixed), tuple(defaults))


def _get(data: dict, dotted: str, default=None):
    node = data
    for p in dotted.split("."):
        if not isinstance(node, dict) or p not in node:
            return default
        node = node[p]
    return default if node is None else node


def _find_base(base: str, source: str, text: str | None, folder: Path | None) -> Path:
    tried = []
    for root in ([folder] if folder is not None else []) + [Path.cwd()]:
        p = Path(base) if Path(base).is_absolute() else Path(os.path.normpath(root / base))
        tried.append(str(p))
        if p.is_file():
            return p
    raise UserError(f"{source}: base{_line(text, ('base',))}: no params file {base!r} (looked for {' and '.join(dict.fromkeys(tried))}). "
                    "Fix: give the path of a params file, relative to the sweep file's folder or the current folder.")


# -- resolving a dotted key against the params schema ---------------------------------------

def _field_at(dotted: str, containers: bool = False):
    """(annotation with its constraints, description) of a params key, or a reason it is not one."""
    model: Any = params_spec.Spec
    parts = dotted.split(".")
    ann: Any = None
    desc = None
    for i, part in enumerate(parts):
        if model is not None:
            fields = model.model_fields
            if part not in fields:
                near = difflib.get_close_matches(part, list(fields), n=1, cutoff=0.5)
                where = ".".join(parts[:i]) or "the top level"
                hint = f"did you mean '{'.'.join(parts[:i] + [near[0]])}'? " if near else ""
                return None, f"{part!r} is not a params key under {where}; {hint}keys there: {', '.join(fields)}"
            f = fields[part]
            ann = Annotated[(f.annotation, *f.metadata)] if f.metadata else f.annotation
            desc = f.description
        else:  # inside a dict[str, X]: any key, value type X
            ann = typing.get_args(ann)[1]
        inner = _unwrap(ann)
        if i < len(parts) - 1:
            if isinstance(inner, type) and issubclass(inner, BaseModel):
                model, ann = inner, None
            elif typing.get_origin(inner) is dict:
                model, ann = None, inner
            else:
                return None, f"{'.'.join(parts[:i + 1])} is a value, it has no key {parts[i + 1]!r}"
    inner = _unwrap(ann)
    if isinstance(inner, type) and issubclass(inner, BaseModel) or (not containers and typing.get_origin(inner) in (dict, tuple, list)):
        return None, f"{dotted} is a section or a list, not one value; vary one of its keys"
    return (ann, desc), None


def _unwrap(ann):
    """The model or container type inside Optional/Annotated, else the annotation."""
    for _ in range(4):
        origin = typing.get_origin(ann)
        if origin is Annotated:
            ann = typing.get_args(ann)[0]
        elif origin in (typing.Union, getattr(__import__("types"), "UnionType", None)):
            args = [a for a in typing.get_args(ann) if a is not type(None)]
            ann = args[0] if len(args) == 1 else ann
            if len(args) != 1:
                break
        else:
            break
    return ann


def _check_value(name: str, v, base_spec, where: str, containers: bool = False):
    """The key's annotation after checking that `name` is a params key and `v` a value it allows."""
    found, why = _field_at(name, containers)
    if found is None:
        raise UserError(f"{where}: not a params key ({why}). Fix: use a dotted key of the params file, e.g. rods.diameter "
                        "(`cogniframe schema` lists them).")
    ann, desc = found
    try:
        TypeAdapter(ann).validate_python(v, strict=False)
    except ValidationError as e:
        msg = e.errors()[0]["msg"].lower()
        raise UserError(f"{where}: {v!r} is outside what the params file allows ({msg}). "
                        f"Fix: keep {name} within {_bounds_text(ann) or desc or 'the schema'}.") from None
    if name.endswith(".material") and isinstance(v, str):
        lib = {**params_spec.MATERIALS, **base_spec.materials}
        if v not in lib:
            raise UserError(f"{where}: unknown material {v!r}. Fix: use one of {', '.join(sorted(lib))}, "
                            "or define it under materials: in the base file.")
    return ann


def _vary_key(name: str, rng, base_spec, source: str, text: str | None) -> VaryKey:
    where = f"{source}: vary.{name}{_line(text, ('vary', name))}"
    values = list(rng.choices) if isinstance(rng, Choices) else list(rng)
    ann = None
    for v in values:
        ann = _check_value(name, v, base_spec, where)
    if isinstance(rng, Choices):
        return VaryKey(name, choices=tuple(rng.choices))
    lo, hi = float(rng[0]), float(rng[1])
    if not lo < hi:
        raise UserError(f"{where}: the range [{rng[0]}, {rng[1]}] is empty. Fix: write [lo, hi] with lo < hi, "
                        f"or use {{choices: [{rng[0]}]}} for a fixed value.")
    integer = _unwrap(ann) is int
    return VaryKey(name, lo=lo, hi=hi, integer=integer)


def _bounds_text(ann) -> str:
    out = []
    stack = [ann]
    while stack:
        a = stack.pop()
        if typing.get_origin(a) is Annotated:
            for meta in typing.get_args(a)[1:]:
                for attr, op in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
                    for m in (meta, *getattr(meta, "metadata", ())):
                        if getattr(m, attr, None) is not None:
                            out.append(f"{op} {getattr(m, attr)}")
            stack.append(typing.get_args(a)[0])
        else:
            stack.extend(typing.get_args(a))
    return " and ".join(dict.fromkeys(out))


# -- error messages -------------------------------------------------------------------------

def _line(text: str | None, loc: tuple[str, ...]) -> str:
    return params_spec._line(text, loc)


def _explain(err: ValidationError, source: str, text: str | None) -> str:
    lines = []
    fields = SweepFile.model_fields
    for item in err.errors():
        loc = tuple(str(p) for p in item["loc"])
        if loc and loc[0] == "vary" and len(loc) >= 2:
            loc = loc[:2]  # the union's branch names are noise; the key is what the user wrote
            key = f"vary.{loc[1]}"
            lines.append(f"{source}: {key}{_line(text, loc)}: give a range [lo, hi] (two numbers) or {{choices: [a, b, ...]}}. "
                         f"Fix: e.g. `{loc[1]}: [2.5, 4.0]`.")
            continue
        key = ".".join(loc) or "(top level)"
        if item["type"] == "extra_forbidden":
            near = difflib.get_close_matches(loc[-1], list(fields), n=1, cutoff=0.5)
            hint = f"did you mean '{near[0]}'? " if near else ""
            lines.append(f"{source}: {key}{_line(text, loc)}: unknown key. Fix: {hint}valid keys are {', '.join(fields)}.")
        elif item["type"] == "missing":
            lines.append(f"{source}: {key}: missing. Fix: add `{key}:` ({fields[loc[0]].description if loc[0] in fields else ''}).")
        else:
            got = item.get("input")
            got_s = "" if isinstance(got, (dict, list)) else f" (got {got!r})"
            desc = fields[loc[0]].description if loc and loc[0] in fields else None
            bounds = _bounds_text(Annotated[(fields[loc[0]].annotation, *fields[loc[0]].metadata)]) if loc and loc[0] in fields and fields[loc[0]].metadata else ""
            fix = f"set {key} to a valid value ({desc}{'; must be ' + bounds if bounds else ''})." if desc else f"check the value of {key}."
            lines.append(f"{source}: {key}{_line(text, loc)}: {item['msg'].lower()}{got_s}. Fix: {fix}")
    # one message per key
    return "\n".join(dict.fromkeys(lines))
