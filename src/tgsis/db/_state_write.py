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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.db._chunk_write import stored_in_chunks, swap_object_rows, write_object_rows
from tgsis.db._cube import box_coordinates, cube_name
from tgsis.db._property_chunks import write_property_rows
from tgsis.db._static import SIMPLEX, copy_extra_rows, part_rows
from tgsis.db._transfer import Storage, delete_chunk_rows, replace_chunk_rows
from tgsis.db.classes import FeatureClass, stores_part_column
from tgsis.db.copy import SQL_TYPES, array_wire
from tgsis.errors import InvalidInputError
from tgsis.merge3 import MeshState

__all__ = [
    "copy_cell_rows",
    "copy_vertex_rows",
    "delete_rows",
    "key_codes",
    "update_geometry_row",
    "write_model_rows",
    "write_property_edit",
    "write_sliced_difference",
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
    # the cube extension's objects by their schema: the session's search_path may not hold it
    box = sql.SQL("{}(%(low)s::float8[], %(high)s::float8[])").format(cube_name(conn, "cube"))
    box_differs = sql.SQL(
        "(bbox IS NULL) <> (%(low)s::float8[] IS NULL) "
        "OR (bbox IS NOT NULL AND {stored} IS DISTINCT FROM %(low)s::float8[] || %(high)s::float8[])"
    ).format(stored=box_coordinates(conn, sql.Identifier("bbox")))  # as stored: a NaN is not hidden
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


#: the values an integer column holds (a float beyond them, or infinite, would be wrapped by the cast to int64)
_INTEGER_RANGES: dict[str, tuple[int, int]] = {
    "int2": (-(2**15), 2**15 - 1),
    "int4": (-(2**31), 2**31 - 1),
    "int8": (-(2**63), 2**63 - 1),
}


def _check_column_range(values: npt.NDArray[Any], wire: str, ids: npt.ArrayLike, what: str) -> None:
    """Refuse values an integer column of ``wire`` cannot hold (infinite, or beyond its range once truncated), or
    a real (float4) one (finite values it would make infinite, non-zero ones it would make 0).

    A float such as an ``average``/``manual`` solution's 1e10 or +inf was cast to int64 and then to the
    column's width, wrapping silently (1e10 was written 1410065408 into an integer column, inf as 0).
    """
    flat = np.asarray(values)
    if wire == "float4" and flat.dtype.kind == "f" and len(flat):  # as PostgreSQL's float8 -> real cast refuses
        with np.errstate(over="ignore", under="ignore"):
            narrow = flat.astype(np.float32)
        bad = (np.isinf(narrow) & np.isfinite(flat)) | ((narrow == 0) & (flat != 0))
        bad = bad.reshape(len(flat), -1).any(axis=1)
        if bad.any():
            raise InvalidInputError(
                f"{what}: values {np.unique(flat.reshape(len(flat), -1)[bad])[:5].tolist()} at ids "
                f"{np.asarray(ids)[bad][:10].tolist()} do not fit the column (float4 overflows or underflows to 0)",
                hint="give those rows values the column holds (a manual solution) or solve the object as a whole",
            )
        return
    if wire not in _INTEGER_RANGES or not len(values):
        return
    low, high = _INTEGER_RANGES[wire]
    if flat.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            bad = ~np.isfinite(flat) | (np.trunc(flat) < float(low)) | (np.trunc(flat) >= float(high) + 1)
    elif flat.dtype.kind in "iu":
        bad = (flat < low) | (flat > high)
    else:
        return
    bad = bad.reshape(len(flat), -1).any(axis=1)
    if bad.any():
        raise InvalidInputError(
            f"{what}: values {np.unique(flat.reshape(len(flat), -1)[bad])[:5].tolist()} at ids "
            f"{np.asarray(ids)[bad][:10].tolist()} do not fit the column ({low} to {high})",
            hint="give those rows values the column holds (a manual solution) or solve the object as a whole",
        )


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
        # an id whose values are all NaN has no row in the state it comes from (the read gives a missing row
        # NaN): it gets none, rather than a row of NaN or a refusal for an integer column
        fresh = fresh[~_without_row(news, fresh)]
        columns: list[tuple[str, npt.ArrayLike, str]] = [
            ("_geoid", np.full(len(fresh), geoid, dtype=np.int64), "int8"),
            ("_idx", new_ids[fresh], "int8"),
        ]
        if len(fresh):
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
                _check_column_range(
                    chosen, wire, new_ids[fresh], f"{new.name}: {alignment.lower()} property {p.name} ({p.type})"
                )
                if wire not in ("float4", "float8") and chosen.dtype.kind == "f":
                    chosen = chosen.astype(np.int64)
                columns.append((p.name, chosen, array_wire(wire, p.size)))
        gone_n, fresh_n = write_property_edit(conn, storage, fc.schema, protable, geoid, gone, columns, len(fresh))
        deleted, inserted = deleted + gone_n, inserted + fresh_n
    return deleted, inserted


def write_property_edit(
    conn: Conn,
    storage: Storage,
    schema: str,
    table: str,
    geoid: int,
    gone: npt.ArrayLike,
    columns: Sequence[tuple[str, npt.ArrayLike, str]],
    count: int,
) -> tuple[int, int]:
    """Write an edit of object ``geoid``'s rows of the property table ``schema.table``; (deleted, inserted).

    The rows of the ids ``gone`` (the ids that go, and those whose row changes) are deleted and the ``count``
    rows of ``columns`` (``_geoid``, ``_idx`` and the properties, as :meth:`Storage.copy` takes them) written.
    Stored in chunks: the whole edit in one call (``tgsis.write_property_rows``), each touched chunk rewritten
    once, not a rewrite per row through the face; on rows: a DELETE and a COPY.

    Parameters
    ----------
    gone : (d,) int
    columns : sequence of (name, (count,) array, wire type)
    count : int
        The rows of ``columns`` (0: only deletes).
    """
    gone = np.asarray(gone, dtype=np.int64)
    if not len(gone) and not count:
        return 0, 0
    storage.check(schema, table)
    if write_property_rows(conn, schema, table, geoid, gone, columns if count else []) is not None:
        return len(gone), count
    deleted = delete_rows(conn, schema, table, "_geoid", geoid, "_idx", gone)
    if count:
        storage.copy(conn, schema, table, columns)
    return deleted, count


def _atoms(state: MeshState) -> tuple[IntArray, IntArray]:
    """(vertex ids, the vertex id each repeats) of a state's GOCAD atoms (its ``refid`` property, -1: none)."""
    refid = state.vertex_properties.get(ATOM_PROPERTY)
    if refid is None:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    refid = np.asarray(refid)
    at = np.flatnonzero(~np.isnan(refid) & (refid >= 0)) if refid.dtype.kind == "f" else np.flatnonzero(refid >= 0)
    _require_whole(refid[at], state.vertex_ids[at], 2.0**63, f"{state.name}: atoms (refid)", "vertex ids")
    return state.vertex_ids[at], refid[at].astype(np.int64)


def _require_whole(values: npt.NDArray[Any], ids: npt.NDArray[np.int64], above: float, what: str, word: str) -> None:
    """Refuse float ids or part numbers that are not whole numbers below ``above`` (a manual mesh's 5.5, 1e19).

    They were cast to int64: truncated (5.5 as 5, where the psql merge rounded it to 6) or, beyond int64,
    wrapped (1e19 as -2**63): written with a success either way.
    """
    if values.dtype.kind != "f" or not len(values):
        return
    bad = (values != np.trunc(values)) | (values >= above)
    if bad.any():
        raise InvalidInputError(
            f"{what}: values {np.unique(values[bad])[:5].tolist()} at ids {ids[bad][:10].tolist()} are no {word}",
            hint="give whole numbers (a manual solution) or solve the object as a whole",
        )


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
    _require_whole(parts[inside], state.cell_ids[inside], 2.0**31, f"{state.name}: cell parts", "part numbers")
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


def _swapped(conn: Conn, table: str, geoid: int, edit: tuple[Any, ...]) -> int | None:
    """:func:`~tgsis.db._chunk_write.swap_object_rows` in a savepoint; None when it does not apply or lost a race.

    A chunk another transaction wrote between the client's read and the swap
    (a psql user's write through the face) makes the swap refuse (TG300,
    nothing written): the edit then goes through ``tgsis.write_object_rows``,
    which merges it into the chunks as they are now, as a check-in on rows
    or before the client path did; the same checks raise there what is a
    real refusal.
    """
    try:
        with conn.transaction():
            return swap_object_rows(conn, table, geoid, *edit)
    except psycopg.Error as error:
        if error.sqlstate != "TG300":
            raise
        return None


def write_model_rows(
    conn: Conn,
    storage: Storage,
    table: str,
    idfield: str,
    geoid: int,
    gone: IntArray,
    ids: IntArray,
    values: npt.NDArray[Any],
) -> tuple[int, int]:
    """Write one model-1 table's difference of one object: rows ``gone`` (d,) go, rows ``ids`` (n,) are written.

    ``values`` (n, k): the vertices' coordinates (``vrtx``) or the cells'
    vertex ids (a simplex table). An id may be in both (a row rewritten: a
    moved vertex). Rows: ``gone`` deleted (closed, when versioned), then the
    rows COPied. A table stored in chunks (``tgsis.stored_in_chunks``): the
    touched chunks read, merged and encoded by the client and swapped in by
    ``tgsis.swap_object_chunks`` (:func:`~tgsis.db._chunk_write.swap_object_rows`),
    or where that path does not apply one call of ``tgsis.write_object_rows``
    for both, each touched chunk rewritten once (:mod:`tgsis.db._chunk_write`). Returns (rows deleted or closed, rows
    written), counted alike on both storages.
    """
    gone = np.asarray(gone, dtype=np.int64)
    ids = np.asarray(ids, dtype=np.int64)
    if stored_in_chunks(conn, table):
        vertices = table == "vrtx"
        edit = (np.setdiff1d(gone, ids), ids, values if vertices else None, None if vertices else values)
        # the client encodes the touched chunks (tgsis.swap_object_chunks); else the server re-aggregates them
        if _swapped(conn, table, geoid, edit) is None:
            write_object_rows(conn, table, geoid, *edit)
        return len(gone), len(ids)
    deleted = delete_rows(conn, "tgsis", table, "geoid", geoid, idfield, gone)
    if table == "vrtx":
        return deleted, copy_vertex_rows(conn, storage, geoid, ids, values)
    return deleted, copy_cell_rows(conn, storage, table, idfield, geoid, ids, values)


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
    for gone, added in (
        write_model_rows(conn, storage, table, idfield, geoid, gone_c, new.cell_ids[fresh_c], new.cells[fresh_c]),
        write_model_rows(
            conn, storage, "vrtx", "vrtxid", geoid, gone_v, new.vertex_ids[fresh_v], new.vertices[fresh_v]
        ),
    ):
        deleted, inserted = deleted + gone, inserted + added
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
    Both tables stored in chunks: model 1's extent function
    (``tgsis.static_extent``) instead of the faces, the same box and counts:
    the cells are counted from the visible chunk versions' array lengths and
    holes without decoding them, the box taken from the vertex chunks' unnested
    coordinates (through the faces every vertex and cell of the object was
    decoded with its id and tested for visibility row by row).
    """
    if stored_in_chunks(conn, "vrtx") and stored_in_chunks(conn, cell_table):
        with conn.cursor(binary=True) as cursor:
            extent = cursor.execute(
                sql.SQL("SELECT e.nvrtx, {coordinates}, e.ncell FROM tgsis.static_extent(%s) AS e").format(
                    coordinates=sql.SQL(", ").join(  # as measured: (0, 0, 0),(NaN, 1, 1) keeps its low x
                        sql.SQL("{}(e.bbox, {})").format(cube_name(conn, "cube_coord"), sql.Literal(d))
                        for d in range(1, 7)
                    )
                ),
                (geoid,),
            ).fetchone()
        assert extent is not None
        n = int(extent[0])
        bounds = np.array([extent[1:4], extent[4:7]], dtype=np.float64) if n else None
        return update_geometry_row(conn, geoid, bounds, n, int(extent[7]))
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


# --------------------------------------------------------------------------- models 2 and 3: slice by slice

#: the time key columns of the class's property tables (the registry's ``timekey``)
_PROPERTY_TIME_KEYS = {"INSTANTS": ("_times",), "EVOLVING": ("_timem", "_timet")}


@dataclass(frozen=True)
class _TableRows:
    """One table's rows of one object: key columns (the row's key within the object) and value columns."""

    schema: str
    table: str
    objectkey: str
    keys: tuple[tuple[str, str, npt.NDArray[Any]], ...]  # (name, wire type, (n,) values)
    values: tuple[tuple[str, str, npt.NDArray[Any]], ...]


def _slice_rows(
    fc: FeatureClass, slices: Mapping[tuple[float, ...], MeshState], within: set[tuple[float, ...]] | None = None
) -> list[_TableRows]:
    """The rows of every model-2/3 table a state's slices make, in the order they are inserted.

    ``within``: the rows of the slices of those keys only (their vertices,
    cells, nodes, property rows), the instant and period tables whole.
    """
    instants = sorted(slices)
    keys = [k for k in instants if within is None or k in within]
    evolving = fc.time_model == "EVOLVING"
    pcols = _PROPERTY_TIME_KEYS[fc.time_model]
    f8, i8 = "float8", "int8"

    def times(column: int, counts: list[int], of: list[tuple[float, ...]]) -> npt.NDArray[np.float64]:
        return np.repeat(np.asarray([k[column] for k in of], dtype=np.float64), counts)

    def cat(arrays: list[npt.NDArray[Any]], dtype: Any, width: int = 0) -> npt.NDArray[Any]:
        if arrays:
            return np.concatenate(arrays).astype(dtype, copy=False)
        return np.zeros((0, width) if width else 0, dtype=dtype)

    tables: list[_TableRows] = []
    nv = [slices[k].n_vertices for k in keys]
    xyz = cat([slices[k].vertices for k in keys], np.float64, 3)
    vids = cat([slices[k].vertex_ids for k in keys], np.int64)
    if evolving:
        all_periods = sorted({k[0] for k in instants})
        periods = sorted({k[0] for k in keys})
        first = [next(k for k in keys if k[0] == m) for m in periods]  # a period's topology: its first instant's
        tables.append(
            _TableRows("tgsis", "timem", "geoid", (("timem", f8, np.asarray(all_periods, dtype=np.float64)),), ())
        )
        tables.append(
            _TableRows(
                "tgsis",
                "timet",
                "geoid",
                (
                    ("timem", f8, times(0, [1] * len(instants), instants)),
                    ("timet", f8, times(1, [1] * len(instants), instants)),
                ),
                (),
            )
        )
        nn = [slices[k].n_vertices for k in first]
        tables.append(
            _TableRows(
                "tgsis",
                "node",
                "geoid",
                (
                    ("timem", f8, times(0, nn, first)),
                    ("nodeid", i8, cat([slices[k].vertex_ids for k in first], np.int64)),
                ),
                (),
            )
        )
        nt = [slices[k].n_cells for k in first]
        tri = cat([slices[k].cells for k in first], np.int64, 3)
        tables.append(
            _TableRows(
                "tgsis",
                "d4dtrgl",
                "geoid",
                (
                    ("timem", f8, times(0, nt, first)),
                    ("trglid", i8, cat([slices[k].cell_ids for k in first], np.int64)),
                ),
                tuple((f"nodeid{j + 1}", i8, tri[:, j]) for j in range(3)),
            )
        )
        tables.append(
            _TableRows(
                "tgsis",
                "d4dvrtx",
                "geoid",
                (("timem", f8, times(0, nv, keys)), ("timet", f8, times(1, nv, keys)), ("nodeid", i8, vids)),
                tuple((c, f8, xyz[:, j]) for j, c in enumerate("xyz")),
            )
        )
    else:
        nc = [slices[k].n_cells for k in keys]
        tri = cat([slices[k].cells for k in keys], np.int64, 3)
        tables.append(
            _TableRows(
                "tgsis", "times", "geoid", (("times", f8, np.asarray([k[0] for k in instants], dtype=np.float64)),), ()
            )
        )
        tables.append(
            _TableRows(
                "tgsis",
                "times_vrtx",
                "geoid",
                (("times", f8, times(0, nv, keys)), ("vrtxid", i8, vids)),
                tuple((c, f8, xyz[:, j]) for j, c in enumerate("xyz")),
            )
        )
        tables.append(
            _TableRows(
                "tgsis",
                "times_trgl",
                "geoid",
                (("times", f8, times(0, nc, keys)), ("trglid", i8, cat([slices[k].cell_ids for k in keys], np.int64))),
                tuple((f"vrtxid{j + 1}", i8, tri[:, j]) for j in range(3)),
            )
        )
    for alignment in ("VERTEX", "CELL"):
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if not props or protable is None:
            continue
        ids = [slices[k].vertex_ids if alignment == "VERTEX" else slices[k].cell_ids for k in keys]
        counts = [len(i) for i in ids]
        columns = []
        for p in props:
            per = [
                np.asarray((s.vertex_properties if alignment == "VERTEX" else s.cell_properties)[p.name])
                for s in (slices[k] for k in keys)
            ]
            columns.append(
                (p.name, array_wire(SQL_TYPES[p.type], p.size), cat(per, per[0].dtype if per else np.float64))
            )
        tables.append(
            _TableRows(
                fc.schema,
                protable,
                "_geoid",
                (*((c, f8, times(i, counts, keys)) for i, c in enumerate(pcols)), ("_idx", i8, cat(ids, np.int64))),
                tuple(columns),
            )
        )
    return tables


def _key_codes(old: _TableRows, new: _TableRows) -> tuple[IntArray, IntArray]:
    """Numbers of the rows' composite keys, equal for equal keys (floats by value, -0.0 as 0.0)."""
    words = []
    for (_, _, a), (_, _, b) in zip(old.keys, new.keys, strict=True):
        both = np.concatenate([a, b])
        words.append(
            np.ascontiguousarray(both.astype(np.float64) + 0.0).view(np.int64)
            if both.dtype.kind == "f"
            else both.astype(np.int64)
        )
    n = len(old.keys[0][2])
    if not len(words[0]):
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    codes = key_codes(np.stack(words, axis=1))
    return codes[:n], codes[n:]


