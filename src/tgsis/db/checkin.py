"""Save only what changed, and check-out / check-in without lost updates.

A modeller checks a stored surface out, edits it in a desktop tool and checks
it back in. :func:`save_feature` writes the edited mesh over a stored feature
by difference (:func:`tgsis.compare_meshes`): deletes for the removed
vertices, simplices and property rows, binary COPY inserts for the new ones,
nothing for the rest, in one transaction. Unchanged vertices keep their
database ids, so unchanged simplices keep pointing at them; on versioned
tables a 1 % edit stores about 1 % new row versions instead of a copy.

:func:`checkout` returns the mesh with a :class:`CheckoutToken` recording the
version and revision it came from and a fingerprint of the stored object
(``tgsis.object_fingerprint``). With feature versioning on, and a role that
may write in the version, the check-out freezes the version's working
revision (``tgsis.checkout_revision``) and reads the mesh there, so that the
state it saw stays stored whatever others write next. :func:`checkin` locks
the object (``tgsis.check_unchanged``), compares the fingerprint with the
database's current state and refuses with
:class:`~tgsis.errors.CheckoutConflictError` when another writer changed the
object meanwhile, or, with ``on_conflict="child"``, creates a child version
based on that frozen revision and writes the edit there by difference from
the check-out, so that the two edits meet as a conflict of the normal merge
path (``find_conflicts``, ``resolve_conflict``, ``merge_version``); otherwise
it saves the difference from the checked-out base.
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
import os
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis._vertex_metadata import renumbered
from tgsis.arguments import checked
from tgsis.compare import MeshDiff, MeshIndex, compare_meshes
from tgsis.db._chunk_write import next_id as next_chunk_id
from tgsis.db._chunk_write import stored_in_chunks
from tgsis.db._settings import read_version_settings, restore_version_settings
from tgsis.db._state_write import (
    PART_PROPERTY,
    update_geometry_row,
    write_model_rows,
    write_property_edit,
    write_state_rows,
)
from tgsis.db._static import (
    MEANING_COLUMNS,
    SIMPLEX,
    Part,
    copy_extra_rows,
    download,
    extra_rows,
    part_meaning,
    restore_extras,
)
from tgsis.db._transfer import (
    Storage,
    aligned_properties,
    check_feature_values,
    consistent_read,
    feature_columns,
    local_positions,
    resolve_class,
)
from tgsis.db.classes import FeatureClass, class_of_feature, stores_part_column
from tgsis.db.copy import SQL_TYPES, array_wire
from tgsis.db.meaning import meaning_of, restore_meaning, z_convention
from tgsis.db.versions import show_name
from tgsis.edits import EditPlan, plan_edit
from tgsis.errors import (
    CheckoutConflictError,
    FileFormatError,
    InvalidGeometryError,
    InvalidInputError,
    NotFoundError,
    reraise,
)
from tgsis.merge3 import MeshState, three_way_merge
from tgsis.mesh import Geotype, Mesh, mesh_class

__all__ = [
    "StoredMesh",
    "SaveResult",
    "CheckoutToken",
    "Checkout",
    "CheckinResult",
    "save_feature",
    "checkout",
    "checkin",
]

log = logging.getLogger(__name__)

Conn = psycopg.Connection[Any]
IntArray = npt.NDArray[np.int64]


# --------------------------------------------------------------------------- the stored object with its ids


@dataclass
class StoredMesh:
    """A stored model-1 geometry with the database ids of its rows.

    Attributes
    ----------
    mesh : Mesh
        In stored id order, with the class's vertex or cell properties.
    vertex_ids : (n,) int64
        ``tgsis.vrtx.vrtxid`` of each vertex, ascending.
    cell_ids : (m,) int64
        Simplex id (``trglid``, ``segid``, ...) of each cell, ascending.
    """

    mesh: Mesh
    vertex_ids: IntArray
    cell_ids: IntArray


def _feature_row(conn: Conn, fc: FeatureClass, geoid: int) -> tuple[str | None, str, dict[str, Any]]:
    """(geoname, geotype, feature properties) of a feature; NotFoundError when the class has no such feature."""
    props = [p.name for p in fc.feature_properties]
    row = conn.execute(
        sql.SQL(
            "SELECT g.geoname, g.geotype{} FROM {} f JOIN tgsis.geometry g ON g.geoid = f._geoid WHERE f._geoid = %s"
        ).format(
            sql.SQL("").join(sql.SQL(", f.{}").format(sql.Identifier(p)) for p in props), fc.qualified(fc.featuretable)
        ),
        (geoid,),
        binary=True,  # float values (properties, colours) bit for bit, whatever the session's extra_float_digits
    ).fetchone()
    if row is None:
        raise NotFoundError(f"feature class {fc.name} has no feature {geoid}")
    return row[0], row[1], dict(zip(props, row[2:]))


def _stored_mesh(conn: Conn, fc: FeatureClass, geoid: int, name: str | None) -> StoredMesh:
    """Download one static, non-collection geometry with its row ids (one query for its tables: :func:`tgsis.db._static.download`)."""
    data = download(conn, fc, {geoid: Part(fc.geotype, name, f"feature {geoid} of class {fc.name}")})
    _, vid, x, y, z = data.vertices
    vorder = np.argsort(vid, kind="stable")
    vertex_ids = vid[vorder]
    cells = data.cells[fc.geotype]
    corder = np.argsort(cells[1], kind="stable")
    cell_ids = cells[1][corder]
    table = SIMPLEX[fc.geotype][0]
    simplices = (
        np.stack([local_positions(vertex_ids, c[corder], f"{table} rows", geoid) for c in cells[2:]], axis=1)
        if len(cells) > 2
        else np.empty((0, mesh_class(fc.geotype).cell_size), dtype=np.int64)
    )
    values: dict[str, dict[str, npt.NDArray[Any]]] = {"VERTEX": {}, "CELL": {}}
    for (alignment, _), columns in data.properties.items():  # the class's alignment, and the other one if any
        pid = columns[1]
        porder = np.argsort(pid, kind="stable")
        targets = vertex_ids if alignment == "VERTEX" else cell_ids
        if not np.array_equal(pid[porder], targets):
            raise InvalidGeometryError(
                f"feature {geoid} of class {fc.name}: {fc.property_table(alignment)} has "
                f"{len(pid)} rows that do not match its {len(targets)} "
                f"{'vertices' if alignment == 'VERTEX' else 'cells'}",
                hint=f"SELECT * FROM tgsis.check_geometry({geoid})",
            )
        values[alignment] = {p.name: columns[2 + i][porder] for i, p in enumerate(fc.aligned(alignment))}  # all of them
    mesh = mesh_class(fc.geotype)(
        np.stack([x[vorder], y[vorder], z[vorder]], axis=1),
        simplices,
        vertex_properties=values["VERTEX"],
        cell_properties=values["CELL"],
        name=name,
    )
    # parts and atoms come with it; z stays in storage's convention (elevation)
    restore_extras(
        mesh,
        Part(fc.geotype, name, ""),
        data,
        geoid,
        vertex_ids.astype(np.int64),
        cell_ids.astype(np.int64),
        file_convention=False,
    )
    return StoredMesh(mesh, vertex_ids.astype(np.int64), cell_ids.astype(np.int64))


def _in_storage_convention(mesh: Mesh) -> Mesh:
    """The mesh with z as stored (elevation): a copy with z negated when its metadata says Depth.

    A mesh without ``metadata["zpositive"]`` (a check-out's) is in storage's
    convention already.
    """
    if z_convention(mesh.metadata) != "Depth":
        return mesh
    flipped = mesh.copy()
    flipped.vertices[:, 2] = -flipped.vertices[:, 2]
    return flipped


def _checked_class(conn: Conn, feature_class: str | FeatureClass | None, feature_id: int) -> FeatureClass:
    """The feature's class, refusing the kinds of features saving by difference does not handle."""
    fc = resolve_class(conn, feature_class) if feature_class is not None else class_of_feature(conn, feature_id)
    if fc.time_model != "STATIC":
        raise InvalidInputError(
            f"feature class {fc.name} is temporal ({fc.time_model}): check-out and saving by "
            "difference are for static (model-1) features",
            hint="store a new SurfaceSeries or EvolvingSurface, or edit its instants",
        )
    if fc.geotype is Geotype.GEOMETRYCOLLECTION:
        raise InvalidInputError(
            f"feature class {fc.name} holds GEOMETRYCOLLECTION features: check-out and saving by "
            "difference take one mesh",
            hint="delete the feature and insert the edited collection (tgsis.insert_feature)",
        )
    return fc


# --------------------------------------------------------------------------- save by difference


@dataclass(frozen=True)
class SaveResult:
    """What a save by difference wrote.

    Attributes
    ----------
    feature_id : int
    version : str
        The version written to.
    diff : MeshDiff
        Edited mesh against the stored one.
    rows_deleted : int
        Rows deleted or closed (vertices, simplices, property rows).
    rows_inserted : int
        Rows inserted (vertices, simplices, property rows).
    rows_updated : int
        Geometry and feature rows updated (bounding box, counts, name, feature properties).
    property_rows_changed : int
        Property rows of kept vertices or cells whose values changed (counted
        in both ``rows_deleted`` and ``rows_inserted``).
    vertices_moved : int
        Removed-and-added vertex pairs written as one vertex moved
        (:mod:`tgsis.edits`): its row rewritten, its cells kept.
    cells_removed, cells_added : int
        Cells deleted and written anew, compared by content: a cell of moved
        vertices is the same cell (kept, as it is stored), unlike in ``diff``,
        which compares by position and sees it removed and added.
    cells_on_moved : int
        Kept cells with a moved vertex (``diff`` counts them removed and added).
    """

    feature_id: int
    version: str
    diff: MeshDiff
    rows_deleted: int
    rows_inserted: int
    rows_updated: int
    property_rows_changed: int
    vertices_moved: int = 0
    cells_removed: int = 0
    cells_added: int = 0
    cells_on_moved: int = 0

    @property
    def rows_written(self) -> int:
        """All rows deleted, closed, inserted or updated."""
        return self.rows_deleted + self.rows_inserted + self.rows_updated


def _same_values(a: npt.NDArray[Any], b: npt.NDArray[Any]) -> npt.NDArray[np.bool_]:
    """Per element (row of a vector property) equality in which NaN equals NaN (a NaN that stays NaN is no change)."""
    same: npt.NDArray[np.bool_] = a == b
    if a.dtype.kind == "f":
        same |= np.isnan(a) & np.isnan(b)
    return np.asarray(same.all(axis=1)) if same.ndim == 2 else same


def _next_id(conn: Conn, storage: Storage, table: str, key: str, idfield: str, geoid: int) -> int:
    """The first id above every id the object has ever had in ``table`` (every row version when versioned)."""
    if stored_in_chunks(conn, table):
        return next_chunk_id(conn, table, geoid)
    row = conn.execute(
        sql.SQL("SELECT max({}) FROM {} WHERE {} = %s").format(
            sql.Identifier(idfield), storage.table("tgsis", table), sql.Identifier(key)
        ),
        (geoid,),
    ).fetchone()
    return 0 if row is None or row[0] is None else int(row[0]) + 1


#: the largest local id: the id columns are bigint
_LARGEST_ID = 2**63 - 1


def _fresh_ids(conn: Conn, storage: Storage, table: str, idfield: str, geoid: int, n: int) -> IntArray:
    """(n,) ids for ``n`` new rows of ``table``: above every id the object has ever had (:func:`_next_id`).

    Raises
    ------
    InvalidInputError
        The object's ids (of some version, in ``table``'s storage) reach so
        high that ``n`` more pass the largest bigint: refused before anything
        is written (the ids would wrap to negative ones, or fail in the server).
    """
    if n == 0:
        return np.empty(0, dtype=np.int64)
    first = _next_id(conn, storage, table, "geoid", idfield, geoid)
    if first + n - 1 > _LARGEST_ID:
        what = "vertex" if table == "vrtx" else "cell"
        raise InvalidInputError(
            f"feature {geoid}: the edit adds {n} {what} row(s) to tgsis.{table}, which take ids above every id the "
            f"object has had there ({first - 1}), and {idfield} is a bigint that ends at {_LARGEST_ID}: "
            "nothing was written",
            hint="store the edited mesh as a new feature (its ids start again from 0) and delete this one",
        )
    return np.arange(first, first + n, dtype=np.int64)


@dataclass(frozen=True)
class _Written:
    """Database ids of the edited mesh's vertices and cells after a save, and the row counts."""

    vertex_ids: IntArray
    cell_ids: IntArray
    cell_values: Mapping[str, npt.NDArray[Any]]
    deleted: int
    inserted: int
    property_changes: int


def _write_diff(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    stored: StoredMesh,
    edited: Mesh,
    plan: EditPlan,
    cell_values: Mapping[str, npt.NDArray[Any]],
    storage: Storage,
) -> _Written:
    """Write the difference ``stored`` -> ``edited`` of one geometry in the session's version (caller's transaction).

    Moved vertices are rewritten under their old id (delete + insert: on a
    versioned table that is closing the old row version and adding one).
    """
    table, idfield = SIMPLEX[fc.geotype]
    if storage.versioned and ("tgsis", "vrtx") in storage.versioned:
        conn.execute(
            "SELECT tgsis.check_objects_unlocked(objectclass, ARRAY[%s]) FROM tgsis.versioned_tables "
            "WHERE schemaname = 'tgsis' AND tablename = 'vrtx'",
            (str(geoid),),
        )

    # ids: kept and moved vertices and kept cells keep theirs, new ones get fresh ones above every id used before
    added_v, added_c, moved = plan.added_vertices, plan.added_cells, plan.moved_vertices
    vertex_ids = np.empty(edited.n_vertices, dtype=np.int64)
    kept_v = plan.vertex_map >= 0
    vertex_ids[kept_v] = stored.vertex_ids[plan.vertex_map[kept_v]]
    if len(added_v):
        vertex_ids[added_v] = _fresh_ids(conn, storage, "vrtx", "vrtxid", geoid, len(added_v))
    cell_ids = np.empty(edited.n_cells, dtype=np.int64)
    kept_c = plan.cell_map >= 0
    cell_ids[kept_c] = stored.cell_ids[plan.cell_map[kept_c]]
    if len(added_c):
        cell_ids[added_c] = _fresh_ids(conn, storage, table, idfield, geoid, len(added_c))

    # property rows: those of removed elements go, those of new elements come, changed values are replaced
    # (per alignment: a class may have vertex and cell properties side by side)
    deleted = inserted = changes = 0
    for alignment in ("VERTEX", "CELL"):
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if not props or protable is None:
            continue
        if alignment == "VERTEX":
            element_map, old_ids, new_ids, removed = (
                plan.vertex_map,
                stored.vertex_ids,
                vertex_ids,
                plan.removed_vertices,
            )
            old_values = stored.mesh.vertex_properties
        else:
            element_map, old_ids, new_ids, removed = plan.cell_map, stored.cell_ids, cell_ids, plan.removed_cells
            old_values = stored.mesh.cell_properties
        kept = np.flatnonzero(element_map >= 0)
        changed = np.zeros(len(kept), dtype=bool)
        for p in props:
            changed |= ~_same_values(old_values[p.name][element_map[kept]], cell_values[p.name][kept])
        rewrite = np.concatenate([kept[changed], np.flatnonzero(element_map < 0)])
        changes += int(changed.sum())
        going = np.concatenate([old_ids[removed], new_ids[kept[changed]]])
        columns: list[tuple[str, npt.ArrayLike, str]] = [
            ("_geoid", np.full(len(rewrite), geoid, dtype=np.int64), "int8"),
            ("_idx", new_ids[rewrite], "int8"),
            *((p.name, cell_values[p.name][rewrite], array_wire(SQL_TYPES[p.type], p.size)) for p in props),
        ]
        gone_n, fresh_n = write_property_edit(conn, storage, fc.schema, protable, geoid, going, columns, len(rewrite))
        deleted, inserted = deleted + gone_n, inserted + fresh_n

    written_v = np.concatenate([moved, added_v])
    for gone, added in (
        write_model_rows(
            conn,
            storage,
            table,
            idfield,
            geoid,
            stored.cell_ids[plan.removed_cells],
            cell_ids[added_c],
            vertex_ids[edited.cells[added_c]].reshape(-1, edited.cell_size),
        ),
        write_model_rows(
            conn,
            storage,
            "vrtx",
            "vrtxid",
            geoid,
            np.concatenate([stored.vertex_ids[plan.removed_vertices], vertex_ids[moved]]),
            vertex_ids[written_v],
            edited.vertices[written_v],
        ),
    ):
        deleted, inserted = deleted + gone, inserted + added
    return _Written(vertex_ids, cell_ids, cell_values, deleted, inserted, changes)


def _meaning_columns(edited: Mesh, vertex_ids: IntArray) -> list[tuple[str, str, Any]]:
    """(column of ``tgsis.geometry``, placeholder, value) of what the edited mesh's metadata says of its file's meaning.

    ``vertex_ids`` (n,) int64: the id each vertex of ``edited`` is stored under. The metadata's vertex flags
    and control nodes name vertices by place in ``edited``; they are stored by id (``tgsis._vertex_metadata``),
    as atoms are, so that they name the same vertices once a download gives the vertices in id order.
    """
    meaning = meaning_of(edited, "the edited mesh")
    if meaning.metadata is not None:
        meaning = replace(
            meaning,
            metadata=renumbered(
                meaning.metadata, edited.n_vertices, vertex_ids, edited.name, "its vertices cannot be stored by id"
            ),
        )
    meta = edited.metadata
    columns: list[tuple[str, str, Any]] = []
    if "zpositive" in meta:
        columns.append(("zpositive", "%s::text", meaning.zpositive))
    if "gocad_coordinate_system" in meta:
        columns.append(("crs", "%s::jsonb", meaning.crs_json()))
    if meaning.color is not None:
        columns += [(c, "%s::real", v) for c, v in zip(("colorred", "colorgreen", "colorblue"), meaning.color)]
    if meaning.metadata is not None:
        # the order of the stored ids (metadata["vertex_order"], set by an upload in the spatial order) is the
        # database's, not the file's: a file written by difference keeps the stored ids, so it keeps the label
        holder = "%s::jsonb" if "vertex_order" in meaning.metadata else _KEEP_VERTEX_ORDER
        columns.append(("metadata", holder, meaning.metadata_json()))
    return columns


#: the edited metadata, with the stored row's "vertex_order" (read where the column ``metadata`` is tgsis.geometry's)
_KEEP_VERTEX_ORDER = (
    "(%s::jsonb || CASE WHEN metadata ? 'vertex_order' "
    "THEN jsonb_build_object('vertex_order', metadata -> 'vertex_order') ELSE '{}'::jsonb END)"
)


_MEANING_WORDS = {
    "zpositive": "z convention",
    "crs": "coordinate system",
    "colorred": "colour",
    "colorgreen": "colour",
    "colorblue": "colour",
    "metadata": "metadata",
}


def _meaning_not_applied(conn: Conn, fc: FeatureClass, geoid: int, edited: Mesh, vertex_ids: IntArray) -> list[str]:
    """What the edited file says of its meaning that differs from the stored one (which a merge keeps): the words
    of :data:`_MEANING_WORDS`, and ``GOCAD atoms``; compared as a plain check-in would write them, but a
    coordinate system or metadata where none is stored (what a file format adds by itself)."""
    differ: list[str] = []
    for column, holder, value in _meaning_columns(edited, vertex_ids):
        # a coordinate system or metadata the database never had: the file format's defaults (a GOCAD writer's
        # coordinate system block, its header keys), which tell nothing of an edit
        optional = column in ("crs", "metadata")
        row = conn.execute(
            sql.SQL(
                "SELECT {c} IS DISTINCT FROM {v} AND ({c} IS NOT NULL OR NOT %s) FROM tgsis.geometry WHERE geoid = %s"
            ).format(c=sql.Identifier(column), v=sql.SQL(holder)),
            (value, optional, geoid),
        ).fetchone()
        word = _MEANING_WORDS[column]
        if row is not None and row[0] and word not in differ:
            differ.append(word)
    meaning = meaning_of(edited, "the edited mesh")
    atoms = sorted((int(vertex_ids[a]), int(vertex_ids[r])) for a, r in meaning.atoms)
    stored = [
        (int(v), int(r))
        for v, r in conn.execute(
            "SELECT vrtxid, refid FROM tgsis.atom WHERE geoid = %s ORDER BY vrtxid, refid", (geoid,)
        ).fetchall()
    ]
    if "gocad_atoms" in edited.metadata and atoms != stored:
        differ.append("GOCAD atoms")
    return differ


def _update_meaning(conn: Conn, fc: FeatureClass, geoid: int, edited: Mesh, written: _Written, storage: Storage) -> int:
    """Bring the file's meaning (z convention, coordinate system, colour, metadata, atoms, parts) up to date.

    What the edited mesh's metadata does not mention stays as stored; atoms
    and parts are rewritten only when they changed (few rows). Returns the
    rows changed.
    """
    meaning = meaning_of(edited, "the edited mesh")
    columns = _meaning_columns(edited, written.vertex_ids)
    changed = 0
    if columns:
        names = [sql.Identifier(c) for c, _, _ in columns]
        holders = [sql.SQL(h) for _, h, _ in columns]
        values = [v for _, _, v in columns]
        changed += max(
            conn.execute(
                sql.SQL(
                    "UPDATE tgsis.geometry SET ({}) = ROW({}) WHERE geoid = %s AND ROW({}) IS DISTINCT FROM ROW({})"
                ).format(
                    sql.SQL(", ").join(names),
                    sql.SQL(", ").join(holders),
                    sql.SQL(", ").join(names),
                    sql.SQL(", ").join(holders),
                ),
                [*values, geoid, *values],
            ).rowcount,
            0,
        )
    atoms, parts = extra_rows(fc, geoid, edited, meaning, written.vertex_ids, written.cell_ids)
    stored_atoms = [
        tuple(int(v) for v in r)
        for r in conn.execute(
            "SELECT geoid, vrtxid, refid, patom::int FROM tgsis.atom WHERE geoid = %s ORDER BY vrtxid", (geoid,)
        ).fetchall()
    ]
    stored_parts = [
        tuple(int(v) for v in r)
        for r in conn.execute(
            "SELECT geoid, firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (geoid,)
        ).fetchall()
    ]
    if sorted(atoms) != stored_atoms:
        changed += max(conn.execute("DELETE FROM tgsis.atom WHERE geoid = %s", (geoid,)).rowcount, 0)
        copy_extra_rows(conn, storage, atoms, [])
        changed += len(atoms)
    if sorted(parts) != stored_parts:
        changed += max(conn.execute("DELETE FROM tgsis.part WHERE geoid = %s", (geoid,)).rowcount, 0)
        copy_extra_rows(conn, storage, [], parts)
        changed += len(parts)
    return changed


def _update_rows(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    edited: Mesh,
    bounds: npt.NDArray[np.float64] | None,
    name: str | None,
    feature_values: Mapping[str, Any] | None,
) -> int:
    """Bring the geometry row (box, counts, name) and the feature row up to date; rows changed (0 when equal)."""
    changed = update_geometry_row(conn, geoid, bounds, edited.n_vertices, edited.n_cells, name=name, set_name=True)
    if feature_values:
        columns = list(feature_values)
        changed += conn.execute(
            sql.SQL("UPDATE {} SET {} WHERE _geoid = %s AND ({}) IS DISTINCT FROM ({})").format(
                fc.qualified(fc.featuretable),
                sql.SQL(", ").join(sql.SQL("{} = %s").format(sql.Identifier(c)) for c in columns),
                sql.SQL(", ").join(sql.Identifier(c) for c in columns),
                sql.SQL(", ").join(sql.Placeholder() for _ in columns),
            ),
            [*feature_values.values(), geoid, *feature_values.values()],
        ).rowcount
    return max(changed, 0)


def _save(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    stored: StoredMesh,
    edited: Mesh,
    plan: EditPlan,
    properties: Mapping[str, Any] | None,
    name: str | None,
    drop_extra: bool,
) -> tuple[SaveResult, _Written]:
    """Write the edit in the caller's transaction and describe it."""
    if edited.geotype != fc.geotype:
        raise InvalidGeometryError(
            f"feature class {fc.name} holds {fc.geotype.value} features, "
            f"not {edited.geotype.value} ({type(edited).__name__})"
        )
    cell_values = aligned_properties(fc, edited, drop_extra, "the edited mesh")
    feature_values = feature_columns(fc, properties)
    check_feature_values(conn, fc, feature_values)
    storage = Storage.of(conn, fc)
    storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
    written = _write_diff(conn, fc, geoid, stored, edited, plan, cell_values, storage)
    updated = _update_rows(conn, fc, geoid, edited, plan.bounds, name, feature_values)
    updated += _update_meaning(conn, fc, geoid, edited, written, storage)
    version = str(conn.execute("SELECT tgsis.get_working_version()").fetchone()[0])  # type: ignore[index]
    result = SaveResult(
        geoid,
        version,
        plan.diff,
        written.deleted,
        written.inserted,
        updated,
        written.property_changes,
        len(plan.moved_vertices),
        len(plan.removed_cells),
        len(plan.added_cells),
        len(plan.diff.added_cells) - len(plan.added_cells),
    )
    log.info(
        "saved %s feature %d in %s by difference: %s, %d vertices moved; %d rows written",
        fc.name,
        geoid,
        version,
        plan.diff,
        result.vertices_moved,
        result.rows_written,
    )
    return result, written


def _plan(old: Mesh | MeshIndex, edited: Mesh, tolerance: float) -> EditPlan:
    """Compare, then plan the rows to write (with the edited mesh's bounding box, for the geometry row)."""
    return plan_edit(old, edited, compare_meshes(old, edited, tolerance))


def _new_name(name: str | None, edited: Mesh, stored_name: str | None) -> str | None:
    """The geometry name after a save: the one asked for, else the edited mesh's, else the stored one."""
    return name if name is not None else edited.name if edited.name is not None else stored_name


def _mesh_arg(edited: Any) -> Mesh:
    if not isinstance(edited, Mesh):
        from tgsis.convert import as_mesh  # a pyvista, meshio or trimesh object (else: what is accepted)

        edited = as_mesh(edited)
    if not isinstance(edited, Mesh):
        raise InvalidGeometryError(
            f"an edited mesh must be a PointSet, LineSet, Surface or TetraMesh, not {type(edited).__name__}"
        )
    return edited


@checked
def save_feature(
    conn: Conn,
    feature_class: str | FeatureClass | None,
    feature_id: int,
    edited: Mesh,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    tolerance: float = 0.0,
    drop_extra_properties: bool = False,
) -> SaveResult:
    """Write an edited mesh over a stored feature, by difference, in the session's version.

    Compares ``edited`` with what the database holds now and writes only the
    difference (one transaction). Unlike :func:`checkin` it does not ask
    whether someone changed the feature since you read it: it is "save over".

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str, FeatureClass or None
        None: found from the feature id.
    feature_id : int
    edited : Mesh
        Of the class's geotype, with the class's vertex or cell properties (or
        a pyvista, meshio or trimesh object, converted by :func:`tgsis.as_mesh`).
    properties : mapping, optional
        Feature properties to change (others are left as they are).
    name : str, optional
        New geometry name (default: ``edited.name``, or the stored name when that is None).
    tolerance : float
        Vertex matching tolerance (see :func:`tgsis.compare_meshes`).
    drop_extra_properties : bool
        Ignore mesh properties the class does not store instead of failing.

    Returns
    -------
    SaveResult

    Raises
    ------
    NotFoundError, InvalidGeometryError, InvalidPropertyError, InvalidInputError
        Nothing is written.
    ReadOnlyRevisionError, ObjectLockedError, MissingPrivilegeError
        The session may not write the feature in its version.
    """
    mesh = _in_storage_convention(_mesh_arg(edited))
    with reraise(), conn.transaction():
        fc = _checked_class(conn, feature_class, feature_id)
        conn.execute("SELECT tgsis.feature_write_lock(%s)", (feature_id,))
        stored_name, _, _ = _feature_row(conn, fc, feature_id)
        stored = _stored_mesh(conn, fc, feature_id, stored_name)
        result, _ = _save(
            conn,
            fc,
            feature_id,
            stored,
            mesh,
            _plan(stored.mesh, mesh, tolerance),
            properties,
            _new_name(name, mesh, stored_name),
            drop_extra_properties,
        )
    return result


# --------------------------------------------------------------------------- check-out / check-in


@dataclass(frozen=True)
class CheckoutToken:
    """Where a checked-out mesh came from.

    Attributes
    ----------
    feature_id : int
    feature_class : str
    version : str
        The version it was checked out of (check-in writes there).
    revision : int
        The revision whose state was checked out: ``base_revision`` when
        there is one, else the version's working revision at check-out.
    fingerprint : str
        ``tgsis.object_fingerprint`` of the feature at check-out.
    database : str
        ``current_database()`` at check-out.
    checked_out_at : str
        ISO time of the check-out.
    base_revision : int or None
        The frozen revision that holds the checked-out state (the base of the
        child version of a conflicting check-in); None when nothing was
        frozen: feature versioning off, a role without the write right in the
        version, a read-only transaction, or a token written before
        check-outs froze revisions (such a check-in tries ``revision``, and
        takes the child path only if that revision is frozen and still holds
        the checked-out state).
    """

    feature_id: int
    feature_class: str
    version: str
    revision: int
    fingerprint: str
    database: str
    checked_out_at: str
    base_revision: int | None = None

    def to_json(self) -> str:
        """The token as a JSON object."""
        return json.dumps(self.__dict__, sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> CheckoutToken:
        """A token from :meth:`to_json`."""
        try:
            data = json.loads(text)
            token = cls(**{k: data[k] for k in cls.__dataclass_fields__ if k in data or k not in _OPTIONAL_FIELDS})
        except (ValueError, KeyError, TypeError) as exc:
            raise FileFormatError(f"not a tgsis check-out token: {exc}") from None
        for key in ("feature_id", "revision", "base_revision"):
            value = getattr(token, key)
            if (value is not None or key != "base_revision") and (
                isinstance(value, bool) or not isinstance(value, int)
            ):
                raise FileFormatError(f"not a tgsis check-out token: {key} is {value!r}, not an integer")
        return token


_OPTIONAL_FIELDS = frozenset({"base_revision"})  # absent from tokens written before check-outs froze revisions


@dataclass
class Checkout:
    """A checked-out feature: the mesh to edit, and the base and token that check-in needs.

    Attributes
    ----------
    token : CheckoutToken
    base : StoredMesh
        The feature as checked out, with its database ids (do not modify).
    properties : dict
        Feature properties at check-out.
    mesh : Mesh
        A copy of the base mesh to edit (or replace by any edited mesh), in
        its file's z convention and with its file's metadata (coordinate
        system, colour, ...); the base is in storage's convention (elevation).
    """

    token: CheckoutToken
    base: StoredMesh
    properties: dict[str, Any] = field(default_factory=dict)
    mesh: Mesh = field(init=False)
    _index: MeshIndex | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self.mesh = self.base.mesh.copy()

    def index(self) -> MeshIndex:
        """The base mesh prepared for comparison (built on first use, so that check-in hashes only the edit)."""
        if self._index is None:
            self._index = MeshIndex(self.base.mesh)
        return self._index

    # ---- files (the command line keeps a check-out beside the edited file)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the token and base to ``path`` (a ``.npz`` file); returns the path."""
        base = self.base.mesh
        arrays: dict[str, Any] = {
            "token": np.array(self.token.to_json()),
            "properties": np.array(json.dumps(self.properties, default=str)),
            "geotype": np.array(base.geotype.value),
            "name": np.array(json.dumps(base.name)),
            "vertices": base.vertices,
            "cells": base.cells,
            "vertex_ids": self.base.vertex_ids,
            "cell_ids": self.base.cell_ids,
        }
        for kind, values in (("vertex", base.vertex_properties), ("cell", base.cell_properties)):
            for key, array in values.items():
                arrays[f"{kind}_property__{key}"] = array
        target = Path(path)
        with open(target, "wb") as out:
            np.savez(out, **arrays)
        return target

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Checkout:
        """A check-out written by :meth:`save`."""
        try:
            with np.load(Path(path), allow_pickle=False) as data:
                token = CheckoutToken.from_json(str(data["token"]))
                props = {
                    kind: {k.split("__", 1)[1]: data[k] for k in data.files if k.startswith(f"{kind}_property__")}
                    for kind in ("vertex", "cell")
                }
                mesh = mesh_class(Geotype(str(data["geotype"])))(
                    data["vertices"],
                    data["cells"],
                    vertex_properties=props["vertex"],
                    cell_properties=props["cell"],
                    name=json.loads(str(data["name"])),
                )
                base = StoredMesh(mesh, data["vertex_ids"].astype(np.int64), data["cell_ids"].astype(np.int64))
                properties = json.loads(str(data["properties"]))
        except (OSError, ValueError, KeyError) as exc:
            raise FileFormatError(f"{path}: not a tgsis check-out file: {exc}") from None
        return cls(token, base, properties)


@dataclass(frozen=True)
class CheckinResult:
    """What a check-in did.

    Attributes
    ----------
    save : SaveResult
        The rows written (in ``save.version``).
    conflict : bool
        True when the feature had changed since check-out: the edit went into
        the new child version ``save.version`` (``on_conflict="child"``), or
        was merged by region with that change (``on_conflict="merge"``, ``merged``).
    checkout : Checkout or None
        With ``keep=True``: a check-out of the new state, to go on editing
        (none after a merge: the stored state holds both edits, not the file's; check out again).
    merged : bool
        The edit and the change made since check-out were merged by region
        (``on_conflict="merge"``); ``save`` counts the rows of the merged state written.
    not_applied : tuple of str
        After a merge: what the edited file says of its meaning that differs
        from the stored one and was not written (the merge keeps the stored
        ``z convention``, ``coordinate system``, ``colour``, ``metadata``,
        ``GOCAD atoms``); empty otherwise.
    """

    save: SaveResult
    conflict: bool = False
    checkout: Checkout | None = None
    merged: bool = False
    not_applied: tuple[str, ...] = ()

    @property
    def version(self) -> str:
        """The version the edit was written to."""
        return self.save.version


def _working_state(conn: Conn) -> tuple[str, int]:
    row = conn.execute("SELECT tgsis.get_working_version(), tgsis.get_working_revision()").fetchone()
    assert row is not None
    return str(row[0]), int(row[1])


def _freeze(conn: Conn) -> int | None:
    """``tgsis.checkout_revision()``: the frozen revision holding the session's state, or None (nothing frozen)."""
    row = conn.execute("SELECT tgsis.checkout_revision()").fetchone()
    return None if row is None or row[0] is None else int(row[0])


@checked
def checkout(conn: Conn, feature_id: int, feature_class: str | FeatureClass | None = None) -> Checkout:
    """Check a feature out of the session's version for editing.

    The mesh, its row ids and the fingerprint come from one snapshot. With
    feature versioning on and the write right in the version, the version's
    working revision is first frozen (``tgsis.checkout_revision``: a short
    transaction of its own that waits for the version's open writers, or
    part of the caller's transaction when one is open) and the feature is
    read at that revision, recorded as ``token.base_revision``: a
    conflicting :func:`checkin` with ``on_conflict="child"`` starts its child
    version there. Viewing an older revision, that revision is the base and
    nothing is frozen; a role without the write right (or a read-only, or
    an enclosing REPEATABLE READ or SERIALIZABLE, transaction) freezes
    nothing and takes no lock.

    Parameters
    ----------
    conn : psycopg.Connection
    feature_id : int
    feature_class : str or FeatureClass, optional
        Found from the id when omitted.

    Returns
    -------
    Checkout
        ``.mesh`` to edit; give it (or any edited mesh) to :func:`checkin`.

    Raises
    ------
    NotFoundError
        No such feature.
    InvalidInputError
        A temporal or GEOMETRYCOLLECTION feature.
    """
    fresh = conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
    with reraise():
        with conn.transaction():  # bad input is refused before anything is frozen
            if fresh:  # the freeze waits for open writers: later statements must see their commits
                conn.execute("SET TRANSACTION ISOLATION LEVEL READ COMMITTED")
            try:
                fc = _checked_class(conn, feature_class, feature_id)
                _feature_row(conn, fc, feature_id)
            except NotFoundError as exc:  # deleted in, or never brought to, the version worked in: say which
                raise NotFoundError(
                    f"{exc.message} in version {show_name(_working_state(conn)[0])}", detail=exc.detail, hint=exc.hint
                ) from exc
            frozen = _freeze(conn)

    def read() -> tuple[Any, ...]:
        """The fingerprint and the rows, of one state (:func:`consistent_read`)."""
        settings = read_version_settings(conn)
        version, revision = _working_state(conn)
        if frozen is not None:  # a frozen revision's state never changes: no lock is needed to read it
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, frozen))
            revision = frozen
        name, _, properties = _feature_row(conn, fc, feature_id)
        row = conn.execute("SELECT tgsis.object_fingerprint(%s), current_database()", (feature_id,)).fetchone()
        assert row is not None
        base = _stored_mesh(conn, fc, feature_id, name)
        meaning = conn.execute(
            f"SELECT {MEANING_COLUMNS} FROM tgsis.geometry g WHERE g.geoid = %s", (feature_id,), binary=True
        ).fetchone()
        restore_version_settings(conn, settings, local=True)  # for the rest of an enclosing transaction
        return version, revision, name, properties, row, base, meaning

    with reraise():
        version, revision, name, properties, row, base, meaning = consistent_read(conn, "checkout", read)
    token = CheckoutToken(
        feature_id,
        fc.name,
        version,
        revision,
        str(row[0]),
        str(row[1]),
        _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        frozen,
    )
    log.info(
        "checked out %s feature %d from %s at revision %d%s",
        fc.name,
        feature_id,
        version,
        revision,
        " (frozen)" if frozen is not None else "",
    )
    checked_out = Checkout(token, base, properties)
    if meaning is not None:  # the mesh to edit is in its file's convention, with its metadata (the base is as stored)
        restore_meaning(checked_out.mesh, **part_meaning(meaning), vertex_ids=base.vertex_ids)
    checked_out.index()  # hashed now, so that the check-in hashes only the edited mesh
    return checked_out


