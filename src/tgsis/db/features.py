"""Feature classes and features of model 1: register classes, upload and download meshes.

Uploads and downloads go through binary COPY built and parsed with numpy
(:mod:`tgsis.db.copy`); every write is one transaction. A feature is one row
of the class's feature table whose ``_geoid`` is its geometry in
``tgsis.geometry``; vertices and simplices are in ``tgsis.vrtx`` and
``tgsis.point|segment|trgl|tetra``, vertex or cell properties in the class's
``<name>_cellpros`` table.

A feature of a GEOMETRYCOLLECTION class is a :class:`~tgsis.mesh.GeometryCollection`:
every member is a geometry row of its own, owned by the collection row
(``tgsis.geometry.collection``), which lists the members in order in
``geoids``; the member rows hold the vertices, simplices and cell properties
(``_geoid`` = member geoid), the feature row points at the collection.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.arguments import check_module
from tgsis.db.copy import SQL_TYPES, array_wire, decode_rows, encode_rows, numpy_dtype
from tgsis.db.meaning import Meaning, meaning_of, part_runs, parts_from_runs, restore_meaning
from tgsis.errors import (InvalidGeometryError, InvalidInputError, InvalidPropertyError, NotFoundError,
                          NotVersionedError, reraise)
from tgsis.mesh import Geometry, GeometryCollection, Geotype, Mesh, mesh_class
from tgsis.temporal import EvolvingSurface, SurfaceSeries

__all__ = [
    "Property",
    "FeatureClass",
    "Feature",
    "create_feature_class",
    "get_feature_class",
    "list_feature_classes",
    "drop_feature_class",
    "insert_feature",
    "fetch_feature",
    "fetch_features",
    "features_in_box",
    "class_of_feature",
    "delete_feature",
]

log = logging.getLogger(__name__)

Conn = psycopg.Connection[Any]
PropertySpec = Mapping[str, str] | Sequence["tuple[str, str] | tuple[str, str, int] | Property"]

_SIMPLEX = {
    Geotype.MULTIPOINT: ("point", "pointid"),
    Geotype.MULTILINESTRING: ("segment", "segid"),
    Geotype.SURFACE: ("trgl", "trglid"),
    Geotype.MULTITETRA: ("tetra", "tetraid"),
}


@dataclass(frozen=True)
class Property:
    """A property of a feature class: column name, SQL type and, for a vector property, its number of components.

    A vertex or cell property of ``size`` k > 1 is one column of arrays of k
    values; in a mesh it is an (n, k) array. ``alignment`` (``"VERTEX"`` or
    ``"CELL"``) is given for a property aligned otherwise than its class
    (alignment is per property; None: the class's).
    """

    name: str
    type: str
    size: int = 1
    alignment: Literal["VERTEX", "CELL"] | None = None

    @property
    def wire(self) -> str:
        """Its binary COPY wire type (``"float8"``, ``"float8[3]"``)."""
        return array_wire(SQL_TYPES[self.type], self.size)


@dataclass(frozen=True)
class FeatureClass:
    """A row of ``tgsis.catalog``.

    Attributes
    ----------
    name : str
        Class name (= feature table name).
    schema : str
        Schema of its tables.
    geotype : Geotype
        Geotype of its features.
    alignment : {"VERTEX", "CELL"}
        Whether ``cell_properties`` are per vertex or per simplex.
    srs : int
        Spatial reference id (0: undefined).
    feature_properties, cell_properties : tuple of Property
        In column order.
    time_model : {"STATIC", "INSTANTS", "EVOLVING"}
        Model 1 (static), model 2 (surfaces at instants) or model 3
        (continuously evolving surfaces).
    time_unit : str or None
        Unit of model time of a temporal class.
    instant_properties : tuple of Property
        Per-instant feature properties of a temporal class (columns of
        ``protable``).
    protable : str or None
        ``<name>_pros`` of a temporal class.
    otherprotable : str or None
        ``<name>_simplexpros`` (a VERTEX class) or ``<name>_vertexpros`` (a
        CELL class): the properties whose alignment is not ``alignment``.
    """

    name: str
    schema: str
    geotype: Geotype
    alignment: Literal["VERTEX", "CELL"]
    srs: int
    feature_properties: tuple[Property, ...]
    cell_properties: tuple[Property, ...]
    featuretable: str
    cellprotable: str
    viewname: str
    description: str | None = None
    time_model: Literal["STATIC", "INSTANTS", "EVOLVING"] = "STATIC"
    time_unit: str | None = None
    instant_properties: tuple[Property, ...] = ()
    protable: str | None = None
    otherprotable: str | None = None

    def alignment_of(self, prop: Property) -> Literal["VERTEX", "CELL"]:
        """Whether ``prop`` has a value per vertex or per cell."""
        return prop.alignment or self.alignment

    def aligned(self, alignment: str) -> tuple[Property, ...]:
        """The vertex (``"VERTEX"``) or cell (``"CELL"``) properties, in column order."""
        return tuple(p for p in self.cell_properties if self.alignment_of(p) == alignment)

    def property_table(self, alignment: str) -> str | None:
        """The table of the vertex or cell properties: ``cellprotable`` for the class's alignment, else ``otherprotable``."""
        return self.cellprotable if alignment == self.alignment else self.otherprotable

    @property
    def mesh_class(self) -> type[Mesh]:
        """The mesh type of the features.

        Raises
        ------
        InvalidGeometryError
            For a GEOMETRYCOLLECTION class: its features are
            :class:`~tgsis.mesh.GeometryCollection` objects of meshes of any type.
        """
        return mesh_class(self.geotype)

    def _table(self, name: str) -> sql.Composed:
        return sql.SQL("{}.{}").format(sql.Identifier(self.schema), sql.Identifier(name))


@dataclass
class Feature:
    """A feature fetched from the database.

    Attributes
    ----------
    id : int
        Its geoid.
    feature_class : str
        Name of its class.
    name : str or None
        Geometry name.
    properties : dict
        Per-feature property values (None where NULL).
    mesh : Mesh or GeometryCollection
        Geometry with its vertex or cell properties, in stored id order; a
        GeometryCollection (members in stored order) for GEOMETRYCOLLECTION
        classes.
    """

    id: int
    feature_class: str
    name: str | None
    properties: dict[str, Any] = field(default_factory=dict)
    mesh: Geometry | None = None


# --------------------------------------------------------------------------- classes


_CATALOG_COLUMNS = ("classname, schemaname, geotype, proalignment, srs, feature_properties, cell_properties, "
                    "featuretable, cellprotable, viewname, description, timemodel, timeunit, instant_properties, "
                    "protablename, otherprotable")


def _class_from_row(row: Sequence[Any]) -> FeatureClass:
    def props(value: Any) -> tuple[Property, ...]:
        items = json.loads(value) if isinstance(value, str) else value
        return tuple(Property(p["name"], p["type"], int(p.get("size", 1)), p.get("alignment")) for p in items)

    return FeatureClass(name=row[0], schema=row[1], geotype=Geotype(row[2]), alignment=row[3], srs=int(row[4]),
                        feature_properties=props(row[5]), cell_properties=props(row[6]), featuretable=row[7],
                        cellprotable=row[8], viewname=row[9], description=row[10], time_model=row[11],
                        time_unit=row[12], instant_properties=props(row[13]), protable=row[14], otherprotable=row[15])


def _spec_json(spec: PropertySpec | None) -> str:
    items: list[Any] = list(spec.items()) if isinstance(spec, Mapping) else list(spec or [])

    def item_json(item: Any) -> Any:
        if isinstance(item, Property):
            return {"name": item.name, "type": item.type, "size": item.size, "alignment": item.alignment}
        return list(item) if isinstance(item, (tuple, list)) else item

    return json.dumps([item_json(item) for item in items])


def create_feature_class(
    conn: Conn,
    name: str,
    geotype: Geotype | str,
    *,
    feature_properties: PropertySpec | None = None,
    cell_properties: PropertySpec | None = None,
    alignment: Literal["VERTEX", "CELL"] = "VERTEX",
    srs: int = 0,
    schema: str = "public",
    description: str | None = None,
    time_model: Literal["STATIC", "INSTANTS", "EVOLVING"] = "STATIC",
    time_unit: str | None = None,
    instant_properties: PropertySpec | None = None,
) -> FeatureClass:
    """Register a feature class (``tgsis.register_feature_class``).

    Parameters
    ----------
    conn : psycopg.Connection
    name : str
        Class and feature-table name: lower case, no quoting needed.
    geotype : Geotype or str
    feature_properties, cell_properties : mapping or sequence of (name, type)
        Property names (letter case kept) and SQL types (see
        ``tgsis.property_types``); order kept. A vertex or cell property may
        be a vector: ``(name, type, k)`` stores an (n, k) mesh property as
        one array column of k values. A :class:`Property` item may give its
        own ``alignment`` (``Property("facies", "integer",
        alignment="CELL")`` in a VERTEX class): a class may have vertex and
        cell properties side by side.
    alignment : {"VERTEX", "CELL"}
    srs : int
    schema : str
        Existing schema for the class's tables (not ``tgsis`` nor a system
        schema). The tables belong to tgsis's owner; the caller must be a
        ``tgsis_admin`` with ``CREATE`` on the schema (docs/security.md).
    description : str, optional
    time_model : {"STATIC", "INSTANTS", "EVOLVING"}
        ``"INSTANTS"``: surfaces known at instants (model 2,
        :class:`~tgsis.temporal.SurfaceSeries`); ``"EVOLVING"``: continuously
        evolving surfaces (model 3, :class:`~tgsis.temporal.EvolvingSurface`).
        Temporal classes hold SURFACE features.
    time_unit : str, optional
        Unit of model time (e.g. ``"Ma"``, ages stored as negative numbers).
    instant_properties : mapping or sequence of (name, type), optional
        Per-instant feature properties of a temporal class (``<name>_pros``).

    Raises
    ------
    InvalidNameError, InvalidPropertyError, InvalidInputError, AlreadyExistsError, NotFoundError,
    MissingPrivilegeError
    """
    geotype_value = geotype.value if isinstance(geotype, Geotype) else str(geotype)
    with reraise(), conn.transaction():
        row = conn.execute(
            f"SELECT {_CATALOG_COLUMNS} FROM tgsis.register_feature_class(%s, %s, %s::jsonb, %s::jsonb, %s, %s, %s, %s, "
            "%s, %s::jsonb, %s)",
            (name, geotype_value, _spec_json(feature_properties), _spec_json(cell_properties), alignment, srs,
             schema, description, time_model, _spec_json(instant_properties), time_unit),
        ).fetchone()
    assert row is not None
    return _class_from_row(row)


def get_feature_class(conn: Conn, name: str) -> FeatureClass:
    """The class called ``name``.

    Raises
    ------
    NotFoundError
        No such class.
    """
    with reraise():
        row = conn.execute(f"SELECT {_CATALOG_COLUMNS} FROM tgsis.catalog WHERE classname = %s", (name,)).fetchone()
    if row is None:
        raise NotFoundError(f"feature class {name!r} does not exist", hint="`tgsis class list` shows the classes")
    return _class_from_row(row)


def list_feature_classes(conn: Conn) -> list[FeatureClass]:
    """All feature classes, by name."""
    with reraise():
        rows = conn.execute(f"SELECT {_CATALOG_COLUMNS} FROM tgsis.catalog ORDER BY classname").fetchall()
    return [_class_from_row(r) for r in rows]


def drop_feature_class(conn: Conn, name: str, *, force: bool = False) -> int:
    """Drop a class; with ``force`` also its features. Returns the number of features deleted.

    Raises
    ------
    NotFoundError, InUseError, MissingPrivilegeError (the caller is no ``tgsis_admin``)
    """
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.drop_feature_class(%s, %s)", (name, force)).fetchone()
    return int(row[0]) if row else 0


# --------------------------------------------------------------------------- upload


def stores_part_column(fc: FeatureClass) -> bool:
    """Whether the class keeps the ``part`` cell property in a column of its own (else: in ``tgsis.part``)."""
    return any(p.name == "part" and fc.alignment_of(p) == "CELL" for p in fc.cell_properties)


def _cell_properties(fc: FeatureClass, mesh: Mesh) -> dict[str, npt.NDArray[Any]]:
    """The mesh's cell properties but ``part`` when that goes to ``tgsis.part``."""
    if stores_part_column(fc):
        return dict(mesh.cell_properties)
    return {k: v for k, v in mesh.cell_properties.items() if k != "part"}


def _aligned_properties(fc: FeatureClass, mesh: Mesh, drop_extra: bool,
                        what: str = "the mesh") -> dict[str, npt.NDArray[Any]]:
    """The mesh properties the class stores, checked and cast to the column types (``what`` names the mesh).

    The ``part`` cell property is not one of them unless the class has a
    ``part`` cell column: it is stored in ``tgsis.part``.
    """
    cells = _cell_properties(fc, mesh)
    sources = {"VERTEX": mesh.vertex_properties, "CELL": cells}
    kinds = {"VERTEX": "vertex", "CELL": mesh.cell_name}
    if fc.otherprotable is None:  # one alignment: the other's properties are extra
        other_alignment = "CELL" if fc.alignment == "VERTEX" else "VERTEX"
        result = class_property_arrays(fc, sources[fc.alignment], sources[other_alignment], kinds[fc.alignment],
                                       drop_extra, what)
    else:  # vertex and cell properties side by side: each side checked against its own columns
        result = {}
        for alignment in ("VERTEX", "CELL"):
            side = replace(fc, cell_properties=fc.aligned(alignment), alignment=alignment)
            result.update(class_property_arrays(side, sources[alignment], {}, kinds[alignment], drop_extra, what))
    for prop in fc.cell_properties:  # (n,) for a scalar property, (n, k) for a vector of k
        kind = kinds[fc.alignment_of(prop)]
        values = result[prop.name]
        if (values.ndim == 1) != (prop.size == 1) or (values.ndim == 2 and values.shape[1] != prop.size):
            shape = "one value" if prop.size == 1 else f"a vector of {prop.size} values"
            got = "one value" if values.ndim == 1 else f"a vector of {values.shape[1]} values"
            raise InvalidPropertyError(f"{kind} property {prop.name!r} of {what} has {got} per element, "
                                       f"but feature class {fc.name} stores {shape}")
    return result


def class_property_arrays(fc: FeatureClass, stored: Mapping[str, npt.NDArray[Any]],
                          other: Mapping[str, npt.NDArray[Any]], kind: str, drop_extra: bool,
                          what: str) -> dict[str, npt.NDArray[Any]]:
    """The class's vertex/cell property arrays (any shape) out of ``stored``, checked and cast to the column types.

    ``other`` holds the properties of the other alignment (never stored);
    ``kind`` and ``what`` name them and their owner in messages.
    """
    wanted = {p.name: p for p in fc.cell_properties}
    missing = sorted(set(wanted) - set(stored))
    if missing:
        raise InvalidPropertyError(f"feature class {fc.name} needs {kind} properties {missing}, which {what} lacks")
    extra = sorted(set(stored) - set(wanted)) + sorted(other)
    if extra and not drop_extra:
        raise InvalidPropertyError(
            f"feature class {fc.name} has no column for properties {extra} of {what}",
            hint=f"it stores {fc.alignment.lower()} properties {sorted(wanted) or 'none'}; "
                 "drop the others (drop_extra_properties=True) or register them in the class",
        )
    if extra:
        log.warning("not stored by feature class %s: properties %s of %s", fc.name, extra, what)
    result: dict[str, npt.NDArray[Any]] = {}
    for prop in fc.cell_properties:
        values = stored[prop.name]
        target = numpy_dtype(SQL_TYPES[prop.type])
        cast = values.astype(target)
        if target.kind in "iub" and not np.array_equal(cast, values):
            raise InvalidPropertyError(f"{kind} property {prop.name!r} has values that are not {prop.type} "
                                       f"in {what}")
        result[prop.name] = cast
    return result


def _feature_columns(fc: FeatureClass, properties: Mapping[str, Any] | None) -> dict[str, Any]:
    known = {p.name for p in fc.feature_properties}
    values = dict(properties or {})
    unknown = sorted(set(values) - known)
    if unknown:
        raise InvalidPropertyError(f"feature class {fc.name} has no feature properties {unknown}",
                                   hint=f"its feature properties: {sorted(known) or 'none'}")
    return {k: (json.dumps(v) if isinstance(v, (dict, list)) else v) for k, v in values.items()}


def _copy_in(conn: Conn, table: sql.Composable, columns: Sequence[str], payload: bytes) -> None:
    statement = sql.SQL("COPY {} ({}) FROM STDIN (FORMAT binary)").format(
        table, sql.SQL(", ").join(sql.Identifier(c) for c in columns))
    with conn.cursor().copy(statement) as copy:
        copy.write(payload)


@dataclass(frozen=True)
class _Storage:
    """Where bulk rows go: the tables themselves, or for versioned tables their
    ``_ver`` storage with the session's working revision (no trigger per row).

    ``version`` and ``viewing`` are the session's working version and viewing
    revision when it is *not* in DEFAULT's working revision (else ``None``):
    then a write to a plain table is refused (:meth:`check`), since it would
    land in DEFAULT.
    """

    versioned: frozenset[tuple[str, str]]
    revision: int | None
    version: str | None = None
    viewing: int | None = None

    @classmethod
    def of(cls, conn: Conn) -> _Storage:
        versioned = frozenset((r[0], r[1]) for r in conn.execute(
            "SELECT schemaname, tablename FROM tgsis.versioned_tables").fetchall())
        session = conn.execute(
            "SELECT tgsis.get_working_version(), tgsis.get_viewing_revision(), "
            "(SELECT workingrevision FROM tgsis.versions WHERE name = tgsis.get_working_version())").fetchone()
        assert session is not None
        version, viewing, working = session
        elsewhere = version != "DEFAULT" or (viewing is not None and viewing != working)
        if not versioned:
            return cls(versioned, None, version if elsewhere else None, viewing if elsewhere else None)
        row = conn.execute("SELECT revision FROM tgsis.write_revision()").fetchone()  # TG301 when read-only
        assert row is not None
        return cls(versioned, int(row[0]), version if elsewhere else None, viewing if elsewhere else None)

    def check(self, schema: str, table: str) -> None:
        """Refuse a write to a plain ``schema.table`` while the session is not in DEFAULT's working revision.

        Raises
        ------
        NotVersionedError
            The write would land in DEFAULT (nothing is written).
        """
        if self.version is None or (schema, table) in self.versioned:
            return
        if self.version != "DEFAULT":
            raise NotVersionedError(
                f"table {schema}.{table} is not versioned: a write in version {self.version!r} would change DEFAULT, "
                "which every version reads",
                detail=f"the connection works in version {self.version!r}, but feature versioning is off, so the "
                       "feature tables hold one state for all versions; nothing was written",
                hint="tgsis.enable_feature_versioning(conn) to write features in versions, or write in DEFAULT "
                     "(tgsis.goto_version(conn, 'DEFAULT'), or outside tgsis.in_version)")
        raise NotVersionedError(
            f"table {schema}.{table} is not versioned: DEFAULT viewed at revision {self.viewing} cannot be written",
            detail="the connection looks at an older revision; the table holds only the current state; "
                   "nothing was written",
            hint="tgsis.goto_version(conn, 'DEFAULT') to write the current state")

    def copy(self, conn: Conn, schema: str, table: str, columns: Sequence[tuple[str, npt.ArrayLike, str]]) -> None:
        """COPY ``(name, values, wire type)`` columns into ``schema.table`` in the working revision."""
        self.check(schema, table)
        count = len(np.asarray(columns[0][1])) if columns else 0
        if (schema, table) in self.versioned:
            assert self.revision is not None
            table += "_ver"
            columns = [*columns, ("revision", np.full(count, self.revision, dtype=np.int32), "int4")]
        _copy_in(conn, sql.SQL("{}.{}").format(sql.Identifier(schema), sql.Identifier(table)),
                 [name for name, _, _ in columns], encode_rows([(values, wire) for _, values, wire in columns]))


#: metadata key of a collection member that has only some of its class's properties: their names
MEMBER_PROPERTIES_KEY = "tgsis_properties"


def _member_class(fc: FeatureClass, member: Mesh) -> FeatureClass:
    """The class as one member of a collection sees it: the class's properties that the member has."""
    cells = _cell_properties(fc, member)
    kept = tuple(p for p in fc.cell_properties
                 if p.name in (member.vertex_properties if fc.alignment_of(p) == "VERTEX" else cells))
    return fc if len(kept) == len(fc.cell_properties) else replace(fc, cell_properties=kept)


def _with_property_names(meaning: Meaning, fc: FeatureClass, member_class: FeatureClass) -> Meaning:
    """A member's meaning, with the names of the properties it has when it lacks some of the class's."""
    if member_class is fc:
        return meaning
    return replace(meaning, metadata={**(meaning.metadata or {}),
                                      MEMBER_PROPERTIES_KEY: [p.name for p in member_class.cell_properties]})


def _member_label(index: int, mesh: Mesh) -> str:
    """How messages name member ``index`` of a collection."""
    named = f" {mesh.name!r}" if mesh.name else ""
    return f"member {index} ({type(mesh).__name__}{named})"


def _stored_bounds(geometry: Geometry, meanings: Sequence[Meaning]) -> list[float] | None:
    """The box of a mesh or collection in storage's convention (elevation): Depth members' z negated."""
    members = geometry.members if isinstance(geometry, GeometryCollection) else (geometry,)
    boxes = []
    for member, meaning in zip(members, meanings):
        if member.n_vertices:
            box = member.bounds()
            if meaning.depth:
                box = np.array([[box[0, 0], box[0, 1], -box[1, 2]], [box[1, 0], box[1, 1], -box[0, 2]]])
            boxes.append(box)
    if not boxes:
        return None
    stacked = np.stack(boxes)
    return [float(v) for v in np.concatenate([stacked[:, 0].min(axis=0), stacked[:, 1].max(axis=0)])]


def _new_geometry(conn: Conn, geometry: Geometry, name: str | None, meaning: Meaning,
                  member_meanings: Sequence[Meaning], *, collection: int | None = None) -> int:
    """Insert the ``tgsis.geometry`` row of a mesh or collection (bbox and counts from it); return its geoid.

    ``meaning`` is the geometry's own (z convention, coordinate system,
    colour, metadata); ``member_meanings`` those of its members (of a mesh:
    its own), whose z conventions give the stored box.
    """
    bounds = _stored_bounds(geometry, member_meanings)
    geoids: list[int] | None = [] if isinstance(geometry, GeometryCollection) else None  # members come next
    row = conn.execute("SELECT tgsis.new_geometry(%s, %s, %s, %s, %s, %s, %s, 'STATIC', false, %s::real[], %s, "
                       "%s::jsonb, %s::jsonb)",
                       (geometry.geotype.value, name, bounds, geometry.n_vertices, geometry.n_cells, geoids,
                        collection, meaning.color, meaning.zpositive, meaning.crs_json(),
                        meaning.metadata_json())).fetchone()
    assert row is not None
    return int(row[0])


def _concat(arrays: Sequence[npt.NDArray[Any]]) -> npt.NDArray[Any]:
    """The arrays one after the other (no copy for one array)."""
    return arrays[0] if len(arrays) == 1 else np.concatenate(arrays)


def _keys(geoids: Sequence[int], counts: Sequence[int]) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """(geoid, local id) columns for ``counts[i]`` rows of each ``geoids[i]``: ids 0..counts[i]-1."""
    total = int(sum(counts))
    if len(counts) == 1:
        return np.full(total, geoids[0], dtype=np.int64), np.arange(total, dtype=np.int64)
    starts = np.cumsum([0, *counts[:-1]])
    return (np.repeat(np.asarray(geoids, dtype=np.int64), counts),
            np.arange(total, dtype=np.int64) - np.repeat(starts, counts).astype(np.int64))


def _copy_meshes(conn: Conn, fc: FeatureClass, geoids: Sequence[int], meshes: Sequence[Mesh],
                 cell_values: Sequence[Mapping[str, npt.NDArray[Any]]], storage: _Storage,
                 meanings: Sequence[Meaning]) -> None:
    """COPY the vertices, simplices and cell properties of meshes: one COPY per table, whatever their number.

    Parameters
    ----------
    geoids : sequence of int
        Geometry row of each mesh.
    meshes : sequence of Mesh
        Of any of the four types.
    cell_values : sequence of mapping
        Per mesh, the class's property arrays from :func:`_aligned_properties`:
        (n_i,) for VERTEX alignment, (m_i,) for CELL.
    storage : _Storage
        Plain or versioned targets.
    meanings : sequence of Meaning
        Per mesh: Depth meshes are stored with z negated (elevation); their
        atoms go to ``tgsis.atom``.
    """
    vertex_geoids, vertex_ids = _keys(geoids, [m.n_vertices for m in meshes])
    xyz = _concat([m.vertices for m in meshes])
    if any(meaning.depth for meaning in meanings):
        xyz = xyz.copy()
        flip = np.repeat([meaning.depth for meaning in meanings], [m.n_vertices for m in meshes])
        xyz[flip, 2] = -xyz[flip, 2]  # exact: only the sign bit changes
    storage.copy(conn, "tgsis", "vrtx", [("geoid", vertex_geoids, "int8"), ("vrtxid", vertex_ids, "int8"),
                                         ("x", xyz[:, 0], "float8"), ("y", xyz[:, 1], "float8"), ("z", xyz[:, 2], "float8")])
    for geotype in dict.fromkeys(m.geotype for m in meshes):  # each simplex table once, in member order
        group = [i for i, m in enumerate(meshes) if m.geotype == geotype]
        table, key = _SIMPLEX[geotype]
        k = meshes[group[0]].cell_size
        cell_geoids, cell_ids = _keys([geoids[i] for i in group], [meshes[i].n_cells for i in group])
        cells = _concat([meshes[i].cells for i in group])
        storage.copy(conn, "tgsis", table, [("geoid", cell_geoids, "int8"), (key, cell_ids, "int8"),
                                            *((f"vrtxid{j + 1}", cells[:, j], "int8") for j in range(k))])
    for alignment in ("VERTEX", "CELL"):  # one table per alignment (the class's own: cellprotable)
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if not props or protable is None:
            continue
        # collection members may have some of the properties each: one COPY per set of properties
        groups: dict[tuple[str, ...], list[int]] = {}
        for i, values in enumerate(cell_values):
            groups.setdefault(tuple(p.name for p in props if p.name in values), []).append(i)
        for names, group in groups.items():
            if not names:
                continue
            counts = [meshes[i].n_vertices if alignment == "VERTEX" else meshes[i].n_cells for i in group]
            prop_geoids, prop_ids = _keys([geoids[i] for i in group], counts)
            storage.copy(conn, fc.schema, protable, [
                ("_geoid", prop_geoids, "int8"), ("_idx", prop_ids, "int8"),
                *((p.name, _concat([cell_values[i][p.name] for i in group]), p.wire)
                  for p in props if p.name in names)])
    _copy_extras(conn, fc, geoids, meshes, meanings, storage)


def extra_rows(fc: FeatureClass, geoid: int, mesh: Mesh, meaning: Meaning,
               vertex_ids: npt.NDArray[np.int64] | None = None,
               cell_ids: npt.NDArray[np.int64] | None = None) -> tuple[list[tuple[int, ...]], list[tuple[int, ...]]]:
    """The ``tgsis.atom`` rows ``(geoid, vrtxid, refid, patom)`` and ``tgsis.part`` rows ``(geoid, firstid, lastid, part)`` of a mesh.

    ``vertex_ids``/``cell_ids`` give the database id of each vertex and cell
    (default: 0..n-1, as a first upload numbers them); a run of parts never
    spans a gap in the cell ids.
    """
    atoms = [(geoid, int(vertex_ids[a]) if vertex_ids is not None else a,
              int(vertex_ids[r]) if vertex_ids is not None else r, int(a in meaning.patoms)) for a, r in meaning.atoms]
    parts: list[tuple[int, ...]] = []
    if "part" in mesh.cell_properties and not stores_part_column(fc):
        values = mesh.cell_properties["part"]
        ids = cell_ids if cell_ids is not None else np.arange(mesh.n_cells, dtype=np.int64)
        order = np.argsort(ids, kind="stable")
        ids, values = ids[order], values[order]
        firsts, _, _ = part_runs(values)
        if len(firsts):
            breaks = np.flatnonzero(np.diff(ids) != 1) + 1
            starts = np.union1d(firsts, breaks).astype(np.int64)
            ends = np.concatenate([starts[1:] - 1, [len(ids) - 1]]).astype(np.int64)
            numbers = values[starts].astype(np.int64)
            parts = [(geoid, int(f), int(last), int(n)) for f, last, n in zip(ids[starts], ids[ends], numbers)]
    return list(atoms), parts


def copy_extra_rows(conn: Conn, storage: _Storage, atoms: Sequence[tuple[int, ...]],
                    parts: Sequence[tuple[int, ...]]) -> None:
    """COPY rows of :func:`extra_rows` into ``tgsis.atom`` and ``tgsis.part``."""
    if atoms:
        columns = np.asarray(atoms, dtype=np.int64).T
        storage.copy(conn, "tgsis", "atom", [("geoid", columns[0], "int8"), ("vrtxid", columns[1], "int8"),
                                             ("refid", columns[2], "int8"), ("patom", columns[3] != 0, "bool")])
    if parts:
        columns = np.asarray(parts, dtype=np.int64).T
        storage.copy(conn, "tgsis", "part", [("geoid", columns[0], "int8"), ("firstid", columns[1], "int8"),
                                             ("lastid", columns[2], "int8"),
                                             ("part", columns[3].astype(np.int32), "int4")])


def _copy_extras(conn: Conn, fc: FeatureClass, geoids: Sequence[int], meshes: Sequence[Mesh],
                 meanings: Sequence[Meaning], storage: _Storage) -> None:
    """COPY the atoms (``tgsis.atom``) and parts (``tgsis.part``) of freshly uploaded meshes."""
    atoms: list[tuple[int, ...]] = []
    parts: list[tuple[int, ...]] = []
    for geoid, mesh, meaning in zip(geoids, meshes, meanings):
        more_atoms, more_parts = extra_rows(fc, geoid, mesh, meaning)
        atoms += more_atoms
        parts += more_parts
    copy_extra_rows(conn, storage, atoms, parts)


def insert_feature(
    conn: Conn,
    feature_class: str | FeatureClass,
    mesh: Geometry | SurfaceSeries | EvolvingSurface,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    drop_extra_properties: bool = False,
) -> int:
    """Store a mesh (or a collection of meshes, or a temporal surface) as a new feature; return its id (geoid).

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
    mesh : Mesh or GeometryCollection
        Of the class's geotype, with exactly the class's vertex (or cell)
        properties; for a GEOMETRYCOLLECTION class a GeometryCollection whose
        every member has them. For a temporal class a
        :class:`~tgsis.temporal.SurfaceSeries` (INSTANTS) or
        :class:`~tgsis.temporal.EvolvingSurface` (EVOLVING), stored by
        :func:`tgsis.db.temporal.insert_series` / ``insert_evolving``.
    properties : mapping, optional
        Per-feature property values; missing ones are NULL.
    name : str, optional
        Geometry name (default: ``mesh.name``). Members of a collection keep
        their own names.
    drop_extra_properties : bool
        Ignore mesh properties the class does not store instead of failing.

    Raises
    ------
    NotFoundError, InvalidGeometryError, InvalidPropertyError
        Nothing is written.

    Notes
    -----
    A collection is stored as one ``tgsis.geometry`` row per member (owned by
    the collection: ``collection`` = its geoid) and the collection row
    (``geoids`` = member geoids in order, bbox = union, counts = sums); the
    feature's id is the collection's geoid. One transaction, and one COPY per
    table whatever the number of members.
    """
    fc = feature_class if isinstance(feature_class, FeatureClass) else get_feature_class(conn, feature_class)
    if isinstance(mesh, (SurfaceSeries, EvolvingSurface)):
        from tgsis.db import temporal  # it builds on this module

        if isinstance(mesh, SurfaceSeries):
            return temporal.insert_series(conn, fc, mesh, properties, name=name,
                                          drop_extra_properties=drop_extra_properties)
        return temporal.insert_evolving(conn, fc, mesh, properties, name=name,
                                        drop_extra_properties=drop_extra_properties)
    if fc.time_model != "STATIC":
        raise InvalidGeometryError(f"feature class {fc.name} holds {fc.time_model} surfaces, not a static "
                                   f"{type(mesh).__name__}",
                                   hint="give a tgsis.SurfaceSeries (INSTANTS) or tgsis.EvolvingSurface (EVOLVING)")
    if mesh.geotype != fc.geotype:
        raise InvalidGeometryError(f"feature class {fc.name} holds {fc.geotype.value} features, "
                                   f"not {mesh.geotype.value} ({type(mesh).__name__})")
    members = mesh.members if isinstance(mesh, GeometryCollection) else (mesh,)
    labels = [_member_label(i, m) if isinstance(mesh, GeometryCollection) else "the mesh"
              for i, m in enumerate(members)]
    meanings = [meaning_of(m, label) for m, label in zip(members, labels)]
    if isinstance(mesh, GeometryCollection):  # each member has the class's properties it has
        member_classes = [_member_class(fc, m) for m in members]
        cell_values = [_aligned_properties(c, m, drop_extra_properties, label)
                       for c, m, label in zip(member_classes, members, labels)]
        meanings = [_with_property_names(meaning, fc, c) for meaning, c in zip(meanings, member_classes)]
    else:
        cell_values = [_aligned_properties(fc, m, drop_extra_properties, label) for m, label in zip(members, labels)]
    own_meaning = meaning_of(mesh) if isinstance(mesh, GeometryCollection) else meanings[0]
    feature_values = _feature_columns(fc, properties)

    with reraise(), conn.transaction():
        storage = _Storage.of(conn)
        storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        geoid = _new_geometry(conn, mesh, name if name is not None else mesh.name, own_meaning, meanings)
        if isinstance(mesh, GeometryCollection):
            member_ids = [_new_geometry(conn, m, m.name, meaning, [meaning], collection=geoid)
                          for m, meaning in zip(members, meanings)]
            conn.execute("UPDATE tgsis.geometry SET geoids = %s WHERE geoid = %s", (member_ids, geoid))
        else:
            member_ids = [geoid]
        _copy_meshes(conn, fc, member_ids, members, cell_values, storage, meanings)
        columns = ["_geoid", *feature_values]
        conn.execute(
            sql.SQL("INSERT INTO {} ({}) VALUES ({})").format(
                fc._table(fc.featuretable), sql.SQL(", ").join(sql.Identifier(c) for c in columns),
                sql.SQL(", ").join(sql.Placeholder() for _ in columns)),
            [geoid, *feature_values.values()])
    log.info("stored %s feature %d: %d vertices, %d cells%s", fc.name, geoid, mesh.n_vertices, mesh.n_cells,
             f" in {len(members)} members" if isinstance(mesh, GeometryCollection) else "")
    return geoid


# --------------------------------------------------------------------------- download


def _copy_out(conn: Conn, query: sql.Composable, types: Sequence[str]) -> list[npt.NDArray[Any]]:
    statement = sql.SQL("COPY ({}) TO STDOUT (FORMAT binary)").format(query)
    with conn.cursor().copy(statement) as copy:
        data = b"".join(bytes(chunk) for chunk in copy)
    return decode_rows(data, types)


def _split(geoids: npt.NDArray[np.int64], ids: npt.NDArray[np.int64],
           wanted: Sequence[int]) -> dict[int, npt.NDArray[np.int64]]:
    """Row positions of each wanted geoid, ordered by the local id."""
    def ascending(values: npt.NDArray[np.int64]) -> bool:
        return bool(np.all(values[1:] >= values[:-1]))

    if len(wanted) == 1:  # the common case: skip the two-key sort
        order = np.arange(len(ids)) if ascending(ids) else np.argsort(ids, kind="stable")
        return {wanted[0]: order}
    order = np.lexsort((ids, geoids))
    sorted_geoids = geoids[order]
    starts = np.searchsorted(sorted_geoids, wanted, side="left")
    ends = np.searchsorted(sorted_geoids, wanted, side="right")
    return {g: order[s:e] for g, s, e in zip(wanted, starts.tolist(), ends.tolist())}


def _positions(ids: npt.NDArray[np.int64], lookup: npt.NDArray[np.int64], what: str, geoid: int) -> npt.NDArray[np.int64]:
    """Indices of ``lookup`` values in the sorted ``ids`` (vertex ids to mesh indices)."""
    if len(ids) and ids[-1] - ids[0] == len(ids) - 1:
        positions = lookup - ids[0] if ids[0] else lookup  # ids k..k+n-1 (unique): index = id - k
        if len(lookup) and (positions.min() < 0 or positions.max() >= len(ids)):
            raise InvalidGeometryError(f"geometry {geoid}: {what} refer to missing vertices",
                                       hint=f"SELECT * FROM tgsis.check_geometry({geoid})")
        return positions
    positions = np.searchsorted(ids, lookup)
    if len(lookup) and (np.any(positions >= len(ids)) or np.any(ids[np.minimum(positions, len(ids) - 1)] != lookup)):
        raise InvalidGeometryError(f"geometry {geoid}: {what} refer to missing vertices",
                                   hint=f"SELECT * FROM tgsis.check_geometry({geoid})")
    return positions


@dataclass(frozen=True)
class _Part:
    """A geometry to download: its geotype, name, how messages name it, and what its file meant."""

    geotype: Geotype
    name: str | None
    label: str
    zpositive: str | None = None
    crs: list[str] | None = None
    color: tuple[float | None, ...] | None = None
    metadata: dict[str, Any] | None = None
    properties: tuple[str, ...] | None = None  # a collection member's properties when it lacks some (None: all)


#: the columns of tgsis.geometry that _part_meaning reads, after geotype and name
MEANING_COLUMNS = "g.zpositive, g.crs, g.colorred, g.colorgreen, g.colorblue, g.metadata"


def _part_meaning(row: Sequence[Any], member: bool = False) -> dict[str, Any]:
    """_Part keyword arguments from the values of :data:`MEANING_COLUMNS` (``member``: of a collection member)."""
    meaning = {"zpositive": row[0], "crs": row[1], "color": tuple(row[2:5]) if row[2] is not None else None,
               "metadata": row[5]}
    if member and isinstance(row[5], dict) and MEMBER_PROPERTIES_KEY in row[5]:
        metadata = dict(row[5])
        names = metadata.pop(MEMBER_PROPERTIES_KEY)
        meaning["metadata"] = metadata or None
        meaning["properties"] = tuple(str(n) for n in names) if isinstance(names, list) else ()
    return meaning


def _collection_members(conn: Conn, fc: FeatureClass, wanted: Sequence[int]) -> dict[int, list[tuple[int, _Part]]]:
    """Members of each collection in ``wanted``, in stored order: ``{collection: [(member geoid, part)]}``."""
    rows = conn.execute(
        f"SELECT c.geoid, m.geoid, g.geotype, g.geoname, {MEANING_COLUMNS} FROM tgsis.geometry c "
        "CROSS JOIN LATERAL unnest(c.geoids) WITH ORDINALITY AS m(geoid, ord) "
        "LEFT JOIN tgsis.geometry g ON g.geoid = m.geoid "
        "WHERE c.geoid = ANY(%s) ORDER BY c.geoid, m.ord", (list(wanted),)).fetchall()
    members: dict[int, list[tuple[int, _Part]]] = {int(g): [] for g in wanted}
    for cid, mid, geotype, geoname, *meaning in rows:
        where = f"member {len(members[cid])} (geometry {mid}) of feature {cid} of class {fc.name}"
        if geotype is None:
            raise InvalidGeometryError(f"{where} does not exist", hint=f"SELECT * FROM tgsis.check_geometry({cid})")
        if geotype == Geotype.GEOMETRYCOLLECTION.value:
            raise InvalidGeometryError(f"{where} is a GEOMETRYCOLLECTION: collections do not nest",
                                       hint=f"SELECT * FROM tgsis.check_geometry({cid})")
        members[cid].append((int(mid), _Part(Geotype(geotype), geoname, where, **_part_meaning(meaning, member=True))))
    empty = [cid for cid, listed in members.items() if not listed]
    if empty:
        raise InvalidGeometryError(f"feature(s) {empty} of class {fc.name} are collections without members",
                                   hint="a collection lists its members in tgsis.geometry.geoids")
    return members


@dataclass
class _Download:
    """What the COPYs of :func:`_download` returned (columns as numpy arrays)."""

    vertices: list[npt.NDArray[Any]]
    cells: dict[Geotype, list[npt.NDArray[Any]]]
    #: per (alignment, property names): _geoid, _idx, one array per property (collection members may
    #: have some of the class's properties each: one COPY per set)
    properties: dict[tuple[str, tuple[str, ...]], list[npt.NDArray[Any]]]
    atoms: dict[int, list[tuple[int, int, bool]]] = field(default_factory=dict)
    parts: dict[int, list[tuple[int, int, int]]] = field(default_factory=dict)


def _download(conn: Conn, fc: FeatureClass, parts: Mapping[int, _Part]) -> _Download:
    """COPY the vertices, simplices and cell properties of the geometries ``parts``.

    One COPY for the vertices, one per geotype for the simplices, one for the
    properties: a bounded number whatever the number of geometries.
    """
    id_list = sql.Literal(list(parts))
    vertices = _copy_out(conn, sql.SQL("SELECT geoid, vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = ANY({})").format(
        id_list), ["int8", "int8", "float8", "float8", "float8"])
    cells: dict[Geotype, list[npt.NDArray[Any]]] = {}
    for geotype in dict.fromkeys(part.geotype for part in parts.values()):
        table, key = _SIMPLEX[geotype]
        cell_cols = [f"vrtxid{i + 1}" for i in range(mesh_class(geotype).cell_size)]
        group = sql.Literal([g for g, part in parts.items() if part.geotype == geotype])
        cells[geotype] = _copy_out(conn, sql.SQL("SELECT geoid, {}, {} FROM tgsis.{} WHERE geoid = ANY({})").format(
            sql.Identifier(key), sql.SQL(", ").join(sql.Identifier(c) for c in cell_cols), sql.Identifier(table),
            group), ["int8"] * (2 + len(cell_cols)))
    properties: dict[tuple[str, tuple[str, ...]], list[npt.NDArray[Any]]] = {}
    for alignment in ("VERTEX", "CELL"):  # one COPY per property table (and set of properties)
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if not props or protable is None:
            continue
        for names, members in _property_groups(props, parts).items():
            if names:
                properties[(alignment, names)] = _copy_out(
                    conn, sql.SQL("SELECT _geoid, _idx, {} FROM {} WHERE _geoid = ANY({})").format(
                        sql.SQL(", ").join(sql.Identifier(n) for n in names), fc._table(protable),
                        sql.Literal(members)),
                    ["int8", "int8", *(p.wire for p in props if p.name in names)])
    atoms: dict[int, list[tuple[int, int, bool]]] = {}
    for geoid, vrtxid, refid, patom in conn.execute(sql.SQL(
            "SELECT geoid, vrtxid, refid, patom FROM tgsis.atom WHERE geoid = ANY({}) ORDER BY geoid, vrtxid").format(
            id_list)).fetchall():
        atoms.setdefault(int(geoid), []).append((int(vrtxid), int(refid), bool(patom)))
    runs: dict[int, list[tuple[int, int, int]]] = {}
    for geoid, first, last, number in conn.execute(sql.SQL(
            "SELECT geoid, firstid, lastid, part FROM tgsis.part WHERE geoid = ANY({}) ORDER BY geoid, firstid").format(
            id_list)).fetchall():
        runs.setdefault(int(geoid), []).append((int(first), int(last), int(number)))
    return _Download(vertices, cells, properties, atoms, runs)


def _names_of(props: Sequence[Property], part: _Part) -> tuple[str, ...]:
    """The names of ``props`` that a geometry has (all, but for some collection members)."""
    return tuple(p.name for p in props if part.properties is None or p.name in part.properties)


def _property_groups(props: Sequence[Property], parts: Mapping[int, _Part]) -> dict[tuple[str, ...], list[int]]:
    """The geometries of ``parts`` by the names of ``props`` they have."""
    groups: dict[tuple[str, ...], list[int]] = {}
    for geoid, part in parts.items():
        groups.setdefault(_names_of(props, part), []).append(geoid)
    return groups


def restore_extras(mesh: Mesh, part: _Part, data: _Download, geoid: int, vertex_ids: npt.NDArray[np.int64],
                   cell_ids: npt.NDArray[np.int64], *, file_convention: bool = True) -> Mesh:
    """The mesh with its parts, atoms and (``file_convention``) its file's z convention and metadata back.

    ``vertex_ids``/``cell_ids`` are the database ids of its vertices and cells, ascending.
    """
    runs = data.parts.get(geoid)
    if runs:
        array = np.asarray(runs, dtype=np.int64)
        values = parts_from_runs(cell_ids, array[:, 0], array[:, 1], array[:, 2])
        mesh.cell_properties = {**mesh.cell_properties, "part": values}
    atoms = data.atoms.get(geoid, [])
    pairs: list[tuple[int, int]] = []
    patoms: list[int] = []
    if atoms:
        array = np.asarray([(a, r) for a, r, _ in atoms], dtype=np.int64)
        flags = np.asarray([p for _, _, p in atoms], dtype=bool)
        found = np.isin(array, vertex_ids).all(axis=1)
        positions = np.searchsorted(vertex_ids, array[found])
        pairs = [(int(a), int(r)) for a, r in positions]
        patoms = [int(a) for (a, _), p in zip(positions, flags[found]) if p]
    if file_convention:
        restore_meaning(mesh, part.zpositive, part.crs, part.color, part.metadata, pairs, patoms)
    elif pairs:
        mesh.metadata = {**mesh.metadata, "gocad_atoms": [list(p) for p in pairs]}
        if patoms:
            mesh.metadata["gocad_patoms"] = patoms
    return mesh


def _assemble(fc: FeatureClass, parts: Mapping[int, _Part], data: _Download) -> dict[int, Mesh]:
    """The mesh of every geometry of ``parts`` from the downloaded rows, in stored id order."""
    wanted = list(parts)
    vg, vid, x, y, z = data.vertices
    vertex_rows = _split(vg, vid, wanted)
    prop_rows: dict[int, list[tuple[str, tuple[str, ...], npt.NDArray[np.int64], list[npt.NDArray[Any]]]]] = {}
    for (alignment, names), columns in data.properties.items():
        group = [g for g, part in parts.items() if _names_of(fc.aligned(alignment), part) == names]
        for geoid, rows in _split(columns[0], columns[1], group).items():
            prop_rows.setdefault(geoid, []).append((alignment, names, rows, columns))
    xyz = np.stack([x, y, z], axis=1)
    meshes: dict[int, Mesh] = {}
    for geotype, cells in data.cells.items():
        table, _ = _SIMPLEX[geotype]
        group = [g for g, part in parts.items() if part.geotype == geotype]
        cell_rows = _split(cells[0], cells[1], group)
        for geoid in group:
            vrows, crows = vertex_rows[geoid], cell_rows[geoid]
            vertex_ids = vid[vrows]
            simplices = np.stack([_positions(vertex_ids, c[crows], f"{table} rows", geoid) for c in cells[2:]],
                                 axis=1)
            values: dict[str, dict[str, npt.NDArray[Any]]] = {"VERTEX": {}, "CELL": {}}
            for alignment, names, prows, columns in prop_rows.get(geoid, []):
                target_ids = vertex_ids if alignment == "VERTEX" else cells[1][crows]
                if len(prows) != len(target_ids) or not np.array_equal(columns[1][prows], target_ids):
                    raise InvalidPropertyError(
                        f"{parts[geoid].label}: {fc.property_table(alignment)} has {len(prows)} rows for "
                        f"{len(target_ids)} {'vertices' if alignment == 'VERTEX' else 'cells'}")
                values[alignment] = {name: columns[2 + i][prows] for i, name in enumerate(names)}
            meshes[geoid] = restore_extras(mesh_class(geotype)(
                xyz[vrows], simplices, vertex_properties=values["VERTEX"], cell_properties=values["CELL"],
                name=parts[geoid].name), parts[geoid], data, geoid, vertex_ids, cells[1][crows])
    return meshes


def fetch_features(conn: Conn, feature_class: str | FeatureClass,
                   ids: Sequence[int] | None = None) -> list[Feature]:
    """Fetch features with their meshes and properties (three COPYs for all of them).

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
    ids : sequence of int, optional
        Feature ids (geoids); all features of the class when omitted.

    Returns
    -------
    list of Feature
        In the order of ``ids`` (by id when omitted). For a GEOMETRYCOLLECTION
        class each ``mesh`` is a GeometryCollection with its members in stored
        order; all members of all the features come with one COPY for the
        vertices, one per member geotype for the simplices and one for the
        properties.

    Raises
    ------
    NotFoundError
        An id is not a feature of the class.
    InvalidGeometryError, InvalidPropertyError
        Stored rows that do not make a valid mesh (written by other means:
        see ``tgsis.check_geometry``).
    """
    fc = feature_class if isinstance(feature_class, FeatureClass) else get_feature_class(conn, feature_class)
    if fc.time_model != "STATIC":
        raise InvalidInputError(f"feature class {fc.name} is temporal ({fc.time_model}): its features have a shape "
                                "at each time", hint="tgsis.get_at(conn, id, t) gives the surface at model time t")
    props = [p.name for p in fc.feature_properties]
    is_collection = fc.geotype is Geotype.GEOMETRYCOLLECTION
    fresh = conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
    with reraise(), conn.transaction():
        if fresh:  # one snapshot for the statements below
            conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ READ ONLY")
        rows = conn.execute(
            sql.SQL("SELECT f._geoid, g.geoname, " + MEANING_COLUMNS + "{} FROM {} f "
                    "JOIN tgsis.geometry g ON g.geoid = f._geoid {} ORDER BY f._geoid").format(
                sql.SQL("").join(sql.SQL(", f.{}").format(sql.Identifier(p)) for p in props),
                fc._table(fc.featuretable),
                sql.SQL("WHERE f._geoid = ANY({})").format(sql.Literal(list(ids))) if ids is not None
                else sql.SQL("")),
        ).fetchall()
        found = {int(r[0]): r for r in rows}
        wanted = [int(i) for i in ids] if ids is not None else sorted(found)
        missing = [i for i in wanted if i not in found]
        if missing:
            raise NotFoundError(f"feature class {fc.name} has no feature(s) {missing}")
        if not wanted:
            return []
        members: dict[int, list[tuple[int, _Part]]] = {}
        if is_collection:
            members = _collection_members(conn, fc, list(dict.fromkeys(wanted)))
            parts = {mid: part for listed in members.values() for mid, part in listed}
        else:
            parts = {g: _Part(fc.geotype, found[g][1], f"feature {g} of class {fc.name}",
                              **_part_meaning(found[g][2:8])) for g in wanted}
        data = _download(conn, fc, parts)

    meshes = _assemble(fc, parts, data)
    features = []
    used: set[int] = set()
    for geoid in wanted:
        row = found[geoid]
        geometry: Geometry
        if is_collection:
            member_meshes = []
            for mid, _ in members[geoid]:  # a geometry listed twice comes as two meshes
                member_meshes.append(meshes[mid].copy() if mid in used else meshes[mid])
                used.add(mid)
            own = _part_meaning(row[2:8])
            collection = GeometryCollection(member_meshes, name=row[1])
            restore_meaning(collection, None, own["crs"], own["color"], own["metadata"])
            geometry = collection
        else:
            geometry = meshes[geoid].copy() if geoid in used else meshes[geoid]
            used.add(geoid)
        features.append(Feature(geoid, fc.name, row[1], dict(zip(props, row[8:])), geometry))
    return features


def fetch_feature(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> Feature:
    """One feature with its mesh and properties (see :func:`fetch_features`)."""
    return fetch_features(conn, feature_class, [feature_id])[0]


def features_in_box(conn: Conn, feature_class: str | FeatureClass, bounds: npt.ArrayLike) -> list[int]:
    """Ids of the class's features whose bounding box meets ``bounds`` (GiST index scan).

    A collection's box is the union of its members' boxes.

    Parameters
    ----------
    bounds : (2, 3) array_like
        ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``.
    """
    box = np.asarray(bounds, dtype=np.float64)
    if box.shape != (2, 3) or not np.all(np.isfinite(box)):
        raise InvalidGeometryError(f"a box is [[xmin, ymin, zmin], [xmax, ymax, zmax]], got {box.tolist()}")
    fc = feature_class if isinstance(feature_class, FeatureClass) else get_feature_class(conn, feature_class)
    with reraise():
        rows = conn.execute(
            sql.SQL("SELECT f._geoid FROM {} f JOIN tgsis.geometries_in_box(%s, %s, %s, %s, %s, %s) AS b(geoid) "
                    "ON b.geoid = f._geoid ORDER BY 1").format(fc._table(fc.featuretable)),
            box.ravel().tolist()).fetchall()
    return [int(r[0]) for r in rows]


def class_of_feature(conn: Conn, feature_id: int) -> FeatureClass:
    """The feature class that holds feature ``feature_id``.

    Raises
    ------
    NotFoundError
        No class has a feature with that id.
    """
    for fc in list_feature_classes(conn):
        with reraise():
            row = conn.execute(sql.SQL("SELECT 1 FROM {} WHERE _geoid = %s").format(fc._table(fc.featuretable)),
                               (feature_id,)).fetchone()
        if row is not None:
            return fc
    raise NotFoundError(f"no feature class has a feature {feature_id}", hint="`tgsis ls` lists the features")


def delete_feature(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> bool:
    """Delete a feature with its geometry and properties; ``False`` if it was not there.

    A collection goes with the members it owns (the ones stored with it), not
    with geometries it only lists.
    """
    fc = feature_class if isinstance(feature_class, FeatureClass) else get_feature_class(conn, feature_class)
    with reraise(), conn.transaction():
        exists = conn.execute(sql.SQL("SELECT 1 FROM {} WHERE _geoid = %s").format(fc._table(fc.featuretable)),
                              (feature_id,)).fetchone()
        if exists is None:
            return False
        _Storage.of(conn).check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        conn.execute("SELECT tgsis.delete_geometry(%s)", (feature_id,))
    return True


# Wrong arguments get an error naming them rather than a raw PostgreSQL one (tgsis.arguments).
check_module(globals(), __all__)
