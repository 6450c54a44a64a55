"""Writing one object's mesh by an id-keyed difference of two states (the merges that write, docs/merge.md).

A merge by region gives the merged :class:`tgsis.merge3.MeshState` with the
ids the rows must keep (the parent's never change; the child's new ones as
:attr:`tgsis.merge3.MeshMerge.child_vertex_renumbering` says). Unlike the
check-in by difference (:mod:`tgsis.db.checkin`), which matches an edited
mesh to the stored one and gives new rows fresh ids, nothing is matched
here: a row is the same row when it has the same id. The rows go the way
check-in writes them (``tgsis.delete_object_rows`` closes rows in the
session's working revision, :meth:`Storage.copy` adds row versions there),
so a psql user sees the result through the versioned views like any other
edit, and ``tgsis.revision_objects`` notes it.

Also holds the pieces check-in by difference shares with it (deleting rows
by id, the geometry row's box and counts).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.db._static import SIMPLEX, copy_extra_rows, part_rows
from tgsis.db._transfer import Storage
from tgsis.db.classes import FeatureClass, stores_part_column
from tgsis.db.copy import SQL_TYPES, array_wire
from tgsis.errors import InvalidInputError
from tgsis.merge3 import MeshState

__all__ = [
    "copy_cell_rows",
    "copy_vertex_rows",
    "delete_rows",
    "update_geometry_row",
    "write_state_difference",
    "write_state_rows",
]

Conn = psycopg.Connection[Any]
IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]

#: the vertex property of a :class:`MeshState` read by ``read_merge_states`` that holds the GOCAD atoms (-1: none)
ATOM_PROPERTY = "refid"
#: the cell property that holds the parts when the class keeps them in ``tgsis.part``
PART_PROPERTY = "part"


def delete_rows(conn: Conn, schema: str, table: str, key: str, geoid: int, idfield: str, ids: IntArray) -> int:
    """Delete (close, when versioned) the rows of object ``geoid`` whose ``idfield`` is one of ``ids``; rows affected."""
    if len(ids) == 0:
        return 0
    row = conn.execute(
        "SELECT tgsis.delete_object_rows(%s, %s, %s, %s, %s, %s)",
        (schema, table, key, [geoid], idfield, np.asarray(ids, dtype=np.int64).tolist()),
    ).fetchone()
    return int(row[0]) if row else 0


def update_geometry_row(
    conn: Conn,
    geoid: int,
    bounds: npt.NDArray[np.float64] | None,
    n_vertices: int,
    n_cells: int,
    *,
    name: str | None = None,
    set_name: bool = False,
) -> int:
    """Bring ``tgsis.geometry``'s box and counts (and with ``set_name`` its name) up to date; rows changed (0 when equal).

    ``bounds`` (2, 3): the low and high corners, None for a mesh without vertices (the box is then NULL).
    """
    low, high = bounds.tolist() if bounds is not None else (None, None)
    # the cube extension's functions by their schema: the session's search_path may not hold it
    row = conn.execute(
        "SELECT n.nspname FROM pg_catalog.pg_extension e JOIN pg_catalog.pg_namespace n ON n.oid = e.extnamespace"
        " WHERE e.extname = 'cube'"
    ).fetchone()
    assert row is not None  # tgsis requires cube
    ll, ur = sql.Identifier(str(row[0]), "cube_ll_coord"), sql.Identifier(str(row[0]), "cube_ur_coord")
    box = sql.SQL("{}(%(low)s::float8[], %(high)s::float8[])").format(sql.Identifier(str(row[0]), "cube"))
    corners = sql.SQL("ARRAY[{ll}(bbox, 1), {ll}(bbox, 2), {ll}(bbox, 3), {ur}(bbox, 1), {ur}(bbox, 2), {ur}(bbox, 3)]")
    box_differs = sql.SQL(
        "(bbox IS NULL) <> (%(low)s::float8[] IS NULL) "
        "OR (bbox IS NOT NULL AND {corners} IS DISTINCT FROM %(low)s::float8[] || %(high)s::float8[])"
    ).format(corners=corners.format(ll=ll, ur=ur))
    naming = sql.SQL(", geoname = %(name)s") if set_name else sql.SQL("")
    name_differs = sql.SQL(" OR geoname IS DISTINCT FROM %(name)s") if set_name else sql.SQL("")
    changed = conn.execute(
        sql.SQL(
            "UPDATE tgsis.geometry SET bbox = {box}, nvrtx = %(n)s, ncell = %(m)s{naming} "
            "WHERE geoid = %(g)s AND ({box_differs} OR nvrtx <> %(n)s OR ncell <> %(m)s{differs})"
        ).format(box=box, naming=naming, box_differs=box_differs, differs=name_differs),
        {"low": low, "high": high, "n": n_vertices, "m": n_cells, "name": name, "g": geoid},
    ).rowcount
    return max(changed, 0)


def _bits(rows: npt.NDArray[Any]) -> npt.NDArray[np.uint64]:
    """(n, c) words of rows of numbers, equal words exactly for equal bits (coordinates compare bit for bit)."""
    flat = np.ascontiguousarray(rows).reshape(len(rows), -1)
    if flat.dtype.kind == "f":
        return np.ascontiguousarray(flat.astype(np.float64, copy=False)).view(np.uint64)
    return np.ascontiguousarray(flat.astype(np.int64, copy=False)).view(np.uint64)


def _same_values(a: npt.NDArray[Any], b: npt.NDArray[Any]) -> npt.NDArray[np.bool_]:
    """Per row, whether two property arrays hold the same values (NaN equals NaN: a value that stays NULL is no change)."""
    same: npt.NDArray[np.bool_] = np.asarray(a == b)
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        same = same | (np.isnan(a.astype(np.float64)) & np.isnan(b.astype(np.float64)))
    return np.asarray(same.reshape(len(same), -1).all(axis=1)) if same.ndim > 1 else same


def _difference(old_ids: IntArray, new_ids: IntArray, same: Any) -> tuple[IntArray, npt.NDArray[np.intp]]:
    """(ids to delete, positions in ``new_ids`` to insert) of one table keyed by id.

    ``same(old_positions, new_positions)`` says per common id whether its row is unchanged.
    """
    common, at_old, at_new = np.intersect1d(old_ids, new_ids, assume_unique=True, return_indices=True)
    differ = ~np.asarray(same(at_old, at_new), dtype=bool) if len(common) else np.zeros(0, dtype=bool)
    gone = old_ids[~np.isin(old_ids, common, assume_unique=True)]
    fresh = np.flatnonzero(~np.isin(new_ids, common, assume_unique=True))
    return np.concatenate([gone, common[differ]]).astype(np.int64), np.concatenate([fresh, at_new[differ]])


def _row_difference(
    old_ids: IntArray, old_rows: npt.NDArray[Any], new_ids: IntArray, new_rows: npt.NDArray[Any]
) -> tuple[IntArray, npt.NDArray[np.intp]]:
    old_bits, new_bits = _bits(old_rows), _bits(new_rows)
    return _difference(old_ids, new_ids, lambda a, b: np.all(old_bits[a] == new_bits[b], axis=1))


def _values(state: MeshState, alignment: str, name: str, what: str) -> npt.NDArray[Any]:
    props = state.vertex_properties if alignment == "VERTEX" else state.cell_properties
    if name not in props:
        raise InvalidInputError(f"{state.name}: the {what} state has no {alignment.lower()} property {name!r}")
    return np.asarray(props[name])


def _without_row(values: list[npt.NDArray[Any]], at: npt.NDArray[np.intp]) -> npt.NDArray[np.bool_]:
    """Per position ``at``, whether every property value there is NaN (no property row in the state)."""
    empty = np.ones(len(at), dtype=bool)
    if not len(at):
        return empty
    for column in values:
        chosen = column[at]
        if chosen.dtype.kind != "f":
            return np.zeros(len(at), dtype=bool)
        empty &= np.isnan(chosen).reshape(len(at), -1).all(axis=1)
    return empty


def _write_properties(
    conn: Conn, fc: FeatureClass, geoid: int, old: MeshState, new: MeshState, storage: Storage
) -> tuple[int, int]:
    """The property rows (``_idx``) of the ids that are gone, new, or whose values differ; (deleted, inserted)."""
    deleted = inserted = 0
    for alignment in ("VERTEX", "CELL"):
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if not props or protable is None:
            continue
        old_ids, new_ids = (old.vertex_ids, new.vertex_ids) if alignment == "VERTEX" else (old.cell_ids, new.cell_ids)
        olds = [_values(old, alignment, p.name, "old") for p in props]
        news = [_values(new, alignment, p.name, "new") for p in props]

        def same(a: npt.NDArray[np.intp], b: npt.NDArray[np.intp], olds: Any = olds, news: Any = news) -> Any:
            result = np.ones(len(a), dtype=bool)
            for o, n in zip(olds, news, strict=True):
                result &= _same_values(o[a], n[b])
            return result

        gone, fresh = _difference(old_ids, new_ids, same)
        deleted += delete_rows(conn, fc.schema, protable, "_geoid", geoid, "_idx", gone)
        # an id whose values are all NaN has no row in the state it comes from (the read gives a missing row
        # NaN): it gets none, rather than a row of NaN or a refusal for an integer column
        fresh = fresh[~_without_row(news, fresh)]
        if len(fresh):
            columns: list[tuple[str, npt.ArrayLike, str]] = [
                ("_geoid", np.full(len(fresh), geoid, dtype=np.int64), "int8"),
                ("_idx", new_ids[fresh], "int8"),
            ]
            for p, values in zip(props, news, strict=True):
                wire = SQL_TYPES[p.type]
                chosen = values[fresh]
                if wire not in ("float4", "float8") and chosen.dtype.kind == "f":
                    if np.isnan(chosen).any():
                        raise InvalidInputError(
                            f"{new.name}: {alignment.lower()} property {p.name} ({p.type}) has no value for ids "
                            f"{new_ids[fresh][np.isnan(chosen).reshape(len(chosen), -1).any(axis=1)][:10].tolist()}: "
                            "the merged rows cannot be written",
                            hint="give those rows values (a manual solution) or solve the object as a whole",
                        )
                    chosen = chosen.astype(np.int64)
                columns.append((p.name, chosen, array_wire(wire, p.size)))
            storage.copy(conn, fc.schema, protable, columns)
            inserted += len(fresh)
    return deleted, inserted


def _atoms(state: MeshState) -> tuple[IntArray, IntArray]:
    """(vertex ids, the vertex id each repeats) of a state's GOCAD atoms (its ``refid`` property, -1: none)."""
    refid = state.vertex_properties.get(ATOM_PROPERTY)
    if refid is None:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    refid = np.asarray(refid)
    at = np.flatnonzero(~np.isnan(refid) & (refid >= 0)) if refid.dtype.kind == "f" else np.flatnonzero(refid >= 0)
    return state.vertex_ids[at], refid[at].astype(np.int64)


