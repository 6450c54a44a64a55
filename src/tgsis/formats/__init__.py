"""Geometry file formats: read meshes from files and write them back, no database involved.

=========  ====================  ====================================  ==========================
name       extensions            geotypes                              module
=========  ====================  ====================================  ==========================
tsurf      ``.ts``               SURFACE, collections of them          :mod:`tgsis.formats.gocad`
pline      ``.pl``               MULTILINESTRING, collections of them  :mod:`tgsis.formats.gocad`
vset       ``.vs``               MULTIPOINT, collections of them       :mod:`tgsis.formats.gocad`
tsolid     ``.so``               MULTITETRA, collections of them       :mod:`tgsis.formats.gocad`
lightsolid ``.lso``              MULTITETRA (read only)                :mod:`tgsis.formats.gocad`
gocadgroup ``.gp``               the members of a GOCAD group (read)   :mod:`tgsis.formats.gocad`
gocadmodel ``.ml``               the TSurfs of a GOCAD model (read)    :mod:`tgsis.formats.gocad`
vtu        ``.vtu``              all four, mixed collections           :mod:`tgsis.formats.vtk`
vtp        ``.vtp``              MULTIPOINT, MULTILINESTRING, SURFACE  :mod:`tgsis.formats.vtk`
vtk        ``.vtk`` (legacy)     all four, mixed collections           :mod:`tgsis.formats.vtk_legacy`
obj, ply,  ``.obj .ply``         SURFACE (read: points too)            :mod:`tgsis.formats.trimesh_io`
off, stl   ``.off .stl``
=========  ====================  ====================================  ==========================

>>> from tgsis import formats                                   # doctest: +SKIP
>>> [fault] = formats.read("fault.ts")                          # doctest: +SKIP
>>> formats.write(fault, "fault.vtu")                           # doctest: +SKIP

A :class:`~tgsis.mesh.GeometryCollection` is written to the formats that
hold several objects: a GOCAD file takes the members when they are all of
its type (one object each), a ``.vtu`` or legacy ``.vtk`` file takes
members of mixed types (one grid of mixed cell types); ``.vtp``, OBJ, PLY,
OFF and STL hold one object and refuse collections. Reading gives the list
of objects (the members of a collection ``.vtu`` or ``.vtk``).

``.vtu``, ``.vtp`` and ``.vtk`` are the files of ParaView, pyvista
(``mesh.save``, ``pyvista.read``) and meshio (``.vtu`` and ``.vtk``: meshio
reads no ``.vtp``); tgsis writes ``.vtu`` and ``.vtp`` zlib-compressed, as
ParaView does, and every file it writes is read by meshio and pyvista
(``tests/test_formats_vtk_libraries.py``).

Each module's documentation says what its format keeps and loses. The
format is chosen from the file extension unless ``format=`` names it (by name
or extension). Every problem with a file raises
:class:`~tgsis.errors.FileFormatError`.

Time series go to ParaView collection files (``.pvd``, one ``.vtu`` per
time) with :func:`~tgsis.formats.pvd.write_pvd` and
:func:`~tgsis.formats.pvd.read_pvd` of :mod:`tgsis.formats.pvd`. They are
not in :data:`FORMATS`: a registry format reads one file into a list of
meshes and writes one geometry to one file, while a ``.pvd`` lists files
that give one geometry, or none, per time; :func:`read` and :func:`write`
on a ``.pvd`` point to those functions.

>>> formats.write_pvd([(0.0, None), (1.5, fault)], "fault.pvd")   # doctest: +SKIP
>>> [(t0, gone), (t1, back)] = formats.read_pvd("fault.pvd")     # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tgsis.errors import FileFormatError
from tgsis.formats._common import PathLike, check_mesh
from tgsis.formats.gocad import (
    format_gocad,
    parse_gocad,
    parse_gocad_model,
    read_gocad,
    read_gocad_model,
    read_tsurf,
    write_gocad,
    write_gocad_many,
)
from tgsis.formats.pvd import read_pvd, write_pvd
from tgsis.formats.trimesh_io import read_trimesh_file, write_trimesh_file
from tgsis.formats.vtk import (
    format_vtp,
    format_vtu,
    parse_vtp,
    parse_vtu,
    parse_vtu_collection,
    read_vtp,
    read_vtu,
    read_vtu_collection,
    write_vtp,
    write_vtu,
)
from tgsis.formats.vtk_legacy import format_vtk, parse_vtk, read_vtk, read_vtk_geometry, write_vtk
from tgsis.mesh import Geometry, GeometryCollection, Geotype, Mesh

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
    "read_gocad_model",
    "parse_gocad_model",
    "write_gocad",
    "write_gocad_many",
    "format_gocad",
    "read_vtu",
    "parse_vtu",
    "read_vtu_collection",
    "parse_vtu_collection",
    "write_vtu",
    "format_vtu",
    "read_vtp",
    "parse_vtp",
    "write_vtp",
    "format_vtp",
    "read_vtk",
    "read_vtk_geometry",
    "parse_vtk",
    "write_vtk",
    "format_vtk",
    "read_trimesh_file",
    "write_trimesh_file",
    "read_pvd",
    "write_pvd",
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
    collection_writer : callable or None
        ``collection_writer(collection, path, **options) -> None`` for formats
        that hold several objects (members of ``geotypes`` only; a format of
        one geotype takes collections of that type only); None: the format
        holds one object.
    """

    name: str
    extensions: tuple[str, ...]
    geotypes: tuple[Geotype, ...]
    reader: Callable[..., list[Mesh]]
    writer: Callable[..., None]
    description: str
    collection_writer: Callable[..., None] | None = None

    def read(self, path: PathLike, **options: Any) -> list[Mesh]:
        """Read every mesh of ``path``."""
        return self.reader(path, **options)

    def write(self, mesh: Geometry, path: PathLike, **options: Any) -> None:
        """Write ``mesh`` (or a collection) to ``path``, after checking the format can store its geotype(s)."""
        if isinstance(mesh, GeometryCollection):
            self._check_collection(mesh, path)
            assert self.collection_writer is not None
            self.collection_writer(mesh, path, **options)
            return
        mesh = check_mesh(mesh, f"the {self.name} writer")
        if mesh.geotype not in self.geotypes:
            fits = [
                f.name + " (" + " ".join(f.extensions) + ")"
                for f in FORMATS.values()
                if mesh.geotype in f.geotypes and f.writer not in _READ_ONLY
            ]
            raise FileFormatError(
                f"{self.name} files store {', '.join(g.value for g in self.geotypes)}, not "
                f"{mesh.geotype.value} ({type(mesh).__name__})",
                path=path,
                hint=f"formats for {mesh.geotype.value}: {', '.join(fits)}",
            )
        self.writer(mesh, path, **options)

    def _check_collection(self, collection: GeometryCollection, path: PathLike) -> None:
        """Raise FileFormatError unless this format holds all the members of ``collection``."""
        what = f"a GEOMETRYCOLLECTION of {len(collection)} members"
        if self.collection_writer is None:
            fits = [
                f.name + " (" + " ".join(f.extensions) + ")"
                for f in FORMATS.values()
                if f.collection_writer and f.writer not in _READ_ONLY
            ]
            raise FileFormatError(
                f"{self.name} files hold one object, not {what}",
                path=path,
                hint=f"formats for collections: {', '.join(fits)}",
            )
        types = list(dict.fromkeys(collection.geotypes))
        listed = ", ".join(t.value for t in types)
        if len(self.geotypes) == 1 and len(types) > 1:
            raise FileFormatError(
                f"{self.name} files hold objects of one type ({self.geotypes[0].value}); {what} mixes {listed}",
                path=path,
                hint="vtu (.vtu) holds members of mixed types; or export the members one by one",
            )
        wrong = [t for t in types if t not in self.geotypes]
        if wrong:
            fits = [
                f.name + " (" + " ".join(f.extensions) + ")"
                for f in FORMATS.values()
                if f.collection_writer and f.writer not in _READ_ONLY and all(t in f.geotypes for t in types)
            ]
            raise FileFormatError(
                f"{self.name} files store {', '.join(g.value for g in self.geotypes)}, not "
                f"{', '.join(t.value for t in wrong)} ({what})",
                path=path,
                hint=f"formats for this collection: {', '.join(fits)}",
            )


