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

import logging
from collections.abc import Callable, Mapping, Sequence
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis import datamodels
from tgsis._zpositive import elevation
from tgsis.arguments import checked, checked_ids
from tgsis.datamodels import StoredObject
from tgsis.db._static import (
    MEANING_COLUMNS,
    Download,
    Part,
    assemble_meshes,
    collection_members,
    copy_meshes,
    download,
    member_class,
    member_label,
    new_static_geometry,
    part_meaning,
    with_property_names,
)
from tgsis.db._static_drawing import drawable_surface, stored_surface
from tgsis.db._transfer import (
    Storage,
    aligned_properties,
    check_class_unchanged,
    check_feature_values,
    consistent_read,
    feature_columns,
    resolve_class,
)
from tgsis.db.classes import (
    FeatureClass,
    Property,
    class_of_feature,
    create_feature_class,
    drop_feature_class,
    get_feature_class,
    list_feature_classes,
)
from tgsis.db.meaning import meaning_of, restore_meaning
from tgsis.drawing import Drawable, StoredSurface, drawable
from tgsis.errors import InvalidGeometryError, InvalidInputError, NotFoundError, reraise
from tgsis.gmaps import EvolvingGMap
from tgsis.mesh import ORDERS, Geometry, GeometryCollection, Geotype, Mesh, spatial_order
from tgsis.temporal import EvolvingSurface

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
    "fetch_object",
    "features_in_box",
    "class_of_feature",
    "delete_feature",
]


log = logging.getLogger(__name__)


Conn = psycopg.Connection[Any]


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


