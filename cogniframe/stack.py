"""The installed library versions that shape cogniframe's output bytes.

`installed()` goes in every build's manifest and key; `versions()` (those and a few more) in
every step's cache key and in the CAD server's key. Light on purpose (importlib.metadata only):
`cogniframe build` computes the server's key first thing, to start the server while it validates
the params (`runtime.cad_server.prestart`).
"""

from __future__ import annotations

import functools
import json
from importlib import metadata

from .version import __version__

# listed in the manifest
LIBRARIES = ("cadquery", "cadquery-ocp", "trimesh", "manifold3d", "numpy", "scipy", "pynitefea", "pyvista", "vtk", "matplotlib")
# also in every step's key
EXTRA_LIBRARIES = ("rectpack", "pillow", "lxml", "networkx", "rich")


@functools.cache
def _lookup(dists: tuple[str, ...]) -> tuple[tuple[str, str | None], ...]:
    """Looked up once per process (each metadata lookup scans sys.path)."""
    out = []
    for dist in dists:
        try:
            out.append((dist, metadata.version(dist)))
        except metadata.PackageNotFoundError:
            out.append((dist, None))
    return tuple(out)


def installed() -> dict:
    """{"cogniframe": version, library: version or None} for LIBRARIES."""
    return {"cogniframe": __version__, **dict(_lookup(LIBRARIES))}


def versions() -> str:
    """Versions of everything that shapes the output bytes (LIBRARIES and EXTRA_LIBRARIES), as JSON."""
    return json.dumps({**installed(), **dict(_lookup(EXTRA_LIBRARIES))}, sort_keys=True)