def _unique_version_name(conn: Conn, wanted: str) -> str:
    name, n = wanted, 1
    while conn.execute("SELECT 1 FROM tgsis.versions WHERE name = %s", (name,)).fetchone() is not None:
        n += 1
        name = f"{wanted}_{n}"
    return name


@checked
def checkin(
    conn: Conn,
    checked_out: Checkout,
    edited: Mesh | None = None,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    tolerance: float = 0.0,
    on_conflict: Literal["raise", "child", "merge"] = "raise",
    child_version: str | None = None,
    keep: bool = False,
    drop_extra_properties: bool = False,
) -> CheckinResult:
    """Write an edited mesh back to the feature it was checked out as, if nobody changed the feature meanwhile.

    In one transaction, in the version of the check-out: lock the feature
    (``tgsis.feature_write_lock``, which other check-ins, saves and deletes
    take too), compare its fingerprint with the token's and, when they are
    equal, write the difference between the checked-out base and ``edited``
    (:func:`save_feature` semantics). The comparison of the meshes runs
    beside the server's fingerprint.

    Parameters
    ----------
    conn : psycopg.Connection
    checked_out : Checkout
        From :func:`checkout` (or :meth:`Checkout.load`).
    edited : Mesh, optional
        The edited mesh (default: ``checked_out.mesh``), or a pyvista, meshio
        or trimesh object (converted by :func:`tgsis.as_mesh`).
    properties : mapping, optional
        Feature properties to change.
    name : str, optional
        New geometry name (default: ``edited.name``).
    tolerance : float
        Vertex matching tolerance (see :func:`tgsis.compare_meshes`).
    on_conflict : {"raise", "child"}
        When the feature changed since check-out: ``"raise"``
        :class:`~tgsis.errors.CheckoutConflictError` and write nothing, or
        ``"child"``: create a child version of the check-out's version (named
        ``child_version``, default ``checkin_<id>``, made unique) based on the
        revision the check-out froze (``token.base_revision``), and write the
        edit there by difference from the checked-out base. The other
        writer's change stays in the parent, and :func:`tgsis.find_conflicts`
        reports the feature, so that :func:`tgsis.resolve_conflict` decides
        what :func:`tgsis.merge_version` keeps (``parent``: theirs,
        ``child``: yours, ``manual``: a merged mesh you save in the child).
        ``"merge"``: a three-way merge by region (:func:`tgsis.merge3.three_way_merge`)
        of the checked-out base, the current state (read under the feature's
        write lock) and the edit (its kept and moved rows with the base's ids,
        new rows with new ids): when no region conflicts, the merged state is
        written over the current one by an id-keyed difference in the
        check-out's version; otherwise :class:`~tgsis.errors.CheckoutConflictError`
        names the conflicting regions (ids, box) and nothing is written. The
        mesh is merged, with its parts (``tgsis.part``); GOCAD atoms and the
        file's meaning (z convention, coordinate system, colour, metadata)
        stay as currently stored, and :attr:`CheckinResult.not_applied` names
        those the edited file gives otherwise.
    child_version : str, optional
        Name for that child version.
    keep : bool
        Return a new :class:`Checkout` of the written state, to go on editing.
    drop_extra_properties : bool

    Returns
    -------
    CheckinResult

    Raises
    ------
    CheckoutConflictError
        The feature changed (or was deleted) since check-out, with
        ``on_conflict="raise"``; or with ``on_conflict="child"`` when no child
        can start from the checked-out state (feature versioning off, the
        check-out froze nothing, its revision was compressed away or its
        version re-based by a merge or refresh since, or the token does not
        match that revision); nothing is written.
    NotFoundError, InvalidGeometryError, InvalidPropertyError, InvalidInputError
        Nothing is written.
    """
    token = checked_out.token
    mesh = _in_storage_convention(_mesh_arg(edited if edited is not None else checked_out.mesh))
    if on_conflict not in ("raise", "child", "merge"):
        raise InvalidInputError(f"on_conflict must be 'raise', 'child' or 'merge', not {on_conflict!r}")
    with reraise(), conn.transaction():
        database = conn.execute("SELECT current_database(), current_setting('transaction_isolation')").fetchone()
        if database is not None and database[1] != "read committed":
            raise InvalidInputError(
                f"check-in runs in a {database[1]} transaction: it must see commits made while "
                "it waits for the feature's lock",
                hint="check in outside a transaction, or in a READ COMMITTED one",
            )
        if database is None or database[0] != token.database:
            raise InvalidInputError(
                f"feature {token.feature_id} was checked out of database {token.database!r}, "
                f"not {database[0] if database else None!r}"
            )
        settings = read_version_settings(conn)
        conn.execute("SELECT tgsis.goto_version(%s, true)", (token.version,))
        fc = _checked_class(conn, token.feature_class, token.feature_id)
        with ThreadPoolExecutor(max_workers=1) as pool:  # numpy compares while the server fingerprints
            pending = pool.submit(_plan, checked_out.index(), mesh, tolerance)
            try:
                with conn.transaction():
                    conn.execute(
                        "SELECT tgsis.check_unchanged(%s, %s, %s)",
                        (token.feature_id, token.fingerprint, token.revision),
                    )
                conflict = None
            except psycopg.Error as exc:
                if getattr(exc, "sqlstate", None) != CheckoutConflictError.code or on_conflict == "raise":
                    raise
                conflict = exc
            plan = pending.result()
        if conflict is None:
            result, written = _save(
                conn,
                fc,
                token.feature_id,
                checked_out.base,
                mesh,
                plan,
                properties,
                _new_name(name, mesh, checked_out.base.mesh.name),
                drop_extra_properties,
            )
        elif on_conflict == "merge":
            result, not_applied = _checkin_merge(
                conn, fc, checked_out, mesh, plan, properties, name, drop_extra_properties, conflict
            )
            restore_version_settings(conn, settings, local=True)
            return CheckinResult(result, True, None, merged=True, not_applied=not_applied)
        else:
            result, written = _checkin_into_child(
                conn, fc, checked_out, mesh, plan, properties, name, child_version, drop_extra_properties, str(conflict)
            )
        kept = _kept_checkout(conn, fc, token, mesh, written) if keep else None
        restore_version_settings(conn, settings, local=True)  # for the rest of an enclosing transaction
    return CheckinResult(result, conflict is not None, kept)