def _vtu_reader(path: PathLike, **options: Any) -> list[Mesh]:
    return list(read_vtu_collection(path, **options))


def _vtk_reader(path: PathLike, **options: Any) -> list[Mesh]:
    geometry = read_vtk_geometry(path, **options)
    return list(geometry.members) if isinstance(geometry, GeometryCollection) else [geometry]


def _vtp_reader(path: PathLike, **options: Any) -> list[Mesh]:
    return [read_vtp(path, **options)]


def _lightsolid_writer(mesh: Mesh, path: PathLike, **options: Any) -> None:
    raise FileFormatError(
        "tgsis reads SKUA LightTSolid files but writes tetrahedra as GOCAD TSolid",
        path=path,
        hint="write a .so file (tsolid)",
    )


def _group_writer(mesh: Mesh, path: PathLike, **options: Any) -> None:
    raise FileFormatError(
        "tgsis reads the members of GOCAD group files but does not write groups",
        path=path,
        hint="write the members to a GOCAD file of their type (.ts, .pl, .vs, .so), which holds several objects",
    )


def _model_writer(mesh: Mesh, path: PathLike, **options: Any) -> None:
    raise FileFormatError(
        "tgsis reads the surfaces of GOCAD model files (.ml) but does not write GOCAD models",
        path=path,
        hint="write the surfaces to a GOCAD TSurf file (.ts), which holds several objects",
    )