def _write_atoms(conn: Conn, geoid: int, old: MeshState, new: MeshState, storage: Storage) -> tuple[int, int]:
    """The ``tgsis.atom`` rows of vertices whose atom is gone, new or repeats another vertex now; rows written.

    An atom row's ``patom`` flag (a GOCAD PATOM) is not in the state: a row
    that comes back as stored in some revision of the object takes its flag
    from there, any other is an ATOM.
    """
    old_ids, old_ref = _atoms(old)
    new_ids, new_ref = _atoms(new)
    gone, fresh = _difference(old_ids, new_ids, lambda a, b: old_ref[a] == new_ref[b])
    deleted = delete_rows(conn, "tgsis", "atom", "geoid", geoid, "vrtxid", gone)
    if not len(fresh):
        return deleted, 0
    ids, refs = new_ids[fresh], new_ref[fresh]
    flags = dict(
        ((int(v), int(r)), bool(p))
        for v, r, p in conn.execute(
            sql.SQL("SELECT DISTINCT vrtxid, refid, patom FROM {} WHERE geoid = %s AND vrtxid = ANY(%s)").format(
                storage.table("tgsis", "atom")
            ),
            (geoid, ids.tolist()),
        ).fetchall()
    )
    rows = [(geoid, int(v), int(r), int(flags.get((int(v), int(r)), False))) for v, r in zip(ids, refs)]
    copy_extra_rows(conn, storage, rows, [])
    return deleted, len(rows)


