"""VTK's cell layout and tgsis meshes: what tgsis.convert and the VTK file readers and writers share.

Private to tgsis (no database, no optional package): cells given as VTK
cell types, offsets from 0 and a flat connectivity (pyvista's
``UnstructuredGrid``, a ``.vtp`` or legacy ``.vtk`` file) become one tgsis mesh
when they are all of one kind (vertices, lines, triangles, tetrahedra), or the
members of a collection tgsis wrote with its member table; and a tgsis mesh
or collection gives those arrays back (:func:`vtk_parts`). Strings of field
data travel as UTF-8 bytes ending in 0 (:func:`string_bytes`, :func:`strings`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidGeometryError, InvalidPropertyError
from tgsis.mesh import Geometry, GeometryCollection, LineSet, Mesh, PointSet, Surface, TetraMesh, mesh_class

__all__ = [
    "KIND_OF_CELL_TYPE",
    "CELL_TYPE_OF",
    "VTK_CELL_NAMES",
    "labelled",
    "strings",
    "string_bytes",
    "first",
    "split_cells",
    "mesh_from_cells",
    "collection_from_cells",
    "mesh_from_vtk_cells",
    "one_mesh",
    "vtk_parts",
    "shared_properties",
    "NO_PART",
    "file_array_names",
    "named_as_read",
    "without_no_part",
]

#: The ``part`` of the cells of a collection member that has no parts, where other members have them: one VTK
#: cell array covers the cells of every member. Read back, a member whose cells all have it has no ``part``.
NO_PART = -1

_T = TypeVar("_T")

# VTK cell types: the kind of tgsis mesh each belongs to
_VERTEX, _POLY_VERTEX, _LINE, _POLY_LINE, _TRIANGLE, _TETRA = 1, 2, 3, 4, 5, 10
KIND_OF_CELL_TYPE: dict[int, type[Mesh]] = {
    _VERTEX: PointSet,
    _POLY_VERTEX: PointSet,
    _LINE: LineSet,
    _POLY_LINE: LineSet,
    _TRIANGLE: Surface,
    _TETRA: TetraMesh,
}
CELL_TYPE_OF: dict[type[Mesh], int] = {PointSet: _VERTEX, LineSet: _LINE, Surface: _TRIANGLE, TetraMesh: _TETRA}
VTK_CELL_NAMES = {
    1: "VERTEX",
    2: "POLY_VERTEX",
    3: "LINE",
    4: "POLY_LINE",
    5: "TRIANGLE",
    6: "TRIANGLE_STRIP",
    7: "POLYGON",
    8: "PIXEL",
    9: "QUAD",
    10: "TETRA",
    11: "VOXEL",
    12: "HEXAHEDRON",
    13: "WEDGE",
    14: "PYRAMID",
    21: "QUADRATIC_EDGE",
    22: "QUADRATIC_TRIANGLE",
    23: "QUADRATIC_QUAD",
    24: "QUADRATIC_TETRA",
    25: "QUADRATIC_HEXAHEDRON",
    42: "POLYHEDRON",
}


def labelled(source: str, build: Callable[[], _T]) -> _T:
    """``build()``, with the name of the source object in front of any mesh or property error."""
    try:
        return build()
    except (InvalidPropertyError, InvalidGeometryError) as exc:
        if exc.message.startswith(source):
            raise
        raise type(exc)(f"{source}: {exc.message}", detail=exc.detail, hint=exc.hint) from None


def strings(values: Any) -> list[str]:
    """A field array as strings: a string array, or null-terminated UTF-8 bytes in an integer array."""
    array = np.asarray(values)
    if array.dtype.kind in "US":
        return [v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v) for v in array.reshape(-1)]
    if array.dtype.kind in "iu" and array.size and array.min() >= 0 and array.max() < 256:
        raw = array.astype(np.uint8).tobytes()
        parts = raw.split(b"\0")
        if raw.endswith(b"\0"):
            parts.pop()
        return [p.decode("utf-8", "replace") for p in parts]
    return []


def string_bytes(*values: str) -> npt.NDArray[np.uint8]:
    """Strings as UTF-8 bytes, each ending in 0 (what :func:`strings` reads back)."""
    return np.frombuffer(b"".join(v.encode("utf-8") + b"\0" for v in values), dtype=np.uint8).copy()


def first(values: Any) -> str | None:
    """The first string of a field array (None: no array, or no string in it)."""
    found = strings(values) if values is not None else []
    return found[0] if found else None


def split_cells(
    types: npt.NDArray[Any], offsets: npt.NDArray[np.int64], connectivity: npt.NDArray[np.int64], source: str
) -> tuple[type[Mesh], npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """The mesh class of cells all of one kind, its (m, k) cells, and the source cell of each.

    POLY_VERTEX and POLY_LINE cells are split into vertices and segments.
    """
    present = sorted({int(t) for t in np.unique(types)})
    unknown = [t for t in present if t not in KIND_OF_CELL_TYPE]
    if unknown:
        listed = ", ".join(f"{VTK_CELL_NAMES.get(t, 'type')} ({t})" for t in unknown)
        polygons = any(t in (6, 7, 8, 9) for t in unknown)
        refused = np.isin(types, unknown)
        point_counts = ", ".join(str(int(v)) for v in np.unique(np.diff(offsets)[refused])[:5])
        raise InvalidGeometryError(
            f"{source} has {listed} cells: tgsis stores vertices, lines, triangles and tetrahedra",
            detail=f"{int(refused.sum())} of {len(types)} cells, of {point_counts} points",
            hint="triangulate it first (pyvista: mesh.triangulate(); ParaView: the Triangulate filter)"
            if polygons
            else "convert them to tetrahedra or triangles first (pyvista: mesh.triangulate(); ParaView: the "
            "Tetrahedralize filter)",
        )
    kinds = list(dict.fromkeys(KIND_OF_CELL_TYPE[t] for t in present))
    if len(kinds) > 1:
        listed = ", ".join(f"{VTK_CELL_NAMES[t]} ({int((types == t).sum())})" for t in present)
        raise InvalidGeometryError(
            f"{source} mixes cells of several kinds ({listed}): a tgsis mesh has one kind of cell",
            hint="extract one kind first (e.g. mesh.extract_cells_by_type(pyvista.CellType.TRIANGLE)), or store "
            "the kinds as members of a tgsis.GeometryCollection",
        )
    kind = kinds[0]
    k = kind.cell_size
    sizes = np.diff(offsets)
    if bool(np.all(sizes == k)):
        return kind, connectivity.reshape(-1, k), np.arange(len(types), dtype=np.int64)
    if kind not in (PointSet, LineSet) or (sizes < k).any():
        bad = int(np.flatnonzero(sizes != k)[0])
        raise InvalidGeometryError(f"{source} cell {bad} has {int(sizes[bad])} points, not {k}")
    # POLY_VERTEX / POLY_LINE: n points give n vertices / n - 1 segments, each from its source cell
    pieces = sizes - (k - 1)
    source_cell = np.repeat(np.arange(len(types), dtype=np.int64), pieces)
    rank = np.arange(int(pieces.sum())) - np.repeat(np.cumsum(pieces) - pieces, pieces)  # piece within its cell
    first_ids = np.repeat(offsets[:-1], pieces) + rank
    cells = np.stack([connectivity[first_ids + j] for j in range(k)], axis=1)
    return kind, cells.astype(np.int64), source_cell


def mesh_from_cells(
    kind: type[Mesh],
    vertices: npt.NDArray[np.float64],
    cells: npt.NDArray[np.int64],
    vertex_properties: dict[str, npt.NDArray[Any]],
    cell_properties: dict[str, npt.NDArray[Any]],
    name: str | None,
    metadata: dict[str, Any],
) -> Mesh:
    if kind is PointSet and len(cells) == 0 and len(vertices):  # points without cells: a point cloud, one each
        return PointSet(vertices, vertex_properties=vertex_properties, name=name, metadata=metadata)
    return kind(
        vertices,
        cells,
        vertex_properties=vertex_properties,
        cell_properties=cell_properties,
        name=name,
        metadata=metadata,
    )


def collection_from_cells(
    vertices: npt.NDArray[np.float64],
    types: npt.NDArray[Any],
    offsets: npt.NDArray[np.int64],
    connectivity: npt.NDArray[np.int64],
    point_data: dict[str, npt.NDArray[Any]],
    cell_data: dict[str, npt.NDArray[Any]],
    table: tuple[list[str], list[str], Any],
    name: str | None,
    metadata: dict[str, Any],
    source: str,
) -> GeometryCollection:
    """The members of a grid written from a GeometryCollection (its member table in the field data)."""
    geotypes, names, sizes_raw = table
    sizes = np.asarray(sizes_raw, dtype=np.int64).reshape(-1, 2)
    if (
        len(sizes) != len(geotypes)
        or sizes.min(initial=0) < 0
        or int(sizes[:, 0].sum()) != len(vertices)
        or int(sizes[:, 1].sum()) != len(types)
    ):
        raise InvalidGeometryError(
            f"{source}: its tgsis member table does not match its {len(vertices)} points and {len(types)} cells"
        )
    members: list[Mesh] = []
    first_point = first_cell = 0
    for i, (geotype, (n_p, n_c)) in enumerate(zip(geotypes, sizes.tolist())):
        kind = mesh_class(geotype)
        cells = slice(first_cell, first_cell + n_c)
        points = slice(first_point, first_point + n_p)
        if np.any(types[cells] != CELL_TYPE_OF[kind]):
            raise InvalidGeometryError(f"{source}: member {i} is a {geotype} but has other cells")
        start = int(offsets[first_cell])
        k = kind.cell_size
        member_cells = (connectivity[start : start + n_c * k] - first_point).reshape(n_c, k)
        member_cell_data = without_no_part({key: v[cells] for key, v in cell_data.items()})
        members.append(
            labelled(
                f"{source} member {i}",
                lambda: kind(
                    vertices[points],
                    member_cells,
                    vertex_properties={key: v[points] for key, v in point_data.items()},
                    cell_properties=member_cell_data,
                    name=(names[i] if i < len(names) else "") or None,
                ),
            )
        )
        first_point, first_cell = first_point + n_p, first_cell + n_c
    return GeometryCollection(members, name=name, metadata=metadata)


def without_no_part(cell_data: dict[str, npt.NDArray[Any]]) -> dict[str, npt.NDArray[Any]]:
    """A member's cell data without ``part`` when all its cells have :data:`NO_PART` (it had no parts)."""
    part = cell_data.get("part")
    if part is not None and part.ndim == 1 and len(part) and np.all(part == NO_PART):
        return {key: values for key, values in cell_data.items() if key != "part"}
    return cell_data


