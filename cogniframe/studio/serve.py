"""`serve(params, port, open_browser)`: the studio on http://127.0.0.1:PORT/ until Ctrl-C.

The socket is bound here, to 127.0.0.1 only (never 0.0.0.0 or ::), before uvicorn starts, so the
address printed is the one listening (also with `--port 0`, any free port) and a port in use is
a plain message (exit 2). Ctrl-C (or SIGTERM) stops the server and the studio exits 0. The
server's errors (a bug, a page that sent something odd) go to the studio's log,
$COGNIFRAME_CACHE/studio/studio.log (else ~/.cache/cogniframe/...), not as tracebacks on the terminal.
"""

from __future__ import annotations

import errno
import socket
import sys
import threading
import time
from pathlib import Path

from ..errors import UserError

HOST = "127.0.0.1"
LOGGERS = ("cogniframe.studio", "uvicorn", "uvicorn.error", "uvicorn.asgi", "websockets")


def log_to_file() -> Path:
    """The studio's log: its errors and uvicorn's, with their tracebacks, in a file of the cache
    (kept small: two files of 1 MB at most), none on the terminal."""
    import logging
    import logging.handlers

    from ..cache import cache_dir

    folder = cache_dir() / "studio"
    path = folder / "studio.log"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        handler: logging.Handler = logging.handlers.RotatingFileHandler(path, maxBytes=1 << 20, backupCount=1, encoding="utf-8")
    except OSError:
        handler = logging.NullHandler()  # no writable cache: the errors are dropped, still never a traceback
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s %(message)s"))
    for name in LOGGERS:
        logger = logging.getLogger(name)
        logger.handlers = [handler]
        logger.propagate = False
        logger.setLevel(logging.WARNING if name.startswith(("uvicorn", "websockets")) else logging.INFO)
    return path


def bind(port: int) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((HOST, port))
    except OSError as e:
        sock.close()
        if e.errno == errno.EADDRINUSE:
            raise UserError(f"--port {port}: another program already listens on {HOST}:{port}. "
                            f"Fix: give another port (--port {port + 1}), or --port 0 for any free one.") from None
        raise UserError(f"--port {port}: cannot listen on {HOST}:{port} ({e.strerror}). Fix: give another port.") from None
    sock.listen(128)
    sock.setblocking(False)
    return sock


def serve(params: str | Path, port: int = 8765, open_browser: bool = True, server: bool | None = None) -> None:
    import uvicorn

    from .app import create_app
    from .session import Session

    session = Session(params, server=server)  # a bad params file: the CLI's message, exit 2, nothing served
    sock = bind(port)
    url = f"http://{HOST}:{sock.getsockname()[1]}/"
    log_path = log_to_file()
    app = create_app(session)

    class Server(uvicorn.Server):
        def handle_exit(self, sig, frame):  # Ctrl-C stops the studio: not an error, nothing to re-raise
            super().handle_exit(sig, frame)
            self._captured_signals.clear()

    # log_config None: uvicorn keeps its hands off logging (log_to_file set it up); ws_max_size: a
    # message over the studio's own limit still arrives whole enough to be refused in a sentence
    config = uvicorn.Config(app, log_level="warning", lifespan="on", ws="auto", access_log=False, log_config=None,
                            ws_max_size=4 << 20)
    srv = Server(config)
    print(f"cogniframe studio: editing {params} at {url} (only this computer can connect; Ctrl-C to stop)", flush=True)
    print(f"cogniframe studio: errors are logged to {log_path}", file=sys.stderr, flush=True)
    if open_browser:
        def opener():
            while not srv.started and not srv.should_exit:
                time.sleep(0.05)
            if srv.started:
                import webbrowser

                webbrowser.open(url)

        threading.Thread(target=opener, name="studio-browser", daemon=True).start()
    try:
        srv.run(sockets=[sock])
    finally:
        session.close()
        sock.close()
    print("cogniframe studio stopped", file=sys.stderr, flush=True)