@checked
def insert_feature(
    conn: Conn,
    feature_class: str | FeatureClass,
    mesh: StoredObject,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    drop_extra_properties: bool = False,
    tolerance: float | None = None,
    sudden_change: float | None = None,
    order: str = "file",
) -> int:
    """Store a mesh (or a collection of meshes, or a temporal surface) as a new feature; return its id (geoid).

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
    mesh : Mesh or GeometryCollection
        Of the class's geotype, with exactly the class's vertex (or cell)
        properties (a pyvista, meshio or trimesh object is converted by
        :func:`tgsis.as_mesh`, its point and cell data as properties); for
        a GEOMETRYCOLLECTION class a GeometryCollection whose every member
        has them. For a temporal class a
        :class:`~tgsis.temporal.SurfaceSeries` (INSTANTS) or
        :class:`~tgsis.temporal.EvolvingSurface` (EVOLVING), stored by
        :func:`tgsis.db.instants.insert_series` / :func:`tgsis.db.evolving.insert_evolving`. For a
        class of G-maps a :class:`~tgsis.gmaps.GMap` or
        :class:`~tgsis.gmaps.EvolvingGMap`, stored by
        :func:`tgsis.db.gmaps.insert_gmap`.
    properties : mapping, optional
        Per-feature property values; missing ones are NULL.
    name : str, optional
        Geometry name (default: ``mesh.name``). Members of a collection keep
        their own names.
    drop_extra_properties : bool
        Ignore mesh properties the class does not store instead of failing.
    tolerance : float, optional
        An EvolvingSurface or EvolvingGMap: the largest gap allowed between
        the last shape of a topology period and the first shape of the next
        (default: the setting ``tgsis.period_tolerance``, else 1e-6 of the
        object's extent; docs/time.md, "Topology changes").
    sudden_change : float, optional
        An EvolvingSurface or EvolvingGMap: store every topology change as a
        short linear transition of this duration (the design's sudden change).
    order : {"file", "spatial"}
        The order of the stored vertex and cell ids. ``"file"`` (default):
        the mesh's own, ids 0..n-1 as given. ``"spatial"``: the mesh is first
        renumbered by :func:`tgsis.mesh.spatial_order` (vertices along a
        Morton curve, cells by part and smallest corner; properties, atoms
        and the metadata's vertex indices follow), and the geometry's
        metadata records ``"vertex_order": "spatial"``: a fetched feature
        then comes back in that order, not the file's (docs/storage.md,
        "Order of ids at upload"). Static features (model 1: meshes and
        collections, every member renumbered on its own) only.

    Raises
    ------
    DiscontinuousPeriodsError
        A topology period starts away from where the one before ends.
    InvalidInputError
        ``order`` is not one of ``"file"``, ``"spatial"``; or ``"spatial"``
        for a feature that is not static (models 2 to 5).
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
    if order not in ORDERS:
        raise InvalidInputError(f"order {order!r} is not one of {', '.join(map(repr, ORDERS))}")
    fc = resolve_class(conn, feature_class)
    if (tolerance is not None or sudden_change is not None) and not isinstance(mesh, (EvolvingSurface, EvolvingGMap)):
        raise InvalidInputError(
            f"tolerance and sudden_change apply to the topology changes of an EvolvingSurface or "
            f"EvolvingGMap, not to a {type(mesh).__name__}"
        )
    # the topology-change options go only to the models that take them (3 and 4: checked just above)
    options = (
        {} if tolerance is None and sudden_change is None else {"tolerance": tolerance, "sudden_change": sudden_change}
    )
    model = datamodels.model_storing(mesh, fc.time_model)  # the class's model if it stores the object's type
    if model is None:
        from tgsis.convert import as_mesh  # a pyvista, meshio or trimesh object (else: what is accepted)

        mesh = as_mesh(mesh)
        model = datamodels.data_model("STATIC")
    if order == "spatial":
        if model.number != 1 or not isinstance(mesh, (Mesh, GeometryCollection)):
            raise InvalidInputError(
                f"order='spatial' renumbers static meshes and collections only (model 1); feature class "
                f"{fc.name!r} stores this {type(mesh).__name__} as model {model.number} ({model.name}), whose "
                "ids keep their order"
            )
        mesh = spatial_order(mesh)
    return datamodels.storage_of(model).insert(
        conn, fc, mesh, properties, name=name, drop_extra_properties=drop_extra_properties, **options
    )


def _insert_static(
    conn: Conn,
    fc: FeatureClass,
    mesh: Geometry,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    drop_extra_properties: bool = False,
) -> int:
    """Model 1's insert (:func:`insert_feature` of a Mesh or GeometryCollection)."""
    if fc.time_model != "STATIC":
        raise InvalidGeometryError(
            f"feature class {fc.name} holds {fc.time_model} surfaces, not a static {type(mesh).__name__}",
            hint="give a tgsis.SurfaceSeries (INSTANTS) or tgsis.EvolvingSurface (EVOLVING)",
        )
    if mesh.geotype != fc.geotype:
        raise InvalidGeometryError(
            f"feature class {fc.name} holds {fc.geotype.value} features, "
            f"not {mesh.geotype.value} ({type(mesh).__name__})"
        )
    members = mesh.members if isinstance(mesh, GeometryCollection) else (mesh,)
    labels = [member_label(i, m) if isinstance(mesh, GeometryCollection) else "the mesh" for i, m in enumerate(members)]
    meanings = [meaning_of(m, label) for m, label in zip(members, labels)]
    if isinstance(mesh, GeometryCollection):  # each member has the class's properties it has
        member_classes = [member_class(fc, m) for m in members]
        cell_values = [
            aligned_properties(c, m, drop_extra_properties, label)
            for c, m, label in zip(member_classes, members, labels)
        ]
        meanings = [with_property_names(meaning, fc, c) for meaning, c in zip(meanings, member_classes)]
    else:
        cell_values = [aligned_properties(fc, m, drop_extra_properties, label) for m, label in zip(members, labels)]
    own_meaning = meaning_of(mesh) if isinstance(mesh, GeometryCollection) else meanings[0]
    feature_values = feature_columns(fc, properties)

    with reraise(), conn.transaction():
        check_feature_values(conn, fc, feature_values)
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        geoid = new_static_geometry(
            conn, mesh, name if name is not None else mesh.name, own_meaning, meanings, feature_class=fc.name
        )
        if isinstance(mesh, GeometryCollection):
            member_ids = [
                new_static_geometry(conn, m, m.name, meaning, [meaning], collection=geoid)
                for m, meaning in zip(members, meanings)
            ]
            conn.execute("UPDATE tgsis.geometry SET geoids = %s WHERE geoid = %s", (member_ids, geoid))
        else:
            member_ids = [geoid]
        copy_meshes(conn, fc, member_ids, members, cell_values, storage, meanings)
        columns = ["_geoid", *feature_values]
        conn.execute(
            sql.SQL("INSERT INTO {} ({}) VALUES ({})").format(
                fc.qualified(fc.featuretable),
                sql.SQL(", ").join(sql.Identifier(c) for c in columns),
                sql.SQL(", ").join(sql.Placeholder() for _ in columns),
            ),
            [geoid, *feature_values.values()],
        )
        check_class_unchanged(conn, fc)  # a property added meanwhile: this feature has no rows for it
    log.info(
        "stored %s feature %d: %d vertices, %d cells%s",
        fc.name,
        geoid,
        mesh.n_vertices,
        mesh.n_cells,
        f" in {len(members)} members" if isinstance(mesh, GeometryCollection) else "",
    )
    return geoid