def _part_rows(geoid: int, state: MeshState) -> list[tuple[int, ...]]:
    """The ``tgsis.part`` runs of a state's cells; a cell in no run (part -1 or NaN, as read) stays in none."""
    parts = np.asarray(state.cell_properties[PART_PROPERTY])
    inside = ~np.isnan(parts) & (parts >= 0) if parts.dtype.kind == "f" else parts >= 0
    return part_rows(geoid, state.cell_ids[inside], parts[inside])


def _write_parts(
    conn: Conn, fc: FeatureClass, geoid: int, old: MeshState, new: MeshState, storage: Storage
) -> tuple[int, int]:
    """The ``tgsis.part`` runs, rewritten when the parts differ (a few rows per object); (deleted, inserted)."""
    if stores_part_column(fc) or PART_PROPERTY not in new.cell_properties:
        return 0, 0
    after = _part_rows(geoid, new)
    if PART_PROPERTY in old.cell_properties:
        before = _part_rows(geoid, old)
        if before == after:
            return 0, 0
    row = conn.execute("SELECT tgsis.delete_object_rows('tgsis', 'part', 'geoid', %s)", ([geoid],)).fetchone()
    copy_extra_rows(conn, storage, [], after)
    return (int(row[0]) if row else 0), len(after)


def write_state_difference(
    conn: Conn, fc: FeatureClass, geoid: int, old: MeshState, new: MeshState, *, whole: bool = True
) -> int:
    """Write ``new`` over ``old`` (the object's stored state) by an id-keyed difference, in the session's version.

    A vertex (cell) row whose id is gone or whose content differs (coordinates
    bit for bit; the cell's vertex ids in order) is deleted (closed in the
    working revision, when versioned), a row whose id is new or whose content
    differs is inserted with exactly ``new``'s id; the same for the vertex and
    cell property rows (``_idx``; values equal with NaN equal to NaN), the
    GOCAD atoms (``tgsis.atom`` from the vertex property ``refid``) and the
    parts (``tgsis.part`` runs from the cell property ``part``, when the class
    keeps them there). Ids are never reassigned. The geometry row's box and
    counts follow. Runs in the caller's transaction; nothing is committed.

    Parameters
    ----------
    conn : psycopg.Connection
        In a transaction, in the version (and working revision) to write.
    fc : FeatureClass
        The class of the feature (a static point set, line set, surface or solid).
    geoid : int
    old, new : MeshState
        ``old``: the object's rows as the session sees them now (as
        :func:`tgsis.db._merge_states.read_merge_states` reads them);
        ``new``: what it must hold, with the class's property columns.
    whole : bool
        False: ``old`` and ``new`` hold only some of the object's rows, the
        same ids outside of which the two agree (a merge restricted to the
        change, :func:`tgsis.db._merge_states.read_merge_change`): the rows
        are written alike, and the geometry row's box and counts are those of
        the object's rows as stored after the write.

    Returns
    -------
    int
        Rows deleted, closed, inserted or updated.

    Raises
    ------
    ReadOnlyRevisionError, ObjectLockedError, MissingPrivilegeError, NotVersionedError
        The session may not write the object there (the caller's transaction is then aborted).
    InvalidInputError
        ``new`` lacks a property column of the class, or has no value for an integer property of a row to write.
    """
    return sum(write_state_rows(conn, fc, geoid, old, new, whole=whole))


