"""Mesh objects of the Python geoscience stack to tgsis meshes and back: pyvista, meshio, trimesh.

No database here, and no hard dependency: pyvista and meshio are optional
extras (``pip install tgsis[pyvista]`` / ``tgsis[meshio]``) imported only
when a conversion to them is asked for; an object *from* them is recognised
through the module that made it (already imported, since the object exists).

>>> import pyvista as pv, tgsis                                   # doctest: +SKIP
>>> surface = tgsis.as_mesh(pv.Sphere())                          # a tgsis.Surface
>>> grid = surface.to_pyvista()                                   # a pyvista.PolyData
>>> m = surface.to_meshio()                                       # a meshio.Mesh

What :func:`as_mesh` takes
--------------------------
* a tgsis :class:`~tgsis.mesh.Mesh` or :class:`~tgsis.mesh.GeometryCollection`:
  returned as it is;
* a pyvista dataset (``PolyData``, ``UnstructuredGrid``, any other
  ``pyvista.DataSet`` through ``cast_to_unstructured_grid``) or a bare VTK
  ``vtkDataSet`` (wrapped by pyvista). Its cells must be all of one kind:
  vertices (VERTEX, POLY_VERTEX: a :class:`~tgsis.mesh.PointSet`), lines
  (LINE, POLY_LINE: a :class:`~tgsis.mesh.LineSet`; a polyline becomes its
  segments, each with the polyline's cell data), TRIANGLE
  (:class:`~tgsis.mesh.Surface`) or TETRA (:class:`~tgsis.mesh.TetraMesh`).
  Points without cells are a PointSet. ``point_data`` and ``cell_data``
  become vertex and cell properties (an (n, k) array: a vector property);
  ``field_data["name"]`` the name;
* a pyvista ``MultiBlock``: a :class:`~tgsis.mesh.GeometryCollection`, one
  member per block (named after its key unless it has a name); no nesting;
* a ``meshio.Mesh``: its cell blocks must be all of one of the types
  ``vertex``, ``line``, ``triangle``, ``tetra`` (several blocks of one type
  are concatenated); ``point_data``, ``cell_data`` (one array per block) as
  above; 2D points get z = 0;
* a ``trimesh.Trimesh`` (:meth:`Surface.from_trimesh`, its vertex and face
  attributes as properties) or a ``trimesh.PointCloud`` (a PointSet).

Array names that are not valid property names (``"gmsh:physical"``,
``"Elevation value"``) are sanitised as the file readers do (``gmsh_physical``)
and the original names kept in ``metadata["vtk_array_names"]``
(``{"point_data": {property: array}, "cell_data": {...}}``), which
:func:`to_pyvista` and :func:`to_meshio` use to give the arrays their names back.

Everything else raises :class:`~tgsis.errors.InvalidGeometryError` listing
what is accepted: polygons that are not triangles (``triangulate()`` them
first), quadratic or other cell types, cells of several kinds in one object,
an object with neither points nor cells. Arrays that tgsis cannot store (strings,
the wrong number of values) raise :class:`~tgsis.errors.InvalidPropertyError`
naming the array; NaN or infinite points :class:`~tgsis.errors.InvalidGeometryError`.

And back
--------
:func:`to_pyvista` gives a ``PolyData`` for points, lines and surfaces
(vertices, 2-point lines, triangles) and an ``UnstructuredGrid`` for
tetrahedra and for collections (cells of mixed types), with the properties as
``point_data``/``cell_data`` (bool as uint8) and in ``field_data`` the name
(``name``), the geotype (``tgsis_geotype``) and, for a collection, its member
table (``tgsis_member_geotypes``, ``tgsis_member_names``,
``tgsis_member_sizes``: points and cells per member), so that
:func:`as_mesh` gives back the same type, empty meshes and collections
included. :func:`to_meshio` gives one cell block per mesh (per member for a
collection); meshio has no name or field data every writer accepts, so the
name, geotype and member table travel in ``mesh.info["tgsis"]`` (in memory:
a meshio file keeps the points, cells and data).

pyvista, meshio and trimesh have no z convention: a mesh whose
``metadata["zpositive"]`` says ``Depth`` is given in elevation (z negated),
and the convention is recorded in ``field_data["tgsis_zpositive"]``
(``tgsis_member_zpositive`` per member) or ``info["tgsis"]["zpositive"]``,
from which :func:`as_mesh` gives the depth mesh back.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Mapping
from types import ModuleType
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis._conversions import Conversions, install
from tgsis._vtk_cells import (
    CELL_TYPE_OF,
    collection_from_cells,
    first,
    labelled,
    one_mesh,
    string_bytes,
    strings,
    vtk_parts,
)
from tgsis._zpositive import (
    MEMBER_ZPOSITIVE_FIELD,
    ZPOSITIVE_FIELD,
    conventions,
    elevation,
    recorded_convention,
    restore,
)
from tgsis.errors import InvalidGeometryError, InvalidPropertyError
from tgsis.mesh import PROPERTY_NAME_RE, Geometry, GeometryCollection, LineSet, Mesh, PointSet, Surface, TetraMesh

__all__ = ["as_mesh", "from_pyvista", "from_meshio", "to_pyvista", "to_meshio", "ACCEPTED"]

#: What :func:`as_mesh` accepts, in the words of its error message.
ACCEPTED = (
    "a tgsis PointSet, LineSet, Surface, TetraMesh or GeometryCollection, a pyvista PolyData or "
    "UnstructuredGrid (or another pyvista/VTK dataset, or a MultiBlock of them), a meshio.Mesh, or a "
    "trimesh.Trimesh or PointCloud"
)

_HINT = (
    "build one with tgsis.Surface(vertices, triangles) (or PointSet, LineSet, TetraMesh), or convert "
    "your object to one of these first"
)

_MESHIO_TYPE_OF: dict[type[Mesh], str] = {PointSet: "vertex", LineSet: "line", Surface: "triangle", TetraMesh: "tetra"}
_MESH_OF_MESHIO_TYPE = {v: k for k, v in _MESHIO_TYPE_OF.items()}
_NAMES_KEY = "vtk_array_names"


# ---------------------------------------------------------------- recognising objects


def _loaded(module: str) -> ModuleType | None:
    """The module if it has been imported (an object of it exists only then), without importing it."""
    return sys.modules.get(module)


def _require(module: str, extra: str) -> ModuleType:
    """Import an optional dependency, or say which extra installs it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise InvalidGeometryError(
            f"this needs the optional package {module}, which is not installed",
            hint=f"pip install 'tgsis[{extra}]' (or pip install {module})",
        ) from None


