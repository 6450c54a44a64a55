"""The cube extension's functions and type, named by the schema cube is installed in.

tgsis stores boxes (``tgsis.geometry.bbox``, ``tgsis.md_gmap.extent``) as
``cube`` values. Its SQL functions pin their own ``search_path``, but the
statements this library composes run under the session's: a DBA may
install cube in a schema of its own and a user may empty the path (``SET
search_path = ''``). So every statement names cube's objects by schema,
through these helpers, never bare.
"""

from __future__ import annotations

from typing import Any

import psycopg
from psycopg import sql

__all__ = ["box_corners", "box_coordinates", "cube_name"]

Conn = psycopg.Connection[Any]


def cube_name(conn: Conn, name: str) -> sql.Identifier:
    """``name`` (a function of the cube extension, or ``cube`` the type) qualified by cube's schema."""
    row = conn.execute(
        "SELECT n.nspname FROM pg_catalog.pg_extension e JOIN pg_catalog.pg_namespace n ON n.oid = e.extnamespace"
        " WHERE e.extname = 'cube'"
    ).fetchone()
    assert row is not None  # tgsis requires cube: CREATE EXTENSION tgsis CASCADE / the plain install create it
    return sql.Identifier(str(row[0]), name)


def box_corners(conn: Conn, box: sql.Composable, order: str = "xyz") -> sql.Composed:
    """The six float8 corner values of the 3D cube ``box``, as a comma-separated select list.

    ``order`` "xyz": xmin, ymin, zmin, xmax, ymax, zmax; "axes": xmin, xmax,
    ymin, ymax, zmin, zmax.
    """
    ll, ur = cube_name(conn, "cube_ll_coord"), cube_name(conn, "cube_ur_coord")
    low = [sql.SQL("{}({}, {})").format(ll, box, sql.Literal(i)) for i in (1, 2, 3)]
    high = [sql.SQL("{}({}, {})").format(ur, box, sql.Literal(i)) for i in (1, 2, 3)]
    if order == "xyz":
        return sql.SQL(", ").join(low + high)
    if order == "axes":
        return sql.SQL(", ").join([v for pair in zip(low, high, strict=True) for v in pair])
    raise ValueError(f"order {order!r} is not xyz or axes")


def box_coordinates(conn: Conn, box: sql.Composable) -> sql.Composed:
    """The cube ``box``'s 2m coordinates as stored (low corner, then high), as one ``float8[]`` expression.

    For comparing a stored box with a measured one: :func:`box_corners` reads
    through ``cube_ll_coord`` / ``cube_ur_coord``, which take the least and the
    greatest of a corner pair by ``<`` and ``>`` and so hide a NaN (a box
    ``(NaN, 0, 0),(1, 1, 1)`` reads as ``(1, 0, 0),(1, 1, 1)``); these are the
    coordinates ``cube(low, high)`` stored, which ``float8[]``'s equality
    compares with NaN equal to NaN.
    """
    return sql.SQL("ARRAY(SELECT {coord}({box}, d) FROM generate_series(1, 2 * {dim}({box})) AS d ORDER BY d)").format(
        coord=cube_name(conn, "cube_coord"), dim=cube_name(conn, "cube_dim"), box=box
    )