def copy_vertex_rows(conn: Conn, storage: Storage, geoid: int, ids: IntArray, xyz: FloatArray) -> int:
    """COPY vertex rows ``ids`` (n,) at ``xyz`` (n, 3) of one geometry into ``tgsis.vrtx``; returns n."""
    if len(ids):
        storage.copy(
            conn,
            "tgsis",
            "vrtx",
            [
                ("geoid", np.full(len(ids), geoid, dtype=np.int64), "int8"),
                ("vrtxid", ids, "int8"),
                ("x", xyz[:, 0], "float8"),
                ("y", xyz[:, 1], "float8"),
                ("z", xyz[:, 2], "float8"),
            ],
        )
    return len(ids)


def copy_cell_rows(
    conn: Conn, storage: Storage, table: str, idfield: str, geoid: int, ids: IntArray, cells: IntArray
) -> int:
    """COPY cell rows ``ids`` (m,) on vertex ids ``cells`` (m, k) of one geometry into its simplex table; returns m."""
    if len(ids):
        storage.copy(
            conn,
            "tgsis",
            table,
            [
                ("geoid", np.full(len(ids), geoid, dtype=np.int64), "int8"),
                (idfield, ids, "int8"),
                *((f"vrtxid{j + 1}", cells[:, j], "int8") for j in range(cells.shape[1])),
            ],
        )
    return len(ids)


