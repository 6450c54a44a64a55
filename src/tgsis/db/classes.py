"""Feature classes: register, look up, list, edit and drop them (``tgsis.catalog``).

Every data model's features belong to a feature class; the model-specific
write and read paths (:mod:`tgsis.db.features` for model 1,
:mod:`tgsis.db.instants` and :mod:`tgsis.db.evolving` for models 2 and 3, ...) take a :class:`FeatureClass`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import psycopg
from psycopg import sql

from tgsis.arguments import checked
from tgsis.datamodels import TimeModel
from tgsis.db.copy import SQL_TYPES, array_wire
from tgsis.errors import NotFoundError, reraise
from tgsis.mesh import Geotype, Mesh, mesh_class

__all__ = [
    "Property",
    "FeatureClass",
    "create_feature_class",
    "get_feature_class",
    "list_feature_classes",
    "drop_feature_class",
    "add_property",
    "rename_property",
    "drop_property",
    "fill_property_rows",
    "class_of_feature",
    "stores_part_column",
]

Conn = psycopg.Connection[Any]
PropertySpec = Mapping[str, str] | Sequence["tuple[str, str] | tuple[str, str, int] | Property | Mapping[str, Any]"]
#: Which list of a class a property is in: per feature, per vertex or cell, per feature and instant.
PropertyKind = Literal["feature", "cell", "instant"]


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
    time_model : str
        The time model of a registered data model (:func:`tgsis.data_models`):
        model 1 (static), model 2 (surfaces at instants), model 3
        (continuously evolving surfaces), model 4 (G-maps in time) or model 5
        (multiply indexed G-maps).
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
    cell_level : int or None
        A class of G-maps: the dimension of the cells its ``cell_properties``
        belong to (``_idx`` is an abstract cell id).
    versioned : bool
        ``True``: versioned with every class while feature versioning is on;
        ``False``: registered without versioning: its features hold one
        state, which every version sees, written in DEFAULT only.
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
    time_model: TimeModel = "STATIC"
    time_unit: str | None = None
    instant_properties: tuple[Property, ...] = ()
    protable: str | None = None
    otherprotable: str | None = None
    cell_level: int | None = None
    versioned: bool = True

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

    def qualified(self, name: str) -> sql.Composed:
        """``schema.name`` of one of the class's tables, quoted for SQL."""
        return sql.SQL("{}.{}").format(sql.Identifier(self.schema), sql.Identifier(name))


_CATALOG_COLUMNS = (
    "classname, schemaname, geotype, proalignment, srs, feature_properties, cell_properties, "
    "featuretable, cellprotable, viewname, description, timemodel, timeunit, instant_properties, "
    "protablename, otherprotable, celllevel, versioned"
)


def _class_from_row(row: Sequence[Any]) -> FeatureClass:
    def props(value: Any) -> tuple[Property, ...]:
        items = json.loads(value) if isinstance(value, str) else value
        return tuple(Property(p["name"], p["type"], int(p.get("size", 1)), p.get("alignment")) for p in items)

    return FeatureClass(
        name=row[0],
        schema=row[1],
        geotype=Geotype(row[2]),
        alignment=row[3],
        srs=int(row[4]),
        feature_properties=props(row[5]),
        cell_properties=props(row[6]),
        featuretable=row[7],
        cellprotable=row[8],
        viewname=row[9],
        description=row[10],
        time_model=row[11],
        time_unit=row[12],
        instant_properties=props(row[13]),
        protable=row[14],
        otherprotable=row[15],
        cell_level=None if row[16] is None else int(row[16]),
        versioned=bool(row[17]),
    )


def _spec_json(spec: PropertySpec | None) -> str:
    items: list[Any] = list(spec.items()) if isinstance(spec, Mapping) else list(spec or [])

    def item_json(item: Any) -> Any:
        if isinstance(item, Property):
            return {"name": item.name, "type": item.type, "size": item.size, "alignment": item.alignment}
        return list(item) if isinstance(item, (tuple, list)) else item

    return json.dumps([item_json(item) for item in items])


