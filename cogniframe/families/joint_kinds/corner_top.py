"""The top corner (corner_top): a `Corner`, printed upside down, no support body."""

from __future__ import annotations

from .corner import Corner


class CornerTop(Corner):
    node = "corner_top"
