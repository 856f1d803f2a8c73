"""The studio's form, generated from the params JSON Schema (`cogniframe schema`, the pydantic model).

One `<fieldset>` per section (frame, rods, joints, core, ...; nested sections such as
core.battery inside theirs), one input per value, named by its dotted key (`name="frame.height"`)
and showing the design's value (defaults and printer presets applied), its unit and description
and the schema's bounds. Every input is text (a number field keeps what was typed, so a bad value
reaches the validator and gets the CLI's message, not the browser's). `Field.parse` turns what
the browser sends back into the value written to the YAML.
"""

from __future__ import annotations

import html
import re
from dataclasses import dataclass, field
from typing import Any

UNITS = ("mm", "g", "cm", "g/cm^3", "MPa", "mAh", "m/s", "degrees", "G", "s", "N/m", "N s/m")
_UNIT_AT_END = re.compile(r"(?:^|,\s*)(" + "|".join(re.escape(u) for u in sorted(UNITS, key=len, reverse=True)) + r")\s*$")
_UNIT_OF_NAME = (("_n_s_per_m", "N s/m"), ("_n_per_m", "N/m"), ("_mah", "mAh"), ("_m_s", "m/s"), ("_cm", "cm"),
                 ("_deg", "degrees"), ("_g", "g"), ("_mm", "mm"), ("_s", "s"))


@dataclass
class Field:
    key: str  # dotted
    label: str
    kind: str  # number | integer | boolean | string | enum | numbers
    nullable: bool = False
    description: str = ""
    unit: str = ""
    bounds: str = ""
    options: tuple = ()
    suggestions: tuple = ()
    length: int | None = None  # numbers: a fixed count (tuple)

    def parse(self, raw: Any) -> Any:
        """The value the browser sent (text, or a bool for a checkbox) as the YAML value to write.
        Text that is not a number stays text: the validator then names the key and the fix."""
        if self.kind == "boolean":  # true/false; anything else goes to the validator as written, as in the file
            if isinstance(raw, bool):
                return raw
            word = "" if raw is None else str(raw).strip()
            return {"true": True, "false": False}.get(word.lower(), word if raw is not None else None)
        text = "" if raw is None else str(raw).strip()
        if text == "" and (self.nullable or self.kind == "enum" and "" in self.options):
            return None
        if text.lower() == "null" and self.nullable:
            return None
        if self.kind in ("number", "integer"):
            return number(text)
        if self.kind == "numbers":
            inner = text.strip("[]() ")
            return [number(p.strip()) for p in inner.split(",")] if inner else []
        return text


