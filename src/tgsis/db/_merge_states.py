"""Reading the three states of one model-1 object a merge by region needs (docs/merge.md).

Shared by :func:`tgsis.object_merge` (in a snapshot of its own) and the merges
that write (in the locked transaction of ``tgsis.lock_for_merge``): the caller
provides the consistent transaction; this module reads, moving the session's
version settings for the reads and putting them back.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis._merge_slices import SlicedState, slice_text
from tgsis.db._chunk_write import last_id
from tgsis.db._settings import read_version_settings, restore_version_settings
from tgsis.db._state_write import key_codes
from tgsis.db._static import SIMPLEX
from tgsis.db._transfer import Packed, columns_out_all
from tgsis.db.classes import (
    FeatureClass,
    class_of_feature,
    list_feature_classes,
    readable_class_names,
    stores_part_column,
)
from tgsis.db.meaning import parts_from_runs
from tgsis.db.versions import show_name
from tgsis.errors import InvalidInputError, NotFoundError, VersioningError
from tgsis.merge3 import MeshState
from tgsis.mesh import Geotype, mesh_class

__all__ = [
    "SLICE_KEYS",
    "MergeInputs",
    "SlicedInputs",
    "feature_time_model",
    "read_merge_change",
    "read_merge_states",
    "read_sliced_states",
    "version_row",
]

Conn = psycopg.Connection[Any]


@dataclass(frozen=True)
class _Rows:
    """One state's rows as read: ids ascending."""

    vertex_ids: npt.NDArray[np.int64]
    vertices: npt.NDArray[np.float64]
    cell_ids: npt.NDArray[np.int64]
    cells: npt.NDArray[np.int64]
    vertex_properties: dict[str, npt.NDArray[Any]]
    cell_properties: dict[str, npt.NDArray[Any]]
    atoms: npt.NDArray[np.int64]  # (a, 2): vertex id, the vertex id it repeats
    runs: npt.NDArray[np.int64]  # (r, 3): first cell id, last cell id, part


def _feature_class(conn: Conn, feature_id: int) -> FeatureClass:
    """The class holding the feature; one in a class the role may not read gives its permission error, not 'not found'."""
    try:
        return class_of_feature(conn, feature_id)
    except NotFoundError:
        readable = readable_class_names(conn)
        for fc in list_feature_classes(conn):  # only looked into when no readable class holds it: refused
            if fc.name not in readable:
                with conn.transaction():  # a savepoint: the refusal leaves the snapshot usable to put settings back
                    conn.execute(
                        sql.SQL("SELECT FROM {} WHERE _geoid = %s").format(fc.qualified(fc.featuretable)), (feature_id,)
                    )
        raise


def version_row(conn: Conn, version: str) -> tuple[int, str, int, int, int]:
    """(version id, parent name, initrevision, working revision, parent's working revision)."""
    row = conn.execute(
        "SELECT v.versionid, p.name, v.initrevision, v.workingrevision, p.workingrevision"
        "  FROM tgsis.versions v LEFT JOIN tgsis.versions p ON p.versionid = v.parentid"
        " WHERE v.versionid = tgsis.version_id(%s)",
        (version,),
    ).fetchone()
    assert row is not None  # version_id raised TG200 otherwise
    if row[1] is None:
        raise InvalidInputError(
            "version DEFAULT has no parent to merge with", hint="give the name of a version made by create_version"
        )
    return int(row[0]), str(row[1]), int(row[2]), int(row[3]), int(row[4])


def _exists(conn: Conn, geoid: int, version: str, revision: int) -> bool:
    """Whether ``version`` has the geometry at ``revision`` (the session is moved there)."""
    conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
    return conn.execute("SELECT 1 FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone() is not None


def _require_same_attributes(
    conn: Conn, fc: FeatureClass, geoid: int, version: str, parent: str, revisions: tuple[int, int, int]
) -> None:
    """Refuse a feature whose attributes (its feature-table row) the two sides changed differently.

    The merge is of the mesh only: such a conflict would be left out of its
    answer. Values are compared as read in binary (floats exactly).
    """
    rows = []
    for side, revision in zip((version, parent, version), revisions, strict=True):
        conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (side, revision))
        with conn.cursor(binary=True) as cursor:
            cursor.execute(
                sql.SQL("SELECT * FROM {} WHERE _geoid = %s").format(fc.qualified(fc.featuretable)), (geoid,)
            )
            names = [d.name for d in cursor.description or ()]
            rows.append({n: repr(v) for n, v in zip(names, cursor.fetchone() or (), strict=False)})
    base, theirs, ours = rows
    if theirs == ours or theirs == base or ours == base:
        return
    differ = sorted(n for n in theirs.keys() | ours.keys() if theirs.get(n) != ours.get(n))
    raise InvalidInputError(
        f"feature {geoid} of class {fc.name}: its attributes were changed both in version {show_name(version)} "
        f"and in its parent {show_name(parent)}, to other values ({', '.join(differ)}): "
        "the merge by region merges the mesh only",
        hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
    )


@dataclass(frozen=True)
class _Table:
    """One table a state is read from: its versioned view, the object's key column there, its columns.

    The first column is the row's key within the object (vertex, cell,
    property row ``_idx``, atom vertex, part run's first cell).
    """

    view: str  # the table's name in ``schema``; its storage is where ``tgsis.storage_table`` says
    schema: str
    key: str
    columns: tuple[tuple[str, str], ...]

    @property
    def source(self) -> sql.Composed:
        return sql.SQL("{}.{}").format(sql.Identifier(self.schema), sql.Identifier(self.view))

    def changed(self, storage: str, sets: Mapping[str, list[int]], since: list[int]) -> sql.Composed:
        """The storage's rows of the object some revision of ``since`` wrote or closed, as a subquery.

        A row visible in one set and not in another was written in a
        revision one set has and the other has not, or closed in one: the
        rows with ``revision`` or ``lastrevs`` in the symmetric differences
        ``since`` are all the rows whose visibility can differ. Column
        ``_seen`` says where each is visible (bit 1 base, 2 parent, 4
        child), with the test of the versioned views.
        """
        seen = sql.SQL(" + ").join(
            sql.SQL("(v.revision = ANY ({s}) AND NOT (v.revclosed AND v.lastrevs && {s}))::int4 * {bit}").format(
                s=_int_array(sets[side]), bit=sql.Literal(bit)
            )
            for side, bit in _SIDE_BITS.items()
        )
        return sql.SQL(
            "(SELECT {cols}, {seen} AS _seen FROM {storage} v "
            "WHERE (v.revision = ANY ({since}) OR (v.revclosed AND v.lastrevs && {since}))) AS _changed"
        ).format(
            cols=sql.SQL(", ").join(
                sql.SQL("v.{}").format(sql.Identifier(c)) for c in (self.key, *(n for n, _ in self.columns))
            ),
            seen=seen,
            storage=sql.SQL(storage),  # quoted by tgsis.storage_table
            since=_int_array(since),
        )


_SIDE_BITS = {"base": 1, "parent": 2, "child": 4}


def _int_array(values: list[int]) -> sql.Composed:
    return sql.SQL("{}::int4[]").format(sql.Literal("{" + ",".join(str(int(v)) for v in values) + "}"))


def _tables(fc: FeatureClass) -> tuple[list[_Table], list[tuple[str, list[str]]]]:
    """The tables of one object's state, in the order :func:`_rows_of` takes them, and the property tables' names."""
    table, key = SIMPLEX[fc.geotype]
    k = mesh_class(fc.geotype).cell_size
    tables = [
        _Table("vrtx", "tgsis", "geoid", (("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8"))),
        _Table(table, "tgsis", "geoid", ((key, "int8"), *((f"vrtxid{i + 1}", "int8") for i in range(k)))),
        _Table("atom", "tgsis", "geoid", (("vrtxid", "int8"), ("refid", "int8"))),
        _Table("part", "tgsis", "geoid", (("firstid", "int8"), ("lastid", "int8"), ("part", "int4"))),
    ]
    properties: list[tuple[str, list[str]]] = []
    for alignment in ("VERTEX", "CELL"):
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if props and protable is not None:
            properties.append((alignment, [p.name for p in props]))
            tables.append(_Table(protable, fc.schema, "_geoid", (("_idx", "int8"), *((p.name, p.wire) for p in props))))
    return tables, properties


