"""cache.py: source hashes that key cached results."""

from __future__ import annotations

import pytest

from cogniframe import cache


def _tree(root):
    (root / "viewer").mkdir(parents=True)
    (root / "viewer" / "viewer.js").write_text("draw()")
    (root / "viewer" / "three.js").write_text("lib")
    return root


def test_sources_hash_ignores_pycache_folders_of_an_installed_package(tmp_path):
    # `pip install .` puts viewer/__pycache__ beside the sources; "viewer/*" matched it and the
    # build died reading a folder (IsADirectoryError) on every non-editable install
    root = _tree(tmp_path / "pkg")
    before = cache.sources_hash(root, ("viewer/*",))
    (root / "viewer" / "__pycache__").mkdir()
    (root / "viewer" / "__pycache__" / "__init__.cpython-311.pyc").write_bytes(b"\0\1")
    assert cache.sources_hash(root, ("viewer/*",)) == before


def test_sources_hash_follows_file_bytes_and_names(tmp_path):
    root = _tree(tmp_path / "pkg")
    h = cache.sources_hash(root, ("viewer/*",))
    (root / "viewer" / "viewer.js").write_text("draw(1)")
    assert cache.sources_hash(root, ("viewer/*",)) != h
    with pytest.raises(FileNotFoundError, match="no cogniframe source matches"):
        cache.sources_hash(root, ("nothing/*.py",))


def test_code_hash_of_the_viewer_folder_reads_files_only():
    import cogniframe.report.viewer  # noqa: F401 - may create report/viewer/__pycache__ beside the sources

    assert len(cache.code_hash("report/viewer/*")) == 16