_REDO_HINT = (
    "check out again and redo the edit on the current state (or save it over that state with "
    "tgsis.save_feature), or check it in with on_conflict='raise' to see the conflict only"
)


def _checkin_into_child(
    conn: Conn,
    fc: FeatureClass,
    checked_out: Checkout,
    mesh: Mesh,
    plan: EditPlan,
    properties: Mapping[str, Any] | None,
    name: str | None,
    child_version: str | None,
    drop_extra: bool,
    reason: str,
) -> tuple[SaveResult, _Written]:
    """Create a child of the check-out's version based on the checked-out state and save the edit there by difference.

    The child starts at the frozen revision the check-out read, so that its
    difference holds only this edit and the other writer's change (made in
    the parent's later revisions) shows as a conflict in ``find_conflicts``.
    Before anything is written, the child must hold exactly what the token's
    fingerprint says was checked out (a token from before check-outs froze
    revisions, or an altered one, is refused).
    """
    token = checked_out.token
    refused = reason.splitlines()[0]
    versioned = conn.execute(
        "SELECT 1 FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'vrtx'"
    ).fetchone()
    if versioned is None:
        raise CheckoutConflictError(
            f"{refused}; no child version can take the edit: feature versioning is off",
            hint="tgsis.enable_feature_versioning(conn) (or `tgsis versioning enable`) makes on_conflict='child' work",
        )
    base = token.base_revision if token.base_revision is not None else token.revision
    child = _unique_version_name(conn, child_version or f"checkin_{token.feature_id}")
    try:
        with conn.transaction():
            conn.execute(
                "SELECT tgsis.create_version(%s, %s, %s, %s)",
                (
                    child,
                    token.version,
                    f"check-in of feature {token.feature_id} checked out at revision "
                    f"{base}, which conflicted in {token.version}",
                    base,
                ),
            )
    except psycopg.Error as exc:
        if getattr(exc, "sqlstate", None) != NotFoundError.code:
            raise
        raise CheckoutConflictError(
            f"{refused}; no child version can start from the state it was checked out as: {exc.diag.message_primary}",
            detail=exc.diag.message_detail,
            hint=_REDO_HINT,
        ) from None
    conn.execute("SELECT tgsis.goto_version(%s, true)", (child,))
    row = conn.execute("SELECT tgsis.object_fingerprint(%s)", (token.feature_id,)).fetchone()
    if row is None or row[0] != token.fingerprint:
        raise CheckoutConflictError(
            f"{refused}; no child version can start from the state it was checked out as: revision {base} of "
            f"version {token.version!r} does not hold feature {token.feature_id} as the check-out token describes "
            "it (a token from before check-outs froze their revision, taken while others could still write in "
            "that revision, or an altered one)",
            hint=_REDO_HINT,
        )
    log.warning(
        "feature %d changed in %s since check-out: the edit goes into new child version %s, based on revision %d",
        token.feature_id,
        token.version,
        child,
        base,
    )
    return _save(
        conn,
        fc,
        token.feature_id,
        checked_out.base,
        mesh,
        plan,
        properties,
        _new_name(name, mesh, checked_out.base.mesh.name),
        drop_extra,
    )


