"""Mesh types on numpy arrays: point sets, line sets, triangle surfaces, tetrahedral meshes, collections.

No database here. A mesh is an indexed face set, the form of model 1:
``vertices`` (n, 3) float64 and ``cells`` (m, k) int64 indices into them, with
k = 1 (points), 2 (segments), 3 (triangles) or 4 (tetrahedra), plus named
per-vertex and per-cell property arrays.

Constructing a mesh validates it and raises on what cannot be stored:

* :class:`~tgsis.errors.InvalidGeometryError`: wrong array shapes, NaN or
  infinite coordinates, a cell index outside ``0..n-1``, a cell that uses one
  vertex twice;
* :class:`~tgsis.errors.InvalidPropertyError`: a property with the wrong
  number of values, a non-numeric property or one of more than two
  dimensions, a bad name.

What is legal but usually a mistake — duplicate vertices, zero-length,
zero-area or zero-volume cells — is *flagged* by :meth:`Mesh.report`.

A :class:`GeometryCollection` (GEOMETRYCOLLECTION) is an ordered tuple of such
meshes, possibly of different types; collections do not nest.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, TypeAlias, overload

import numpy as np
import numpy.typing as npt

from tgsis._conversions import installed as _conversions
from tgsis._vertex_metadata import renumbered, vertex_indices
from tgsis.errors import InvalidGeometryError, InvalidPropertyError

__all__ = [
    "Geotype",
    "Mesh",
    "PointSet",
    "LineSet",
    "Surface",
    "TetraMesh",
    "GeometryCollection",
    "Geometry",
    "MeshReport",
    "mesh_class",
    "PROPERTY_NAME_RE",
    "ORDERS",
    "morton_codes",
    "spatial_order",
]

#: Property names: letters (either case, kept as given: feature-class columns are quoted identifiers),
#: digits and underscores, starting with a letter, at most 63 characters.
PROPERTY_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,62}$")

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


class Geotype(str, enum.Enum):
    """Geometry types: model 1's meshes and collections, and GMAP (a G-map of model 4, :mod:`tgsis.gmaps`)."""

    MULTIPOINT = "MULTIPOINT"
    MULTILINESTRING = "MULTILINESTRING"
    SURFACE = "SURFACE"
    MULTITETRA = "MULTITETRA"
    GEOMETRYCOLLECTION = "GEOMETRYCOLLECTION"
    GMAP = "GMAP"


@dataclass(frozen=True)
class MeshReport:
    """What :meth:`Mesh.report` flags (legal, but usually a mistake).

    Attributes
    ----------
    duplicate_vertices : (d, 2) int64
        Pairs ``(i, j)``, ``i < j``: vertex ``j`` has exactly the coordinates
        of the lower-numbered vertex ``i``.
    degenerate_cells : (q,) int64
        Cells of zero length, area or volume (at most ``tolerance``).
    """

    duplicate_vertices: IntArray
    degenerate_cells: IntArray

    @property
    def ok(self) -> bool:
        """Nothing flagged."""
        return len(self.duplicate_vertices) == 0 and len(self.degenerate_cells) == 0

    def summary(self) -> str:
        """One line for logs and the command line."""
        if self.ok:
            return "no duplicate vertices, no degenerate cells"
        return f"{len(self.duplicate_vertices)} duplicate vertices, {len(self.degenerate_cells)} degenerate cells"