@checked
def fetch_features(conn: Conn, feature_class: str | FeatureClass, ids: Sequence[int] | None = None) -> list[Feature]:
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
    ids = checked_ids("ids", ids) if ids is not None else None  # 1.5 is no id (int() would make it 1)
    fc = resolve_class(conn, feature_class)
    if fc.time_model != "STATIC":
        raise InvalidInputError(
            f"feature class {fc.name} is temporal ({fc.time_model}): its features have a shape at each time",
            hint="tgsis.get_at(conn, id, t) gives the surface at model time t",
        )
    props = [p.name for p in fc.feature_properties]
    is_collection = fc.geotype is Geotype.GEOMETRYCOLLECTION

    def read() -> tuple[dict[int, Any], list[int], dict[int, list[tuple[int, Part]]], dict[int, Part], Download | None]:
        """The features' rows, members and meshes' rows of one state (:func:`consistent_read`)."""
        rows = conn.execute(
            sql.SQL(
                "SELECT f._geoid, g.geoname, " + MEANING_COLUMNS + "{} FROM {} f "
                "JOIN tgsis.geometry g ON g.geoid = f._geoid {} ORDER BY f._geoid"
            ).format(
                sql.SQL("").join(sql.SQL(", f.{}").format(sql.Identifier(p)) for p in props),
                fc.qualified(fc.featuretable),
                sql.SQL("WHERE f._geoid = ANY({})").format(sql.Literal(list(ids))) if ids is not None else sql.SQL(""),
            ),
            binary=True,  # float values (properties, colours) bit for bit, whatever the session's extra_float_digits
        ).fetchall()
        found = {int(r[0]): r for r in rows}
        wanted = list(ids) if ids is not None else sorted(found)
        missing = [i for i in wanted if i not in found]
        if missing:
            raise NotFoundError(f"feature class {fc.name} has no feature(s) {missing}")
        members: dict[int, list[tuple[int, Part]]] = {}
        if is_collection:
            members = collection_members(conn, fc, list(dict.fromkeys(wanted)))
            parts = {mid: part for listed in members.values() for mid, part in listed}
        else:
            parts = {
                g: Part(fc.geotype, found[g][1], f"feature {g} of class {fc.name}", **part_meaning(found[g][2:8]))
                for g in wanted
            }
        return found, wanted, members, parts, download(conn, fc, parts) if wanted else None

    with reraise():
        found, wanted, members, parts, data = consistent_read(conn, "fetch_features", read)
    if data is None:
        return []
    meshes = assemble_meshes(fc, parts, data)
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
            own = part_meaning(row[2:8])
            collection = GeometryCollection(member_meshes, name=row[1])
            restore_meaning(collection, None, own["crs"], own["color"], own["metadata"])
            geometry = collection
        else:
            geometry = meshes[geoid].copy() if geoid in used else meshes[geoid]
            used.add(geoid)
        features.append(Feature(geoid, fc.name, row[1], dict(zip(props, row[8:])), geometry))
    return features