def _mesh_state(
    fc: FeatureClass,
    mesh: Mesh,
    vertex_ids: IntArray,
    cell_ids: IntArray,
    what: str,
    parts: npt.NDArray[Any] | None = None,
) -> MeshState:
    """A mesh with the database ids of its rows as a :class:`MeshState`, with the class's property columns
    (and ``parts``, (m,), as the cell property ``part`` that :mod:`tgsis.db._state_write` writes to ``tgsis.part``)."""
    by_alignment = {a: [p.name for p in fc.aligned(a)] for a in ("VERTEX", "CELL")}
    cell_properties = {n: np.asarray(mesh.cell_properties[n]) for n in by_alignment["CELL"]}
    if parts is not None:
        cell_properties[PART_PROPERTY] = parts
    return MeshState(
        mesh.cell_size,
        vertex_ids,
        mesh.vertices,
        cell_ids,
        vertex_ids[mesh.cells] if mesh.n_cells else np.empty((0, mesh.cell_size), dtype=np.int64),
        {n: np.asarray(mesh.vertex_properties[n]) for n in by_alignment["VERTEX"]},
        cell_properties,
        what,
    )


def _merge_parts(fc: FeatureClass, base: Mesh, current: Mesh, edited: Mesh, cell_map: IntArray) -> list[Any]:
    """The part of each cell of the base, the current state and the edit, when the class keeps parts in ``tgsis.part``.

    ``[None, None, None]`` when neither has parts. -1: a cell in no part. An
    edit without parts (a file that dropped them) keeps the base's parts of
    the cells it kept: it changed no part.
    """
    if stores_part_column(fc) or not any(PART_PROPERTY in m.cell_properties for m in (base, current, edited)):
        return [None, None, None]

    def of(mesh: Mesh) -> npt.NDArray[Any]:
        values = mesh.cell_properties.get(PART_PROPERTY)
        return np.full(mesh.n_cells, -1, dtype=np.int64) if values is None else np.asarray(values)

    mine = edited.cell_properties.get(PART_PROPERTY)
    if mine is None:
        known = of(base)
        kept = cell_map >= 0
        mine = np.full(edited.n_cells, -1, dtype=known.dtype)
        mine[kept] = known[cell_map[kept]]
    return [of(base), of(current), np.asarray(mine)]