@checked
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
    time_model: TimeModel = "STATIC",
    time_unit: str | None = None,
    instant_properties: PropertySpec | None = None,
    cell_level: int | None = None,
    versioned: bool | None = None,
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
        cell properties side by side. An item may also be a mapping as the
        SQL function takes it (``{"name": ..., "type": ..., "size": k}``).
    alignment : {"VERTEX", "CELL"}
    srs : int
    schema : str
        Existing schema for the class's tables (not ``tgsis`` nor a system
        schema). The tables belong to tgsis's owner; the caller must be a
        ``tgsis_admin`` with ``CREATE`` on the schema (docs/security.md).
    description : str, optional
    time_model : str
        The time model of a registered data model (:func:`tgsis.data_models`; ``"STATIC"``: model 1).
        ``"INSTANTS"``: surfaces known at instants (model 2,
        :class:`~tgsis.temporal.SurfaceSeries`); ``"EVOLVING"``: continuously
        evolving surfaces (model 3, :class:`~tgsis.temporal.EvolvingSurface`).
        Temporal classes hold SURFACE features; ``"GMAP"``: n-G-maps in time
        (model 4, :class:`~tgsis.gmaps.EvolvingGMap`), geotype ``"GMAP"``;
        ``"MULTIDIM"``: n-G-maps whose extra axes are time, knowledge or scale
        (model 5, :class:`~tgsis.gmaps.GMap`), geotype ``"GMAP"``.
    time_unit : str, optional
        Unit of model time (e.g. ``"Ma"``, ages stored as negative numbers).
    instant_properties : mapping or sequence of (name, type), optional
        Per-instant feature properties of a temporal class (``<name>_pros``).
    cell_level : int, optional
        A class of G-maps: the dimension of the cells that ``cell_properties``
        belong to (0: vertices, 1: edges, 2: faces, 3: volumes); required for
        ``time_model="GMAP"``, refused otherwise.
    versioned : bool, optional
        Leave it out (or ``True``): the class is versioned when feature
        versioning is on (:func:`~tgsis.enable_feature_versioning`), with
        every other class; ``True`` is refused while it is off
        (:class:`~tgsis.errors.VersioningError`). ``False``: a class without
        versioning, before or after feature versioning is enabled: its
        tables stay plain, its features hold one state that every version
        and revision sees, and they are written in DEFAULT only
        (:class:`~tgsis.errors.NotVersionedError` elsewhere;
        docs/versioning.md, "Versioning per class").

    Raises
    ------
    InvalidNameError, InvalidPropertyError, InvalidInputError, AlreadyExistsError, NotFoundError,
    MissingPrivilegeError, VersioningError (``versioned``), InstallationError (``tgsis.storage`` naming no storage)

    Notes
    -----
    Storage: a STATIC class's vertex and cell property tables are made in
    chunks when model 1 is stored in chunks in the database and the setting
    ``tgsis.storage`` is not ``rows`` (``tgsis.chunk_class_by_default``;
    docs/storage.md, "Property chunks by default: the rule"); a temporal class,
    or one registered under ``SET tgsis.storage = rows``, keeps rows.
    """
    geotype_value = geotype.value if isinstance(geotype, Geotype) else str(geotype)
    with reraise(), conn.transaction():
        row = conn.execute(
            f"SELECT {_CATALOG_COLUMNS} FROM tgsis.register_feature_class(%s, %s, %s::jsonb, %s::jsonb, %s, %s, %s, %s, "
            "%s, %s::jsonb, %s, %s, %s)",
            (
                name,
                geotype_value,
                _spec_json(feature_properties),
                _spec_json(cell_properties),
                alignment,
                srs,
                schema,
                description,
                time_model,
                _spec_json(instant_properties),
                time_unit,
                cell_level,
                versioned,
            ),
        ).fetchone()
    assert row is not None
    return _class_from_row(row)


@checked
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


@checked
def list_feature_classes(conn: Conn) -> list[FeatureClass]:
    """All feature classes, by name."""
    with reraise():
        rows = conn.execute(f"SELECT {_CATALOG_COLUMNS} FROM tgsis.catalog ORDER BY classname").fetchall()
    return [_class_from_row(r) for r in rows]


@checked
def drop_feature_class(conn: Conn, name: str, *, force: bool = False) -> int:
    """Drop a class; with ``force`` also its features. Returns the number of features deleted.

    Raises
    ------
    NotFoundError, InUseError, MissingPrivilegeError (the caller is no ``tgsis_admin``)
    """
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.drop_feature_class(%s, %s)", (name, force)).fetchone()
    return int(row[0]) if row else 0


def _default_text(value: object) -> str | None:
    """A default value as the text PostgreSQL reads (``true``/``false`` for booleans)."""
    if value is None:
        return None
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


@checked
def add_property(
    conn: Conn,
    feature_class: str,
    prop: Property | tuple[str, str] | tuple[str, str, int],
    *,
    kind: PropertyKind = "cell",
    default: object = None,
) -> FeatureClass:
    """Give a class one more property, in every version (``tgsis.add_property``).

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str
        The class's name.
    prop : Property or (name, type) or (name, type, k)
        As :func:`create_feature_class` takes them; a vertex or cell
        property may be a vector of k components, and a :class:`Property`
        may give an ``alignment`` other than the class's if the class has a
        table for that alignment.
    kind : {"feature", "cell", "instant"}
        A value per feature, per vertex or cell (the default), or per feature
        and instant (temporal classes).
    default : optional
        The value every stored row gets (each component of a vector);
        required for a vertex or cell property of a class that has stored
        rows (they may not be NULL); feature and per-instant properties of
        stored rows are NULL without one. New rows give their own values.

    Returns
    -------
    FeatureClass
        The class as it is now (fetch and save its features with this one).

    Raises
    ------
    NotFoundError, InvalidNameError, InvalidPropertyError, AlreadyExistsError, InvalidInputError, InUseError,
    MissingPrivilegeError (the caller is no ``tgsis_admin``)
    """
    if isinstance(prop, Property):
        item: Any = {"name": prop.name, "type": prop.type, "size": prop.size, "alignment": prop.alignment}
    else:
        item = list(prop)
    with reraise(), conn.transaction():
        row = conn.execute(
            f"SELECT {_CATALOG_COLUMNS} FROM tgsis.add_property(%s, %s, %s::jsonb, %s)",
            (feature_class, kind, json.dumps(item), _default_text(default)),
        ).fetchone()
    assert row is not None
    return _class_from_row(row)


@checked
def fill_property_rows(conn: Conn, feature_class: str, values: Mapping[str, object]) -> dict[str, tuple[int, int]]:
    """Give stored features that have no vertex or cell property rows a row per vertex or cell (``tgsis.fill_property_rows``).

    The repair of a class whose features cannot be read ("... has 0 rows for
    N vertices"): a vertex or cell property added by tgsis 0.2.0 or earlier to a
    class registered without one gave the features stored then no rows.
    Each vertex or cell of those features (in every version and revision)
    gets a row holding ``values``; features that have rows keep them.

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str
        The class's name.
    values : mapping of str to str, int, float or bool
        A value for every vertex or cell property of each table whose
        features lack rows (a vector property gets it in each component).

    Returns
    -------
    dict of str to (int, int)
        Per property table of the class: the geometries (features, or
        collection members) and the rows (vertices or cells) given rows.

    Raises
    ------
    NotFoundError, InvalidPropertyError, MissingPrivilegeError (the caller is no ``tgsis_admin``)
    """
    with reraise(), conn.transaction():
        rows = conn.execute(
            "SELECT tablename, features, rows FROM tgsis.fill_property_rows(%s, %s::jsonb)",
            (feature_class, json.dumps(dict(values))),
        ).fetchall()
    return {str(table): (int(features), int(count)) for table, features, count in rows}


@checked
def rename_property(
    conn: Conn, feature_class: str, name: str, new_name: str, *, kind: PropertyKind | None = None
) -> FeatureClass:
    """Rename a property of a class, in every version, keeping its values (``tgsis.rename_property``).

    ``kind`` (``"feature"``, ``"cell"``, ``"instant"``) says which property
    is meant when the class has more than one of that name. Returns the
    class as it is now.

    Raises
    ------
    NotFoundError, InvalidNameError, InvalidPropertyError, AlreadyExistsError, InUseError, MissingPrivilegeError
    """
    with reraise(), conn.transaction():
        row = conn.execute(
            f"SELECT {_CATALOG_COLUMNS} FROM tgsis.rename_property(%s, %s, %s, %s)",
            (feature_class, name, new_name, kind),
        ).fetchone()
    assert row is not None
    return _class_from_row(row)


@checked
def drop_property(
    conn: Conn, feature_class: str, name: str, *, kind: PropertyKind | None = None, force: bool = False
) -> FeatureClass:
    """Drop a property of a class, in every version (``tgsis.drop_property``).

    Refused (:class:`~tgsis.errors.InUseError`) while a stored row of any
    version holds a value of it, unless ``force``. ``kind`` as for
    :func:`rename_property`. Returns the class as it is now.

    Raises
    ------
    NotFoundError, InvalidNameError, InvalidPropertyError, InUseError, MissingPrivilegeError
    """
    with reraise(), conn.transaction():
        row = conn.execute(
            f"SELECT {_CATALOG_COLUMNS} FROM tgsis.drop_property(%s, %s, %s, %s)", (feature_class, name, kind, force)
        ).fetchone()
    assert row is not None
    return _class_from_row(row)


def readable_class_names(conn: Conn) -> set[str]:
    """The classes whose feature table the session's role may read.

    A class in a schema the role may not use is not readable (not an error:
    ``has_table_privilege`` of a name in such a schema raises one).
    """
    rows = conn.execute(
        "SELECT classname FROM tgsis.catalog WHERE CASE WHEN has_schema_privilege(schemaname, 'USAGE') "
        "THEN has_table_privilege(format('%I.%I', schemaname, featuretable), 'SELECT') END"
    ).fetchall()
    return {str(r[0]) for r in rows}


@checked
def class_of_feature(conn: Conn, feature_id: int) -> FeatureClass:
    """The feature class that holds feature ``feature_id``.

    Raises
    ------
    NotFoundError
        No class has a feature with that id.
    """
    classes = list_feature_classes(conn)
    with reraise():
        # only the classes the role may read are looked into (a class it may not read would end the search
        # with a permission error, though the feature may be in a later one)
        readable = readable_class_names(conn)
        for fc in classes:
            if fc.name not in readable:
                continue
            row = conn.execute(
                sql.SQL("SELECT 1 FROM {} WHERE _geoid = %s").format(fc.qualified(fc.featuretable)), (feature_id,)
            ).fetchone()
            if row is not None:
                return fc
    hidden = len(classes) - len(readable & {fc.name for fc in classes})
    raise NotFoundError(
        f"no feature class has a feature {feature_id}"
        + (f" among those this role may read ({hidden} it may not)" if hidden else ""),
        hint="`tgsis ls` lists the features",
    )


def stores_part_column(fc: FeatureClass) -> bool:
    """Whether the class keeps the ``part`` cell property in a column of its own (else: in ``tgsis.part``)."""
    return any(p.name == "part" and fc.alignment_of(p) == "CELL" for p in fc.cell_properties)