#: The writers of formats tgsis reads only: they refuse, so hints do not offer them.
_READ_ONLY = (_lightsolid_writer, _group_writer, _model_writer)


def _gocad_collection_writer(collection: GeometryCollection, path: PathLike, **options: Any) -> None:
    write_gocad_many(collection.members, path, **options)


def _trimesh_format(name: str, description: str) -> FileFormat:
    def reader(path: PathLike, **options: Any) -> list[Mesh]:
        return [read_trimesh_file(path, file_type=name, **options)]

    def writer(mesh: Mesh, path: PathLike, **options: Any) -> None:
        write_trimesh_file(mesh, path, file_type=name, **options)  # type: ignore[arg-type]  # checked by write

    return FileFormat(name, (f".{name}",), (Geotype.SURFACE,), reader, writer, description)


_ALL = (Geotype.MULTIPOINT, Geotype.MULTILINESTRING, Geotype.SURFACE, Geotype.MULTITETRA)

#: The known formats by name, in the order they are listed to users.
FORMATS: dict[str, FileFormat] = {
    f.name: f
    for f in (
        FileFormat(
            "tsurf",
            (".ts",),
            (Geotype.SURFACE,),
            read_gocad,
            write_gocad,
            "GOCAD TSurf (triangulated surface)",
            _gocad_collection_writer,
        ),
        FileFormat(
            "pline",
            (".pl",),
            (Geotype.MULTILINESTRING,),
            read_gocad,
            write_gocad,
            "GOCAD PLine (polylines)",
            _gocad_collection_writer,
        ),
        FileFormat(
            "vset",
            (".vs",),
            (Geotype.MULTIPOINT,),
            read_gocad,
            write_gocad,
            "GOCAD VSet (points)",
            _gocad_collection_writer,
        ),
        FileFormat(
            "tsolid",
            (".so",),
            (Geotype.MULTITETRA,),
            read_gocad,
            write_gocad,
            "GOCAD TSolid (tetrahedra)",
            _gocad_collection_writer,
        ),
        FileFormat(
            "lightsolid",
            (".lso",),
            (Geotype.MULTITETRA,),
            read_gocad,
            _lightsolid_writer,
            "SKUA LightTSolid (tetrahedra; read only)",
        ),
        FileFormat(
            "gocadgroup",
            (".gp",),
            _ALL,
            read_gocad,
            _group_writer,
            "GOCAD HeterogeneousGroup/HomogeneousGroup (read only: its members)",
        ),
        FileFormat(
            "gocadmodel",
            (".ml",),
            (Geotype.SURFACE,),
            read_gocad_model,
            _model_writer,
            "GOCAD Model3d (read only: the TSurfs of the model, with their TFACEs)",
            _model_writer,
        ),
        FileFormat(
            "vtu", (".vtu",), _ALL, _vtu_reader, write_vtu, "VTK XML UnstructuredGrid (ParaView; zlib)", write_vtu
        ),
        FileFormat(
            "vtp",
            (".vtp",),
            (Geotype.MULTIPOINT, Geotype.MULTILINESTRING, Geotype.SURFACE),
            _vtp_reader,
            write_vtp,
            "VTK XML PolyData (ParaView, pyvista; zlib)",
        ),
        FileFormat(
            "vtk",
            (".vtk",),
            _ALL,
            _vtk_reader,
            write_vtk,
            "legacy VTK 5.1 UnstructuredGrid (binary; reads POLYDATA too)",
            write_vtk,
        ),
        _trimesh_format("obj", "Wavefront OBJ (text, 8 decimals, no properties)"),
        _trimesh_format("ply", "Stanford PLY (binary, exact, with properties)"),
        _trimesh_format("off", "Object File Format (text, 10 decimals, no properties)"),
        _trimesh_format("stl", "STL (binary float32 triangle soup, no properties)"),
    )
}