def _as_vertices(vertices: npt.ArrayLike) -> FloatArray:
    try:
        array = np.ascontiguousarray(vertices, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidGeometryError(f"vertices are not numbers: {exc}") from None
    if array.ndim != 2 or array.shape[1] != 3:
        raise InvalidGeometryError(f"vertices must be an (n, 3) array, got shape {array.shape}")
    bad = ~np.isfinite(array)
    if bad.any():
        row, col = (int(v) for v in np.argwhere(bad)[0])
        raise InvalidGeometryError(
            f"vertex {row} has a non-finite {'xyz'[col]} coordinate ({array[row, col]})",
            detail=f"{int(bad.any(axis=1).sum())} vertices have NaN or infinite coordinates",
        )
    return array


_PLURAL = {"vertex": "vertices", "tetrahedron": "tetrahedra"}


def _plural(what: str) -> str:
    return _PLURAL.get(what, what + "s")


def _as_properties(
    properties: Mapping[str, npt.ArrayLike] | None, count: int, what: str
) -> dict[str, npt.NDArray[Any]]:
    result: dict[str, npt.NDArray[Any]] = {}
    for name, values in (properties or {}).items():
        if not isinstance(name, str) or not PROPERTY_NAME_RE.match(name):
            raise InvalidPropertyError(
                f"{what} property name {name!r} is not allowed",
                hint="use letters, digits and underscores, starting with a letter (at most 63)",
            )
        array = np.ascontiguousarray(values)
        if array.dtype.kind not in "biuf":
            raise InvalidPropertyError(f"{what} property {name!r} has values of type {array.dtype}, not numbers")
        if array.ndim not in (1, 2) or (array.ndim == 2 and array.shape[1] < 1):
            raise InvalidPropertyError(
                f"{what} property {name!r} must be one value or one vector of values per "
                f"{what}, got shape {array.shape}"
            )
        if len(array) != count:
            raise InvalidPropertyError(f"{what} property {name!r} has {len(array)} values for {count} {_plural(what)}")
        result[name] = array
    return result


class Mesh:
    """Base of the mesh types: vertices, cells of ``cell_size`` vertices, properties.

    Parameters
    ----------
    vertices : (n, 3) array_like of float
        Vertex coordinates; stored as float64.
    cells : (m, k) array_like of int
        Vertex indices of each cell, k = :attr:`cell_size`; stored as int64.
    vertex_properties : mapping of str to (n,) or (n, k) array_like, optional
        Numeric values per vertex; (n, k): a vector of k components per vertex
        (GOCAD ``ESIZES k``).
    cell_properties : mapping of str to (m,) or (m, k) array_like, optional
        Numeric values per cell.
    name : str, optional
        The object's name (e.g. from a GOCAD header).
    metadata : mapping, optional
        Free-form facts a file format keeps for a faithful round trip
        (colour, GOCAD header lines, original property names, ...).

    Raises
    ------
    InvalidGeometryError, InvalidPropertyError
        See the module documentation.
    """

    geotype: ClassVar[Geotype]
    cell_size: ClassVar[int]
    cell_name: ClassVar[str]

    vertices: FloatArray
    cells: IntArray

    def __init__(
        self,
        vertices: npt.ArrayLike,
        cells: npt.ArrayLike,
        *,
        vertex_properties: Mapping[str, npt.ArrayLike] | None = None,
        cell_properties: Mapping[str, npt.ArrayLike] | None = None,
        name: str | None = None,
        metadata: Mapping[str, Any] | None = None,
    ) -> None:
        self.vertices = _as_vertices(vertices)
        self.cells = self._as_cells(cells, len(self.vertices))
        self.vertex_properties = _as_properties(vertex_properties, len(self.vertices), "vertex")
        self.cell_properties = _as_properties(cell_properties, len(self.cells), self.cell_name)
        self.name = name
        self.metadata: dict[str, Any] = dict(metadata or {})

    @classmethod
    def _as_cells(cls, cells: npt.ArrayLike, n_vertices: int) -> IntArray:
        k, what = cls.cell_size, cls.cell_name
        raw = np.asarray(cells)
        if raw.size == 0:
            return np.empty((0, k), dtype=np.int64)
        if raw.dtype.kind not in "iu" and not (raw.dtype.kind == "f" and np.all(raw == np.round(raw))):
            raise InvalidGeometryError(f"{what} indices must be integers, got {raw.dtype}")
        array = np.ascontiguousarray(raw, dtype=np.int64)
        if array.ndim != 2 or array.shape[1] != k:
            raise InvalidGeometryError(
                f"{_plural(what)} must be an (m, {k}) array of vertex indices, got shape {array.shape}"
            )
        outside = (array < 0) | (array >= n_vertices)
        if outside.any():
            row, col = (int(v) for v in np.argwhere(outside)[0])
            raise InvalidGeometryError(
                f"{what} {row} refers to vertex {array[row, col]}, but the mesh has {n_vertices} vertices",
                detail=f"{int(outside.any(axis=1).sum())} {_plural(what)} have out-of-range vertex indices",
            )
        if k > 1:
            # every pair of corners compared: k(k - 1)/2 passes, cheaper than sorting each row for k <= 4
            repeated = np.zeros(len(array), dtype=bool)
            for i in range(k):
                for j in range(i + 1, k):
                    repeated |= array[:, i] == array[:, j]
            if repeated.any():
                row = int(np.flatnonzero(repeated)[0])
                raise InvalidGeometryError(
                    f"{what} {row} uses a vertex twice: {array[row].tolist()}",
                    detail=f"{int(repeated.sum())} {_plural(what)} repeat a vertex index",
                )
        return array

    # ---- facts

    @property
    def n_vertices(self) -> int:
        """Number of vertices n."""
        return len(self.vertices)

    @property
    def n_cells(self) -> int:
        """Number of cells m."""
        return len(self.cells)

    def bounds(self) -> FloatArray:
        """Axis-aligned bounding box as a (2, 3) array ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``.

        Raises
        ------
        InvalidGeometryError
            The mesh has no vertex.
        """
        if self.n_vertices == 0:
            raise InvalidGeometryError(f"{type(self).__name__} {self.name or ''} has no vertex: no bounding box")
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    def cell_measures(self) -> FloatArray:
        """Length, area or volume of every cell: (m,) float64 (zeros for points)."""
        v = self.vertices[self.cells]
        if self.cell_size == 1:
            return np.zeros(self.n_cells)
        if self.cell_size == 2:
            return np.asarray(np.linalg.norm(v[:, 1] - v[:, 0], axis=1))
        if self.cell_size == 3:
            return np.asarray(0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1))
        edges = v[:, 1:] - v[:, :1]
        return np.asarray(np.abs(np.linalg.det(edges)) / 6.0)

    def duplicate_vertex_pairs(self) -> IntArray:
        """(d, 2) int64 pairs ``(first, duplicate)`` of vertices with identical coordinates."""
        if self.n_vertices < 2:
            return np.empty((0, 2), dtype=np.int64)
        # -0.0 and 0.0 are the same point: compare values, not bits
        coords = self.vertices + 0.0
        order = np.lexsort(coords.T[::-1])  # stable: equal rows keep index order
        ordered = coords[order]
        starts_group = np.concatenate([[True], (ordered[1:] != ordered[:-1]).any(axis=1)])
        if starts_group.all():
            return np.empty((0, 2), dtype=np.int64)
        group = np.cumsum(starts_group) - 1
        first = order[np.flatnonzero(starts_group)][group]
        dup = ~starts_group
        pairs = np.stack([first[dup], order[dup]], axis=1).astype(np.int64)
        return pairs[np.lexsort(pairs.T[::-1])]

    def report(self, tolerance: float = 0.0) -> MeshReport:
        """Flag duplicate vertices and cells whose measure is at most ``tolerance``.

        Parameters
        ----------
        tolerance : float
            Largest length/area/volume still counted as degenerate (0: exactly zero).
        """
        degenerate = (
            np.flatnonzero(self.cell_measures() <= tolerance) if self.cell_size > 1 else np.empty(0, dtype=np.int64)
        )
        return MeshReport(self.duplicate_vertex_pairs(), degenerate.astype(np.int64))

    # ---- comparison and copies

    def same_as(self, other: Mesh | GeometryCollection) -> bool:
        """Same type, bit-identical vertices and cells, and equal properties (NaN equals NaN)."""

        def same_props(a: Mapping[str, npt.NDArray[Any]], b: Mapping[str, npt.NDArray[Any]]) -> bool:
            return a.keys() == b.keys() and all(
                a[k].shape == b[k].shape and np.array_equal(a[k], b[k], equal_nan=a[k].dtype.kind == "f") for k in a
            )

        return (
            type(self) is type(other)
            and self.vertices.shape == other.vertices.shape
            and bool(np.all(self.vertices.view(np.int64) == other.vertices.view(np.int64)))
            and np.array_equal(self.cells, other.cells)
            and same_props(self.vertex_properties, other.vertex_properties)
            and same_props(self.cell_properties, other.cell_properties)
        )

    def copy(self) -> Mesh:
        """A deep copy."""
        return type(self)(
            self.vertices.copy(),
            self.cells.copy(),
            vertex_properties={k: v.copy() for k, v in self.vertex_properties.items()},
            cell_properties={k: v.copy() for k, v in self.cell_properties.items()},
            name=self.name,
            metadata=dict(self.metadata),
        )

    # ---- other libraries' mesh objects (tgsis.convert, reached through tgsis._conversions: it imports this
    # module; pyvista and meshio are optional)

    def to_pyvista(self) -> Any:
        """This mesh as a pyvista ``PolyData`` (points, lines, surfaces) or ``UnstructuredGrid`` (tetrahedra).

        See :func:`tgsis.convert.to_pyvista`; needs pyvista (``pip install 'tgsis[pyvista]'``).
        """
        return _conversions().to_pyvista(self)

    def to_meshio(self) -> Any:
        """This mesh as a ``meshio.Mesh`` of one cell block.

        See :func:`tgsis.convert.to_meshio`; needs meshio (``pip install 'tgsis[meshio]'``).
        """
        return _conversions().to_meshio(self)

    @classmethod
    def from_pyvista(cls, obj: Any) -> Mesh:
        """A mesh of this class from a pyvista dataset; see :func:`tgsis.convert.from_pyvista`.

        Raises
        ------
        InvalidGeometryError
            The dataset is not a mesh of this class (``Surface.from_pyvista`` of
            lines), or not one tgsis can store.
        """
        return cls._expect(_conversions().from_pyvista(obj), "pyvista dataset")

    @classmethod
    def from_meshio(cls, obj: Any) -> Mesh:
        """A mesh of this class from a ``meshio.Mesh``; see :func:`tgsis.convert.from_meshio`.

        Raises
        ------
        InvalidGeometryError
            As :meth:`from_pyvista`.
        """
        return cls._expect(_conversions().from_meshio(obj), "meshio.Mesh")

    @classmethod
    def _expect(cls, mesh: Mesh | GeometryCollection, what: str) -> Mesh:
        if not isinstance(mesh, cls):
            raise InvalidGeometryError(
                f"the {what} is a {type(mesh).__name__}, not a {cls.__name__}",
                hint=f"tgsis.as_mesh(obj) gives whatever mesh it is; {cls.__name__}.from_... only a {cls.__name__}",
            )
        return mesh

    def __repr__(self) -> str:
        props = list(self.vertex_properties) + list(self.cell_properties)
        return (
            f"{type(self).__name__}(name={self.name!r}, n_vertices={self.n_vertices}, "
            f"n_{_plural(self.cell_name)}={self.n_cells}, properties={props})"
        )