def key_codes(words: npt.NDArray[np.int64]) -> IntArray:
    """(n,) numbers of (n, k) rows of int64 words: equal for equal rows, ordered as the rows lexicographically.

    What ``np.unique(words, axis=0, return_inverse=True)`` gives up to
    gaps between the numbers (the same order, the same equalities), without
    its sort of the rows as opaque records (tens of seconds for millions of
    rows). Each column is ranked (an id column by its offset from its least
    value; one of few values, such as an instant's time, run by run, which
    costs a pass when the rows come grouped by it, as they do from the
    storage) and the ranks are packed into one int64. Rows whose ranks do
    not fit one int64 are numbered by ``np.lexsort``.
    """
    n = len(words)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    columns = [np.ascontiguousarray(words[:, j], dtype=np.int64) for j in range(words.shape[1])]
    packed = np.zeros(n, dtype=np.int64)
    room = 1
    for column in columns:
        rank, size = _column_rank(column)
        room *= size
        if room >= 2**62:
            return _lexsorted_codes(columns)
        packed = packed * size + rank
    return packed


def _column_rank(column: IntArray) -> tuple[IntArray, int]:
    """(ranks, how many ranks) of one column's values, in their order: equal values, equal ranks."""
    low, high = int(column.min()), int(column.max())
    if high - low < 2**40:  # ids, integer times: the offset is the rank
        return column - low, high - low + 1
    starts = np.flatnonzero(np.concatenate([[True], column[1:] != column[:-1]]))
    values = column[starts]
    distinct = np.unique(values)
    lengths = np.diff(np.append(starts, len(column)))
    return np.repeat(np.searchsorted(distinct, values), lengths).astype(np.int64), len(distinct)


