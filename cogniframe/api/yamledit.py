"""Set dotted keys in a params file's YAML text, changing nothing else.

`set_values(text, {"rods.diameter": 4.0})` returns the text with only that value replaced: its
comments, key order, blank lines, quoting and indentation stay byte for byte, so what the
studio's Save writes (and what an error message's line numbers refer to) is the user's file with
the edited values, not a re-serialised copy. A round trip through ruamel.yaml keeps comments but
rewrites other things (`null` becomes an empty value, list indentation moves), so the edit is
made on the text at the span PyYAML's composer reports for the value:

- a value already in the file: its span is replaced (a quoted string keeps its quotes);
- an empty value (`key:` with nothing after it): the new value is written after the colon;
- a key not in the file: a line is added after the last line of its section, at the section's
  indentation (missing sections in between are added as nested lines); in a flow mapping
  (`{name: ..., mass: 6}`) it is added before the closing brace;
- a key under a value that is not a mapping (`camera: null`, then `camera.tilt_deg`): that value
  becomes a flow mapping holding the key.

Values are written in YAML flow style (`[120, 120, 120]`, `null`, `true`, `'1404'`). A list index
past the end of a list is a `KeyError` (a value cannot be appended to a list this way).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

import yaml
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml: the same marks (in characters), 15x faster


def set_values(text: str, values: Mapping[str, Any]) -> str:
    """`text` with each dotted key set to its value, in order: the same text as `set_value` one
    key at a time, from one parse of `text` (the studio applies a whole form's edits per
    keystroke, and a parse per key made 1000 keys take a minute). Edits whose spans overlap (a
    key and a key inside it) are made one key at a time."""
    values = dict(values)
    if len(values) <= 1 or not text.strip():
        return _one_by_one(text, values)
    root = yaml.compose(text, Loader=_LOADER)
    if root is None:
        return _one_by_one(text, values)
    spans: list[tuple[int, int, str]] = []  # (start, end, new text) of the values already in the file
    blocks: dict[int, list] = {}  # id(node) -> [node, where, tree]: keys added under one mapping or scalar
    for key, value in values.items():
        kind, node, key_node, rest = _locate(root, key)
        if kind == "replace":
            spans.append(_replacement(text, node, key_node, value))
        else:
            entry = blocks.setdefault(id(node), [node, (kind, key_node), _Tree()])
            if not entry[2].add(rest, value):
                return _one_by_one(text, values)  # a key and a key inside it, both new: key by key
    inserts: dict[int, list[tuple[int, int, list[str]]]] = {}  # position -> (indent, order, lines)
    for order, (node, (kind, key_node), tree) in enumerate(blocks.values()):
        if kind == "nest":  # a scalar where a section is wanted: it becomes a flow mapping
            spans.append(_replacement(text, node, key_node, tree.plain()))
        elif node.flow_style:
            close = _flow_close(text, node)
            inner = text[node.start_mark.index + 1: close].strip()
            entries = ", ".join(f"{k}: {render(v.plain() if isinstance(v, _Tree) else v)}" for k, v in tree.items())
            spans.append((close, close, (", " if inner else "") + entries))
        else:
            indent = node.value[0][0].start_mark.column if node.value else 0
            newline = text.find("\n", _content_end(node))
            at = len(text) if newline < 0 else newline
            inserts.setdefault(at, []).append((indent, order, tree.lines(indent, bool(text.strip()))))
    for at, found in inserts.items():
        # deeper sections first: their lines continue the innermost block that ends there
        lines = [line for _, _, ls in sorted(found, key=lambda f: (-f[0], f[1])) for line in ls]
        if at == len(text):
            spans.append((at, at, ("" if text.endswith("\n") else "\n") + "\n".join(lines) + "\n"))
        else:
            spans.append((at, at, "\n" + "\n".join(lines)))
    spans.sort(key=lambda s: (s[0], s[1]))
    for a, b in zip(spans, spans[1:]):
        if b[0] < a[1] or (b[0] == a[0] and max(a[1], b[1]) > a[0]):
            return _one_by_one(text, values)  # nested or repeated spans: key by key, as written
    for start, end, new in reversed(spans):
        text = text[:start] + new + text[end:]
    return text


def _one_by_one(text: str, values: Mapping[str, Any]) -> str:
    for key, value in values.items():
        text = set_value(text, key, value)
    return text


class _Tree(dict):
    """Keys added under one node: dotted parts nested as dicts, in the order they came."""

    def add(self, parts: list[str], value: Any) -> bool:
        """False when a value and a section would share a name (the caller then goes key by key)."""
        node = self
        for p in parts[:-1]:
            child = node.setdefault(p, _Tree())
            if not isinstance(child, _Tree):
                return False
            node = child
        if parts[-1] in node:
            return False
        node[parts[-1]] = value
        return True

    def plain(self) -> dict:
        return {k: v.plain() if isinstance(v, _Tree) else v for k, v in self.items()}

    def lines(self, indent: int, blank_before_sections: bool) -> list[str]:
        """As `_append_lines` writes them: one line per level, two more spaces a level, a blank
        line before a new top-level section."""
        out: list[str] = []
        for k, v in self.items():
            if isinstance(v, _Tree):
                if indent == 0 and blank_before_sections:
                    out.append("")
                out.append(" " * indent + f"{k}:")
                out += v.lines(indent + 2, False)
            else:
                out.append(" " * indent + f"{k}: {render(v)}")
        return out


def _locate(root: Node, key: str) -> tuple[str, Node, Node | None, list[str]]:
    """Where `set_value` puts `key`: ("replace", value node, its key node, []), ("insert", the
    mapping, None, the parts it lacks) or ("nest", the scalar, its key node, the parts under it)."""
    parts = key.split(".")
    if not key or any(p == "" for p in parts):
        raise KeyError(f"{key!r} is not a dotted key such as rods.diameter")
    node: Node = root
    key_node: Node | None = None
    for i, part in enumerate(parts):
        if isinstance(node, MappingNode):
            found = next(((k, v) for k, v in node.value if isinstance(k, ScalarNode) and k.value == part), None)
            if found is None:
                return "insert", node, None, parts[i:]
            key_node, node = found
        elif isinstance(node, SequenceNode) and part.isdigit():
            index = int(part)
            if index >= len(node.value):
                raise KeyError(f"{'.'.join(parts[:i])} has {len(node.value)} entries; there is no entry {index}")
            key_node, node = None, node.value[index]
        else:
            return "nest", node, key_node, parts[i:]
    return "replace", node, key_node, []


def render(value: Any) -> str:
    """One value as YAML flow text (a single line)."""
    value = _plain(value)
    out = yaml.safe_dump(value, default_flow_style=True, width=1 << 30, allow_unicode=True, sort_keys=False)
    for tail in ("\n...\n", "\n"):
        if out.endswith(tail):
            out = out[: -len(tail)]
            break
    return out


def _plain(value: Any) -> Any:
    """Plain Python values for the YAML dumper (numpy scalars, tuples)."""
    if hasattr(value, "item") and not isinstance(value, (str, bytes)) and getattr(value, "shape", None) == ():
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    return value


def set_value(text: str, key: str, value: Any) -> str:
    if not key or any(p == "" for p in key.split(".")):
        raise KeyError(f"{key!r} is not a dotted key such as rods.diameter")
    root = yaml.compose(text, Loader=_LOADER) if text.strip() else None
    if root is None:  # an empty file (or only comments): the key goes at the end
        return _append_lines(text, len(text), 0, key.split("."), value)
    how, node, key_node, rest = _locate(root, key)
    if how == "insert":
        return _insert(text, node, rest, value)
    if how == "nest":  # a scalar (null, a number) where a section is wanted: it becomes a flow mapping
        return _replace(text, node, key_node, _nested(rest, value))
    return _replace(text, node, key_node, value)


def _nested(parts: list[str], value: Any) -> dict:
    out: Any = value
    for p in reversed(parts):
        out = {p: out}
    return out


def _empty(node: Node) -> bool:
    return isinstance(node, ScalarNode) and node.start_mark.index == node.end_mark.index


def _content_end(node: Node) -> int:
    """Index just past the last character of `node`'s own text (a block collection's end mark
    lies at the next token, past blank lines and comments)."""
    if isinstance(node, MappingNode) and not node.flow_style and node.value:
        k, v = node.value[-1]
        return k.end_mark.index if _empty(v) else _content_end(v)
    if isinstance(node, SequenceNode) and not node.flow_style and node.value:
        return _content_end(node.value[-1])
    return node.end_mark.index


def _replace(text: str, node: Node, key_node: Node | None, value: Any) -> str:
    start, end, new = _replacement(text, node, key_node, value)
    return text[:start] + new + text[end:]


def _replacement(text: str, node: Node, key_node: Node | None, value: Any) -> tuple[int, int, str]:
    """(start, end, new text) that set the value of `node`."""
    if _empty(node):  # `key:` with no value: write it after the colon
        if key_node is None:
            raise KeyError("an empty list entry cannot be set")
        colon = text.index(":", key_node.end_mark.index)
        return colon + 1, colon + 1, " " + render(value)
    start, end = node.start_mark.index, _content_end(node)
    new = render(value)
    if isinstance(node, ScalarNode) and isinstance(value, str) and node.style in ('"', "'"):
        new = json.dumps(value, ensure_ascii=False) if node.style == '"' else "'" + value.replace("'", "''") + "'"
    return start, end, new


def _flow_close(text: str, mapping: MappingNode) -> int:
    close = mapping.end_mark.index - 1
    while close > mapping.start_mark.index and text[close] != "}":
        close -= 1
    return close


def _insert(text: str, mapping: MappingNode, parts: list[str], value: Any) -> str:
    if mapping.flow_style:
        close = _flow_close(text, mapping)
        inner = text[mapping.start_mark.index + 1: close].strip()
        entry = f"{parts[0]}: {render(_nested(parts[1:], value) if len(parts) > 1 else value)}"
        return text[:close] + (", " if inner else "") + entry + text[close:]
    indent = mapping.value[0][0].start_mark.column if mapping.value else 0
    end = _content_end(mapping)
    newline = text.find("\n", end)
    return _append_lines(text, len(text) if newline < 0 else newline, indent, parts, value)


def _append_lines(text: str, at: int, indent: int, parts: list[str], value: Any) -> str:
    """Lines for `parts: value` (one per level, two more spaces a level) inserted as new lines at
    `at` (the end of a line, or the end of the text)."""
    lines = [" " * (indent + 2 * i) + f"{p}:" for i, p in enumerate(parts)]
    lines[-1] += " " + render(value)
    if indent == 0 and len(parts) > 1 and text.strip():
        lines.insert(0, "")  # a new top-level section: a blank line before it, as the presets have
    block = "\n".join(lines)
    before, after = text[:at], text[at:]
    if at == len(text):
        if before and not before.endswith("\n"):
            before += "\n"
        return before + block + "\n"
    return before + "\n" + block + after
