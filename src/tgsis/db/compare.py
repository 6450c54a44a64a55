"""Mesh comparison in the database: what changed between two stored geometries, or two versions of one.

Typed wrappers of the SQL functions ``tgsis.compare_geometries`` and
``tgsis.compare_geometry_versions`` (counts, and the ids of removed and added
rows) and, with ``pairs=True``, of ``tgsis.geometry_changes`` and
``tgsis.geometry_version_changes`` (also the kept pairs). The definitions are
those of :func:`tgsis.compare_meshes` (``docs/comparison.md``): a vertex is
kept when the other side has one with numerically equal coordinates, a cell
when its vertices are kept and the other side has the cell on them in the
same orientation; the answers are in stored ids (``vrtxid`` and the cell ids
``pointid``, ``segid``, ``trglid``, ``tetraid``) instead of mesh indices. The
comparison runs in the server: no mesh is downloaded.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.arguments import checked
from tgsis.db.copy import decode_rows
from tgsis.errors import reraise

__all__ = ["GeometryChanges", "compare_stored", "compare_versions"]

Conn = psycopg.Connection[Any]
IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class GeometryChanges:
    """What changed from an old geometry (or version of it) to a new one, in stored ids.

    Attributes
    ----------
    vertices_kept, cells_kept : int
        Numbers of vertices and cells (points, segments, triangles or
        tetrahedra) found on both sides.
    vertices_removed, cells_removed : (r,) int64
        Old ids of the rows the new side does not have, ascending.
    vertices_added, cells_added : (a,) int64
        New ids of the rows the old side does not have, ascending.
    vertex_pairs, cell_pairs : (kept, 2) int64 or None
        With ``pairs=True``: (old id, new id) of each kept row, ascending by
        new id; else None.
    """

    vertices_kept: int
    vertices_removed: IntArray
    vertices_added: IntArray
    cells_kept: int
    cells_removed: IntArray
    cells_added: IntArray
    vertex_pairs: IntArray | None = None
    cell_pairs: IntArray | None = None

    @property
    def identical(self) -> bool:
        """Whether nothing changed (same vertices and oriented cells, whatever their ids and order)."""
        return not (
            len(self.vertices_removed) or len(self.vertices_added) or len(self.cells_removed) or len(self.cells_added)
        )

    def counts(self) -> dict[str, int]:
        """Numbers of kept, removed and added vertices and cells (the keys of :meth:`tgsis.MeshDiff.counts`)."""
        return {
            "vertices_kept": self.vertices_kept,
            "vertices_removed": len(self.vertices_removed),
            "vertices_added": len(self.vertices_added),
            "cells_kept": self.cells_kept,
            "cells_removed": len(self.cells_removed),
            "cells_added": len(self.cells_added),
        }

    def __repr__(self) -> str:
        return "GeometryChanges(" + ", ".join(f"{k}={v}" for k, v in self.counts().items()) + ")"


def _ids(values: Any) -> IntArray:
    return np.asarray(values if values is not None else [], dtype=np.int64)


def _summary(conn: Conn, query: str, params: tuple[Any, ...]) -> GeometryChanges:
    with reraise(), conn.transaction():  # a savepoint: an error leaves the caller's transaction usable
        rows = conn.execute(query, params).fetchall()
    got = {(str(r[0]), str(r[1])): (int(r[2]), r[3]) for r in rows}
    return GeometryChanges(
        vertices_kept=got[("vertex", "kept")][0],
        vertices_removed=_ids(got[("vertex", "removed")][1]),
        vertices_added=_ids(got[("vertex", "added")][1]),
        cells_kept=got[("cell", "kept")][0],
        cells_removed=_ids(got[("cell", "removed")][1]),
        cells_added=_ids(got[("cell", "added")][1]),
    )


def _with_pairs(conn: Conn, changes: sql.Composable) -> GeometryChanges:
    """Read every row of a ``*_changes`` call by binary COPY and split it with numpy."""
    query = sql.SQL(
        "COPY (SELECT CASE c.element WHEN 'vertex' THEN 0 ELSE 1 END::int2, "
        "CASE c.status WHEN 'kept' THEN 0 WHEN 'removed' THEN 1 ELSE 2 END::int2, "
        "coalesce(c.old_id, -1), coalesce(c.new_id, -1) FROM {} c) TO STDOUT (FORMAT binary)"
    ).format(changes)
    with reraise(), conn.transaction(), conn.cursor().copy(query) as copy:
        data = b"".join(bytes(chunk) for chunk in copy)
    element, status, old, new = decode_rows(data, ["int2", "int2", "int8", "int8"])

    def split(code: int) -> tuple[int, IntArray, IntArray, IntArray]:
        mine = element == code
        kept = mine & (status == 0)
        pairs = np.stack([old[kept], new[kept]], axis=1).astype(np.int64).reshape(-1, 2)
        return (
            int(np.count_nonzero(kept)),
            np.sort(old[mine & (status == 1)]).astype(np.int64),
            np.sort(new[mine & (status == 2)]).astype(np.int64),
            pairs[np.argsort(pairs[:, 1], kind="stable")],
        )

    vertices_kept, vertices_removed, vertices_added, vertex_pairs = split(0)
    cells_kept, cells_removed, cells_added, cell_pairs = split(1)
    return GeometryChanges(
        vertices_kept,
        vertices_removed,
        vertices_added,
        cells_kept,
        cells_removed,
        cells_added,
        vertex_pairs,
        cell_pairs,
    )


@checked
def compare_stored(conn: Conn, old_id: int, new_id: int, *, pairs: bool = False) -> GeometryChanges:
    """Compare two stored geometries (as the session's version sees them).

    Parameters
    ----------
    conn : psycopg.Connection
    old_id, new_id : int
        Geometry ids (``geoid``, the feature id of a class's feature) of two
        static geometries of one geotype, not collections.
    pairs : bool
        Also return the (old id, new id) pairs of the kept vertices and
        cells (read by binary COPY; the summary alone is six rows).

    Returns
    -------
    GeometryChanges

    Raises
    ------
    NotFoundError
        A geometry does not exist.
    InvalidInputError
        Different geotypes, a GEOMETRYCOLLECTION or a temporal surface.
    """
    if pairs:
        return _with_pairs(
            conn, sql.SQL("tgsis.geometry_changes({}, {})").format(sql.Literal(old_id), sql.Literal(new_id))
        )
    return _summary(conn, "SELECT * FROM tgsis.compare_geometries(%s, %s)", (old_id, new_id))


@checked
def compare_versions(
    conn: Conn,
    geoid: int,
    old_version: str,
    new_version: str,
    *,
    old_revision: int | None = None,
    new_revision: int | None = None,
    pairs: bool = False,
) -> GeometryChanges:
    """Compare one geometry as two versions (or revisions) see it, without moving the session.

    Parameters
    ----------
    conn : psycopg.Connection
    geoid : int
        A static geometry that exists on both sides, of one geotype there.
    old_version, new_version : str
        Version names (the same name twice compares two revisions of it).
    old_revision, new_revision : int, optional
        A revision in the version's history (default: its working revision).
    pairs : bool
        Also return the kept (old id, new id) pairs, as :func:`compare_stored`.

    Returns
    -------
    GeometryChanges

    Raises
    ------
    NotFoundError
        An unknown version, a revision outside the version's history, or a
        geometry that does not exist on one side.
    InvalidInputError
        Model 1 is not versioned (:func:`tgsis.enable_feature_versioning`),
        or the geometry is a collection, a temporal surface, or of two
        geotypes.
    """
    if pairs:
        return _with_pairs(
            conn,
            sql.SQL("tgsis.geometry_version_changes({}, {}, {}, {}, {})").format(
                sql.Literal(geoid),
                sql.Literal(old_version),
                sql.Literal(new_version),
                sql.Literal(old_revision),
                sql.Literal(new_revision),
            ),
        )
    return _summary(
        conn,
        "SELECT * FROM tgsis.compare_geometry_versions(%s, %s, %s, %s, %s)",
        (geoid, old_version, new_version, old_revision, new_revision),
    )