def _lexsorted_codes(columns: list[IntArray]) -> IntArray:
    n = len(columns[0])
    order = np.lexsort(columns[::-1])  # the last key of lexsort is the primary one
    starts = np.zeros(n, dtype=bool)
    for column in columns:
        ranked = column[order]
        starts[1:] |= ranked[1:] != ranked[:-1]
    codes = np.empty(n, dtype=np.int64)
    codes[order] = np.cumsum(starts)
    return codes


def _write_table_difference(
    conn: Conn, storage: Storage, geoid: int, old: _TableRows, new: _TableRows
) -> tuple[int, int]:
    """Delete the rows whose key is gone or whose values differ, insert the new and differing ones; (deleted, inserted)."""
    old_codes, new_codes = _key_codes(old, new)

    def same(a: npt.NDArray[np.intp], b: npt.NDArray[np.intp]) -> Any:
        result = np.ones(len(a), dtype=bool)
        for (_, _, o), (_, _, n) in zip(old.values, new.values, strict=True):
            if o.dtype.kind == "f" and n.dtype.kind == "f" and o.ndim == 1:
                result &= _bits(o[a].reshape(-1, 1))[:, 0] == _bits(n[b].reshape(-1, 1))[:, 0]
            else:
                result &= _same_values(o[a], n[b])
        return result

    gone, fresh = _difference(old_codes, new_codes, same)
    at = np.flatnonzero(np.isin(old_codes, gone)) if len(gone) else np.zeros(0, dtype=np.intp)
    chunked = (old.schema, old.table) in storage.chunked
    keys: list[tuple[str, npt.ArrayLike, str]] = []
    if len(at) and chunked:
        storage.check(old.schema, old.table)
        keys = [(old.objectkey, np.full(len(at), geoid, dtype=np.int64), "int8")]
        keys += [(k, np.asarray(v)[at], w) for k, w, v in old.keys]
    if new.objectkey == "_geoid":  # a property row whose values are all NaN had none where it comes from: none
        fresh = fresh[~_without_row([np.asarray(v) for _, _, v in new.values], fresh)]
    columns = _fresh_columns(geoid, new, fresh) if len(fresh) else []
    if keys and columns:  # one set-based call: each touched chunk written once (not a chunk rewrite per row)
        deleted, _ = replace_chunk_rows(conn, old.table, keys, columns)
        return deleted, len(fresh)
    deleted = 0
    if keys:
        deleted = delete_chunk_rows(conn, old.table, keys)
    elif len(at):
        deleted = _delete_keys(conn, old, geoid, at)
    if not columns:
        return deleted, 0
    storage.copy(conn, new.schema, new.table, columns)
    return deleted, len(fresh)