class PointSet(Mesh):
    """Points (MULTIPOINT): cells are (m, 1); by default one cell per vertex."""

    geotype = Geotype.MULTIPOINT
    cell_size = 1
    cell_name = "point"

    def __init__(self, vertices: npt.ArrayLike, cells: npt.ArrayLike | None = None, **kwargs: Any) -> None:
        n = len(np.asarray(vertices)) if np.ndim(vertices) else 0
        super().__init__(vertices, np.arange(n).reshape(-1, 1) if cells is None else cells, **kwargs)


class LineSet(Mesh):
    """Lines (MULTILINESTRING) as segments: cells are (m, 2)."""

    geotype = Geotype.MULTILINESTRING
    cell_size = 2
    cell_name = "segment"


class Surface(Mesh):
    """Triangulated surface (SURFACE): cells are (m, 3) triangles."""

    geotype = Geotype.SURFACE
    cell_size = 3
    cell_name = "triangle"

    @property
    def triangles(self) -> IntArray:
        """The cells: (m, 3) int64."""
        return self.cells

    def to_trimesh(self) -> Any:
        """A :class:`trimesh.Trimesh` with the same vertices, faces and properties (not processed).

        trimesh has no z convention: a surface whose ``metadata["zpositive"]``
        says ``Depth`` is given with z negated (elevation, up positive).
        """
        import trimesh

        up: Surface = _conversions().elevation(self)  # tgsis._zpositive.elevation
        return trimesh.Trimesh(
            vertices=up.vertices.copy(),
            faces=self.cells.copy(),
            process=False,
            validate=False,
            vertex_attributes={k: v.copy() for k, v in self.vertex_properties.items()},
            face_attributes={k: v.copy() for k, v in self.cell_properties.items()},
            metadata={"name": self.name} if self.name else {},
        )

    @classmethod
    def from_trimesh(cls, mesh: Any, *, name: str | None = None, strict: bool = False) -> Surface:
        """A surface from a :class:`trimesh.Trimesh` (its vertex/face attributes become properties).

        Parameters
        ----------
        mesh : trimesh.Trimesh
        name : str, optional
            Default: ``mesh.metadata["name"]``.
        strict : bool
            Every attribute must become a property: one that is not numeric,
            or has the wrong number of values, raises
            :class:`~tgsis.errors.InvalidPropertyError` (default: it is left
            out, as trimesh's file loaders add attributes of their own).
        """

        def numeric(attrs: Mapping[str, Any], count: int) -> dict[str, npt.NDArray[Any]]:
            if strict:
                return {k: np.asarray(v) for k, v in attrs.items()}  # the constructor names a bad one
            return {
                k: np.asarray(v)
                for k, v in attrs.items()
                if np.asarray(v).ndim == 1 and len(v) == count and np.asarray(v).dtype.kind in "biuf"
            }

        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        faces = np.asarray(mesh.faces, dtype=np.int64)
        return cls(
            vertices,
            faces,
            vertex_properties=numeric(getattr(mesh, "vertex_attributes", {}), len(vertices)),
            cell_properties=numeric(getattr(mesh, "face_attributes", {}), len(faces)),
            name=name or (mesh.metadata or {}).get("name"),
        )


