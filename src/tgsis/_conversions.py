"""The hook through which the mesh classes' conversion methods reach :mod:`tgsis.convert` (issue 38, part 4).

``Mesh.to_pyvista``, ``to_meshio``, ``from_pyvista``, ``from_meshio`` (and
``GeometryCollection.to_*``) and ``Surface.to_trimesh`` are front doors to
code that builds and reads the mesh classes (:mod:`tgsis.convert`,
:mod:`tgsis._vtk_cells`, :mod:`tgsis._zpositive`), so that code imports
:mod:`tgsis.mesh`; were :mod:`tgsis.mesh` to import it back, even inside the
methods, the two would form one import cycle. Instead :mod:`tgsis.mesh`
imports only this module, below both, and :mod:`tgsis.convert` installs its
functions here when it is imported. The package's ``__init__`` imports
:mod:`tgsis.convert`, and Python runs it before any submodule, so the methods
work for whoever imported ``tgsis.mesh`` alone.

Pure Python: imports nothing of tgsis. The functions are typed ``Any`` here
(this module cannot name the mesh classes); the methods of :mod:`tgsis.mesh`
give their results their types.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["Conversions", "install", "installed"]


@dataclass(frozen=True)
class Conversions:
    """The functions the mesh classes' methods call, as :mod:`tgsis.convert` installs them.

    Attributes
    ----------
    to_pyvista, to_meshio : callable
        A tgsis mesh or collection to the other library's object
        (:func:`tgsis.convert.to_pyvista`, :func:`tgsis.convert.to_meshio`).
    from_pyvista, from_meshio : callable
        The other library's object to a tgsis mesh or collection.
    elevation : callable
        A mesh with z up (:func:`tgsis._zpositive.elevation`), for
        ``Surface.to_trimesh``.
    """

    to_pyvista: Callable[[Any], Any]
    to_meshio: Callable[[Any], Any]
    from_pyvista: Callable[[Any], Any]
    from_meshio: Callable[[Any], Any]
    elevation: Callable[[Any], Any]


_installed: Conversions | None = None


def install(conversions: Conversions) -> None:
    """Make ``conversions`` the functions the mesh classes' methods call (:mod:`tgsis.convert` does, on import)."""
    global _installed
    _installed = conversions


def installed() -> Conversions:
    """The installed functions.

    Raises
    ------
    RuntimeError
        :mod:`tgsis.convert` has not been imported (only possible when
        ``tgsis.mesh`` was loaded without its package).
    """
    if _installed is None:
        raise RuntimeError(
            "the mesh conversions are not installed: tgsis.convert has not been imported (import tgsis does it)"
        )
    return _installed