def format_for(path: PathLike, format: str | None = None) -> FileFormat:
    """The format of ``path``: the one named by ``format`` (a name or an extension), else from the extension.

    Raises
    ------
    FileFormatError
        The format or extension is not known; the message lists the known ones.
        The path holds a NUL byte (no file system allows it).
    """
    if "\x00" in os.fspath(path):
        raise FileFormatError(
            "the file name contains a NUL byte, which no file name can hold", path=repr(os.fspath(path))
        )
    key = (format if format is not None else Path(path).suffix).lower()
    if key in ("pvd", ".pvd"):
        raise FileFormatError(
            "a .pvd file is a time series of .vtu files, not a file of meshes",
            path=path,
            hint="use tgsis.formats.read_pvd or write_pvd",
        )
    for candidate in FORMATS.values():
        if key == candidate.name or key in candidate.extensions or "." + key in candidate.extensions:
            return candidate
    known = ", ".join(ext for f in FORMATS.values() for ext in f.extensions)
    what = f"format {format!r}" if format is not None else f"file extension {Path(path).suffix or '(none)'!r}"
    raise FileFormatError(
        f"unknown {what}: known extensions are {known}",
        path=path,
        hint="pass format= with one of " + ", ".join(FORMATS),
    )


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
        GOCAD files may hold several objects, and ``.vtu`` files written from
        a collection its members; the other formats give one mesh.
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
        raise FileFormatError(
            f"expected one mesh, the file holds {len(meshes)}",
            path=path,
            hint="use tgsis.formats.read to get all of them",
        )
    return meshes[0]


def write(mesh: Geometry, path: PathLike, format: str | None = None, **options: Any) -> None:
    """Write a mesh (or a collection) to a file in the format named or implied by the extension.

    Parameters
    ----------
    mesh : Mesh or GeometryCollection
        The mesh; its geotype must be one the format stores. A collection
        needs a format that holds several objects of its members' types
        (GOCAD: all members of the file's type; ``.vtu``: any).
    path : str or path-like
        The file (replaced if it exists).
    format : str, optional
        A format name or extension; by default from ``path``.
    **options
        Passed to the format's writer (``drop_cell_properties=True`` for GOCAD,
        ``encoding="appended"`` and ``compression=None`` for VTU and VTP,
        ``ascii=True`` for legacy VTK, ``digits=`` / ``drop_properties=True``
        for OBJ/OFF/STL).

    Raises
    ------
    FileFormatError
        Unknown format, a geotype the format cannot store (for a collection:
        a format of one object, or a GOCAD type that is not every member's),
        data the format cannot hold, or an unwritable file.
    """
    format_for(path, format).write(mesh, path, **options)