class TetraMesh(Mesh):
    """Tetrahedral solid (MULTITETRA): cells are (m, 4) tetrahedra."""

    geotype = Geotype.MULTITETRA
    cell_size = 4
    cell_name = "tetrahedron"


_CLASSES: dict[Geotype, type[Mesh]] = {c.geotype: c for c in (PointSet, LineSet, Surface, TetraMesh)}


class GeometryCollection:
    """An ordered collection of meshes (GEOMETRYCOLLECTION), possibly of different types.

    Parameters
    ----------
    members : iterable of Mesh
        At least one PointSet, LineSet, Surface or TetraMesh, in order; each
        keeps its own vertices, cells, properties and name. Collections do
        not nest.
    name : str, optional
        The collection's name.
    metadata : mapping, optional
        Free-form facts about the whole collection.

    Raises
    ------
    InvalidGeometryError
        No member, or a member that is not one of the four mesh types (a
        collection, a plain :class:`Mesh`, anything else).

    Examples
    --------
    >>> c = GeometryCollection([Surface(v, t), PointSet(p)], name="block")   # doctest: +SKIP
    >>> c.n_vertices == c.members[0].n_vertices + c.members[1].n_vertices    # doctest: +SKIP
    True
    """

    geotype: ClassVar[Geotype] = Geotype.GEOMETRYCOLLECTION

    members: tuple[Mesh, ...]

    def __init__(
        self, members: Iterable[Mesh], *, name: str | None = None, metadata: Mapping[str, Any] | None = None
    ) -> None:
        if isinstance(members, (Mesh, GeometryCollection)):
            raise InvalidGeometryError(
                f"the members of a GeometryCollection are a sequence of meshes, got one {type(members).__name__}",
                hint="wrap it in a list",
            )
        items = tuple(members)
        for i, member in enumerate(items):
            if isinstance(member, GeometryCollection):
                raise InvalidGeometryError(
                    f"member {i} of collection {name!r} is a GeometryCollection: collections do not nest",
                    hint="add its members to the outer collection instead",
                )
            if not isinstance(member, (PointSet, LineSet, Surface, TetraMesh)):
                raise InvalidGeometryError(
                    f"member {i} of collection {name!r} is a {type(member).__name__}, "
                    "not a PointSet, LineSet, Surface or TetraMesh"
                )
        if not items:
            raise InvalidGeometryError(f"collection {name!r} has no member: a GeometryCollection needs at least one")
        self.members = items
        self.name = name
        self.metadata: dict[str, Any] = dict(metadata or {})

    # ---- facts

    def __len__(self) -> int:
        return len(self.members)

    def __iter__(self) -> Iterator[Mesh]:
        return iter(self.members)

    def __getitem__(self, index: int) -> Mesh:
        return self.members[index]

    @property
    def n_vertices(self) -> int:
        """Number of vertices of all members."""
        return sum(m.n_vertices for m in self.members)

    @property
    def n_cells(self) -> int:
        """Number of cells (points, segments, triangles, tetrahedra) of all members."""
        return sum(m.n_cells for m in self.members)

    @property
    def geotypes(self) -> tuple[Geotype, ...]:
        """Geotype of each member, in order."""
        return tuple(m.geotype for m in self.members)

    def bounds(self) -> FloatArray:
        """Bounding box of all members' vertices: (2, 3) ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``.

        Raises
        ------
        InvalidGeometryError
            No member has a vertex.
        """
        boxes = [m.bounds() for m in self.members if m.n_vertices]
        if not boxes:
            raise InvalidGeometryError(f"collection {self.name or ''} has no vertex: no bounding box")
        stacked = np.stack(boxes)
        return np.stack([stacked[:, 0].min(axis=0), stacked[:, 1].max(axis=0)])

    def report(self, tolerance: float = 0.0) -> tuple[MeshReport, ...]:
        """:meth:`Mesh.report` of each member, in order.

        Parameters
        ----------
        tolerance : float
            Largest length/area/volume still counted as degenerate (0: exactly zero).
        """
        return tuple(m.report(tolerance) for m in self.members)

    # ---- comparison and copies

    def same_as(self, other: Mesh | GeometryCollection) -> bool:
        """Also a collection, with as many members, each :meth:`Mesh.same_as` its counterpart."""
        return (
            isinstance(other, GeometryCollection)
            and len(self.members) == len(other.members)
            and all(a.same_as(b) for a, b in zip(self.members, other.members))
        )

    def copy(self) -> GeometryCollection:
        """A deep copy."""
        return GeometryCollection([m.copy() for m in self.members], name=self.name, metadata=dict(self.metadata))

    def to_pyvista(self) -> Any:
        """The collection as one pyvista ``UnstructuredGrid`` of mixed cells; see :func:`tgsis.convert.to_pyvista`."""
        return _conversions().to_pyvista(self)

    def to_meshio(self) -> Any:
        """The collection as a ``meshio.Mesh`` of one cell block per member; see :func:`tgsis.convert.to_meshio`."""
        return _conversions().to_meshio(self)

    def __repr__(self) -> str:
        kinds = ", ".join(type(m).__name__ for m in self.members)
        return (
            f"GeometryCollection(name={self.name!r}, members=[{kinds}], n_vertices={self.n_vertices}, "
            f"n_cells={self.n_cells})"
        )


