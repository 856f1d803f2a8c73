"""`cogniframe studio PARAMS [--port N] [--no-browser]`: edit a design in the browser.

A local web app on 127.0.0.1 (cogniframe/studio/): the params as a form, the figures of
`check` live as you type, the 3D view, Save (comments kept) and Build, each tab's design in its
address (undo, snapshots, compare). It runs until Ctrl-C; its errors go to its log (docs/studio.md).
``register(app)`` adds the command to a Typer app.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer


def studio(params: Annotated[Path, typer.Argument(help="params YAML file, e.g. params/carbon.yaml", show_default=False)],
           port: Annotated[int, typer.Option("--port", min=0, max=65535, help="port on 127.0.0.1 (0: any free port)")] = 8765,
           no_browser: Annotated[bool, typer.Option("--no-browser", help="do not open a browser; just print the address")] = False) -> None:
    """Edit a design in the browser: live mass, stiffness and crash figures, 3D view, Save and Build (127.0.0.1 only)."""
    from cogniframe.studio.serve import serve

    serve(params, port=port, open_browser=not no_browser)


def register(app: typer.Typer) -> None:
    app.command("studio")(studio)