def _rows_of(fc: FeatureClass, properties: list[tuple[str, list[str]]], read: list[list[npt.NDArray[Any]]]) -> _Rows:
    """A state's rows from its tables' columns as read (``[key, *columns]`` per table of :func:`_tables`)."""
    k = mesh_class(fc.geotype).cell_size
    vertex_cols, cell_cols, atom_cols, part_cols, *prop_cols = read
    vids, xyz = _sorted_rows(vertex_cols[1], np.stack(vertex_cols[2:5], axis=1) if len(vertex_cols[1]) else None)
    cids, cells = _sorted_rows(cell_cols[1], np.stack(cell_cols[2:], axis=1) if len(cell_cols[1]) else None)
    xyz = xyz.reshape(-1, 3).astype(np.float64, copy=False)  # (stacked: arrays of their own)
    cells = cells.reshape(-1, k).astype(np.int64, copy=False)
    props_by: dict[str, dict[str, npt.NDArray[Any]]] = {"VERTEX": {}, "CELL": {}}
    for (alignment, names), columns in zip(properties, prop_cols, strict=True):
        ids = vids if alignment == "VERTEX" else cids
        idx = np.asarray(columns[1], dtype=np.int64)
        for name, values in zip(names, columns[2:], strict=True):
            props_by[alignment][name] = _aligned_values(ids, idx, np.asarray(values))
    atoms = np.stack([np.asarray(c, dtype=np.int64) for c in atom_cols[1:3]], axis=1).reshape(-1, 2)
    runs = np.stack([np.asarray(c, dtype=np.int64) for c in part_cols[1:4]], axis=1).reshape(-1, 3)
    return _Rows(
        vids,
        xyz,
        cids,
        cells,
        props_by["VERTEX"],
        props_by["CELL"],
        atoms[np.argsort(atoms[:, 0], kind="stable")],
        runs[np.argsort(runs[:, 0], kind="stable")],
    )


def _read_state(conn: Conn, fc: FeatureClass, geoid: int, version: str, revision: int) -> _Rows:
    """The object's rows as ``version`` sees them at ``revision``, all through the views (the session is moved there)."""
    conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
    tables, properties = _tables(fc)
    return _rows_of(
        fc, properties, columns_out_all(conn, [Packed(t.source, t.key, t.columns, [geoid]) for t in tables])
    )


def _readable_storages(conn: Conn, tables: list[_Table]) -> list[str] | None:
    """Each table's storage (``tgsis.storage_table``: quoted) when all are versioned with the object key read here
    and the role may read them; else None.

    A table stored in chunks (``tgsis.stored_in_chunks``) is read through its
    decoded view ``tgsis.<table>_chunk_rows``: the rows of every chunk version
    with the version's ``revision``, ``lastrevs`` and ``revclosed``, which the
    readers here filter as they filter row versions. A chunk version written
    or closed in a revision carries all its rows: the change read is the
    changed chunks' rows, a superset of the changed rows, which the patching
    and the merge tell apart by key and content as they do a rewritten row.

    A role that may read a view but not its storage (a grant made on the
    view only; for a table in chunks, the chunk table as well as its decoded
    view, which reads it with its owner's rights) reads as before: three full
    reads through the views.
    """
    rows = conn.execute(
        "SELECT s.storage, t.objectkeyfield IS NOT DISTINCT FROM k.key AND has_table_privilege(s.storage, 'SELECT')"
        "       AND has_table_privilege(tgsis.storage_table(k.schemaname, k.tablename), 'SELECT')"
        "  FROM unnest(%s::text[], %s::text[], %s::text[]) WITH ORDINALITY AS k(schemaname, tablename, key, n)"
        "  LEFT JOIN tgsis.versioned_tables t ON t.schemaname = k.schemaname AND t.tablename = k.tablename"
        "  CROSS JOIN LATERAL (SELECT CASE WHEN tgsis.stored_in_chunks(k.schemaname, k.tablename)"
        "                                  THEN format('%%I.%%I', k.schemaname, k.tablename || '_chunk_rows')"
        "                                  ELSE tgsis.storage_table(k.schemaname, k.tablename) END AS storage) s"
        " ORDER BY k.n",
        ([t.schema for t in tables], [t.view for t in tables], [t.key for t in tables]),
    ).fetchall()
    if len(rows) != len(tables) or not all(r[1] for r in rows):
        return None
    return [str(r[0]) for r in rows]


def _by_key(columns: list[npt.NDArray[Any]]) -> list[npt.NDArray[Any]]:
    """A table's columns (``[object key, row key, ...]``) with the rows in ascending row key."""
    keys = np.asarray(columns[1])
    if _ascending(keys):
        return [np.asarray(c) for c in columns]
    order = np.argsort(keys, kind="stable")
    return [np.asarray(c)[order] for c in columns]


def _ascending(ids: npt.NDArray[Any]) -> bool:
    """Whether the ids are strictly ascending (as the rows of an uploaded object usually come)."""
    return len(ids) < 2 or bool(np.all(ids[1:] > ids[:-1]))


def _patched(base: list[npt.NDArray[Any]], changed: list[npt.NDArray[Any]], bit: int) -> list[npt.NDArray[Any]]:
    """A side's columns: the base's rows without those the side does not see, with those only the side sees.

    ``base`` is in ascending row key (:func:`_by_key`), and so is the
    result. ``changed`` holds ``[object key, row key, *columns, _seen]`` of
    the rows whose visibility can differ (:meth:`_Table.changed`); rows are
    told apart by their row key, of which a revision set sees one version
    at most. The cost follows the change: the base's rows are found by
    binary search and copied once.
    """
    seen = np.asarray(changed[-1])
    in_base, in_side = (seen & 1) != 0, (seen & bit) != 0
    gone, added = in_base & ~in_side, in_side & ~in_base
    if not gone.any() and not added.any():
        return base  # (the states made of it copy what they keep: _rows_of)
    keys = base[1]
    gone_keys = np.unique(np.asarray(changed[1])[gone])
    at = np.searchsorted(keys, gone_keys)
    at = at[(at < len(keys)) & (keys[np.minimum(at, len(keys) - 1)] == gone_keys)] if len(keys) else at[:0]
    new = [np.asarray(c)[added] for c in changed[:-1]]
    order = np.argsort(new[1], kind="stable")
    new = [c[order] for c in new]
    if len(at) == len(new[1]) and np.array_equal(keys[at], new[1]):  # rows rewritten in place: same keys
        out = [c.copy() for c in base]
        for column, values in zip(out, new, strict=True):
            column[at] = values
        return out
    kept = [np.delete(c, at, axis=0) for c in base]
    where = np.searchsorted(kept[1], new[1])
    return [
        np.insert(c, where, values, axis=0) if len(c) else values.astype(c.dtype, copy=False)
        for c, values in zip(kept, new, strict=True)
    ]


def _read_states(conn: Conn, fc: FeatureClass, geoid: int, sides: Mapping[str, tuple[str, int]]) -> dict[str, _Rows]:
    """The rows of base, parent and child (``sides``: side -> (version, revision)).

    The base is read in full through the views; of parent and child only
    the rows their revisions since the base wrote or closed, from the
    storage, with the test of the views, in the same statement: the sides
    are the base patched with them. The cost of the sides follows their
    change (the storage's object index, the object's rows filtered on
    ``revision``/``lastrevs``), not three full transfers. A role that may
    not read the storage reads the three states in full through the views.
    """
    tables, properties = _tables(fc)
    sets = {}
    for side, (version, revision) in sides.items():
        conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        row = conn.execute("SELECT tgsis.get_revisions(true)").fetchone()
        assert row is not None
        sets[side] = sorted(int(r) for r in row[0])
    base_version, base_revision = sides["base"]
    storages = _readable_storages(conn, tables)
    if storages is None:
        return {side: _read_state(conn, fc, geoid, version, revision) for side, (version, revision) in sides.items()}
    conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (base_version, base_revision))
    since = sorted(
        set(sets["base"]).symmetric_difference(sets["parent"]) | set(sets["base"]).symmetric_difference(sets["child"])
    )
    requests = [Packed(t.source, t.key, t.columns, [geoid]) for t in tables]
    requests += [
        Packed(t.changed(storage, sets, since), t.key, (*t.columns, ("_seen", "int4")), [geoid])
        for t, storage in zip(tables, storages, strict=True)
    ]
    read = columns_out_all(conn, requests)
    base, changed = [_by_key(columns) for columns in read[: len(tables)]], read[len(tables) :]
    rows = {"base": _rows_of(fc, properties, base)}
    for side in ("parent", "child"):
        rows[side] = _rows_of(
            fc, properties, [_patched(b, c, _SIDE_BITS[side]) for b, c in zip(base, changed, strict=True)]
        )
    return rows


def _sorted_rows(ids: npt.ArrayLike, rows: npt.NDArray[Any] | None) -> tuple[npt.NDArray[np.int64], npt.NDArray[Any]]:
    """Ids ascending with their rows (the packed reads come in no order)."""
    ids = np.array(ids, dtype=np.int64)  # a copy: no array is shared between two states, their users may change them
    if rows is None:
        return ids, np.empty((0,), dtype=np.float64)
    if _ascending(ids):
        return ids, rows
    order = np.argsort(ids, kind="stable")
    return ids[order], rows[order]