def _merged_name(
    name: str | None, mesh: Mesh, base_name: str | None, stored_name: str | None, refused: str
) -> str | None:
    """The geometry name after a merging check-in: the edit's when it renamed (``name``, else the mesh's), else the
    stored one (a rename made since check-out is kept); both renamed, differently: CheckoutConflictError."""
    wanted = name if name is not None else mesh.name
    if wanted is None or (name is None and wanted == base_name):
        return stored_name  # the edit did not rename
    if stored_name not in (base_name, wanted):
        raise CheckoutConflictError(
            f"{refused}; its name was changed since check-out to {stored_name!r} (from {base_name!r}) and the edit "
            f"names it {wanted!r}: a merge by region does not choose between two names; nothing was written",
            hint="check in with the current name (name=..., tgsis checkin --name), or into a new child version "
            '(on_conflict="child", tgsis checkin --on-conflict child)',
        )
    return wanted


def _check_feature_values_merge(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    checked_out_values: Mapping[str, Any],
    values: Mapping[str, Any],
    refused: str,
) -> None:
    """Refuse (CheckoutConflictError) feature properties the edit sets that were changed since check-out to another value.

    The three values are compared as the column's type (the database casts
    them): a property changed since check-out and set by the edit to the
    same value, or set by the edit only, merges.
    """
    clashes = []
    for column, value in values.items():
        base = checked_out_values.get(column)
        row = conn.execute(
            sql.SQL(
                "SELECT (jsonb_populate_record(NULL::{t}, %(base)s::jsonb)).{c} IS DISTINCT FROM f.{c}, "
                "(jsonb_populate_record(NULL::{t}, %(new)s::jsonb)).{c} IS DISTINCT FROM f.{c}, f.{c}::text "
                "FROM {t} f WHERE f._geoid = %(g)s"
            ).format(t=fc.qualified(fc.featuretable), c=sql.Identifier(column)),
            {
                "base": json.dumps({column: base}, default=str),
                "new": json.dumps({column: value}, default=str),
                "g": geoid,
            },
        ).fetchone()
        if row is None:
            continue
        # a check-out that did not record the value: whether it changed since is unknown, so it may have
        base_differs = bool(row[0]) if column in checked_out_values else True
        if base_differs and row[1]:
            clashes.append(f"{column} (now {row[2]!r}, checked out as {base!r}, the edit sets {value!r})")
    if clashes:
        raise CheckoutConflictError(
            f"{refused}; feature properties changed since check-out that the edit sets to other values: "
            + ", ".join(clashes)
            + "; a merge by region does not choose between two values; nothing was written",
            hint="check in without setting them, or with their current values, or into a new child version "
            '(on_conflict="child", tgsis checkin --on-conflict child)',
        )


