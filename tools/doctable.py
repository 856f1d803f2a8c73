"""A generated table in a doc: the text between two marker comments, replaced whole.

The tools that make the docs' tables of figures (tools/stiffness_results.py,
tools/authors_differences.py) write them with this; a test compares the doc's table with what the
tool prints now (tests/test_docs_tables.py)."""

from __future__ import annotations

from pathlib import Path


def write_between(doc: Path, begin: str, end: str, table: str) -> None:
    """Replace what stands between the markers in `doc` with `table`."""
    head, rest = doc.read_text(encoding="utf-8").split(begin, 1)
    tail = rest.split(end, 1)[1]
    doc.write_text(f"{head}{begin}\n{table}\n{end}{tail}", encoding="utf-8")


def emit(table: str, doc: Path, begin: str, end: str, write: bool) -> int:
    """A tool's last step: the table into the doc (`--write`) or onto stdout. Returns 0."""
    if write:
        write_between(doc, begin, end, table)
    else:
        print(table)
    return 0