def _aligned_values(
    ids: npt.NDArray[np.int64], idx: npt.NDArray[np.int64], values: npt.NDArray[Any]
) -> npt.NDArray[Any]:
    """A property's values in the order of ``ids`` (rows keyed by ``_idx``); an id without a row gets NaN."""
    if len(idx) == len(ids) and np.array_equal(idx, ids):  # a value for every id, in their order
        return values.copy()  # (not shared with another state's)
    if not _ascending(idx):
        order = np.argsort(idx, kind="stable")
        idx, values = idx[order], values[order]
    pos = np.searchsorted(idx, ids)
    found = pos < len(idx)
    found[found] = idx[pos[found]] == ids[found]
    if found.all():
        return values[pos]
    out = np.full((len(ids), *values.shape[1:]), np.nan, dtype=_with_nan(values))
    out[found] = values[pos[found]]
    return out


def _with_nan(values: npt.NDArray[Any]) -> npt.DTypeLike:
    """The type of a property column that gets NaN for its missing rows: float64, or for 64-bit integers the
    long double that holds every one of them exactly (float64 turns 2**53 + 1 into 2**53, 2**63 - 1 into -2**63)."""
    if values.dtype.kind not in "iu" or values.dtype.itemsize < 8:
        return np.float64
    if np.finfo(np.longdouble).nmant >= 63:
        return np.longdouble
    if len(values) and np.abs(values.astype(np.float64)).max(initial=0) >= 2.0**53:
        raise InvalidInputError(
            f"64-bit integer property values of {2**53} or more with missing property rows cannot be merged "
            "exactly on this platform (numpy's long double is a double)",
            hint="give every row a value, or solve the object as a whole (resolve_conflict)",
        )
    return np.float64


def _states(fc: FeatureClass, geoid: int, rows: Mapping[str, _Rows]) -> dict[str, MeshState]:
    """MeshStates of the three reads; GOCAD atoms (``refid``) and parts (``part``) as properties when a state has them."""
    with_atoms = any(len(r.atoms) for r in rows.values())
    with_parts = not stores_part_column(fc) and any(len(r.runs) for r in rows.values())
    states = {}
    for side, r in rows.items():
        vprops = dict(r.vertex_properties)
        cprops = dict(r.cell_properties)
        if with_atoms:
            refid = np.full(len(r.vertex_ids), -1, dtype=np.int64)
            at = np.searchsorted(r.vertex_ids, r.atoms[:, 0])
            ok = at < len(r.vertex_ids)
            ok[ok] = r.vertex_ids[at[ok]] == r.atoms[ok, 0]
            refid[at[ok]] = r.atoms[ok, 1]
            vprops.setdefault("refid", refid)
        if with_parts:
            cprops.setdefault("part", parts_from_runs(r.cell_ids, r.runs[:, 0], r.runs[:, 1], r.runs[:, 2]))
        states[side] = MeshState(
            mesh_class(fc.geotype).cell_size,
            r.vertex_ids,
            r.vertices,
            r.cell_ids,
            r.cells,
            vprops,
            cprops,
            f"feature {geoid} ({side})",
        )
    return states


@dataclass(frozen=True)
class MergeInputs:
    """What a merge by region of one object reads.

    Attributes
    ----------
    feature_class : FeatureClass
    versionid : int
    parent : str
        The parent version's name.
    revisions : (int, int, int)
        The base (the version's ``initrevision``), the parent's and the version's working revisions.
    states : dict
        ``base``, ``parent``, ``child``: :class:`tgsis.merge3.MeshState`.
    """

    feature_class: FeatureClass
    versionid: int
    parent: str
    revisions: tuple[int, int, int]
    states: dict[str, MeshState]


def read_merge_states(conn: Conn, version: str, feature_id: int) -> MergeInputs:
    """Read base, parent and child of one object changed on both sides, in the caller's transaction.

    The caller makes the reads consistent: one snapshot (``object_merge``) or
    the versions locked by ``tgsis.lock_for_merge`` (no writer of either side
    can commit meanwhile). The session's version settings are put back.

    Raises
    ------
    InvalidInputError
        Not a model-1 point set, line set, surface or solid; deleted on one
        side; attributes changed on both sides.
    VersioningError
        Not changed on both sides since the version was based.
    """
    settings = read_version_settings(conn)
    try:
        versionid, parent, (initrevision, parent_working, working), fc = _checked_object(conn, version, feature_id)
        rows = _read_states(
            conn,
            fc,
            feature_id,
            {"base": (version, initrevision), "parent": (parent, parent_working), "child": (version, working)},
        )
    finally:
        if conn.info.transaction_status != psycopg.pq.TransactionStatus.INERROR:
            restore_version_settings(conn, settings, local=True)
    return MergeInputs(fc, versionid, parent, (initrevision, parent_working, working), _states(fc, feature_id, rows))


def _refuse_unless_static_mesh(fc: FeatureClass, feature_id: int, version: str) -> None:
    """The model rule of :func:`read_merge_states`: a static (model 1) point set, line set, surface or solid."""
    if fc.time_model != "STATIC" or fc.geotype not in SIMPLEX:
        what = "a geometry collection" if fc.geotype is Geotype.GEOMETRYCOLLECTION else f"of model {fc.time_model}"
        raise InvalidInputError(
            f"feature {feature_id} of class {fc.name} is {what}: only a static (model 1) point set, line set, "
            f"surface or tetrahedral solid merges by region (version {show_name(version)})",
            hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
        )


def _refuse_unless_sliced_surface(fc: FeatureClass, feature_id: int, version: str) -> None:
    """The model rule of :func:`read_sliced_states`: a surface at instants (model 2) or an evolving one (model 3)."""
    if fc.time_model not in SLICE_KEYS or fc.geotype is not Geotype.SURFACE:
        raise InvalidInputError(
            f"feature {feature_id} of class {fc.name} is of model {fc.time_model}: only a surface at instants "
            f"(model 2) or an evolving surface (model 3) merges slice by slice (version {show_name(version)})",
            hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
        )


def _checked_object(
    conn: Conn,
    version: str,
    feature_id: int,
    model_rule: Callable[[FeatureClass, int, str], None] = _refuse_unless_static_mesh,
) -> tuple[int, str, tuple[int, int, int], FeatureClass]:
    """(version id, parent, (base, parent's, version's working revisions), class) of an object that merges by region.

    ``model_rule`` refuses a class whose objects do not merge so. Raises what
    :func:`read_merge_states` says; moves the session's version settings (the
    caller puts them back).
    """
    versionid, parent, initrevision, working, parent_working = version_row(conn, version)
    # the class is looked up as the version sees its features; as the parent does, when the version
    # deleted a feature of its base
    in_child = _exists(conn, feature_id, version, working)
    in_parent = _exists(conn, feature_id, parent, parent_working)
    if in_child or not (in_parent and _exists(conn, feature_id, version, initrevision)):
        conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, working))
    fc = _feature_class(conn, feature_id)
    model_rule(fc, feature_id, version)
    both = conn.execute(
        "SELECT 1 FROM tgsis.current_conflicts(%s) WHERE objectclass = 'feature' AND objectkey = %s",
        (versionid, str(feature_id)),
    ).fetchone()
    if both is None:
        raise VersioningError(
            f"feature {feature_id} of class {fc.name} was not changed both in version {show_name(version)} "
            f"and in its parent {show_name(parent)} since the version was based: there is nothing to merge",
            hint=f"tgsis.find_conflicts(conn, {version!r}) lists the objects changed on both sides",
        )
    if not (in_child and in_parent):
        raise InvalidInputError(
            f"feature {feature_id} of class {fc.name} was deleted in version "
            f"{show_name(parent if in_child else version)} and changed in "
            f"{show_name(version if in_child else parent)}: a deletion does not merge by region",
            hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
        )
    _require_same_attributes(conn, fc, feature_id, version, parent, (initrevision, parent_working, working))
    return versionid, parent, (initrevision, parent_working, working), fc


# --------------------------------------------------------------------------- the change and its one-ring


def _visible_in(sets: Mapping[str, list[int]]) -> sql.Composed:
    """A row ``v`` of storage visible in at least one of the revision sets (the test of the versioned views)."""
    return sql.SQL("({})").format(
        sql.SQL(" OR ").join(
            sql.SQL("(v.revision = ANY ({s}) AND NOT (v.revclosed AND v.lastrevs && {s}))").format(s=_int_array(s))
            for s in sets.values()
        )
    )