def _checkin_merge(
    conn: Conn,
    fc: FeatureClass,
    checked_out: Checkout,
    mesh: Mesh,
    plan: EditPlan,
    properties: Mapping[str, Any] | None,
    name: str | None,
    drop_extra: bool,
    conflict: psycopg.Error,
) -> tuple[SaveResult, tuple[str, ...]]:
    """Merge the edit with the change made since check-out by region and write the result (caller's transaction).

    Also returns what the edited file says of its meaning that differs from
    the stored one, which the merge keeps (see :attr:`CheckinResult.not_applied`).

    The feature's write lock is taken again (the refused ``check_unchanged``
    took it in a savepoint, whose rollback let it go): the current state read
    here stays current until the transaction ends.
    """
    token = checked_out.token
    geoid = token.feature_id
    refused = str(conflict).splitlines()[0]
    conn.execute("SELECT tgsis.feature_write_lock(%s)", (geoid,))
    try:
        stored_name, _, _ = _feature_row(conn, fc, geoid)
    except NotFoundError:
        raise CheckoutConflictError(
            f"{refused}; it was deleted since: there is nothing to merge the edit with", hint=_REDO_HINT
        ) from None
    cell_values = aligned_properties(fc, mesh, drop_extra, "the edited mesh")
    feature_values = feature_columns(fc, properties)
    check_feature_values(conn, fc, feature_values)
    _check_feature_values_merge(conn, fc, geoid, checked_out.properties, properties or {}, refused)
    merged_name = _merged_name(name, mesh, checked_out.base.mesh.name, stored_name, refused)
    storage = Storage.of(conn, fc)
    current = _stored_mesh(conn, fc, geoid, stored_name)
    base = checked_out.base
    # the edit's ids as the check-in by difference gives them: kept and moved rows keep the base's, new rows get
    # ids above every id the object ever had (so never one the current state gives to something else)
    table, idfield = SIMPLEX[fc.geotype]
    vertex_ids = np.empty(mesh.n_vertices, dtype=np.int64)
    kept_v = plan.vertex_map >= 0
    vertex_ids[kept_v] = base.vertex_ids[plan.vertex_map[kept_v]]
    vertex_ids[~kept_v] = _fresh_ids(conn, storage, "vrtx", "vrtxid", geoid, int((~kept_v).sum()))
    cell_ids = np.empty(mesh.n_cells, dtype=np.int64)
    kept_c = plan.cell_map >= 0
    cell_ids[kept_c] = base.cell_ids[plan.cell_map[kept_c]]
    cell_ids[~kept_c] = _fresh_ids(conn, storage, table, idfield, geoid, int((~kept_c).sum()))
    # a vertex the comparison matched (within the tolerance) and did not pair as moved is unchanged, as a plain
    # check-in keeps it: the base's coordinates, not the file's rounding of them (else every such vertex is an edit)
    vertices = mesh.vertices.copy()
    unchanged = (plan.vertex_map >= 0) & ~plan.moved
    vertices[unchanged] = base.mesh.vertices[plan.vertex_map[unchanged]]
    # likewise a kept cell is the stored row, from the corner it is stored from (a tool may write a triangle from
    # another corner, the same oriented cell): else the merge rewrites it, unchanged, into a new row version
    cells = mesh.cells.copy()
    if len(cells) and kept_c.any():
        position_of = np.full(base.mesh.n_vertices, -1, dtype=np.int64)
        position_of[plan.vertex_map[kept_v]] = np.flatnonzero(kept_v)
        cells[kept_c] = position_of[base.mesh.cells[plan.cell_map[kept_c]]]
    edit = mesh_class(fc.geotype)(
        vertices,
        cells,
        vertex_properties={p.name: cell_values[p.name] for p in fc.aligned("VERTEX")},
        cell_properties={p.name: cell_values[p.name] for p in fc.aligned("CELL")},
    )  # the class's columns, cast as stored
    what = f"feature {geoid} of class {fc.name}"
    # the parts (GOCAD TFACEs...) merge with the mesh: a cell's part is a value of its row like its properties
    parts = _merge_parts(fc, base.mesh, current.mesh, mesh, plan.cell_map)
    theirs = _mesh_state(fc, current.mesh, current.vertex_ids, current.cell_ids, f"{what} (stored now)", parts[1])
    merge = three_way_merge(
        _mesh_state(fc, base.mesh, base.vertex_ids, base.cell_ids, f"{what} (checked out)", parts[0]),
        theirs,
        _mesh_state(fc, edit, vertex_ids, cell_ids, f"{what} (edited)", parts[2]),
    )
    if merge.conflicts:
        described = "; ".join(
            f"region {r.index}: stored-now vertices {r.parent_vertex_ids[:10].tolist()}, edited vertices "
            f"{r.child_vertex_ids[:10].tolist()}, box {r.bounds[0].tolist()}-{r.bounds[1].tolist()}"
            for r in merge.conflicts[:5]
        )
        raise CheckoutConflictError(
            f"{refused}; the edit and the change made since check-out meet in {len(merge.conflicts)} region(s) "
            f"where they differ: {described}; nothing was written",
            hint='check in into a new child version (on_conflict="child", tgsis checkin --on-conflict child)',
        )
    assert merge.merged is not None
    deleted, inserted, updated = write_state_rows(conn, fc, geoid, theirs, merge.merged.state)
    merged_mesh = merge.merged.state.to_mesh()
    updated += _update_rows(
        conn,
        fc,
        geoid,
        merged_mesh,
        merged_mesh.bounds() if merged_mesh.n_vertices else None,
        merged_name,
        feature_values,
    )
    version = str(conn.execute("SELECT tgsis.get_working_version()").fetchone()[0])  # type: ignore[index]
    log.warning(
        "feature %d changed in %s since check-out: the edit was merged with that change by region (%d regions)",
        geoid,
        token.version,
        len(merge.regions),
    )
    not_applied = tuple(_meaning_not_applied(conn, fc, geoid, mesh, vertex_ids))
    if not_applied:
        log.warning(
            "feature %d: the merge kept the stored %s, not the edited file's (it merges the mesh only)",
            geoid,
            ", ".join(not_applied),
        )
    return SaveResult(
        geoid,
        version,
        plan.diff,
        deleted,
        inserted,
        updated,
        0,
        len(plan.moved_vertices),
        len(plan.removed_cells),
        len(plan.added_cells),
        len(plan.diff.added_cells) - len(plan.added_cells),
    ), not_applied


