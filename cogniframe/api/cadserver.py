"""The CAD server that `cogniframe build` keeps between builds: what `cogniframe server status`
and `server stop` do, from Python.

A server belongs to one environment (interpreter, cogniframe source, library versions,
environment variables, cache folder): these functions see the one this process's builds use.
It exits by itself after 10 minutes without a build; `stop_cad_server` ends it now.
"""

from __future__ import annotations


def cad_server_pid() -> int | None:
    """The pid of this environment's CAD server; None when none runs."""
    from ..runtime import cad_server
    from ..stack import versions

    return cad_server.running(versions())


def stop_cad_server() -> int | None:
    """Stop this environment's CAD server (the next build starts a new one); returns its pid,
    None when none ran."""
    from ..runtime import cad_server
    from ..stack import versions

    return cad_server.stop(versions())