#: What a feature's geometry can be: one mesh or a collection of meshes.
Geometry: TypeAlias = Mesh | GeometryCollection


def mesh_class(geotype: Geotype | str) -> type[Mesh]:
    """The mesh class of a geotype (``"SURFACE"`` gives :class:`Surface`).

    Raises
    ------
    InvalidGeometryError
        Unknown geotype, or GEOMETRYCOLLECTION (which has no single mesh: its
        members are meshes of a :class:`GeometryCollection`).
    """
    try:
        key = geotype if isinstance(geotype, Geotype) else Geotype(str(geotype).upper())
        return _CLASSES[key]
    except (ValueError, KeyError):
        raise InvalidGeometryError(
            f"no mesh type for geotype {geotype!r}",
            hint="use MULTIPOINT, MULTILINESTRING, SURFACE or MULTITETRA; a GEOMETRYCOLLECTION is a "
            "GeometryCollection of such meshes",
        ) from None


# --------------------------------------------------------------------------- the spatial order of ids (issue 40)

#: The orders of ids :func:`tgsis.insert_feature` and ``tgsis import --order`` take: the mesh's own
#: (``file``) or :func:`spatial_order`'s (``spatial``).
ORDERS = ("file", "spatial")

_MORTON_BITS = 21  # per axis: three axes fill 63 bits of a uint64