def _seen_in(sets: Mapping[str, list[int]]) -> sql.Composed:
    """Column ``_seen`` of a row ``v``: where it is visible (bit 1 base, 2 parent, 4 child), as in :meth:`_Table.changed`."""
    return sql.SQL(" + ").join(
        sql.SQL("(v.revision = ANY ({s}) AND NOT (v.revclosed AND v.lastrevs && {s}))::int4 * {bit}").format(
            s=_int_array(sets[side]), bit=sql.Literal(bit)
        )
        for side, bit in _SIDE_BITS.items()
    )


def _int8_array(values: npt.ArrayLike) -> sql.Composed:
    """A literal int8[]: a constant the planner hashes in ``= ANY`` (a scan tests each row in constant time)."""
    ids = np.unique(np.asarray(values, dtype=np.int64))
    return sql.SQL("{}::int8[]").format(sql.Literal("{" + ",".join(str(int(v)) for v in ids) + "}"))


def _rows_where(table: _Table, storage: str, sets: Mapping[str, list[int]], where: sql.Composable) -> sql.Composed:
    """The storage's rows visible in some side and satisfying ``where`` (over ``v``), with ``_seen``, as a subquery."""
    return sql.SQL("(SELECT {cols}, {seen} AS _seen FROM {storage} v WHERE {visible} AND ({where})) AS _rows").format(
        cols=sql.SQL(", ").join(
            sql.SQL("v.{}").format(sql.Identifier(c)) for c in (table.key, *(n for n, _ in table.columns))
        ),
        seen=_seen_in(sets),
        storage=sql.SQL(storage),  # quoted by tgsis.storage_table
        visible=_visible_in(sets),
        where=where,
    )


def _id_spans(ids: npt.NDArray[np.int64], cuts: int = 3) -> list[tuple[int, int]]:
    """(first, last) spans covering the sorted unique ``ids``, cut at their ``cuts`` widest gaps (at most ``cuts + 1``).

    What a BRIN is searched by: one search per span, the page ranges whose
    values meet it rechecked (as ``tgsis.mesh_merge_work`` cuts them).
    """
    # the differences of sorted int64 ids, exact as uint64 (as int64 they wrap between ids at both ends of the
    # range); ~gaps sorts them widest first, the first of equal gaps first
    gaps = np.diff(ids).view(np.uint64)
    widest = np.argsort(~gaps, kind="stable")[:cuts]
    cut = np.sort(widest[gaps[widest] > 1])
    starts, ends = np.concatenate([[0], cut + 1]), np.concatenate([cut, [len(ids) - 1]])
    return [(int(ids[a]), int(ids[b])) for a, b in zip(starts, ends, strict=True)]


def _corner_ids(columns: list[npt.NDArray[Any]], k: int) -> npt.NDArray[np.int64]:
    """The vertex ids of cell rows read as ``[object key, cell id, vrtxid1..k, _seen]``, of rows some side sees."""
    seen = np.asarray(columns[-1]) != 0
    return np.concatenate([np.asarray(c, dtype=np.int64)[seen] for c in columns[2 : 2 + k]] + [np.empty(0, np.int64)])


def _revision_sets(conn: Conn, sides: Mapping[str, tuple[str, int]]) -> dict[str, list[int]]:
    sets = {}
    for side, (version, revision) in sides.items():
        conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        row = conn.execute("SELECT tgsis.get_revisions(true)").fetchone()
        assert row is not None
        sets[side] = sorted(int(r) for r in row[0])
    return sets


def _read_change(
    conn: Conn, fc: FeatureClass, geoid: int, sides: Mapping[str, tuple[str, int]]
) -> tuple[dict[str, _Rows], tuple[int, int]] | None:
    """The rows of base, parent and child restricted to the change and its one-ring, and the largest ids of the three.

    The sets of :func:`tgsis.merge3.change_neighbourhood` with ``rings=1``
    (enough for the regions, automatic merges and side solutions; a manual
    mesh is applied to whole states), read by key: the rows the sides'
    revisions since the base wrote or closed (the storage's revision
    indexes), the cells of those ids, the cells on the vertices found (one
    scan of the object's cells, a hashed ``= ANY`` of constants per row),
    then the rows of the vertex and cell ids so found. None when
    the object is read whole instead: a role that may not read the storage,
    or an object with GOCAD atoms or part runs (kept whole by
    :func:`read_merge_states`: an atom refers to a vertex anywhere, the runs
    are the object's).
    """
    tables, properties = _tables(fc)
    storages = _readable_storages(conn, tables)
    if storages is None:
        return None
    vertex_t, cell_t, atom_t, part_t = tables[:4]
    vertex_s, cell_s, atom_s, part_s = storages[:4]
    for storage, t in ((atom_s, atom_t), (part_s, part_t)):
        any_row = conn.execute(
            sql.SQL("SELECT EXISTS (SELECT FROM {} v WHERE v.{} = %s)").format(sql.SQL(storage), sql.Identifier(t.key)),
            (geoid,),
        ).fetchone()
        if any_row is None or any_row[0]:
            return None
    sets = _revision_sets(conn, sides)
    since = sorted(
        set(sets["base"]).symmetric_difference(sets["parent"]) | set(sets["base"]).symmetric_difference(sets["child"])
    )
    k = mesh_class(fc.geotype).cell_size
    alignments = [a for a, _ in properties]
    cell_cols = (*cell_t.columns, ("_seen", "int4"))

    def decoded_by(function: str, call: str, args: tuple[Any, ...], fallback: str) -> str:
        """The relation (a parenthesized subquery, aliased by the reads) that ``call`` of the SQL function
        ``function`` (its signature) names for ``args``; ``fallback`` for a role that may not execute it (granted to
        tgsis's roles: another role reads the decoded view, as before)."""
        allowed = conn.execute("SELECT has_function_privilege(%s, 'EXECUTE')", (function,)).fetchone()
        if not (allowed and allowed[0]):
            return fallback
        row = conn.execute(call, args).fetchone()
        assert row is not None
        return str(row[0])

    def changes(t: _Table, s: str) -> str:
        """The relation to read the change of ``t`` from: of a table stored in chunks, only the slots of the changed
        chunks whose values (bit for bit) or presence differ between the three states (``tgsis.storage_changed_rows``:
        the change, not its chunks); else the storage ``s``."""
        if s != f"tgsis.{t.view}_chunk_rows":
            return s
        return decoded_by(
            "tgsis.storage_changed_rows(text, text, bigint[], integer[], integer[], integer[])",
            "SELECT tgsis.storage_changed_rows(%s, %s, %s::bigint[], %s::integer[], %s::integer[], %s::integer[])",
            (t.schema, t.view, [geoid], sets["base"], sets["parent"], sets["child"]),
            s,
        )

    # the rows whose visibility differs: their ids are the change (any superset of it will do)
    changed = columns_out_all(
        conn,
        [
            Packed(t.changed(changes(t, s), sets, since), t.key, (*t.columns, ("_seen", "int4")), [geoid])
            for t, s in zip([vertex_t, cell_t, *tables[4:]], [vertex_s, cell_s, *storages[4:]], strict=True)
        ],
    )
    v0 = [np.asarray(changed[0][1], dtype=np.int64)]
    c0 = [np.asarray(changed[1][1], dtype=np.int64)]
    for alignment, columns in zip(alignments, changed[2:], strict=True):
        (v0 if alignment == "VERTEX" else c0).append(np.asarray(columns[1], dtype=np.int64))
    v0_ids, c0_ids = np.unique(np.concatenate(v0)), np.unique(np.concatenate(c0))

    def holding(t: _Table, s: str, ids: npt.NDArray[np.int64]) -> str:
        """The relation to read rows of ``ids`` from: of a table stored in chunks, only the chunks holding them
        decoded (``tgsis.storage_row_versions``, the merges' one way to name it); else the storage ``s``."""
        if s != f"tgsis.{t.view}_chunk_rows" or not len(ids):
            return s
        return decoded_by(
            "tgsis.storage_row_versions(text, text, bigint[])",
            "SELECT tgsis.storage_row_versions(%s, %s, %s::bigint[])",
            (t.schema, t.view, np.unique(ids).tolist()),
            s,
        )

    def around(vertex_ids: npt.NDArray[np.int64]) -> str:
        """The relation to read the cells on ``vertex_ids`` from: of a table stored in chunks, only the chunks whose
        vertex-id bounds hold one of them decoded (``tgsis.storage_cells_on``; no vertex-to-cell index there); else
        the storage ``cell_s``, whose vertex BRIN :func:`on` searches."""
        if cell_s != f"tgsis.{cell_t.view}_chunk_rows" or not len(vertex_ids):
            return cell_s
        return decoded_by(
            "tgsis.storage_cells_on(text, bigint[])",
            "SELECT tgsis.storage_cells_on(%s, %s::bigint[])",
            (cell_t.view, np.unique(vertex_ids).tolist()),
            cell_s,
        )

    def cells(where: sql.Composable, within: str = cell_s) -> list[npt.NDArray[Any]]:
        return columns_out_all(
            conn, [Packed(_rows_where(cell_t, within, sets, where), cell_t.key, cell_cols, [geoid])]
        )[0]

    def on(vertex_ids: npt.NDArray[np.int64]) -> sql.Composable:
        # the storage's vertex BRIN (tgsis.create_revision_indexes) searched by a few spans of the ids, each
        # cell found tested exactly against the hashed ids (+ 0: not an index condition, which would search
        # the BRIN once per id)
        if len(vertex_ids) == 0:
            return sql.SQL("false")
        ids = _int8_array(vertex_ids)
        columns = [sql.Identifier(f"vrtxid{j + 1}") for j in range(k)]
        spans = sql.SQL(" OR ").join(
            sql.SQL("v.{} BETWEEN {} AND {}").format(c, sql.Literal(lo), sql.Literal(hi))
            for c in columns
            for lo, hi in _id_spans(np.unique(vertex_ids))
        )
        exact = sql.SQL(" OR ").join(sql.SQL("(v.{} + 0) = ANY ({})").format(c, ids) for c in columns)
        return sql.SQL("({}) AND ({})").format(spans, exact)

    by_id = (
        cells(
            sql.SQL("v.{} = ANY ({})").format(sql.Identifier(cell_t.columns[0][0]), _int8_array(c0_ids)),
            holding(cell_t, cell_s, c0_ids),
        )
        if len(c0_ids)
        else None
    )
    v1 = np.unique(np.concatenate([v0_ids, _corner_ids(by_id, k) if by_id is not None else v0_ids[:0]]))
    ring1 = cells(on(v1), around(v1))
    c1 = np.unique(np.concatenate([c0_ids, np.asarray(ring1[1], dtype=np.int64)[np.asarray(ring1[-1]) != 0]]))
    v2 = np.unique(np.concatenate([v1, _corner_ids(ring1, k)] + ([_corner_ids(by_id, k)] if by_id is not None else [])))

    def by_ids(t: _Table, ids: npt.NDArray[np.int64]) -> sql.Composable:
        if len(ids) == 0:
            return sql.SQL("false")
        return sql.SQL("v.{} = ANY ({})").format(sql.Identifier(t.columns[0][0]), _int8_array(ids))

    wanted = [(vertex_t, vertex_s, v2), (cell_t, cell_s, c1)] + [
        (t, s, v2 if alignment == "VERTEX" else c1)
        for t, s, alignment in zip(tables[4:], storages[4:], alignments, strict=True)
    ]
    read = columns_out_all(
        conn,
        [
            Packed(
                _rows_where(t, holding(t, s, ids), sets, by_ids(t, ids)),
                t.key,
                (*t.columns, ("_seen", "int4")),
                [geoid],
            )
            for t, s, ids in wanted
        ],
    )
    top = []
    for t, s in ((vertex_t, vertex_s), (cell_t, cell_s)):
        idcol = sql.Identifier(t.columns[0][0])
        if s == f"tgsis.{t.view}_chunk_rows":  # stored in chunks: the visible chunk versions' last ids, not decoded
            query = sql.SQL("SELECT max({last}) FROM {chunks} v WHERE v.{key} = %s AND {visible}").format(
                last=last_id(conn, t.view, "v"),
                chunks=sql.Identifier("tgsis", f"{t.view}_chunk"),
                key=sql.Identifier(t.key),
                visible=_visible_in(sets),
            )
        else:
            query = sql.SQL(
                "SELECT v.{id} FROM {storage} v WHERE v.{key} = %s AND {visible} ORDER BY v.{id} DESC LIMIT 1"
            ).format(id=idcol, storage=sql.SQL(s), key=sql.Identifier(t.key), visible=_visible_in(sets))
        row = conn.execute(query, (geoid,)).fetchone()
        top.append(-1 if row is None or row[0] is None else int(row[0]))

    none = np.empty(0, dtype=np.int64)
    rows = {}
    for side, bit in _SIDE_BITS.items():
        per_table = []
        for columns in read:
            mine = (np.asarray(columns[-1]) & bit) != 0
            per_table.append([np.asarray(c)[mine] for c in columns[:-1]])
        vertex_cols, cell_cols_read, *prop_cols = per_table
        rows[side] = _rows_of(fc, properties, [vertex_cols, cell_cols_read, [none] * 3, [none] * 4, *prop_cols])
    return rows, (top[0], top[1])