def mesh_from_vtk_cells(
    vertices: npt.NDArray[np.float64],
    types: npt.NDArray[Any],
    offsets: npt.NDArray[np.int64],
    connectivity: npt.NDArray[np.int64],
    point_data: dict[str, npt.NDArray[Any]],
    cell_data: dict[str, npt.NDArray[Any]],
    *,
    name: str | None,
    geotype: str | None,
    metadata: dict[str, Any],
    source: str,
) -> Mesh:
    """One tgsis mesh from cells in VTK's layout (types, offsets from 0, connectivity), as for pyvista objects.

    For the VTK file readers (:mod:`tgsis.formats.vtk` for .vtp, :mod:`tgsis.formats.vtk_legacy`): the same rules
    as :func:`from_pyvista`. ``geotype``: the type a file written by tgsis names (for a mesh without cells).

    Raises
    ------
    InvalidGeometryError, InvalidPropertyError
        As :func:`as_mesh` (the readers turn them into FileFormatError).
    """
    return one_mesh(vertices, types, offsets, connectivity, point_data, cell_data, name, geotype, metadata, source)


def one_mesh(
    vertices: npt.NDArray[np.float64],
    types: npt.NDArray[Any],
    offsets: npt.NDArray[np.int64],
    connectivity: npt.NDArray[np.int64],
    point_data: dict[str, npt.NDArray[Any]],
    cell_data: dict[str, npt.NDArray[Any]],
    name: str | None,
    geotype: str | None,
    metadata: dict[str, Any],
    source: str,
) -> Mesh:
    if len(types) == 0:
        if geotype is not None:
            kind = mesh_class(geotype)  # written by tgsis: an empty mesh keeps its type
        elif len(vertices):
            kind = PointSet
        else:
            raise InvalidGeometryError(
                f"{source} is empty (no point, no cell): nothing says what kind of mesh it is",
                hint="give it points (and cells), or build the empty tgsis mesh you mean "
                "(e.g. tgsis.Surface(numpy.empty((0, 3)), numpy.empty((0, 3))))",
            )
        return mesh_from_cells(
            kind, vertices, np.empty((0, kind.cell_size), dtype=np.int64), point_data, cell_data, name, metadata
        )
    kind, cells, source_cell = split_cells(types, offsets, connectivity, source)
    if len(source_cell) != len(types):
        cell_data = {k: v[source_cell] for k, v in cell_data.items()}
    return mesh_from_cells(kind, vertices, cells, point_data, cell_data, name, metadata)