def _fresh_columns(geoid: int, new: _TableRows, fresh: npt.NDArray[np.intp]) -> list[tuple[str, npt.ArrayLike, str]]:
    """The ``(name, values, wire type)`` columns of the rows ``fresh`` of ``new`` (with the object key ``geoid``).

    Raises
    ------
    InvalidInputError
        A merged row with no value for a column that is not a float, or a value out of its column's range.
    """
    columns: list[tuple[str, npt.ArrayLike, str]] = [
        (new.objectkey, np.full(len(fresh), geoid, dtype=np.int64), "int8")
    ]
    for name, wire, values in (*new.keys, *new.values):
        chosen = np.asarray(values)[fresh]
        if wire not in ("float4", "float8") and chosen.dtype.kind == "f" and not wire.endswith("[]"):
            if np.isnan(chosen).any():
                raise InvalidInputError(
                    f"feature {geoid}: {new.table}.{name} has no value for some merged rows: they cannot be written",
                    hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
                )
        if not wire.endswith("[]"):  # (a value the column cannot hold was cast and wrapped)
            at = np.asarray(new.keys[0][2])[fresh] if new.keys else fresh
            _check_column_range(chosen, wire, at, f"feature {geoid}: {new.table}.{name}")
        if wire not in ("float4", "float8") and chosen.dtype.kind == "f" and not wire.endswith("[]"):
            chosen = chosen.astype(np.int64)
        columns.append((name, chosen, wire))
    return columns