def read_merge_change(conn: Conn, version: str, feature_id: int) -> tuple[MergeInputs, tuple[int, int]] | None:
    """:func:`read_merge_states` restricted to the change and its one-ring, and the largest vertex and cell ids.

    The states hold the rows :func:`tgsis.merge3.change_neighbourhood` names
    with ``rings=1`` (docs/merge.md): :func:`tgsis.merge3.three_way_merge` of
    them with ``top_ids`` finds exactly the regions, renumbering and merged
    rows of the whole states, and so do the solutions ``parent``, ``child``
    and ``base``, reading rows in proportion to the change rather than the
    object. For the merges that need regions and the merged rows; not for
    what needs the whole object (an export, a manual or average mesh, which
    may hold rows elsewhere and drop cells of the ring). Same checks,
    refusals and settings as :func:`read_merge_states`.

    Returns
    -------
    (MergeInputs, (int, int)) or None
        None when the object is read whole instead (a role that may not read
        the storage, GOCAD atoms or part runs): then :func:`read_merge_states`.
    """
    settings = read_version_settings(conn)
    try:
        versionid, parent, (initrevision, parent_working, working), fc = _checked_object(conn, version, feature_id)
        read = _read_change(
            conn,
            fc,
            feature_id,
            {"base": (version, initrevision), "parent": (parent, parent_working), "child": (version, working)},
        )
    finally:
        if conn.info.transaction_status != psycopg.pq.TransactionStatus.INERROR:
            restore_version_settings(conn, settings, local=True)
    if read is None:
        return None
    rows, top = read
    inputs = MergeInputs(fc, versionid, parent, (initrevision, parent_working, working), _states(fc, feature_id, rows))
    return inputs, top


# --------------------------------------------------------------------------- models 2 and 3: the states slice by slice

#: per time model: the tables a state is read from (the view's name in tgsis, and how many of its first columns,
#: after the object key, make the row's key within the object: the slice key columns and the row id)
_SLICE_TABLES: dict[str, tuple[tuple[_Table, int], ...]] = {
    "INSTANTS": (
        (_Table("times", "tgsis", "geoid", (("times", "float8"),)), 1),
        (
            _Table(
                "times_vrtx",
                "tgsis",
                "geoid",
                (("times", "float8"), ("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8")),
            ),
            2,
        ),
        (
            _Table(
                "times_trgl",
                "tgsis",
                "geoid",
                (
                    ("times", "float8"),
                    ("trglid", "int8"),
                    ("vrtxid1", "int8"),
                    ("vrtxid2", "int8"),
                    ("vrtxid3", "int8"),
                ),
            ),
            2,
        ),
    ),
    "EVOLVING": (
        (_Table("timet", "tgsis", "geoid", (("timem", "float8"), ("timet", "float8"))), 2),
        (
            _Table(
                "d4dvrtx",
                "tgsis",
                "geoid",
                (
                    ("timem", "float8"),
                    ("timet", "float8"),
                    ("nodeid", "int8"),
                    ("x", "float8"),
                    ("y", "float8"),
                    ("z", "float8"),
                ),
            ),
            3,
        ),
        (
            _Table(
                "d4dtrgl",
                "tgsis",
                "geoid",
                (
                    ("timem", "float8"),
                    ("trglid", "int8"),
                    ("nodeid1", "int8"),
                    ("nodeid2", "int8"),
                    ("nodeid3", "int8"),
                ),
            ),
            2,
        ),
    ),
}
#: per time model: the time key columns of the class's property tables (the registry's ``timekey``)
SLICE_KEYS = {"INSTANTS": ("_times",), "EVOLVING": ("_timem", "_timet")}


def _sliced_tables(fc: FeatureClass) -> tuple[list[tuple[_Table, int]], list[tuple[str, list[str]]]]:
    """The tables of a model-2/3 object's state (with their key widths) and the property tables' names."""
    tables = list(_SLICE_TABLES[fc.time_model])
    keys = SLICE_KEYS[fc.time_model]
    properties: list[tuple[str, list[str]]] = []
    for alignment in ("VERTEX", "CELL"):
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if props and protable is not None:
            properties.append((alignment, [p.name for p in props]))
            columns = (*((k, "float8") for k in keys), ("_idx", "int8"), *((p.name, p.wire) for p in props))
            tables.append((_Table(protable, fc.schema, "_geoid", columns), len(keys) + 1))
    return tables, properties


