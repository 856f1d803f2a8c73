"""Which material each read part is: part-name patterns, overridable by a YAML file.

Default patterns (case-insensitive regular expressions, first match wins): names with `flex` or
`tpu` (and cogniframe's `core_link`) are TPU 95A (the authors' `Flex_*` parts), names with `base`, `abs`, `holder`, `core`,
`plate` are ABS, `pla` / `petg` those filaments; anything else is `default` (TPU 95A: the joints of
a soft exoskeleton). A `--materials FILE` YAML replaces or adds patterns, checked first:

    parts:              # pattern -> material (a cogniframe material name)
      Flex_.*: tpu_95a
      MainBase: abs
    default: tpu_95a    # optional
    rods: carbon_rod    # optional: the rods' material (default carbon_rod)
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import UserError

DEFAULT_PATTERNS: tuple[tuple[str, str], ...] = (
    (r"flex|tpu|core_link", "tpu_95a"),  # core_link: cogniframe's own printed TPU links (before `core`)
    (r"base|abs|holder|core|plate", "abs"),
    (r"petg", "petg"),
    (r"pla(?![a-z])|pla_", "pla"),
)


@dataclass(frozen=True)
class MaterialMap:
    patterns: tuple[tuple[str, str], ...] = DEFAULT_PATTERNS
    default: str = "tpu_95a"
    rods: str = "carbon_rod"
    from_file: tuple[str, ...] = field(default=())  # the patterns that came from the file

    def of(self, name: str) -> tuple[str, str]:
        """(material, where it came from: "file" | "name" | "default")."""
        for pat, mat in self.patterns:
            if re.search(pat, name, re.IGNORECASE):
                return mat, ("file" if pat in self.from_file else "name")
        return self.default, "default"


def load_material_map(path: str | Path | None) -> MaterialMap:
    if path is None:
        return MaterialMap()
    import yaml

    from ..materials import MATERIALS

    p = Path(path)
    try:
        data = yaml.safe_load(p.read_text())
    except FileNotFoundError:
        raise UserError(f"{p}: no such materials file") from None
    except yaml.YAMLError as exc:
        raise UserError(f"{p}: not valid YAML ({exc})") from None
    if not isinstance(data, dict) or not isinstance(data.get("parts", {}), dict):
        raise UserError(f"{p}: a materials file is a mapping with `parts:` (name pattern -> material), "
                        f"optionally `default:` and `rods:`")
    pats = []
    for pat, mat in (data.get("parts") or {}).items():
        try:
            re.compile(str(pat))
        except re.error as exc:
            raise UserError(f"{p}: parts: {pat!r} is not a valid pattern ({exc})") from None
        pats.append((str(pat), str(mat)))
    default = str(data.get("default", "tpu_95a"))
    rods = str(data.get("rods", "carbon_rod"))
    for where, mat in [*((f"parts: {k}", m) for k, m in pats), ("default", default), ("rods", rods)]:
        if mat not in MATERIALS:
            raise UserError(f"{p}: {where}: unknown material {mat!r}; one of {', '.join(sorted(MATERIALS))}")
    return MaterialMap(tuple(pats) + DEFAULT_PATTERNS, default, rods, tuple(k for k, _ in pats))