def _delete_keys(conn: Conn, rows: _TableRows, geoid: int, at: npt.NDArray[np.intp]) -> int:
    """Delete the rows ``at`` of ``rows`` (by key) through the table's view; rows deleted."""
    names = [k for k, _, _ in rows.keys]
    arrays = [np.asarray(v)[at].tolist() for _, _, v in rows.keys]
    wires = [w for _, w, _ in rows.keys]
    return max(
        conn.execute(
            sql.SQL("DELETE FROM {} WHERE {} = %s AND ({}) IN (SELECT * FROM unnest({}))").format(
                sql.Identifier(rows.schema, rows.table),
                sql.Identifier(rows.objectkey),
                sql.SQL(", ").join(sql.Identifier(n) for n in names),
                sql.SQL(", ").join(sql.SQL("%s::{}[]").format(sql.SQL(w)) for w in wires),  # wires: ours, fixed
            ),
            (geoid, *arrays),
        ).rowcount,
        0,
    )


def _write_instant_rows(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    old: Mapping[tuple[float, ...], tuple[str | None, ...]],
    new: Mapping[tuple[float, ...], tuple[str | None, ...]],
) -> int:
    """The per-instant feature property rows (``<class>_pros``, few rows of any column type, as text); rows written."""
    if not fc.instant_properties or fc.protable is None:
        return 0
    keys = _PROPERTY_TIME_KEYS[fc.time_model]
    names = [p.name for p in fc.instant_properties]
    table = fc.qualified(fc.protable)
    where = sql.SQL(" AND ").join(sql.SQL("{} = %s").format(sql.Identifier(k)) for k in ("_geoid", *keys))
    written = 0
    for key in sorted(set(old) | set(new)):
        before, after = old.get(key), new.get(key)
        if before == after:
            continue
        if after is None:
            written += max(
                conn.execute(sql.SQL("DELETE FROM {} WHERE {}").format(table, where), (geoid, *key)).rowcount, 0
            )
        elif before is None:
            written += max(
                conn.execute(
                    sql.SQL("INSERT INTO {} ({}) VALUES ({})").format(
                        table,
                        sql.SQL(", ").join(sql.Identifier(c) for c in ("_geoid", *keys, *names)),
                        sql.SQL(", ").join(sql.Placeholder() for _ in ("_geoid", *keys, *names)),
                    ),
                    (geoid, *key, *after),
                ).rowcount,
                0,
            )
        else:
            changed = [(n, v) for n, b, v in zip(names, before, after, strict=True) if b != v]
            written += max(
                conn.execute(
                    sql.SQL("UPDATE {} SET {} WHERE {}").format(
                        table,
                        sql.SQL(", ").join(sql.SQL("{} = %s").format(sql.Identifier(n)) for n, _ in changed),
                        where,
                    ),
                    (*(v for _, v in changed), geoid, *key),
                ).rowcount,
                0,
            )
    return written