def number(text: str) -> Any:
    """'4' -> 4, '4.25' -> 4.25, '1e3' -> 1000.0; anything else stays text."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


@dataclass
class Group:
    key: str  # dotted ("" for the top level)
    title: str
    description: str = ""
    items: list = field(default_factory=list)  # Field | Group | str (a note)


def _resolve(prop: dict, defs: dict) -> tuple[dict, bool]:
    """(the schema of a property with $ref and Optional unwrapped, whether null is allowed)."""
    nullable = False
    if "anyOf" in prop:
        branches = [b for b in prop["anyOf"] if b.get("type") != "null"]
        nullable = len(branches) < len(prop["anyOf"])
        merged = dict(branches[0]) if len(branches) == 1 else {"type": "string"}
        for k in ("description", "default", "title"):
            if k in prop:
                merged.setdefault(k, prop[k])
        prop = merged
    if "$ref" in prop:
        target = dict(defs[prop["$ref"].rsplit("/", 1)[-1]])
        for k in ("description", "default"):
            if k in prop:
                target[k] = prop[k]
        prop = target
    return prop, nullable


def _bounds(schema: dict) -> str:
    parts = []
    for key, op in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<")):
        if key in schema:
            parts.append(f"{op} {schema[key]:g}" if isinstance(schema[key], (int, float)) else f"{op} {schema[key]}")
    return ", ".join(parts)


def unit_of(key: str, description: str) -> str:
    m = _UNIT_AT_END.search(description.strip())
    if m:
        return m.group(1)
    name = key.rsplit(".", 1)[-1]
    for suffix, unit in _UNIT_OF_NAME:
        if name.endswith(suffix):
            return unit
    return ""


def suggestions() -> dict[str, tuple]:
    """Known names for the string keys that take one (free text stays allowed: the validator
    says what is wrong and lists the choices)."""
    from ..materials import CONNECTORS, MATERIALS, MOTOR_PRESETS, PROPS, SCREWS, STACK_PATTERNS

    mats = tuple(sorted(MATERIALS))
    return {"rods.material": mats, "joints.material": mats, "core.material": mats, "motors.model": tuple(MOTOR_PRESETS),
            "motors.prop": tuple(PROPS), "core.battery.connector": tuple(CONNECTORS), "core.stack_pattern": tuple(STACK_PATTERNS),
            "core.stack_screw": tuple(SCREWS), "core.computer.screw": tuple(SCREWS), "motors.screw": tuple(SCREWS)}


def groups_of(schema: dict, values: dict) -> list[Group]:
    """The form's groups for a design whose validated values (model_dump, json mode) are `values`."""
    defs = schema.get("$defs", {})
    known = suggestions()
    top = Group("", "design")
    groups = [top]
    for name, prop in schema["properties"].items():
        node, nullable = _resolve(prop, defs)
        item = _item(name, name, node, nullable, values.get(name), defs, known)
        if isinstance(item, Group):
            groups.append(item)
        else:
            top.items.append(item)
    return [g for g in groups if g.items]


def _item(key: str, name: str, node: dict, nullable: bool, value: Any, defs: dict, known: dict):
    description = node.get("description", "")
    if "properties" in node:  # a section
        group = Group(key, name.replace("_", " "), description)
        if value is None:
            group.items.append(f"not set ({key}: null)" + (f": {description}" if description else ""))
            return group
        for sub, prop in node["properties"].items():
            child, child_null = _resolve(prop, defs)
            group.items.append(_item(f"{key}.{sub}", sub, child, child_null, (value or {}).get(sub), defs, known))
        return group
    if node.get("type") == "object":  # a mapping of names: one field (or section) per name the design has
        group = Group(key, name.replace("_", " "), description)
        inner, inner_null = _resolve(node.get("additionalProperties") or {}, defs)
        for sub, v in (value or {}).items():
            group.items.append(_item(f"{key}.{sub}", sub, inner, inner_null, v, defs, known))
        if not group.items:
            group.items.append(f"none in this file (add them under `{key}:` in the YAML)")
        return group
    if node.get("type") == "array" and "$ref" in (node.get("items") or {}):  # a list of records (components)
        group = Group(key, name.replace("_", " "), description)
        inner, _ = _resolve(node["items"], defs)
        for i, row in enumerate(value or []):
            group.items.append(_item(f"{key}.{i}", f"{i + 1}. {row.get('name', '')}".strip(), inner, False, row, defs, known))
        if not group.items:
            group.items.append("none")
        return group
    if node.get("type") == "array":
        bounds = _bounds((node.get("prefixItems") or [node.get("items") or {}])[0])
        length = len(node["prefixItems"]) if "prefixItems" in node else None
        return Field(key, name, "numbers", nullable, description, unit_of(key, description),
                     f"each {bounds}" if bounds else "", length=length)
    if "enum" in node:
        options = tuple(node["enum"]) + (("",) if nullable else ())
        return Field(key, name, "enum", nullable, description, unit_of(key, description), options=options)
    kind = {"number": "number", "integer": "integer", "boolean": "boolean"}.get(node.get("type"), "string")
    return Field(key, name, kind, nullable, description, unit_of(key, description) if kind in ("number", "integer") else "",
                 _bounds(node), suggestions=known.get(key, ()))