def _key_words(columns: list[npt.NDArray[Any]]) -> npt.NDArray[np.int64]:
    """(n, k) words of k key columns, equal words exactly for equal keys (a float's -0.0 as 0.0, as PostgreSQL)."""
    words = []
    for c in columns:
        a = np.asarray(c)
        if a.dtype.kind == "f":
            words.append(np.ascontiguousarray(a.astype(np.float64) + 0.0).view(np.int64))
        else:
            words.append(a.astype(np.int64))
    return np.stack(words, axis=1) if words else np.zeros((0, 0), dtype=np.int64)


def _patched_by_keys(
    base: list[npt.NDArray[Any]], changed: list[npt.NDArray[Any]], width: int, bit: int
) -> list[npt.NDArray[Any]]:
    """:func:`_patched` for rows keyed by their first ``width`` columns (after the object key): slice key and id.

    The composite keys of both reads are numbered in their order
    (``np.unique`` over the rows), the number stands in as :func:`_patched`'s
    row key, and is dropped again.
    """
    n = len(np.asarray(base[0]))
    words = _key_words(
        [
            np.concatenate([np.asarray(b), np.asarray(c)])
            for b, c in zip(base[1 : 1 + width], changed[1 : 1 + width], strict=True)
        ]
    )
    if len(words):
        codes = key_codes(words)
    else:
        codes = np.zeros(0, dtype=np.int64)
    order = np.argsort(codes[:n], kind="stable")
    coded_base = [np.asarray(base[0])[order], codes[:n][order], *(np.asarray(c)[order] for c in base[1:])]
    coded_changed = [np.asarray(changed[0]), codes[n:], *(np.asarray(c) for c in changed[1:])]
    patched = _patched(coded_base, coded_changed, bit)
    return [patched[0], *patched[2:]]


def _read_sliced_rows(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    sides: Mapping[str, tuple[str, int]],
    changed_only: bool = False,
    ring: bool = False,
) -> tuple[dict[str, list[list[npt.NDArray[Any]]]], dict[tuple[float, ...], tuple[int, int]]]:
    """Each side's columns of each table of :func:`_sliced_tables` (``[object key, *columns]``).

    As :func:`_read_states`: the base in full through the views, the sides
    patched with the storage rows their revisions since the base wrote or
    closed (``tgsis.storage_table``, the caller's rights and row-level
    security); a role that may not read the storage reads every side in full
    through the views.

    ``changed_only``: the rows of the instants (model 3: the topology
    periods) some side's revisions since the base touched only, the others
    left out of all three sides alike (they are the same on all three). The
    storage rows that changed are read first; their first time key (model
    2: ``times``; model 3: ``timem``) chooses the base's rows to read. With
    the full read through the views, everything is read.
    """
    tables = [t for t, _ in _sliced_tables(fc)[0]]
    widths = [w for _, w in _sliced_tables(fc)[0]]
    sets = {}
    for side, (version, revision) in sides.items():
        conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        row = conn.execute("SELECT tgsis.get_revisions(true)").fetchone()
        assert row is not None
        sets[side] = sorted(int(r) for r in row[0])
    storages = _readable_storages(conn, tables)
    full = [Packed(t.source, t.key, t.columns, [geoid]) for t in tables]
    if storages is None:
        out = {}
        for side, (version, revision) in sides.items():
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
            out[side] = [list(c) for c in columns_out_all(conn, full)]
        return out, {}
    base_version, base_revision = sides["base"]
    conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (base_version, base_revision))
    since = sorted(
        set(sets["base"]).symmetric_difference(sets["parent"]) | set(sets["base"]).symmetric_difference(sets["child"])
    )
    changes = [
        Packed(t.changed(storage, sets, since), t.key, (*t.columns, ("_seen", "int4")), [geoid])
        for t, storage in zip(tables, storages, strict=True)
    ]
    if changed_only:
        changed = columns_out_all(conn, changes)
        touched = sorted({float(v) + 0.0 for c in changed for v in np.asarray(c[1], dtype=np.float64).tolist()})
        if ring:
            return _sliced_ring(conn, fc, geoid, tables, storages, sets, changed, touched)
        base = columns_out_all(conn, [_within(t, touched, geoid) for t in tables])
    else:
        read = columns_out_all(conn, full + changes)
        base, changed = read[: len(tables)], read[len(tables) :]
    out = {"base": [list(c) for c in base]}
    for side in ("parent", "child"):
        out[side] = [
            _patched_by_keys(list(b), list(c), w, _SIDE_BITS[side])
            for b, c, w in zip(base, changed, widths, strict=True)
        ]
    return out, {}


def _in_groups(
    columns: list[npt.NDArray[Any]], width: int, wanted: Mapping[float, npt.NDArray[np.int64]]
) -> npt.NDArray[np.bool_]:
    """Which rows (``[object key, *key columns, ...]``) have an id of their group's ``wanted`` ids.

    A row's group is its first time key (model 2: its instant; model 3: its
    topology period), its id the last key column (``width``).
    """
    group = np.asarray(columns[1], dtype=np.float64) + 0.0
    ids = np.asarray(columns[width], dtype=np.int64)
    mask = np.zeros(len(ids), dtype=bool)
    for g, wanted_ids in wanted.items():
        at = group == g
        if at.any() and len(wanted_ids):
            mask[at] = np.isin(ids[at], wanted_ids)
    return mask