def _same_slice_rows(a: MeshState, b: MeshState) -> bool:
    """Whether two slices make the same rows as :func:`_write_table_difference` compares them (none to write).

    Ids, cells and property columns alike, coordinates bit for bit (-0.0 is
    not 0.0 there), property values as the writer compares them.
    """
    if a is b:
        return True
    if not (
        np.array_equal(a.vertex_ids, b.vertex_ids)
        and np.array_equal(a.cell_ids, b.cell_ids)
        and np.array_equal(a.cells, b.cells)
        and a.vertices.shape == b.vertices.shape
        and np.array_equal(_bits(a.vertices), _bits(b.vertices))
        and a.vertex_properties.keys() == b.vertex_properties.keys()
        and a.cell_properties.keys() == b.cell_properties.keys()
    ):
        return False
    for ours, theirs in ((a.vertex_properties, b.vertex_properties), (a.cell_properties, b.cell_properties)):
        for name, values in ours.items():
            o, n = np.asarray(values), np.asarray(theirs[name])
            if o.shape != n.shape:
                return False
            if o.dtype.kind == "f" and n.dtype.kind == "f" and o.ndim == 1:
                if not np.array_equal(_bits(o.reshape(-1, 1)), _bits(n.reshape(-1, 1))):
                    return False
            elif len(o) and not bool(np.all(_same_values(o, n))):
                return False
    return True


