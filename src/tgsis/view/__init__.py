"""The browser view of a tgsis database (``tgsis view``; the optional extra ``tgsis[view]``).

A local web server (Starlette on uvicorn, bound to 127.0.0.1) that shows the
feature classes and features, the version tree, surfaces in 3D at any time
(three.js, shipped in ``static/vendor/three`` with its licence: no network at run
time), two versions of a surface compared and a version's conflicts; see
docs/view.md. It connects with the user's own role and is read-only unless
started writable.
"""

from __future__ import annotations

import socket
import webbrowser
from collections.abc import Callable
from typing import TYPE_CHECKING

from tgsis.errors import InvalidInputError

if TYPE_CHECKING:
    from starlette.applications import Starlette

__all__ = ["THREE_VERSION", "create_app", "serve", "ViewConfig"]

#: the three.js release shipped in static/vendor/three (from the npm package ``three``)
THREE_VERSION = "0.187.0"


def _missing(exc: ImportError) -> InvalidInputError:
    return InvalidInputError(
        f"the browser view needs the optional extra 'view' ({exc.name} is not installed)",
        hint="pip install 'tgsis[view]'",
    )


def create_app(conninfo: str, *, writable: bool = False, database: str = "") -> Starlette:
    """The view's ASGI application for the database of ``conninfo``.

    Parameters
    ----------
    conninfo : str
        libpq conninfo; every request connects with it (the user's role).
    writable : bool
        Leave transactions writable (default: read-only).
    database : str
        Name shown in the pages.
    """
    try:
        from tgsis.view.app import ViewConfig
        from tgsis.view.app import create_app as make
    except ImportError as exc:  # pragma: no cover - the extra is installed in the tests
        raise _missing(exc) from exc
    return make(ViewConfig(conninfo, writable, database))


def serve(
    conninfo: str,
    *,
    host: str = "127.0.0.1",
    port: int = 8765,
    writable: bool = False,
    database: str = "",
    open_browser: bool = False,
    default_version: str | None = None,
    on_listening: Callable[[str], None] | None = None,
) -> None:
    """Serve the view until interrupted (uvicorn).

    Parameters
    ----------
    conninfo : str
    host : str
        Address to listen on (default 127.0.0.1: this machine only).
    port : int
        0 picks a free port.
    writable, database
        As :func:`create_app`.
    open_browser : bool
        Open the system's browser on the first page.
    default_version : str, optional
        ``VERSION`` or ``VERSION@REVISION`` shown until the browser chooses one (default: DEFAULT).
    on_listening : callable, optional
        Called with the first page's URL once the socket listens.
    """
    try:
        import uvicorn
    except ImportError as exc:  # pragma: no cover
        raise _missing(exc) from exc
    from tgsis.view.app import ViewConfig
    from tgsis.view.app import create_app as make

    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        raise InvalidInputError(
            f"cannot listen on {host}:{port}: {exc.strerror}", hint="choose another port with --port (0: any free one)"
        ) from exc
    sock.listen(128)  # connections wait in the queue until uvicorn accepts them
    bound = sock.getsockname()[1]
    shown = f"[{host}]" if family == socket.AF_INET6 else host
    url = f"http://{shown}:{bound}/classes"
    app = make(ViewConfig(conninfo, writable, database, default_version), hosts=["127.0.0.1", "localhost", host])
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning"))
    if on_listening is not None:
        on_listening(url)
    if open_browser:
        webbrowser.open(url)
    try:
        server.run(sockets=[sock])
    finally:
        sock.close()


def __getattr__(name: str) -> object:
    if name == "ViewConfig":
        from tgsis.view.app import ViewConfig

        return ViewConfig
    raise AttributeError(f"module 'tgsis.view' has no attribute {name!r}")