def as_mesh(obj: Any) -> Geometry:
    """A tgsis mesh (or collection) for a mesh object of pyvista, meshio or trimesh.

    Parameters
    ----------
    obj : Mesh, GeometryCollection, pyvista.DataSet, vtkDataSet, meshio.Mesh, trimesh.Trimesh or trimesh.PointCloud
        See the module documentation for what each becomes.

    Returns
    -------
    Mesh or GeometryCollection
        ``obj`` itself when it is one already.

    Raises
    ------
    InvalidGeometryError
        ``obj`` is none of these (the message lists what is accepted), or
        holds what no tgsis mesh can (see the module documentation).
    InvalidPropertyError
        A data array tgsis cannot store.
    """
    if isinstance(obj, (Mesh, GeometryCollection)):
        return obj
    pv = _loaded("pyvista")
    if pv is not None and isinstance(obj, (pv.DataSet, pv.MultiBlock)):
        return from_pyvista(obj)
    vtk = _loaded("vtkmodules.vtkCommonDataModel")
    if vtk is not None and isinstance(obj, vtk.vtkDataObject):
        return from_pyvista(obj)
    meshio = _loaded("meshio")
    if meshio is not None and isinstance(obj, meshio.Mesh):
        return from_meshio(obj)
    trimesh = _loaded("trimesh")
    if trimesh is not None and isinstance(obj, trimesh.Trimesh):
        return labelled("trimesh.Trimesh", lambda: Surface.from_trimesh(obj, strict=True))
    if trimesh is not None and isinstance(obj, trimesh.PointCloud):
        return labelled(
            "trimesh.PointCloud",
            lambda: PointSet(
                np.asarray(obj.vertices, dtype=np.float64),
                vertex_properties=_numeric(
                    getattr(obj, "vertex_attributes", None) or {}, "trimesh.PointCloud", "vertex_attributes"
                ),
                name=(obj.metadata or {}).get("name"),
            ),
        )
    raise InvalidGeometryError(f"cannot store a {_type_name(obj)} as a mesh: tgsis takes {ACCEPTED}", hint=_HINT)