def write_state_rows(
    conn: Conn, fc: FeatureClass, geoid: int, old: MeshState, new: MeshState, *, whole: bool = True
) -> tuple[int, int, int]:
    """:func:`write_state_difference`, counted: (rows deleted or closed, rows inserted, geometry rows updated)."""
    if fc.geotype not in SIMPLEX:
        raise InvalidInputError(f"feature {geoid} of class {fc.name}: {fc.geotype.value} is not written by rows")
    table, idfield = SIMPLEX[fc.geotype]
    storage = Storage.of(conn, fc)
    storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
    if ("tgsis", "vrtx") in storage.versioned:
        conn.execute(
            "SELECT tgsis.check_objects_unlocked(objectclass, ARRAY[%s]) FROM tgsis.versioned_tables "
            "WHERE schemaname = 'tgsis' AND tablename = 'vrtx'",
            (str(geoid),),
        )
    deleted, inserted = _write_properties(conn, fc, geoid, old, new, storage)
    gone_c, fresh_c = _row_difference(old.cell_ids, old.cells, new.cell_ids, new.cells)
    gone_v, fresh_v = _row_difference(old.vertex_ids, old.vertices, new.vertex_ids, new.vertices)
    deleted += delete_rows(conn, "tgsis", table, "geoid", geoid, idfield, gone_c)
    deleted += delete_rows(conn, "tgsis", "vrtx", "geoid", geoid, "vrtxid", gone_v)
    inserted += copy_vertex_rows(conn, storage, geoid, new.vertex_ids[fresh_v], new.vertices[fresh_v])
    inserted += copy_cell_rows(conn, storage, table, idfield, geoid, new.cell_ids[fresh_c], new.cells[fresh_c])
    for gone, added in (_write_atoms(conn, geoid, old, new, storage), _write_parts(conn, fc, geoid, old, new, storage)):
        deleted, inserted = deleted + gone, inserted + added
    if not whole:
        return deleted, inserted, _update_geometry_row_from_rows(conn, geoid, table)
    bounds = np.stack([new.vertices.min(axis=0), new.vertices.max(axis=0)]) if new.n_vertices else None
    return deleted, inserted, update_geometry_row(conn, geoid, bounds, new.n_vertices, new.n_cells)


def _update_geometry_row_from_rows(conn: Conn, geoid: int, cell_table: str) -> int:
    """:func:`update_geometry_row` with the box and counts of the object's rows as the session sees them now.

    For a write of part of the object's rows: one pass over its vertex rows
    and one over its cell rows (their count), in the server. Read in binary:
    the coordinates exactly, whatever the session's ``extra_float_digits``.
    """
    with conn.cursor(binary=True) as cursor:
        row = cursor.execute(
            "SELECT count(*), min(x), min(y), min(z), max(x), max(y), max(z) FROM tgsis.vrtx WHERE geoid = %s",
            (geoid,),
        ).fetchone()
        cells = cursor.execute(
            sql.SQL("SELECT count(*) FROM {} WHERE geoid = %s").format(sql.Identifier("tgsis", cell_table)), (geoid,)
        ).fetchone()
    assert row is not None and cells is not None
    n = int(row[0])
    bounds = np.array([row[1:4], row[4:7]], dtype=np.float64) if n else None
    return update_geometry_row(conn, geoid, bounds, n, int(cells[0]))
