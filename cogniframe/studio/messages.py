"""What a page's message may hold, and the plain sentence when it holds something else.

Every message a page sends (an edit, Save, Build, a compare) is checked here before the studio
does any work with it: its size, its number of keys, that each key is an input of the form and
each value text, a number, true/false or null of a sensible length. A message refused is answered
with `Refused`'s sentence, in well under a second whatever was sent, and a value is never echoed
whole (`shorten`).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from typing import Any

# What one message may hold. The form has about 100 fields; a page sends only the ones it changed.
MAX_MESSAGE_BYTES = 256 * 1024
MAX_KEYS = 400
MAX_VALUE_CHARS = 1000  # a name is at most 64 characters, a list of numbers a few dozen
MAX_DESIGNS = 8  # designs in one compare
MAX_SHOWN = 600  # characters of a message a page shows: a huge value is never echoed whole


class Refused(Exception):
    """A message the studio does not take: the plain reason, for the page."""


def text_hash(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def shorten(text: str, limit: int = MAX_SHOWN) -> str:
    """`text`, with its long runs cut so that a 1 MB value in a message is not sent back whole."""
    if len(text) <= limit:
        return text
    keep = limit // 2
    return f"{text[:keep]}… ({len(text) - 2 * keep} characters left out) …{text[-keep:]}"


def parse_values(values: Any, fields: Mapping[str, Any]) -> dict[str, Any]:
    """The values a page sent, as the YAML values to write (`fields`: the form's inputs by dotted
    key, each parsing what its input sends). Refused: not a mapping, too many keys, a key that is
    not an input of the form, a value that is not text, a number, true/false or null, or a very
    long one."""
    if values is None:
        return {}
    if not isinstance(values, dict):
        raise Refused("refused: `values` must be a mapping of dotted keys to values.")
    if len(values) > MAX_KEYS:
        raise Refused(f"refused: {len(values)} keys in one message; the studio takes at most {MAX_KEYS} "
                      f"(the form has {len(fields)} inputs).")
    parsed = {}
    for key, raw in values.items():
        f = fields.get(key)
        if f is None:
            raise Refused(f"refused: {shorten(str(key), 80)!s} is not an input of the form.")
        if raw is not None and not isinstance(raw, (str, bool, int, float)):
            raise Refused(f"refused: {key}: a value is text, a number, true/false or null, not a {type(raw).__name__}.")
        if isinstance(raw, str) and len(raw) > MAX_VALUE_CHARS:
            raise Refused(f"refused: {key}: a value of {len(raw)} characters; the studio takes at most {MAX_VALUE_CHARS}.")
        parsed[key] = f.parse(raw)
    return parsed


def compare_items(designs: Any) -> list[tuple[str, Any, Any]]:
    """(name, base, values) of each design of a compare message ({"name", "base", "values"})."""
    if not isinstance(designs, list) or not designs:
        raise Refused("refused: `designs` must be a list of designs to compare.")
    if len(designs) > MAX_DESIGNS:
        raise Refused(f"refused: {len(designs)} designs; the compare takes at most {MAX_DESIGNS}.")
    out = []
    for i, item in enumerate(designs):
        if not isinstance(item, dict):
            raise Refused("refused: each design to compare is {name, base, values}.")
        out.append((shorten(str(item.get("name") or f"design {i + 1}"), 80), item.get("base"), item.get("values")))
    return out