def _kept_checkout(conn: Conn, fc: FeatureClass, token: CheckoutToken, mesh: Mesh, written: _Written) -> Checkout:
    """A check-out of the state just written (same transaction), ordered by database id like a fresh check-out.

    The revision holding the write is frozen, as :func:`checkout` does, so
    that the kept check-out has a base for a later conflicting check-in.
    """
    version, revision = _working_state(conn)
    frozen = _freeze(conn)
    if frozen is not None:
        revision = frozen
    row = conn.execute("SELECT tgsis.object_fingerprint(%s)", (token.feature_id,)).fetchone()
    assert row is not None
    name, _, properties = _feature_row(conn, fc, token.feature_id)
    vorder, corder = np.argsort(written.vertex_ids), np.argsort(written.cell_ids)
    rank = np.empty_like(vorder)
    rank[vorder] = np.arange(len(vorder))
    by_alignment = {a: {p.name for p in fc.aligned(a)} for a in ("VERTEX", "CELL")}
    stored = {
        a: {k: v[vorder if a == "VERTEX" else corder] for k, v in written.cell_values.items() if k in by_alignment[a]}
        for a in ("VERTEX", "CELL")
    }
    base_mesh = type(mesh)(
        mesh.vertices[vorder],
        rank[mesh.cells[corder]],
        vertex_properties=stored["VERTEX"],
        cell_properties=stored["CELL"],
        name=name,
    )
    new_token = replace(
        token,
        version=version,
        revision=revision,
        fingerprint=str(row[0]),
        base_revision=frozen,
        checked_out_at=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    )
    return Checkout(new_token, StoredMesh(base_mesh, written.vertex_ids[vorder], written.cell_ids[corder]), properties)
