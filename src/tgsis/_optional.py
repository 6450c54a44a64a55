"""Optional dependencies of the client, imported when a feature needs them.

``pip install tgsis`` brings what storing, versioning and files need;
pictures (matplotlib), graphs (networkx), pyvista and meshio are extras
(``pip install 'tgsis[pictures]'``). A feature that needs one calls
:func:`require` first, so that a missing package is an
:class:`~tgsis.errors.InstallationError` naming the extra, not an
``ImportError`` from deep inside.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from tgsis.errors import InstallationError

__all__ = ["require", "EXTRAS"]

#: The extra of ``pyproject.toml`` that installs each optional package.
EXTRAS = {"matplotlib": "pictures", "networkx": "graph", "pyvista": "pyvista", "meshio": "meshio"}


def require(module: str, purpose: str) -> ModuleType:
    """Import the optional package ``module`` for ``purpose``, or say which extra installs it.

    Parameters
    ----------
    module : str
        A key of :data:`EXTRAS` (``"matplotlib"``, ``"networkx"``, ...).
    purpose : str
        What needs it, for the message (``"tgsis.pictures"``).

    Raises
    ------
    InstallationError
        If the package is not installed.
    """
    extra = EXTRAS[module]
    try:
        return importlib.import_module(module)
    except ImportError:
        raise InstallationError(
            f"{purpose} needs the optional package {module}, which is not installed",
            hint=f"pip install 'tgsis[{extra}]' (or pip install {module})",
        ) from None
