"""PostGIS, when it is installed: tgsis features as PostGIS geometries and back (docs/postgis.md).

The SQL side builds PostGIS's extended WKB itself (``tgsis.ewkb_geometry``),
so :func:`fetch_ewkb` works on any database; :func:`enable_postgis` and
:func:`create_postgis_view` need PostGIS in the database, and
:func:`insert_wkb_feature` stores a PostGIS geometry read by
:func:`tgsis.postgis.mesh_from_wkb` through the ordinary write path.
"""

from __future__ import annotations

from typing import Any, Literal

import psycopg

from tgsis.arguments import checked
from tgsis.errors import reraise
from tgsis.postgis import mesh_from_wkb

__all__ = ["create_postgis_view", "enable_postgis", "fetch_ewkb", "insert_wkb_feature", "postgis_enabled"]


@checked
def postgis_enabled(conn: psycopg.Connection[Any]) -> bool:
    """Whether :func:`enable_postgis` has created tgsis's PostGIS functions in this database."""
    with reraise():
        row = conn.execute("SELECT to_regprocedure('tgsis.postgis_geometry(text, bigint)') IS NOT NULL").fetchone()
    return bool(row and row[0])


@checked
def enable_postgis(conn: psycopg.Connection[Any]) -> str:
    """Create ``tgsis.postgis_geometry`` and ``tgsis.postgis_geometry_at`` (they return PostGIS geometries).

    Run once after PostGIS and tgsis are both installed, in either order (and
    again if PostGIS moves to another schema); :func:`tgsis.install` runs it
    again after an upgrade when it was run before.

    Parameters
    ----------
    conn : psycopg.Connection
        As a member of ``tgsis_admin``.

    Returns
    -------
    str
        The schema PostGIS is installed in.

    Raises
    ------
    InstallationError
        PostGIS is not installed in the database (TG001).
    MissingPrivilegeError
        The role is not a member of ``tgsis_admin``.
    """
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.enable_postgis()").fetchone()
    assert row is not None
    return str(row[0])


@checked
def create_postgis_view(conn: psycopg.Connection[Any], class_name: str) -> str:
    """(Re)create the view ``<class>_postgis``: the class's features with a PostGIS ``geom`` column.

    ``geom`` is ``geometry(TINZ, srs)`` for surfaces (``POLYHEDRALSURFACEZ``
    for tetrahedral solids: their boundary, ``MULTILINESTRINGZ``,
    ``MULTIPOINTZ``, ``GEOMETRYCOLLECTIONZ``), with the class's SRS as
    SRID, so QGIS lists it as a layer; a temporal class gives one row per
    feature and instant (column ``_t``).

    Parameters
    ----------
    conn : psycopg.Connection
        As a member of ``tgsis_admin``.
    class_name : str
        The feature class.

    Returns
    -------
    str
        The view's qualified name.

    Raises
    ------
    InstallationError
        PostGIS is not installed in the database.
    NotFoundError
        No such class.
    AlreadyExistsError
        A relation of that name exists that is not this view.
    MissingPrivilegeError
        The role is not a member of ``tgsis_admin``.
    """
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.create_postgis_view(%s)::text", (class_name,)).fetchone()
    assert row is not None
    return str(row[0])


@checked
def fetch_ewkb(
    conn: psycopg.Connection[Any],
    class_name: str,
    feature_id: int,
    t: float | None = None,
    *,
    convention: Literal["left", "right"] = "left",
) -> bytes | None:
    """A feature as PostGIS EWKB with the class's SRS as SRID; needs no PostGIS in the database.

    Parameters
    ----------
    conn : psycopg.Connection
        Any tgsis reader.
    class_name : str
        The feature's class.
    feature_id : int
        The feature (its ``_geoid``).
    t : float, optional
        Model time: the shape at ``t`` (required for temporal classes).
    convention : {"left", "right"}
        Step convention of model 2 at ``t``.

    Returns
    -------
    bytes or None
        ``TIN Z`` / ``POLYHEDRALSURFACE Z`` / ... EWKB; ``None`` when the
        feature does not exist at ``t``. :func:`tgsis.postgis.mesh_from_wkb`
        reads it back.

    Raises
    ------
    NotFoundError
        No such class or feature in it.
    InvalidInputError
        A temporal feature without ``t``, or a bad ``t`` or ``convention``.
    """
    with reraise():
        if t is None:
            row = conn.execute(
                "SELECT tgsis.ewkb_geometry(%s, tgsis.feature_srid(%s, %s))", (feature_id, class_name, feature_id)
            ).fetchone()
        else:
            row = conn.execute(
                "SELECT tgsis.ewkb_geometry_at(%s, %s, %s, tgsis.feature_srid(%s, %s))",
                (feature_id, float(t), convention, class_name, feature_id),
            ).fetchone()
    assert row is not None
    return None if row[0] is None else bytes(row[0])


@checked
def insert_wkb_feature(
    conn: psycopg.Connection[Any],
    class_name: str,
    data: bytes | bytearray | memoryview | str,
    properties: dict[str, Any] | None = None,
    *,
    name: str | None = None,
) -> int:
    """Store a PostGIS geometry ((E)WKB bytes or hex text) as a new feature; returns its id.

    The geometry is read by :func:`tgsis.postgis.mesh_from_wkb` and stored
    by :func:`tgsis.insert_feature` (so the class may have feature
    properties; vertex and cell properties it cannot carry). Needs no PostGIS
    in the database.

    Raises
    ------
    InvalidGeometryError
        The geometry cannot be read (see :func:`tgsis.postgis.mesh_from_wkb`).
    """
    from tgsis.db.features import insert_feature

    mesh = mesh_from_wkb(data, name=name)
    mesh.metadata.pop("srid", None)
    return insert_feature(conn, class_name, mesh, properties)
