"""`cogniframe server status|stop`: the CAD server that `cogniframe build` keeps between builds.
It exits by itself after 10 minutes without a build; `stop` ends it now. The work is the API's
(`api.cadserver`); these print what it returns.
A server belongs to one environment (interpreter, cogniframe source, library versions,
environment variables, cache folder): these commands see the one this shell's builds use.
``register(app)`` adds the command group to a Typer app.
"""

from __future__ import annotations

import typer

server_app = typer.Typer(help="The CAD server that keeps CadQuery loaded between builds (status, stop).",
                         no_args_is_help=True)


@server_app.command("status")
def status_cmd() -> None:
    """Say whether this environment's CAD server runs (and its pid)."""
    from cogniframe.api.cadserver import cad_server_pid

    pid = cad_server_pid()
    typer.echo(f"CAD server running (pid {pid})" if pid else "no CAD server running")


@server_app.command("stop")
def stop_cmd() -> None:
    """Stop this environment's CAD server (the next build starts a new one)."""
    from cogniframe.api.cadserver import stop_cad_server

    pid = stop_cad_server()
    typer.echo(f"stopped the CAD server (pid {pid})" if pid else "no CAD server running")


def register(app: typer.Typer) -> None:
    app.add_typer(server_app, name="server")