def _type_name(obj: Any) -> str:
    kind = type(obj)
    module = kind.__module__.split(".")[0]
    return kind.__qualname__ if module == "builtins" else f"{module}.{kind.__qualname__}"


def _numeric(arrays: Mapping[str, Any], source: str, where: str) -> dict[str, npt.NDArray[Any]]:
    """Arrays as numpy; a non-numeric one raises InvalidPropertyError naming it (lengths: the mesh checks)."""
    result: dict[str, npt.NDArray[Any]] = {}
    for name, values in arrays.items():
        array = np.asarray(values)
        if array.dtype.kind not in "biuf":
            raise InvalidPropertyError(
                f"{source} array {name!r} in {where} holds {array.dtype} values: a tgsis property holds numbers",
                hint=f"remove it from {where} before converting (del mesh.{where}[{name!r}])",
            )
        result[str(name)] = array
    return result


def _renamed(
    arrays: dict[str, npt.NDArray[Any]], names: dict[str, dict[str, str]], key: str
) -> dict[str, npt.NDArray[Any]]:
    """Arrays under valid, distinct property names; ``names[key]`` records {property: original} for renamed ones."""
    from tgsis.formats._common import sanitize_property_name

    result: dict[str, npt.NDArray[Any]] = {}
    renamed: dict[str, str] = {}
    for original, values in arrays.items():
        name = (
            original
            if PROPERTY_NAME_RE.match(original) and original not in result
            else sanitize_property_name(original, result)
        )
        if name != original:
            renamed[name] = original
        result[name] = values
    if renamed:
        names[key] = renamed
    return result


# ---------------------------------------------------------------- cells of one kind, from VTK's layout


# ---------------------------------------------------------------- pyvista