def morton_codes(points: npt.ArrayLike) -> npt.NDArray[np.uint64]:
    """Morton (Z-order) codes of points, 21 bits per axis, one scale for all axes.

    Parameters
    ----------
    points : (n, 3) array_like of float
        Finite coordinates.

    Returns
    -------
    (n,) uint64
        The code of each point: its coordinates quantized over the points'
        bounding box with the box's largest extent as the one scale (so the
        curve is the same in every direction), bits interleaved x, y, z.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(p) == 0:
        return np.empty(0, dtype=np.uint64)
    # halves first: the differences of finite doubles then stay finite (1e308 - -1e308 would not)
    half = p / 2.0
    low = half.min(axis=0)
    extent = float((half.max(axis=0) - low).max())
    top = 2**_MORTON_BITS - 1
    scaled = (half - low) / extent * top if extent > 0 else np.zeros_like(p)
    q = np.clip(np.floor(scaled), 0, top).astype(np.uint64)

    def spread(v: npt.NDArray[np.uint64]) -> npt.NDArray[np.uint64]:
        v = v & np.uint64(0x1FFFFF)
        for shift, mask in (
            (32, 0x1F00000000FFFF),
            (16, 0x1F0000FF0000FF),
            (8, 0x100F00F00F00F00F),
            (4, 0x10C30C30C30C30C3),
            (2, 0x1249249249249249),
        ):
            v = (v | (v << np.uint64(shift))) & np.uint64(mask)
        return v

    codes: npt.NDArray[np.uint64] = (
        spread(q[:, 0]) | (spread(q[:, 1]) << np.uint64(1)) | (spread(q[:, 2]) << np.uint64(2))
    )
    return codes


_SPATIAL = "it cannot be renumbered in the spatial order"
_SPATIAL_HINT = "correct or remove that metadata entry, or keep the file's order"


def _renumbered_metadata(mesh: Mesh, new_of_old: IntArray) -> dict[str, Any]:
    """The mesh's metadata with its vertex indices renumbered: atoms, patoms, vertex flags, control nodes."""
    n, name = mesh.n_vertices, mesh.name
    meta = dict(mesh.metadata)
    if "gocad_atoms" in meta:
        pairs = vertex_indices(meta["gocad_atoms"], n, "gocad_atoms", name, _SPATIAL, _SPATIAL_HINT)
        if len(pairs) % 2:
            raise InvalidGeometryError(f"metadata['gocad_atoms'] of {name or 'the mesh'} is not a list of pairs")
        new_pairs = new_of_old[pairs.reshape(-1, 2)]
        new_pairs = new_pairs[np.argsort(new_pairs[:, 0], kind="stable")]
        meta["gocad_atoms"] = [[int(a), int(r)] for a, r in new_pairs]
    if "gocad_patoms" in meta:
        meta["gocad_patoms"] = sorted(
            int(v)
            for v in new_of_old[vertex_indices(meta["gocad_patoms"], n, "gocad_patoms", name, _SPATIAL, _SPATIAL_HINT)]
        )
    meta = renumbered(meta, n, new_of_old, name, _SPATIAL, _SPATIAL_HINT)  # flags and control nodes
    meta["vertex_order"] = "spatial"
    return meta