def _differing_slices(
    fc: FeatureClass, old: Mapping[tuple[float, ...], MeshState], new: Mapping[tuple[float, ...], MeshState]
) -> set[tuple[float, ...]]:
    """The keys of the slices whose rows may differ: the written difference is found among theirs only.

    A slice on one side only, or whose rows differ; model 3: every geometry
    instant of a period one of whose instants differs (a period's nodes and
    triangles are its first instant's). The slices left out make the same
    rows on both sides: none of them would be written. The cost of the
    difference follows the change, not the object's instants.
    """
    differ = {k for k in set(old) | set(new) if k not in old or k not in new or not _same_slice_rows(old[k], new[k])}
    if fc.time_model != "EVOLVING":
        return differ
    periods = {k[0] for k in differ}
    return {k for k in set(old) | set(new) if k[0] in periods}


def write_sliced_difference(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    old: Mapping[tuple[float, ...], MeshState],
    new: Mapping[tuple[float, ...], MeshState],
    old_rows: Mapping[tuple[float, ...], tuple[str | None, ...]] | None = None,
    new_rows: Mapping[tuple[float, ...], tuple[str | None, ...]] | None = None,
) -> int:
    """Write a model-2/3 object's slices ``new`` over ``old`` by a difference keyed by (slice, id), in the session's version.

    The generalisation of :func:`write_state_difference` to a surface at
    instants (tables ``tgsis.times``, ``times_vrtx``, ``times_trgl``) and an
    evolving surface (``tgsis.timem``, ``timet``, ``node``, ``d4dtrgl``,
    ``d4dvrtx``), with the class's property rows (keyed with the time key) and
    per-instant feature property rows (``old_rows``/``new_rows``, as text):
    a row whose key (the slice's time key and the row's id) is gone or whose
    content differs is deleted through the versioned view (closed in the
    working revision), a row whose key is new or whose content differs is
    added. Nothing is renumbered. The geometry row's box and counts follow
    (``tgsis.refresh_geometry``). Runs in the caller's transaction.

    Returns
    -------
    int
        Rows deleted, closed, inserted or updated.
    """
    storage = Storage.of(conn, fc)
    storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
    conn.execute(
        "SELECT tgsis.check_objects_unlocked(objectclass, ARRAY[%s]) FROM tgsis.versioned_tables "
        "WHERE schemaname = 'tgsis' AND tablename = 'geometry'",
        (str(geoid),),
    )
    within = _differing_slices(fc, old, new)
    olds, news = _slice_rows(fc, old, within), _slice_rows(fc, new, within)
    written = _write_instant_rows(conn, fc, geoid, old_rows or {}, new_rows or {})
    for o, n in zip(olds, news, strict=True):
        deleted, inserted = _write_table_difference(conn, storage, geoid, o, n)
        written += deleted + inserted
    conn.execute("SELECT tgsis.refresh_geometry(%s)", (geoid,))
    return written