def vtk_parts(
    geometry: Geometry,
) -> tuple[
    npt.NDArray[np.float64],
    npt.NDArray[np.int64],
    npt.NDArray[np.int64],
    npt.NDArray[np.uint8],
    dict[str, npt.NDArray[Any]],
    dict[str, npt.NDArray[Any]],
]:
    """Points, flat connectivity, offsets (m + 1, from 0), VTK cell types, point data, cell data."""
    members = geometry.members if isinstance(geometry, GeometryCollection) else (geometry,)
    first_point = np.cumsum([0] + [m.n_vertices for m in members[:-1]])
    connectivity = np.concatenate([m.cells.reshape(-1) + start for m, start in zip(members, first_point)])
    sizes = np.concatenate([np.full(m.n_cells, m.cell_size, dtype=np.int64) for m in members])
    types = np.concatenate([np.full(m.n_cells, CELL_TYPE_OF[type(m)], dtype=np.uint8) for m in members])
    if isinstance(geometry, GeometryCollection):
        point_data, cell_data = shared_properties(members, "vertex"), shared_properties(members, "cell")
    else:
        point_data, cell_data = geometry.vertex_properties, geometry.cell_properties
    vertices = np.concatenate([m.vertices for m in members]) if members else np.empty((0, 3))
    return (
        vertices,
        connectivity.astype(np.int64),
        np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
        types,
        dict(point_data),
        dict(cell_data),
    )