def _sliced_ring(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    tables: list[_Table],
    storages: list[str],
    sets: Mapping[str, list[int]],
    changed: list[list[npt.NDArray[Any]]],
    touched: list[float],
) -> tuple[dict[str, list[list[npt.NDArray[Any]]]], dict[tuple[float, ...], tuple[int, int]]]:
    """The touched slices restricted to the change and its one-ring, group by group, and each slice's largest ids.

    :func:`_read_change` of model 1 per group of slices sharing their
    triangles (model 2: an instant; model 3: a topology period, so that its
    geometry instants keep one topology): the ids the sides' revisions wrote
    or closed in the group (``changed``), the group's cells of those ids and
    on those vertices, then the vertex, cell and property rows of the ids so
    found, all visible in some side. The instant (period) tables' rows of the
    touched groups are read whole (few), and so is a group whose instant
    (geometry instant) row a side added or removed (the slice is taken or
    dropped whole). Returns each side's columns as
    :func:`_read_sliced_rows` does, and per slice key the largest vertex and
    cell ids any side sees there (``top_ids`` of the merge).
    """
    evolving = fc.time_model == "EVOLVING"
    widths = [w for _, w in _sliced_tables(fc)[0]]
    properties = _sliced_tables(fc)[1]
    keys_t, vertex_t, cell_t, *prop_ts = tables
    keys_s, vertex_s, cell_s, *prop_ss = storages
    vw, cw = widths[1], widths[2]
    groups = [float(g) for g in touched]
    none = np.empty(0, dtype=np.int64)

    def ids_by_group(columns: list[npt.NDArray[Any]], width: int) -> dict[float, npt.NDArray[np.int64]]:
        group = np.asarray(columns[1], dtype=np.float64) + 0.0
        ids = np.asarray(columns[width], dtype=np.int64)
        return {g: ids[group == g] for g in groups}

    def union(*parts: Mapping[float, npt.NDArray[np.int64]]) -> dict[float, npt.NDArray[np.int64]]:
        return {g: np.unique(np.concatenate([p.get(g, none) for p in parts] + [none])) for g in groups}

    v0 = [ids_by_group(changed[1], vw)]
    c0 = [ids_by_group(changed[2], cw)]
    for (alignment, _), columns, w in zip(properties, changed[3:], widths[3:], strict=True):
        (v0 if alignment == "VERTEX" else c0).append(ids_by_group(columns, w))
    v0_by, c0_by = union(*v0), union(*c0)

    def in_groups(t: _Table) -> sql.Composable:  # its first time key (times, timem, _times, _timem): the group
        return sql.SQL("v.{} = ANY ({}::float8[])").format(sql.Identifier(t.columns[0][0]), sql.Literal(groups))

    corners = [sql.Identifier(n) for n, _ in cell_t.columns[cw : cw + 3]]

    def read(t: _Table, s: str, where: sql.Composable) -> list[npt.NDArray[Any]]:
        return columns_out_all(
            conn,
            [
                Packed(
                    _rows_where(t, s, sets, sql.SQL("{} AND ({})").format(in_groups(t), where)),
                    t.key,
                    (*t.columns, ("_seen", "int4")),
                    [geoid],
                )
            ],
        )[0]

    def per_group(
        t: _Table, ids: Mapping[float, npt.NDArray[np.int64]], test: Callable[[npt.NDArray[np.int64]], sql.Composable]
    ) -> sql.Composable:
        # each group's own ids (not the union's at every group): the rows read follow each group's change
        parts = [
            sql.SQL("(v.{} = {}::float8 AND {})").format(sql.Identifier(t.columns[0][0]), sql.Literal(g), test(i))
            for g, i in ids.items()
            if len(i)
        ]
        return sql.SQL(" OR ").join(parts) if parts else sql.SQL("false")

    def by_ids(t: _Table, width: int, ids: Mapping[float, npt.NDArray[np.int64]]) -> sql.Composable:
        column = sql.Identifier(t.columns[width - 1][0])
        return per_group(t, ids, lambda i: sql.SQL("v.{} = ANY ({})").format(column, _int8_array(i)))

    def on_ids(every: npt.NDArray[np.int64]) -> sql.Composable:
        # the storage's vertex BRIN (tgsis.create_revision_indexes) searched by a few spans of the ids, each
        # cell found tested exactly against the hashed ids (+ 0: not an index condition), as model 1's
        every = np.unique(every)
        spans = sql.SQL(" OR ").join(
            sql.SQL("v.{} BETWEEN {} AND {}").format(c, sql.Literal(lo), sql.Literal(hi))
            for c in corners
            for lo, hi in _id_spans(every)
        )
        exact = sql.SQL(" OR ").join(sql.SQL("(v.{} + 0) = ANY ({})").format(c, _int8_array(every)) for c in corners)
        return sql.SQL("({}) AND ({})").format(spans, exact)

    def on(ids: Mapping[float, npt.NDArray[np.int64]]) -> sql.Composable:
        return per_group(cell_t, ids, on_ids)

    def only(columns: list[npt.NDArray[Any]], mask: npt.NDArray[np.bool_]) -> list[npt.NDArray[Any]]:
        return [np.asarray(c)[mask] for c in columns]

    def cell_corners(columns: list[npt.NDArray[Any]]) -> dict[float, npt.NDArray[np.int64]]:
        seen = np.asarray(columns[-1]) != 0
        group = np.asarray(columns[1], dtype=np.float64) + 0.0
        out = {}
        for g in groups:
            at = seen & (group == g)
            out[g] = np.concatenate([np.asarray(c, dtype=np.int64)[at] for c in columns[1 + cw : 1 + cw + 3]] + [none])
        return out

    def cells_on(columns: list[npt.NDArray[Any]], vertices: Mapping[float, npt.NDArray[np.int64]]) -> npt.NDArray[Any]:
        group = np.asarray(columns[1], dtype=np.float64) + 0.0
        mask = np.zeros(len(group), dtype=bool)
        for g in groups:
            at = group == g
            if at.any() and len(vertices[g]):
                mask[at] = np.any(
                    [np.isin(np.asarray(c, dtype=np.int64)[at], vertices[g]) for c in columns[1 + cw : 1 + cw + 3]],
                    axis=0,
                )
        return mask

    by_id = read(cell_t, cell_s, by_ids(cell_t, cw, c0_by))
    by_id = only(by_id, _in_groups(by_id, cw, c0_by))
    v1 = union(v0_by, cell_corners(by_id))
    ring1 = read(cell_t, cell_s, on(v1))
    ring1 = only(ring1, cells_on(ring1, v1))
    seen1 = only(ring1, np.asarray(ring1[-1]) != 0)
    c1 = union(c0_by, ids_by_group(seen1, cw))
    v2 = union(v1, cell_corners(ring1), cell_corners(by_id))
    wanted = [(vertex_t, vertex_s, vw, v2), (cell_t, cell_s, cw, c1)] + [
        (t, s, w, v2 if alignment == "VERTEX" else c1)
        for t, s, w, (alignment, _) in zip(prop_ts, prop_ss, widths[3:], properties, strict=True)
    ]
    # a group whose instant (model 3: geometry instant) row some side added or removed is read whole: its slice
    # is added or removed as a whole, every row of it written (rows a psql user left without their instant row too)
    whole = sorted({float(v) + 0.0 for v in np.asarray(changed[0][1], dtype=np.float64).tolist()})
    rows = []
    for t, s, w, ids in wanted:
        in_whole = sql.SQL("v.{} = ANY ({}::float8[])").format(sql.Identifier(t.columns[0][0]), sql.Literal(whole))
        columns = read(t, s, sql.SQL("({}) OR {}").format(by_ids(t, w, ids), in_whole) if whole else by_ids(t, w, ids))
        mask = _in_groups(columns, w, ids) | np.isin(np.asarray(columns[1], dtype=np.float64) + 0.0, whole)
        rows.append(only(columns, mask))
    slice_keys = read(keys_t, keys_s, sql.SQL("true"))
    out: dict[str, list[list[npt.NDArray[Any]]]] = {}
    for side, bit in _SIDE_BITS.items():
        per_table = []
        for columns in [slice_keys, *rows]:
            mine = (np.asarray(columns[-1]) & bit) != 0
            per_table.append([np.asarray(c)[mine] for c in columns[:-1]])
        out[side] = per_table
    # each slice's largest ids some side sees (the storage's primary key searched backwards, one row per slice)
    seen_keys = sorted(
        {
            tuple(float(v) + 0.0 for v in row)
            for row in zip(*(np.asarray(c).tolist() for c in slice_keys[1 : 1 + (2 if evolving else 1)]))
        }
    )
    return out, _slice_tops(conn, geoid, vertex_t, vertex_s, cell_t, cell_s, sets, seen_keys)


def _slice_tops(
    conn: Conn,
    geoid: int,
    vertex_t: _Table,
    vertex_s: str,
    cell_t: _Table,
    cell_s: str,
    sets: Mapping[str, list[int]],
    keys: list[tuple[float, ...]],
) -> dict[tuple[float, ...], tuple[int, int]]:
    """Per slice key: the largest vertex id and cell id visible in some side there (-1 for none).

    One statement for all the keys (they come as arrays, unnested): per key
    and table a subquery that searches the storage's primary key backwards
    (``ORDER BY id DESC LIMIT 1``), so that the cost is an index descent per
    key, not a scan of the object, and not two statements per touched slice.
    """
    if not keys:
        return {}
    width = len(keys[0])
    names = [f"k{i}" for i in range(width)]

    def top(t: _Table, s: str, n: int) -> sql.Composable:
        where = sql.SQL(" AND ").join(
            sql.SQL("v.{} = k.{}").format(sql.Identifier(c), sql.Identifier(k))
            for (c, _), k in zip(t.columns[:n], names, strict=False)
        )
        return sql.SQL(
            "coalesce((SELECT v.{id} FROM {storage} v WHERE v.{key} = {geoid} AND {where} AND {visible}"
            " ORDER BY v.{id} DESC LIMIT 1), -1)"
        ).format(
            id=sql.Identifier(t.columns[n][0]),
            storage=sql.SQL(s),
            key=sql.Identifier(t.key),
            geoid=sql.Placeholder("geoid"),
            where=where,
            visible=_visible_in(sets),
        )

    arrays = sql.SQL(", ").join(
        sql.SQL("{}::{}[]").format(sql.Placeholder(k), sql.SQL(typ))
        for k, (_, typ) in zip(names, vertex_t.columns[:width], strict=True)
    )
    query = sql.SQL("SELECT {}, {} FROM unnest({}) WITH ORDINALITY AS k ({}, o) ORDER BY k.o").format(
        top(vertex_t, vertex_s, width),
        top(cell_t, cell_s, 1),
        arrays,
        sql.SQL(", ").join(sql.Identifier(k) for k in names),
    )
    params: dict[str, Any] = {"geoid": geoid, **{k: [key[i] for key in keys] for i, k in enumerate(names)}}
    rows = conn.execute(query, params).fetchall()
    return {key: (int(v), int(c)) for key, (v, c) in zip(keys, rows, strict=True)}


def _within(table: _Table, touched: list[float], geoid: int) -> Packed:
    """The request of ``table``'s rows (through its view) whose first time key is one of ``touched``."""
    first = table.columns[0][0]  # times, timem, _times or _timem
    source = sql.SQL("(SELECT * FROM {} WHERE {} = ANY ({}::float8[])) AS _touched").format(
        table.source, sql.Identifier(first), sql.Literal(touched)
    )
    return Packed(source, table.key, table.columns, [geoid])