def from_pyvista(obj: Any) -> Geometry:
    """A tgsis mesh or collection from a pyvista dataset (or a bare VTK one); see the module documentation.

    Parameters
    ----------
    obj : pyvista.DataSet or vtkDataSet

    Raises
    ------
    InvalidGeometryError, InvalidPropertyError
        See :func:`as_mesh`.
    """
    pv = _require("pyvista", "pyvista")
    if not isinstance(obj, pv.DataObject):
        vtk = _loaded("vtkmodules.vtkCommonDataModel")
        if vtk is None or not isinstance(obj, vtk.vtkDataObject):
            raise InvalidGeometryError(
                f"{_type_name(obj)} is not a pyvista dataset: tgsis takes {ACCEPTED}", hint=_HINT
            )
        obj = pv.wrap(obj)
    source = f"pyvista {type(obj).__name__}"
    if isinstance(obj, pv.MultiBlock):
        return _blocks(pv, obj)
    if not isinstance(obj, pv.DataSet):
        raise InvalidGeometryError(
            f"{source} is not a dataset with points and cells: tgsis takes {ACCEPTED}", hint=_HINT
        )
    grid = obj if isinstance(obj, pv.UnstructuredGrid) else obj.cast_to_unstructured_grid()
    vertices = np.array(grid.points, dtype=np.float64).reshape(-1, 3)
    types = np.asarray(grid.celltypes, dtype=np.int64)
    offsets = np.asarray(grid.cell_offsets if hasattr(type(grid), "cell_offsets") else grid.offset, dtype=np.int64)
    connectivity = np.asarray(grid.cell_connectivity, dtype=np.int64)
    fields = {str(k): obj.field_data[k] for k in obj.field_data.keys()}
    name = first(fields.get("tgsis_name")) or first(fields.get("name"))
    geotype = first(fields.get("tgsis_geotype"))
    names: dict[str, dict[str, str]] = {}
    point_data = _renamed(
        _numeric({k: obj.point_data[k] for k in obj.point_data.keys()}, source, "point_data"), names, "point_data"
    )
    cell_data = _renamed(
        _numeric({k: obj.cell_data[k] for k in obj.cell_data.keys()}, source, "cell_data"), names, "cell_data"
    )
    metadata: dict[str, Any] = {_NAMES_KEY: names} if names else {}
    geometry: Geometry
    if geotype == GeometryCollection.geotype.value:
        table = (
            strings(fields.get("tgsis_member_geotypes", [])),
            strings(fields.get("tgsis_member_names", [])),
            fields.get("tgsis_member_sizes", np.empty((0, 2))),
        )
        geometry = collection_from_cells(
            vertices, types, offsets, connectivity, point_data, cell_data, table, name, metadata, source
        )
    else:
        geometry = labelled(
            source,
            lambda: one_mesh(
                vertices, types, offsets, connectivity, point_data, cell_data, name, geotype, metadata, source
            ),
        )
    _restore_convention(geometry, fields, source)
    return geometry


def _restore_convention(geometry: Geometry, fields: Mapping[str, Any], source: str) -> None:
    """The z convention that field data tgsis wrote records (the points' z is up), given back to the mesh(es)."""
    if isinstance(geometry, GeometryCollection):
        where, recorded = MEMBER_ZPOSITIVE_FIELD, strings(fields.get(MEMBER_ZPOSITIVE_FIELD, []))
        if MEMBER_ZPOSITIVE_FIELD in fields and len(recorded) != len(geometry):
            raise InvalidGeometryError(
                f"{source} field_data {where!r} has {len(recorded)} values for {len(geometry)} members"
            )
        values: list[str | None] = list(recorded)
    else:
        where, values = ZPOSITIVE_FIELD, [first(fields.get(ZPOSITIVE_FIELD))]
    restore(geometry, [recorded_convention(v, f"{source} field_data {where!r}") for v in values])


def _blocks(pv: ModuleType, blocks: Any) -> GeometryCollection:
    """A MultiBlock as a collection: one member per block, named after its key unless it has a name of its own."""
    members: list[Mesh] = []
    for i, key in enumerate(blocks.keys()):
        block = blocks[i]
        label = f"pyvista MultiBlock block {i} ({key!r})"
        if block is None or isinstance(block, pv.MultiBlock):
            raise InvalidGeometryError(
                f"{label} is {'empty' if block is None else 'a MultiBlock'}: the blocks "
                "become the members of a GeometryCollection, which do not nest",
                hint="remove it, or flatten the blocks first (blocks.flatten())",
            )
        member = labelled(label, lambda: from_pyvista(block))
        if isinstance(member, GeometryCollection):
            raise InvalidGeometryError(
                f"{label} is itself a collection tgsis wrote: collections do not nest", hint="add its members instead"
            )
        if member.name is None and key:
            member.name = str(key)
        members.append(member)
    if not members:
        raise InvalidGeometryError(
            "pyvista MultiBlock has no block: nothing to store", hint="give it at least one dataset"
        )
    return GeometryCollection(members)


def _original_names(mesh: Mesh | GeometryCollection, key: str) -> dict[str, str]:
    names = mesh.metadata.get(_NAMES_KEY)
    return dict(names.get(key, {})) if isinstance(names, Mapping) else {}