def _spatial_mesh(mesh: Mesh) -> Mesh:
    n, m = mesh.n_vertices, mesh.n_cells
    vertex_order = np.argsort(morton_codes(mesh.vertices), kind="stable")  # ties: the original index
    new_of_old = np.empty(n, dtype=np.int64)
    new_of_old[vertex_order] = np.arange(n, dtype=np.int64)
    cells = new_of_old[mesh.cells]  # corners keep their order in the cell (orientation)
    part = mesh.cell_properties.get("part")
    keys: list[npt.NDArray[Any]] = [np.arange(m), cells.min(axis=1) if m else np.empty(0, np.int64)]
    if part is not None and part.ndim == 1:
        keys.append(part)  # GOCAD parts (TFACE, ILINE, TVOLUME) stay runs of cells, in part order
    cell_order = np.lexsort(keys)
    return type(mesh)(
        mesh.vertices[vertex_order],
        cells[cell_order],
        vertex_properties={k: v[vertex_order] for k, v in mesh.vertex_properties.items()},
        cell_properties={k: v[cell_order] for k, v in mesh.cell_properties.items()},
        name=mesh.name,
        metadata=_renumbered_metadata(mesh, new_of_old),
    )


@overload
def spatial_order(geometry: Mesh) -> Mesh: ...