def _slice_rows(columns: list[npt.NDArray[Any]], width: int) -> dict[tuple[float, ...], npt.NDArray[np.intp]]:
    """The rows of each slice: the positions whose first ``width`` columns (after the object key) are its key.

    One sort of the rows by their key (not a scan per slice): the cost
    stays that of the rows however many instants an object has.
    """
    keys = [np.asarray(c, dtype=np.float64) + 0.0 for c in columns[1 : 1 + width]]
    if not len(keys[0]):
        return {}
    codes = key_codes(_key_words(keys))
    order = np.argsort(codes, kind="stable")  # each slice's positions ascending; a pass when grouped
    ranked = codes[order]
    starts = np.flatnonzero(np.concatenate([[True], ranked[1:] != ranked[:-1]]))
    ends = np.append(starts[1:], len(order))
    return {tuple(float(k[order[a]]) for k in keys): order[a:b] for a, b in zip(starts.tolist(), ends.tolist())}


def _sliced_state(
    fc: FeatureClass,
    geoid: int,
    side: str,
    read: list[list[npt.NDArray[Any]]],
    properties: list[tuple[str, list[str]]],
    instant_rows: Mapping[tuple[float, ...], tuple[str | None, ...]],
) -> SlicedState:
    """One side's slices (:class:`tgsis._merge_slices.SlicedState`) from its tables' columns."""
    evolving = fc.time_model == "EVOLVING"
    keys_cols, vertex_cols, cell_cols, *prop_cols = read
    width = 2 if evolving else 1
    keys = sorted(
        {tuple(float(v) for v in row) for row in zip(*(np.asarray(c).tolist() for c in keys_cols[1 : 1 + width]))}
    )
    slices: dict[tuple[float, ...], MeshState] = {}
    none = np.zeros(0, dtype=np.intp)
    vertex_rows = _slice_rows(vertex_cols, width)
    cell_rows = _slice_rows(cell_cols, 1)  # model 3: the period's triangles; model 2: the instant's
    prop_rows = [_slice_rows(columns, width) for columns in prop_cols]
    for key in keys:
        at_v = vertex_rows.get(key, none)
        at_c = cell_rows.get(key[:1], none)
        first_v, first_c = 1 + width, 1 + (1 if evolving else width)
        vids, xyz = _sorted_rows(
            np.asarray(vertex_cols[first_v])[at_v],
            np.stack([np.asarray(vertex_cols[first_v + i])[at_v] for i in (1, 2, 3)], axis=1),
        )
        cids, cells = _sorted_rows(
            np.asarray(cell_cols[first_c])[at_c],
            np.stack([np.asarray(cell_cols[first_c + i])[at_c] for i in (1, 2, 3)], axis=1),
        )
        props_by: dict[str, dict[str, npt.NDArray[Any]]] = {"VERTEX": {}, "CELL": {}}
        for (alignment, names), columns, rows in zip(properties, prop_cols, prop_rows, strict=True):
            at = rows.get(key, none)
            ids = vids if alignment == "VERTEX" else cids
            idx = np.asarray(columns[1 + width], dtype=np.int64)[at]
            for i, name in enumerate(names):
                props_by[alignment][name] = _aligned_values(ids, idx, np.asarray(columns[2 + width + i])[at])
        slices[key] = MeshState(
            3,
            vids,
            xyz.reshape(-1, 3).astype(np.float64, copy=False),
            cids,
            cells.reshape(-1, 3).astype(np.int64, copy=False),
            props_by["VERTEX"],
            props_by["CELL"],
            f"feature {geoid} ({side}, {slice_text(fc.time_model, key)})",
        )
    kind: Literal["INSTANTS", "EVOLVING"] = "EVOLVING" if evolving else "INSTANTS"
    return SlicedState(
        kind,
        slices,
        dict(instant_rows),
        f"feature {geoid} of class {fc.name}",
        tuple(p.name for p in fc.instant_properties),
    )


def _instant_rows(
    conn: Conn, fc: FeatureClass, geoid: int, version: str, revision: int
) -> dict[tuple[float, ...], tuple[str | None, ...]]:
    """The per-instant feature property rows (``<class>_pros``) as ``version`` sees them at ``revision``, as text."""
    if not fc.instant_properties or fc.protable is None:
        return {}
    keys = SLICE_KEYS[fc.time_model]
    conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
    digits = conn.execute("SELECT current_setting('extra_float_digits')").fetchone()
    conn.execute("SELECT set_config('extra_float_digits', '3', true)")  # floats as text, exactly
    try:
        rows = conn.execute(
            sql.SQL("SELECT {}, {} FROM {} WHERE _geoid = %s").format(
                sql.SQL(", ").join(sql.Identifier(k) for k in keys),
                sql.SQL(", ").join(sql.SQL("{}::text").format(sql.Identifier(p.name)) for p in fc.instant_properties),
                fc.qualified(fc.protable),
            ),
            (geoid,),
        ).fetchall()
    finally:
        if conn.info.transaction_status != psycopg.pq.TransactionStatus.INERROR:
            conn.execute("SELECT set_config('extra_float_digits', %s, true)", (str(digits[0] if digits else "1"),))
    return {tuple(float(v) for v in r[: len(keys)]): tuple(r[len(keys) :]) for r in rows}


@dataclass(frozen=True)
class SlicedInputs:
    """What a merge by region of one model-2 or model-3 object reads (as :class:`MergeInputs`, slice by slice).

    Attributes
    ----------
    feature_class : FeatureClass
    versionid : int
    parent : str
    revisions : (int, int, int)
    states : dict
        ``base``, ``parent``, ``child``: :class:`tgsis._merge_slices.SlicedState`.
    """

    feature_class: FeatureClass
    versionid: int
    parent: str
    revisions: tuple[int, int, int]
    states: dict[str, SlicedState]


def feature_time_model(conn: Conn, version: str, feature_id: int) -> str | None:
    """The time model of a feature as the version (else its parent) sees it now; None when neither has it."""
    settings = read_version_settings(conn)
    try:
        _, parent, _, working, parent_working = version_row(conn, version)
        for side, revision in ((version, working), (parent, parent_working)):
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (side, revision))
            row = conn.execute("SELECT timemodel::text FROM tgsis.geometry WHERE geoid = %s", (feature_id,)).fetchone()
            if row is not None:
                return str(row[0])
        return None
    finally:
        if conn.info.transaction_status != psycopg.pq.TransactionStatus.INERROR:
            restore_version_settings(conn, settings, local=True)


def read_sliced_states(
    conn: Conn, version: str, feature_id: int, *, changed_only: bool = False, ring: bool = False
) -> SlicedInputs:
    """Read base, parent and child of one model-2 or model-3 object changed on both sides, slice by slice.

    As :func:`read_merge_states` (the caller's transaction makes the reads
    consistent; the session's version settings are put back; the same
    refusals), for a surface at instants (model 2: a slice per instant) or an
    evolving surface (model 3: a slice per geometry instant of each topology
    period), with the per-instant feature properties.

    ``changed_only``: the slices of the instants (model 3: periods) some
    side changed only, the others left out of all three states alike: what
    a merge that writes by difference needs (they merge as themselves and
    write nothing), read at the cost of the change. The per-instant feature
    property rows are read whole.

    ``ring`` (with ``changed_only``): the touched slices restricted further
    to the change and its one-ring (:func:`read_merge_change` per instant,
    model 3 per topology period), with each slice's largest ids as the
    states' ``top_ids``: the same regions and merged rows, for the merges
    that need no whole slice (not a recorded average or manual mesh). A role
    that may not read the storage reads the touched slices whole.

    Raises
    ------
    InvalidInputError
        Not of model 2 or 3; deleted on one side; attributes changed on both sides.
    VersioningError
        Not changed on both sides since the version was based.
    """
    settings = read_version_settings(conn)
    try:
        versionid, parent, (initrevision, parent_working, working), fc = _checked_object(
            conn, version, feature_id, _refuse_unless_sliced_surface
        )
        sides = {"base": (version, initrevision), "parent": (parent, parent_working), "child": (version, working)}
        rows, tops = _read_sliced_rows(conn, fc, feature_id, sides, changed_only, ring)
        instants = {side: _instant_rows(conn, fc, feature_id, v, r) for side, (v, r) in sides.items()}
    finally:
        if conn.info.transaction_status != psycopg.pq.TransactionStatus.INERROR:
            restore_version_settings(conn, settings, local=True)
    properties = _sliced_tables(fc)[1]
    states = {
        side: dataclasses.replace(
            _sliced_state(fc, feature_id, side, rows[side], properties, instants[side]), top_ids=tops
        )
        for side in sides
    }
    return SlicedInputs(fc, versionid, parent, (initrevision, parent_working, working), states)
