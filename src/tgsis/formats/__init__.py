"""Geometry file formats: read meshes from files and write them back, no database involved.

=========  ====================  ====================================  ==========================
name       extensions            geotypes                              module
=========  ====================  ====================================  ==========================
tsurf      ``.ts``               SURFACE                               :mod:`tgsis.formats.gocad`
pline      ``.pl``               MULTILINESTRING                       :mod:`tgsis.formats.gocad`
vset       ``.vs``               MULTIPOINT                            :mod:`tgsis.formats.gocad`
tsolid     ``.so``               MULTITETRA                            :mod:`tgsis.formats.gocad`
vtu        ``.vtu``              all four                              :mod:`tgsis.formats.vtk`
obj, ply,  ``.obj .ply``         SURFACE                               :mod:`tgsis.formats.trimesh_io`
off, stl   ``.off .stl``
=========  ====================  ====================================  ==========================

>>> from tgsis import formats                                   # doctest: +SKIP
>>> [fault] = formats.read("fault.ts")                          # doctest: +SKIP
>>> formats.write(fault, "fault.vtu")                           # doctest: +SKIP

Each module's documentation says what its format keeps and loses. The
format is chosen from the file extension unless ``format=`` names it (by name
or extension). Every problem with a file raises
:class:`~tgsis.errors.FileFormatError`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tgsis.errors import FileFormatError
from tgsis.formats._common import PathLike, check_mesh
from tgsis.formats.gocad import (format_gocad, parse_gocad, read_gocad, read_tsurf, write_gocad,
                                 write_gocad_many)
from tgsis.formats.trimesh_io import read_trimesh_file, write_trimesh_file
from tgsis.formats.vtk import format_vtu, parse_vtu, read_vtu, write_vtu
from tgsis.mesh import Geotype, Mesh

__all__ = [
    "FileFormat",
    "FORMATS",
    "format_for",
    "read",
    "read_one",
    "write",
    "read_gocad",
    "read_tsurf",
    "parse_gocad",
    "write_gocad",
    "write_gocad_many",
    "format_gocad",
    "read_vtu",
    "parse_vtu",
    "write_vtu",
    "format_vtu",
    "read_trimesh_file",
    "write_trimesh_file",
]


@dataclass(frozen=True)
class FileFormat:
    """A file format the registry knows.

    Attributes
    ----------
    name : str
        Short name, usable as ``format=``.
    extensions : tuple of str
        File extensions, lower case with the dot.
    geotypes : tuple of Geotype
        What the format can store.
    reader : callable
        ``reader(path, **options) -> list[Mesh]``.
    writer : callable
        ``writer(mesh, path, **options) -> None``.
    description : str
        One line for users.
    """

    name: str
    extensions: tuple[str, ...]
    geotypes: tuple[Geotype, ...]
    reader: Callable[..., list[Mesh]]
    writer: Callable[..., None]
    description: str

    def read(self, path: PathLike, **options: Any) -> list[Mesh]:
        """Read every mesh of ``path``."""
        return self.reader(path, **options)

    def write(self, mesh: Mesh, path: PathLike, **options: Any) -> None:
        """Write ``mesh`` to ``path``, after checking the format can store its geotype."""
        mesh = check_mesh(mesh, f"the {self.name} writer")
        if mesh.geotype not in self.geotypes:
            fits = [f.name + " (" + " ".join(f.extensions) + ")" for f in FORMATS.values() if mesh.geotype in f.geotypes]
            raise FileFormatError(f"{self.name} files store {', '.join(g.value for g in self.geotypes)}, not "
                                  f"{mesh.geotype.value} ({type(mesh).__name__})", path=path,
                                  hint=f"formats for {mesh.geotype.value}: {', '.join(fits)}")
        self.writer(mesh, path, **options)


def _vtu_reader(path: PathLike, **options: Any) -> list[Mesh]:
    return [read_vtu(path, **options)]


def _trimesh_format(name: str, description: str) -> FileFormat:
    def reader(path: PathLike, **options: Any) -> list[Mesh]:
        return [read_trimesh_file(path, file_type=name, **options)]

    def writer(mesh: Mesh, path: PathLike, **options: Any) -> None:
        write_trimesh_file(mesh, path, file_type=name, **options)  # type: ignore[arg-type]  # checked by write

    return FileFormat(name, (f".{name}",), (Geotype.SURFACE,), reader, writer, description)


_ALL = (Geotype.MULTIPOINT, Geotype.MULTILINESTRING, Geotype.SURFACE, Geotype.MULTITETRA)

#: The known formats by name, in the order they are listed to users.
FORMATS: dict[str, FileFormat] = {f.name: f for f in (
    FileFormat("tsurf", (".ts",), (Geotype.SURFACE,), read_gocad, write_gocad, "GOCAD TSurf (triangulated surface)"),
    FileFormat("pline", (".pl",), (Geotype.MULTILINESTRING,), read_gocad, write_gocad, "GOCAD PLine (polylines)"),
    FileFormat("vset", (".vs",), (Geotype.MULTIPOINT,), read_gocad, write_gocad, "GOCAD VSet (points)"),
    FileFormat("tsolid", (".so",), (Geotype.MULTITETRA,), read_gocad, write_gocad, "GOCAD TSolid (tetrahedra)"),
    FileFormat("vtu", (".vtu",), _ALL, _vtu_reader, write_vtu, "VTK XML UnstructuredGrid (ParaView)"),
    _trimesh_format("obj", "Wavefront OBJ (text, 8 decimals, no properties)"),
    _trimesh_format("ply", "Stanford PLY (binary, exact, with properties)"),
    _trimesh_format("off", "Object File Format (text, 10 decimals, no properties)"),
    _trimesh_format("stl", "STL (binary float32 triangle soup, no properties)"),
)}


def format_for(path: PathLike, format: str | None = None) -> FileFormat:
    """The format of ``path``: the one named by ``format`` (a name or an extension), else from the extension.

    Raises
    ------
    FileFormatError
        The format or extension is not known; the message lists the known ones.
    """
    key = (format if format is not None else Path(path).suffix).lower()
    for candidate in FORMATS.values():
        if key == candidate.name or key in candidate.extensions or "." + key in candidate.extensions:
            return candidate
    known = ", ".join(ext for f in FORMATS.values() for ext in f.extensions)
    what = f"format {format!r}" if format is not None else f"file extension {Path(path).suffix or '(none)'!r}"
    raise FileFormatError(f"unknown {what}: known extensions are {known}", path=path,
                          hint="pass format= with one of " + ", ".join(FORMATS))


def read(path: PathLike, format: str | None = None, **options: Any) -> list[Mesh]:
    """Read every mesh in a file.

    Parameters
    ----------
    path : str or path-like
        The file.
    format : str, optional
        A format name (see :data:`FORMATS`) or extension; by default from ``path``.
    **options
        Passed to the format's reader (e.g. ``merge_atoms=True`` for GOCAD,
        ``merge_vertices=True`` for STL).

    Returns
    -------
    list of Mesh
        GOCAD files may hold several objects; the other formats give one mesh.
    """
    return format_for(path, format).read(path, **options)


def read_one(path: PathLike, format: str | None = None, **options: Any) -> Mesh:
    """Read a file that holds exactly one mesh; see :func:`read`.

    Raises
    ------
    FileFormatError
        The file holds more than one mesh (or cannot be read).
    """
    meshes = read(path, format, **options)
    if len(meshes) != 1:
        raise FileFormatError(f"expected one mesh, the file holds {len(meshes)}", path=path,
                              hint="use tgsis.formats.read to get all of them")
    return meshes[0]


def write(mesh: Mesh, path: PathLike, format: str | None = None, **options: Any) -> None:
    """Write a mesh to a file in the format named or implied by the extension.

    Parameters
    ----------
    mesh : Mesh
        The mesh; its geotype must be one the format stores.
    path : str or path-like
        The file (replaced if it exists).
    format : str, optional
        A format name or extension; by default from ``path``.
    **options
        Passed to the format's writer (``drop_cell_properties=True`` for GOCAD,
        ``encoding="appended"`` for VTU, ``digits=`` / ``drop_properties=True``
        for OBJ/OFF/STL).

    Raises
    ------
    FileFormatError
        Unknown format, a geotype the format cannot store, data the format
        cannot hold, or an unwritable file.
    """
    format_for(path, format).write(mesh, path, **options)