def _named(arrays: Mapping[str, npt.NDArray[Any]], originals: Mapping[str, str]) -> dict[str, npt.NDArray[Any]]:
    """Properties under the array names they came from; bool as uint8 (VTK has no bool)."""
    return {originals.get(k, k): (v.astype(np.uint8) if v.dtype.kind == "b" else v) for k, v in arrays.items()}


def to_pyvista(geometry: Geometry) -> Any:
    """The pyvista dataset of a tgsis mesh or collection; see the module documentation.

    Parameters
    ----------
    geometry : Mesh or GeometryCollection

    Returns
    -------
    pyvista.PolyData or pyvista.UnstructuredGrid
        PolyData for a PointSet, LineSet or Surface; UnstructuredGrid for a
        TetraMesh or a collection. Points are float64, exactly the vertices.

    Raises
    ------
    InvalidGeometryError
        ``geometry`` is not a tgsis mesh, or pyvista is not installed.
    """
    pv = _require("pyvista", "pyvista")
    if not isinstance(geometry, (Mesh, GeometryCollection)):
        raise InvalidGeometryError(
            f"to_pyvista converts tgsis meshes, not {_type_name(geometry)}",
            hint="tgsis.as_mesh(obj) converts other mesh objects to tgsis meshes",
        )
    recorded = conventions(geometry)
    vertices, connectivity, offsets, types, point_data, cell_data = vtk_parts(elevation(geometry))
    kind = type(geometry)
    if kind in (PointSet, LineSet, Surface):
        k = geometry.cell_size  # type: ignore[union-attr]
        cell_array = pv.CellArray.from_regular_cells(connectivity.reshape(-1, k)) if len(types) else pv.CellArray()
        keyword = {PointSet: "verts", LineSet: "lines", Surface: "faces"}[kind]
        data = pv.PolyData(vertices.copy(), **{keyword: cell_array})
        if data.n_cells != len(types):  # an empty cell array: pyvista made a vertex of each point
            data.verts = pv.CellArray()
    else:
        cells = np.insert(connectivity, offsets[:-1], np.diff(offsets)) if len(types) else np.empty(0, np.int64)
        data = pv.UnstructuredGrid(cells, types, vertices.copy())
    for key, values in _named(point_data, _original_names(geometry, "point_data")).items():
        data.point_data[key] = values
    for key, values in _named(cell_data, _original_names(geometry, "cell_data")).items():
        data.cell_data[key] = values
    # strings as UTF-8 bytes ending in 0 (uint8), as in tgsis's .vtu files: pyvista refuses non-ASCII strings
    if geometry.name:
        data.field_data["tgsis_name"] = string_bytes(geometry.name)
        if geometry.name.isascii():
            data.field_data["name"] = np.array([geometry.name])
    data.field_data["tgsis_geotype"] = string_bytes(geometry.geotype.value)
    if isinstance(geometry, GeometryCollection):
        data.field_data["tgsis_member_geotypes"] = string_bytes(*(m.geotype.value for m in geometry.members))
        data.field_data["tgsis_member_names"] = string_bytes(*(m.name or "" for m in geometry.members))
        data.field_data["tgsis_member_sizes"] = np.array(
            [[m.n_vertices, m.n_cells] for m in geometry.members], dtype=np.int64
        )
        if any(recorded):
            data.field_data[MEMBER_ZPOSITIVE_FIELD] = string_bytes(*(z or "" for z in recorded))
    elif recorded[0] is not None:
        data.field_data[ZPOSITIVE_FIELD] = string_bytes(recorded[0])
    return data


# ---------------------------------------------------------------- meshio