@overload
def spatial_order(geometry: GeometryCollection) -> GeometryCollection: ...


def spatial_order(geometry: Geometry) -> Geometry:
    """The same geometry with its vertices and cells renumbered in a spatial order (deterministic).

    Vertices are ordered by the Morton code of their position
    (:func:`morton_codes`: 21 bits per axis, one scale for all axes), ties by
    their index; cells by their ``part`` cell property when there is one (so
    GOCAD parts stay runs of cells), then by their smallest new vertex index,
    then by their index. A cell keeps its corners in their order (a
    triangle its orientation). Vertex and cell properties follow their
    vertex or cell; the vertex indices of the metadata (``gocad_atoms``,
    ``gocad_patoms``, ``gocad_vertex_flags``,
    ``gocad_property_control_nodes``) are renumbered; ``metadata["vertex_order"]``
    is set to ``"spatial"``. A collection's members are ordered each on its own.

    Nearby vertices then have nearby ids, so that a region of the surface lives
    in few chunks of 1,024 ids (docs/storage.md, "Order of ids at upload").

    Parameters
    ----------
    geometry : Mesh or GeometryCollection

    Returns
    -------
    Mesh or GeometryCollection
        A new object of the same type; ``geometry`` is not changed.

    Raises
    ------
    InvalidGeometryError
        A metadata entry above that does not hold vertex indices of the mesh.
    """
    if isinstance(geometry, GeometryCollection):
        meta = {**geometry.metadata, "vertex_order": "spatial"}
        return GeometryCollection([_spatial_mesh(m) for m in geometry.members], name=geometry.name, metadata=meta)
    return _spatial_mesh(geometry)