@checked
def fetch_feature(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> Feature:
    """One feature with its mesh and properties (see :func:`fetch_features`)."""
    return fetch_features(conn, feature_class, [feature_id])[0]


@checked
def fetch_object(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> Any:
    """The object a feature of any data model stores, read by the model of its class (:mod:`tgsis.datamodels`).

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
    feature_id : int

    Returns
    -------
    Mesh, GeometryCollection, SurfaceSeries, EvolvingSurface, EvolvingGMap, GMap, ...
        What :func:`insert_feature` stored: model 1 as :func:`fetch_feature`'s
        ``mesh``, model 2 as :func:`~tgsis.db.instants.fetch_series`, model 3
        as :func:`~tgsis.db.evolving.fetch_evolving`, model 4 as
        :func:`~tgsis.db.gmaps.fetch_gmap`, model 5 the G-map of
        :func:`~tgsis.db.multidim.fetch_md_gmap` (without its axis names); a model
        added later as its module's fetch function returns.

    Raises
    ------
    NotFoundError
        ``feature_id`` is not a feature of the class.
    InvalidInputError
        No Python module registered the class's data model.
    """
    fc = resolve_class(conn, feature_class)
    return datamodels.storage_of(datamodels.data_model(fc.time_model)).fetch(conn, fc, feature_id)


def _fetch_static(conn: Conn, fc: FeatureClass, feature_id: int) -> Geometry | None:
    """Model 1's fetch: the feature's mesh or collection."""
    return fetch_feature(conn, fc, feature_id).mesh


@checked
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
    fc = resolve_class(conn, feature_class)
    with reraise():
        rows = conn.execute(
            sql.SQL(
                "SELECT f._geoid FROM {} f JOIN tgsis.geometries_in_box(%s, %s, %s, %s, %s, %s) AS b(geoid) "
                "ON b.geoid = f._geoid ORDER BY 1"
            ).format(fc.qualified(fc.featuretable)),
            box.ravel().tolist(),
        ).fetchall()
    return [int(r[0]) for r in rows]


@checked
def delete_feature(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> bool:
    """Delete a feature with its geometry and properties; ``False`` if it was not there.

    A collection goes with the members it owns (the ones stored with it), not
    with geometries it only lists.
    """
    fc = resolve_class(conn, feature_class)
    with reraise(), conn.transaction():
        exists = conn.execute(
            sql.SQL("SELECT 1 FROM {} WHERE _geoid = %s").format(fc.qualified(fc.featuretable)), (feature_id,)
        ).fetchone()
        if exists is None:
            return False
        Storage.of(conn, fc).check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        deleted = conn.execute("SELECT tgsis.delete_geometry(%s)", (feature_id,)).fetchone()
    return bool(deleted is not None and deleted[0])


# --------------------------------------------------------------------------- model 1 in the browser view


def _draw_static(
    conn: Conn,
    fc: FeatureClass,
    feature_id: int,
    t: float | None,
    /,
    *,
    colour: str | None = None,
    beside: Callable[[], AbstractContextManager[Conn]] | None = None,
) -> Drawable:
    """Model 1's drawing (:class:`tgsis.datamodels.DrawFunction`; no time): a surface from its stored rows, else the mesh.

    A surface is the view's own download (:func:`tgsis.db._static_drawing.drawable_surface`:
    the vertices and, through ``beside``, the triangles side by side); other
    geotypes are fetched whole. The view draws z up: a Depth mesh's z is negated.
    """
    if fc.geotype is Geotype.SURFACE:
        if beside is None:
            return drawable_surface(conn, fc, feature_id, colour)
        with beside() as other:
            return drawable_surface(conn, fc, feature_id, colour, beside=other)
    mesh = fetch_feature(conn, fc, feature_id).mesh
    assert mesh is not None
    return drawable(elevation(mesh))


def _surface_static(conn: Conn, fc: FeatureClass, feature_id: int) -> StoredSurface:
    """Model 1's surface for the view's comparisons: a static surface's stored rows with their ids."""
    if fc.geotype is not Geotype.SURFACE:
        raise InvalidInputError(
            f"feature {feature_id} (class {fc.name}) is a {fc.geotype.value}: versions are compared on surfaces"
        )
    return stored_surface(conn, fc, feature_id)


datamodels.register_storage(
    "STATIC", insert=_insert_static, fetch=_fetch_static, draw=_draw_static, surface=_surface_static
)