def from_meshio(obj: Any) -> Geometry:
    """A tgsis mesh or collection from a ``meshio.Mesh``; see the module documentation.

    Parameters
    ----------
    obj : meshio.Mesh

    Raises
    ------
    InvalidGeometryError, InvalidPropertyError
        See :func:`as_mesh`.
    """
    meshio = _require("meshio", "meshio")
    if not isinstance(obj, meshio.Mesh):
        raise InvalidGeometryError(f"{_type_name(obj)} is not a meshio.Mesh: tgsis takes {ACCEPTED}", hint=_HINT)
    source = "meshio.Mesh"
    points = np.asarray(obj.points)
    if points.ndim == 2 and points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])  # meshio's 2D meshes lie in z = 0
    info = obj.info.get("tgsis", {}) if isinstance(getattr(obj, "info", None), Mapping) else {}
    fields = {str(k): v for k, v in (obj.field_data or {}).items()}
    name = info.get("name") or first(fields.get("tgsis_name"))
    geotype = info.get("geotype") or first(fields.get("tgsis_geotype"))
    blocks = list(obj.cells)
    unknown = [b.type for b in blocks if b.type not in _MESH_OF_MESHIO_TYPE]
    if unknown:
        listed = ", ".join(dict.fromkeys(unknown))
        polygons = any(t.startswith(("quad", "polygon")) or t in ("triangle6", "triangle7") for t in unknown)
        raise InvalidGeometryError(
            f"{source} has {listed} cells: tgsis stores vertex, line, triangle and tetra cells",
            hint="split them into triangles first" if polygons else "split them into tetra (or triangle) cells first",
        )
    names: dict[str, dict[str, str]] = {}
    point_data = _renamed(_numeric(obj.point_data or {}, source, "point_data"), names, "point_data")
    cell_data: dict[str, npt.NDArray[Any]] = {}
    for key, per_block in (obj.cell_data or {}).items():
        arrays = list(per_block)
        if len(arrays) != len(blocks):
            raise InvalidPropertyError(
                f"{source} cell_data {key!r} has {len(arrays)} arrays for {len(blocks)} cell blocks",
                hint="give cell_data one array per cell block",
            )
        for block, values in zip(blocks, arrays):
            if len(np.asarray(values)) != len(block.data):
                raise InvalidPropertyError(
                    f"{source} cell_data {key!r} has {len(np.asarray(values))} values for "
                    f"the {len(block.data)} {block.type} cells of its block"
                )
        cell_data[str(key)] = np.concatenate([np.asarray(v) for v in arrays]) if arrays else np.empty(0)
    cell_data = _renamed(_numeric(cell_data, source, "cell_data"), names, "cell_data")
    metadata: dict[str, Any] = {_NAMES_KEY: names} if names else {}
    kinds = list(dict.fromkeys(_MESH_OF_MESHIO_TYPE[b.type] for b in blocks))
    connectivity = (
        np.concatenate([np.asarray(b.data, dtype=np.int64).reshape(-1) for b in blocks])
        if blocks
        else np.empty(0, np.int64)
    )
    types = (
        np.concatenate([np.full(len(b.data), CELL_TYPE_OF[_MESH_OF_MESHIO_TYPE[b.type]]) for b in blocks])
        if blocks
        else np.empty(0, np.int64)
    )
    sizes = (
        np.concatenate([np.full(len(b.data), _MESH_OF_MESHIO_TYPE[b.type].cell_size) for b in blocks])
        if blocks
        else np.empty(0, np.int64)
    )
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    vertices = points.astype(np.float64) if points.dtype.kind in "biuf" else points
    if geotype == GeometryCollection.geotype.value:
        if "members" in info:
            members = info["members"]
            table = ([m[0] for m in members], [m[1] for m in members], [[m[2], m[3]] for m in members])
        else:  # a .vtu file tgsis wrote, read by meshio: the member table is in the field data
            table = (
                strings(fields.get("tgsis_member_geotypes", [])),
                strings(fields.get("tgsis_member_names", [])),
                fields.get("tgsis_member_sizes", np.empty((0, 2))),
            )
        collection = collection_from_cells(
            vertices, types, offsets, connectivity, point_data, cell_data, table, name, metadata, source
        )
        _restore_convention(collection, _recorded_fields(info, fields), source)
        return collection
    if len(kinds) > 1:
        listed = ", ".join(f"{b.type} ({len(b.data)})" for b in blocks)
        raise InvalidGeometryError(
            f"{source} mixes cell blocks of several kinds ({listed}): a tgsis mesh has one kind of cell",
            hint="convert one kind at a time: meshio.Mesh(m.points, [m.cells[i]]), or store "
            "the kinds as members of a tgsis.GeometryCollection",
        )
    if not blocks or not len(types):
        if kinds:
            geotype = geotype or kinds[0].geotype.value
    mesh = labelled(
        source,
        lambda: one_mesh(
            vertices, types, offsets, connectivity, point_data, cell_data, name, geotype, metadata, source
        ),
    )
    _restore_convention(mesh, _recorded_fields(info, fields), source)
    return mesh