def fields(groups: list[Group]) -> dict[str, Field]:
    """Every input of the form by its dotted key."""
    out: dict[str, Field] = {}

    def walk(items):
        for it in items:
            if isinstance(it, Field):
                out[it.key] = it
            elif isinstance(it, Group):
                walk(it.items)

    for g in groups:
        walk(g.items)
    return out


def shown(value: Any) -> str:
    """A value as the text an input shows."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return ", ".join(shown(v) for v in value)
    if isinstance(value, float) and value.is_integer():
        return f"{value:g}" if abs(value) < 1e15 else repr(value)
    return str(value)


def value_at(values: dict, key: str) -> Any:
    node: Any = values
    for part in key.split("."):
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        elif isinstance(node, dict):
            node = node.get(part)
        else:
            return None
    return node


def render(groups: list[Group], values: dict) -> str:
    """The form's HTML."""
    lists: dict[tuple, str] = {}
    out = ['<form id="params" autocomplete="off" onsubmit="return false">']
    for g in groups:
        out.append(_group_html(g, values, lists, top=True))
    out += [f'<datalist id="{lid}">' + "".join(f'<option value="{html.escape(str(o))}">' for o in opts) + "</datalist>"
            for opts, lid in lists.items()]
    out.append("</form>")
    return "\n".join(out)


def _group_html(g: Group, values: dict, lists: dict, top: bool = False) -> str:
    e = html.escape
    title = e(g.title if g.key else "design")
    head = f'<summary>{title}</summary>' if top else f"<legend>{title}</legend>"
    parts = [f'<details class="section" open data-section="{e(g.key)}">{head}' if top
             else f'<fieldset class="group" data-section="{e(g.key)}">{head}']
    if g.description:
        parts.append(f'<p class="group-help">{e(g.description)}</p>')
    for it in g.items:
        if isinstance(it, Group):
            parts.append(_group_html(it, values, lists))
        elif isinstance(it, Field):
            parts.append(_field_html(it, value_at(values, it.key), lists))
        else:
            parts.append(f'<p class="note">{e(it)}</p>')
    parts.append("</details>" if top else "</fieldset>")
    return "\n".join(parts)


def _field_html(f: Field, value: Any, lists: dict) -> str:
    e = html.escape
    fid = "f-" + f.key
    help_bits = [f.description] if f.description else []
    if f.bounds:
        help_bits.append(f.bounds)
    if f.nullable:
        help_bits.append("empty = null")
    if f.kind == "numbers":
        help_bits.append(f"{f.length} numbers" if f.length else "numbers")
        help_bits[-1] += ", comma-separated"
    help_text = "; ".join(b for b in help_bits if b)
    attrs = f'id="{e(fid)}" name="{e(f.key)}" data-kind="{f.kind}" aria-describedby="{e(fid)}-help"'
    if f.kind == "boolean":
        control = f'<input type="checkbox" {attrs}{" checked" if value else ""}>'
    elif f.kind == "enum":
        opts = "".join(f'<option value="{e(str(o))}"{" selected" if (o == value or (o == "" and value is None)) else ""}>'
                       f'{e(str(o)) if o != "" else "(none)"}</option>' for o in f.options)
        control = f"<select {attrs}>{opts}</select>"
    else:
        extra = ' inputmode="decimal"' if f.kind in ("number", "integer", "numbers") else ""
        if f.suggestions:
            lid = lists.setdefault(tuple(f.suggestions), f"choices-{len(lists)}")
            extra += f' list="{lid}"'
        placeholder = ' placeholder="null"' if f.nullable else ""
        control = f'<input type="text" {attrs} value="{e(shown(value))}"{extra}{placeholder} spellcheck="false">'
    unit = f'<span class="unit">{e(f.unit)}</span>' if f.unit else '<span class="unit"></span>'
    return (f'<div class="field" data-key="{e(f.key)}"><label for="{e(fid)}" title="{e(f.key)}">{e(f.label.replace("_", " "))}</label>'
            f'{control}{unit}<p class="help" id="{e(fid)}-help">{e(help_text)}</p>'
            f'<p class="error" data-error-for="{e(f.key)}" role="alert" hidden></p></div>')
