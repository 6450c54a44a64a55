"""The z convention of a mesh (``metadata["zpositive"]``) and the files that have none: z up, always.

A mesh read from a GOCAD file keeps its coordinates as written and says in
``metadata["zpositive"]`` whether z is ``Elevation`` (up positive, the
default) or ``Depth`` (down positive); the database stores elevation and gives
a fetched mesh its file's convention back. VTK (``.vtu``, ``.vtp``, ``.vtk``),
PLY, OBJ, OFF, STL, pyvista, meshio and trimesh have no z convention: every
viewer draws +z up. So what goes to them is in elevation, always
(:func:`elevation`), and the convention, when the format has a place for
tgsis's own facts (VTK field data, a PLY comment, meshio's ``info``), is
recorded beside it (:data:`ZPOSITIVE_FIELD`, :data:`MEMBER_ZPOSITIVE_FIELD`) so that tgsis reading
the file gives the mesh back as it was (:func:`restore`), depth coordinates
and all. Negating a double only flips its sign bit: both ways are bit-exact.

Pure numpy, no database: the file formats, :mod:`tgsis.convert` and the
database layer (:mod:`tgsis.db.meaning`) share it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, TypeVar

from tgsis.errors import InvalidGeometryError
from tgsis.mesh import Geometry, GeometryCollection, Mesh

__all__ = [
    "CONVENTIONS",
    "ZPOSITIVE_FIELD",
    "MEMBER_ZPOSITIVE_FIELD",
    "z_convention",
    "conventions",
    "elevation",
    "restore",
    "recorded_convention",
]

#: The z conventions, as GOCAD spells them (``ZPOSITIVE Elevation`` / ``ZPOSITIVE Depth``).
CONVENTIONS = ("Elevation", "Depth")
#: The field-data name that records the convention of a mesh written in elevation (VTK files, pyvista).
ZPOSITIVE_FIELD = "tgsis_zpositive"
#: The same for the members of a collection: one string per member, "" for none.
MEMBER_ZPOSITIVE_FIELD = "tgsis_member_zpositive"

_G = TypeVar("_G", bound=Geometry)


def z_convention(metadata: Mapping[str, Any]) -> str | None:
    """``"Elevation"``, ``"Depth"`` or None from ``metadata["zpositive"]`` (any letter case).

    Raises
    ------
    InvalidGeometryError
        Any other value.
    """
    value = metadata.get("zpositive")
    if value is None:
        return None
    if isinstance(value, str) and value.strip().lower() in ("elevation", "depth"):
        return value.strip().capitalize()
    raise InvalidGeometryError(
        f"metadata['zpositive'] is {value!r}: the z convention is 'Elevation' or 'Depth'",
        hint="set mesh.metadata['zpositive'] to 'Elevation', 'Depth' or leave it out",
    )


def conventions(geometry: Geometry) -> list[str | None]:
    """The z convention of a mesh (a list of one), or of each member of a collection."""
    members = geometry.members if isinstance(geometry, GeometryCollection) else (geometry,)
    return [z_convention(m.metadata) for m in members]


def _elevation_mesh(mesh: Mesh) -> Mesh:
    if z_convention(mesh.metadata) != "Depth":
        return mesh
    flipped = mesh.copy()
    flipped.vertices[:, 2] = -flipped.vertices[:, 2]
    flipped.metadata.pop("zpositive", None)  # z is up now: the copy says nothing else
    return flipped


def elevation(geometry: _G) -> _G:
    """``geometry`` with z up: itself, or a copy with z negated where a mesh (member) says ``Depth``.

    Raises
    ------
    InvalidGeometryError
        A ``metadata["zpositive"]`` that is not Elevation or Depth.
    """
    if isinstance(geometry, GeometryCollection):
        members = [_elevation_mesh(m) for m in geometry.members]
        if all(a is b for a, b in zip(members, geometry.members)):
            return geometry
        return GeometryCollection(members, name=geometry.name, metadata=geometry.metadata)  # type: ignore[return-value]
    return _elevation_mesh(geometry)  # type: ignore[return-value]


def recorded_convention(value: str | None, where: str) -> str | None:
    """A convention as a file recorded it (:data:`ZPOSITIVE_FIELD`), checked: None, ``Elevation`` or ``Depth``.

    Raises
    ------
    InvalidGeometryError
        Any other text; ``where`` names the place in the message.
    """
    if value is None or value == "":
        return None
    if value not in CONVENTIONS:
        raise InvalidGeometryError(f"{where} is {value!r}: tgsis records the z convention as 'Elevation' or 'Depth'")
    return value


def restore(geometry: Geometry, recorded: Sequence[str | None]) -> None:
    """Give a mesh (the members of a collection) read in elevation its recorded convention back, in place.

    ``recorded`` has one convention per mesh (member); for ``Depth`` z is
    negated again, and ``metadata["zpositive"]`` says the convention.
    """
    members = geometry.members if isinstance(geometry, GeometryCollection) else (geometry,)
    for mesh, convention in zip(members, recorded):
        if convention is None:
            continue
        if convention == "Depth":
            vertices = mesh.vertices if mesh.vertices.flags.writeable else mesh.vertices.copy()
            vertices[:, 2] = -vertices[:, 2]
            mesh.vertices = vertices
        mesh.metadata["zpositive"] = convention