def _recorded_fields(info: Mapping[str, Any], fields: Mapping[str, Any]) -> dict[str, Any]:
    """The z convention a meshio.Mesh records: in ``info["tgsis"]`` (to_meshio) or the field data (a tgsis file)."""
    result = {k: v for k, v in fields.items() if k in (ZPOSITIVE_FIELD, MEMBER_ZPOSITIVE_FIELD)}
    if "zpositive" in info:
        value = info["zpositive"]
        if isinstance(value, (list, tuple)):
            result[MEMBER_ZPOSITIVE_FIELD] = np.array([v or "" for v in value])
        else:
            result[ZPOSITIVE_FIELD] = np.array([value or ""])
    return result


def to_meshio(geometry: Geometry) -> Any:
    """The ``meshio.Mesh`` of a tgsis mesh or collection; see the module documentation.

    Parameters
    ----------
    geometry : Mesh or GeometryCollection

    Returns
    -------
    meshio.Mesh
        One cell block (one per member of a collection: points of all
        members, one after the other), properties as ``point_data`` and
        ``cell_data``; name, geotype and member table in ``info["tgsis"]``.

    Raises
    ------
    InvalidGeometryError
        ``geometry`` is not a tgsis mesh, or meshio is not installed.
    """
    meshio = _require("meshio", "meshio")
    if not isinstance(geometry, (Mesh, GeometryCollection)):
        raise InvalidGeometryError(
            f"to_meshio converts tgsis meshes, not {_type_name(geometry)}",
            hint="tgsis.as_mesh(obj) converts other mesh objects to tgsis meshes",
        )
    recorded = conventions(geometry)
    vertices, connectivity, offsets, types, point_data, cell_data = vtk_parts(elevation(geometry))
    members = geometry.members if isinstance(geometry, GeometryCollection) else (geometry,)
    first_point = np.cumsum([0] + [m.n_vertices for m in members[:-1]])
    blocks = [meshio.CellBlock(_MESHIO_TYPE_OF[type(m)], m.cells + start) for m, start in zip(members, first_point)]
    ends = np.cumsum([m.n_cells for m in members])
    starts = ends - [m.n_cells for m in members]
    info: dict[str, Any] = {"geotype": geometry.geotype.value, "name": geometry.name}
    if isinstance(geometry, GeometryCollection):
        info["members"] = [(m.geotype.value, m.name or "", m.n_vertices, m.n_cells) for m in members]
        if any(recorded):
            info["zpositive"] = recorded
    elif recorded[0] is not None:
        info["zpositive"] = recorded[0]
    return meshio.Mesh(
        vertices.copy(),
        blocks,
        point_data=_named(point_data, _original_names(geometry, "point_data")),
        cell_data={
            k: [v[s:e] for s, e in zip(starts, ends)]
            for k, v in _named(cell_data, _original_names(geometry, "cell_data")).items()
        },
        info={"tgsis": info},
    )


# the mesh classes' methods (Mesh.to_pyvista, ..., Surface.to_trimesh) call these: tgsis.mesh cannot import this module
install(
    Conversions(
        to_pyvista=to_pyvista,
        to_meshio=to_meshio,
        from_pyvista=from_pyvista,
        from_meshio=from_meshio,
        elevation=elevation,
    )
)