def shared_properties(members: tuple[Mesh, ...], kind: str) -> dict[str, npt.NDArray[Any]]:
    """The members' vertex or cell properties, concatenated: one array covers all points (cells) of a grid.

    The ``part`` cell property of members that have parts (a GOCAD file of
    faults, some of several TFACEs) is :data:`NO_PART` on the cells of the
    members without it; any other property must be on every member.
    """

    def of(mesh: Mesh) -> dict[str, npt.NDArray[Any]]:
        return mesh.vertex_properties if kind == "vertex" else mesh.cell_properties

    names = dict.fromkeys(name for m in members for name in of(m))
    for name in names:
        lacking = [i for i, m in enumerate(members) if name not in of(m)]
        if lacking and not (kind == "cell" and name == "part"):
            raise InvalidPropertyError(
                f"{kind} property {name!r} is on some members of the collection but not on "
                f"members {lacking}: one array covers the points or cells of all members",
                hint="give every member the property, or remove it before converting",
            )
    return {
        name: np.concatenate(
            [of(m)[name] if name in of(m) else np.full(m.n_cells, NO_PART, dtype=np.int64) for m in members]
        )
        for name in names
    }


def file_array_names(geometry: Geometry, key: str) -> dict[str, str]:
    """``{mesh property name: name in the file read}`` from ``metadata["vtk_array_names"][key]``.

    ``key`` is ``"point_data"`` or ``"cell_data"``. A collection's own table
    comes first, then its members'. For point data, the names of a GOCAD file
    (``metadata["property_names"]``, ``" default property"``) come after them.
    Entries that are not two strings are left out (metadata may have been
    edited).
    """
    sources: list[Geometry] = [geometry, *geometry.members] if isinstance(geometry, GeometryCollection) else [geometry]
    result: dict[str, str] = {}
    for source in sources:
        table = source.metadata.get("vtk_array_names") if isinstance(source.metadata, dict) else None
        names = table.get(key) if isinstance(table, dict) else None
        for name, file_name in names.items() if isinstance(names, dict) else ():
            if isinstance(name, str) and isinstance(file_name, str) and file_name and name not in result:
                result[name] = file_name
    for source in sources if key == "point_data" else ():
        gocad = source.metadata.get("property_names") if isinstance(source.metadata, dict) else None
        for name, file_name in gocad.items() if isinstance(gocad, dict) else ():
            if isinstance(name, str) and isinstance(file_name, str) and file_name.strip() and name not in result:
                result[name] = file_name
    return result


def named_as_read(
    arrays: dict[str, npt.NDArray[Any]], names: dict[str, str], allowed: Callable[[str], bool]
) -> dict[str, npt.NDArray[Any]]:
    """``arrays`` under the names of the file they were read from (``names``), where the format allows the name
    and no two arrays would get one name (those keep their mesh names)."""
    final = {name: names[name] if name in names and allowed(names[name]) else name for name in arrays}
    for _ in range(len(final) + 1):
        taken = list(final.values())
        clashing = [name for name, target in final.items() if target != name and taken.count(target) > 1]
        if not clashing:
            break
        for name in clashing:
            final[name] = name
    return {final[name]: values for name, values in arrays.items()}
