"""The three-way merge of one model-1 object of a version, read from the database (docs/merge.md).

A first, read-only database step of issue 39: for a version and one object
changed both in it and in its parent since it was based (a conflict of
``tgsis.find_conflicts``), the three states are read by key, as stored —

- **base**: the object at the version's initial revision (``initrevision``:
  the state both sides started from),
- **parent**: the parent version's current state,
- **child**: the version's current state —

as :class:`tgsis.merge3.MeshState` rows keyed by the stored vertex and cell
ids (check-in by difference keeps them stable; nothing is renumbered), with
the vertex and cell property values, and handed to
:func:`tgsis.merge3.three_way_merge`. Nothing is written: what
``merge_version`` and ``refresh_version`` do is unchanged.

The three reads see one snapshot (a read-only repeatable-read transaction), so a writer
committing meanwhile cannot mix states. The session's version settings are
moved for the reads (``SET LOCAL``) and put back.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.arguments import checked
from tgsis.db._settings import read_version_settings, restore_version_settings
from tgsis.db._static import SIMPLEX
from tgsis.db._transfer import Packed, columns_out_all, one_snapshot
from tgsis.db.classes import (
    FeatureClass,
    class_of_feature,
    list_feature_classes,
    readable_class_names,
    stores_part_column,
)
from tgsis.db.meaning import parts_from_runs
from tgsis.db.versions import show_name
from tgsis.errors import InvalidInputError, NotFoundError, VersioningError, reraise
from tgsis.merge3 import MeshMerge, MeshState, three_way_merge
from tgsis.mesh import Geotype, Mesh, mesh_class

__all__ = ["export_conflict", "merge_regions_json", "object_merge"]

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


@contextmanager
def _snapshot(conn: Conn, version: str) -> Iterator[None]:
    """One snapshot for every read (:func:`one_snapshot`); a caller's READ COMMITTED transaction is refused.

    There each statement would see what others committed meanwhile: the
    states of two moments mixed.
    """
    with one_snapshot(conn) as consistent:
        if not consistent:
            raise InvalidInputError(
                f"the merge of an object of version {show_name(version)} reads three states, which need one "
                "snapshot: the caller's transaction is read committed",
                hint="call tgsis.object_merge outside a transaction, or in a REPEATABLE READ or SERIALIZABLE one",
            )
        yield


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


def _version_row(conn: Conn, version: str) -> tuple[int, str, int, int, int]:
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


def _read_state(conn: Conn, fc: FeatureClass, geoid: int, version: str, revision: int) -> _Rows:
    """The object's rows as ``version`` sees them at ``revision`` (the session is moved there for the reads)."""
    conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
    table, key = SIMPLEX[fc.geotype]
    k = mesh_class(fc.geotype).cell_size
    requests = [
        Packed(
            sql.SQL("tgsis.vrtx"),
            "geoid",
            [("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8")],
            [geoid],
        ),
        Packed(
            sql.SQL("tgsis.{}").format(sql.Identifier(table)),
            "geoid",
            [(key, "int8"), *((f"vrtxid{i + 1}", "int8") for i in range(k))],
            [geoid],
        ),
    ]
    tables: list[tuple[str, list[str]]] = []
    for alignment in ("VERTEX", "CELL"):
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if props and protable is not None:
            tables.append((alignment, [p.name for p in props]))
            requests.append(
                Packed(
                    fc.qualified(protable), "_geoid", [("_idx", "int8"), *((p.name, p.wire) for p in props)], [geoid]
                )
            )
    vertex_cols, cell_cols, *prop_cols = columns_out_all(conn, requests)
    vids, xyz = _sorted_rows(vertex_cols[1], np.stack(vertex_cols[2:5], axis=1) if len(vertex_cols[1]) else None)
    cids, cells = _sorted_rows(cell_cols[1], np.stack(cell_cols[2:], axis=1) if len(cell_cols[1]) else None)
    xyz = xyz.reshape(-1, 3).astype(np.float64)
    cells = cells.reshape(-1, k).astype(np.int64)
    props_by: dict[str, dict[str, npt.NDArray[Any]]] = {"VERTEX": {}, "CELL": {}}
    for (alignment, names), columns in zip(tables, prop_cols, strict=True):
        ids = vids if alignment == "VERTEX" else cids
        idx = np.asarray(columns[1], dtype=np.int64)
        for name, values in zip(names, columns[2:], strict=True):
            props_by[alignment][name] = _aligned_values(ids, idx, np.asarray(values))
    atoms = conn.execute("SELECT vrtxid, refid FROM tgsis.atom WHERE geoid = %s ORDER BY vrtxid", (geoid,)).fetchall()
    runs = conn.execute(
        "SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (geoid,)
    ).fetchall()
    return _Rows(
        vids,
        xyz,
        cids,
        cells,
        props_by["VERTEX"],
        props_by["CELL"],
        np.asarray(atoms, dtype=np.int64).reshape(-1, 2),
        np.asarray(runs, dtype=np.int64).reshape(-1, 3),
    )


def _sorted_rows(ids: npt.ArrayLike, rows: npt.NDArray[Any] | None) -> tuple[npt.NDArray[np.int64], npt.NDArray[Any]]:
    """Ids ascending with their rows (the packed reads come in no order)."""
    ids = np.asarray(ids, dtype=np.int64)
    if rows is None:
        return ids, np.empty((0,), dtype=np.float64)
    order = np.argsort(ids, kind="stable")
    return ids[order], rows[order]


def _aligned_values(
    ids: npt.NDArray[np.int64], idx: npt.NDArray[np.int64], values: npt.NDArray[Any]
) -> npt.NDArray[Any]:
    """A property's values in the order of ``ids`` (rows keyed by ``_idx``); an id without a row gets NaN."""
    order = np.argsort(idx, kind="stable")
    idx, values = idx[order], values[order]
    pos = np.searchsorted(idx, ids)
    found = pos < len(idx)
    found[found] = idx[pos[found]] == ids[found]
    if found.all():
        return values[pos]
    out = np.full((len(ids), *values.shape[1:]), np.nan, dtype=np.float64)
    out[found] = values[pos[found]]
    return out


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


@checked
def object_merge(conn: Conn, version: str, feature_id: int) -> MeshMerge:
    """The three-way merge of one model-1 object changed both in ``version`` and in its parent (read-only).

    Reads the object as the version's base saw it (its initial revision),
    as the parent holds it now and as the version holds it now, keyed by the
    stored vertex and cell ids, with their property values (GOCAD atoms as
    the vertex property ``refid``, -1 for none; parts kept in ``tgsis.part``
    as the cell property ``part``), in one snapshot, and merges them with
    :func:`tgsis.merge3.three_way_merge`. Nothing is written.

    Parameters
    ----------
    conn : psycopg.Connection
        Idle, or in a ``REPEATABLE READ`` or ``SERIALIZABLE`` transaction.
    version : str
        A version other than DEFAULT.
    feature_id : int
        A feature (geoid) of a static (model 1) class of points, lines,
        surfaces or tetrahedral solids.

    Returns
    -------
    MeshMerge
        ``base``, ``parent``, ``child`` states, the ``regions`` (``conflicts``
        among them) and ``merged`` when no region conflicts.

    Raises
    ------
    NotFoundError
        No such version, or no class has the feature.
    InvalidInputError
        The feature is not of model 1 (or is a geometry collection); the
        caller's transaction is READ COMMITTED.
    VersioningError
        The object was not changed both in the version and in its parent
        since the version was based (nothing to merge).
    MissingPrivilegeError
        The role may not read the class or the version.
    """
    with reraise(), _snapshot(conn, version):
        settings = read_version_settings(conn)
        try:
            versionid, parent, initrevision, working, parent_working = _version_row(conn, version)
            # the class is looked up as the version sees its features; as the parent does, when the version
            # deleted a feature of its base
            in_child = _exists(conn, feature_id, version, working)
            in_parent = _exists(conn, feature_id, parent, parent_working)
            if in_child or not (in_parent and _exists(conn, feature_id, version, initrevision)):
                conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, working))
            fc = _feature_class(conn, feature_id)
            if fc.time_model != "STATIC" or fc.geotype not in SIMPLEX:
                what = (
                    "a geometry collection" if fc.geotype is Geotype.GEOMETRYCOLLECTION else f"of model {fc.time_model}"
                )
                raise InvalidInputError(
                    f"feature {feature_id} of class {fc.name} is {what}: only a static (model 1) point set, line set, "
                    f"surface or tetrahedral solid merges by region (version {show_name(version)})",
                    hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
                )
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
            rows = {
                "base": _read_state(conn, fc, feature_id, version, initrevision),
                "parent": _read_state(conn, fc, feature_id, parent, parent_working),
                "child": _read_state(conn, fc, feature_id, version, working),
            }
        finally:
            if conn.info.transaction_status != psycopg.pq.TransactionStatus.INERROR:
                restore_version_settings(conn, settings, local=True)
    states = _states(fc, feature_id, rows)
    return three_way_merge(states["base"], states["parent"], states["child"])


# --------------------------------------------------------------------------- export of a conflict's three states

#: GOCAD's file of each kind (what ``tgsis export`` writes by default)
_GOCAD = {1: "vs", 2: "pl", 3: "ts", 4: "so"}
_SIDES = ("base", "parent", "child")
_GOCAD_FORMATS = ("tsurf", "pline", "vset", "tsolid")
#: metadata of the stored object that holds vertex indices of its own state: not valid for the other states
#: (atoms travel as the vertex property ``refid``)
_INDEXED_METADATA = ("gocad_atoms", "gocad_patoms")


@checked
def merge_regions_json(merge: MeshMerge | str) -> dict[str, Any]:
    """One object's regions as plain JSON values (what ``tgsis version conflicts --regions --json`` prints).

    Parameters
    ----------
    merge : MeshMerge or str
        A :func:`object_merge` result, or why the object merges as a whole only.

    Returns
    -------
    dict
        ``merges_by_region``, ``merges_by_itself`` and ``regions`` (index, conflict, the sides' vertex and
        cell ids, largest displacements, ``bounds`` as [[xmin, ymin, zmin], [xmax, ymax, zmax]] in stored z).
    """
    if isinstance(merge, str):
        return {"merges_by_region": False, "reason": merge, "regions": []}
    return {
        "merges_by_region": True,
        "merges_by_itself": not merge.conflicts,
        "regions": [
            {
                "index": r.index,
                "conflict": r.conflict,
                "changed_in": r.sides,
                "merges_by_itself": not r.conflict,
                "vertex_ids": r.vertex_ids.tolist(),
                "cell_ids": r.cell_ids.tolist(),
                "parent": {
                    "vertex_ids": r.parent_vertex_ids.tolist(),
                    "cell_ids": r.parent_cell_ids.tolist(),
                    "largest_displacement": r.parent_displacement,
                },
                "child": {
                    "vertex_ids": r.child_vertex_ids.tolist(),
                    "cell_ids": r.child_cell_ids.tolist(),
                    "largest_displacement": r.child_displacement,
                },
                "bounds": r.bounds.tolist(),
            }
            for r in merge.regions
        ],
    }


def _state_mesh(state: MeshState, cell_key: str, name: str | None, metadata: Mapping[str, Any]) -> Mesh:
    """A state as a tgsis mesh: file vertex i is the i-th stored id ascending (``vrtxid``), cells likewise."""
    if "vrtxid" in state.vertex_properties:
        raise InvalidInputError(f"{state.name} has a vertex property 'vrtxid', the name the export gives the ids")
    if cell_key in state.cell_properties:
        raise InvalidInputError(f"{state.name} has a cell property {cell_key!r}, the name the export gives the ids")
    order = np.argsort(state.vertex_ids, kind="stable")  # kept ascending by the reads; made sure here
    vids = state.vertex_ids[order]
    xyz = state.vertices[order].copy()
    if metadata.get("zpositive") == "Depth":
        xyz[:, 2] = -xyz[:, 2]  # stored z is elevation; a Depth object's file has depths (negation is exact)
    corder = np.argsort(state.cell_ids, kind="stable")
    cells = np.searchsorted(vids, state.cells[corder]).reshape(-1, state.cell_size)
    return mesh_class(_GEOTYPE_OF_K[state.cell_size])(
        xyz,
        cells,
        vertex_properties={
            **{n: np.asarray(v)[order] for n, v in state.vertex_properties.items()},
            "vrtxid": vids,
        },
        cell_properties={
            **{n: np.asarray(v)[corder] for n, v in state.cell_properties.items()},
            cell_key: state.cell_ids[corder],
        },
        name=name,
        metadata=metadata,
    )


_GEOTYPE_OF_K = {1: Geotype.MULTIPOINT, 2: Geotype.MULTILINESTRING, 3: Geotype.SURFACE, 4: Geotype.MULTITETRA}


def _looks(conn: Conn, version: str, parent: str, feature_id: int) -> tuple[str | None, dict[str, Any]]:
    """The object's name and file facts (z convention, CRS, colour) as the version holds it, else as its parent."""
    from tgsis.db.features import class_of_feature, fetch_feature  # features imports much; only needed here
    from tgsis.db.versions import in_version

    for side in (version, parent):
        with conn.transaction(), in_version(conn, side):
            try:
                mesh = fetch_feature(conn, class_of_feature(conn, feature_id), feature_id).mesh
            except NotFoundError:
                continue
        if mesh is None:
            continue
        return mesh.name, {k: v for k, v in mesh.metadata.items() if k not in _INDEXED_METADATA}
    return None, {}


def _file_stem(feature_id: int, name: str | None) -> str:
    """``<feature>_<name>`` with the name's characters a file name may not hold as ``_``."""
    if not name:
        return str(feature_id)
    return f"{feature_id}_{re.sub(r'[^A-Za-z0-9._-]+', '_', name).strip('._') or 'object'}"


@checked
def export_conflict(
    conn: Conn,
    version: str,
    feature_id: int,
    folder: str | os.PathLike[str],
    *,
    format: str | None = None,
    picture: bool = True,
    overwrite: bool = False,
) -> list[Path]:
    """Write the base, parent and child states of a conflicting model-1 object as files, with its regions.

    Reads the three states as :func:`object_merge` does (one snapshot) and
    writes, in ``folder`` (made when missing):

    - ``<feature>_<name>_base.<ext>``, ``..._parent.<ext>``, ``..._child.<ext>``: each state as a mesh of the
      object's kind with its name, file facts (z convention — a Depth object's files hold depths —, CRS,
      colour) and vertex/cell properties. File vertex i is the i-th stored vertex id in ascending order, kept
      as the vertex property ``vrtxid``; cells likewise, their stored ids as the cell property named after the
      key (``trglid``, ``segid``, ``pointid``, ``tetraid``). GOCAD atoms are the vertex property ``refid``.
    - ``<feature>_regions.json``: the regions, as :func:`merge_regions_json` gives them;
    - ``<feature>_<name>_overlay.png`` when ``picture``: a map view (x, y) of the base in grey, the parent's
      edits in blue, the child's in orange, conflict regions boxed in red, regions that merge by themselves
      dashed green (:func:`tgsis.pictures.conflict_overlay`).

    The files are written into a temporary folder inside ``folder`` and moved into place only when all are
    written; none replaces an existing file unless ``overwrite``.

    Parameters
    ----------
    version : str
        A version other than DEFAULT.
    feature_id : int
        A feature of a static (model 1) class changed both in the version and in its parent.
    folder : path
        Where the files go.
    format : str, optional
        A file extension of :mod:`tgsis.formats` that stores the object's kind (``ts``, ``pl``, ``vs``,
        ``so``, ``vtu``, ``vtp``, ``ply``, ...); default: the GOCAD file of the kind (``ts`` for surfaces).
    picture : bool
        Also draw the PNG (needs the extra ``pictures``: matplotlib).
    overwrite : bool
        Replace files of these names.

    Returns
    -------
    list of Path
        The files written: base, parent, child, regions, then the picture.

    Raises
    ------
    InvalidInputError
        Not a model-1 mesh; ``format`` unknown or unable to store the kind; a file exists and not ``overwrite``.
    VersioningError
        The object was not changed on both sides.
    MissingPrivilegeError
        The role may not read the class or the version (no file is written).
    InstallationError
        ``picture`` and matplotlib is not installed (no file is written).
    """
    from tgsis import formats

    if picture:
        from tgsis._optional import require

        require("matplotlib", "the picture of tgsis.export_conflict")
    with reraise(), _snapshot(conn, version):
        merge = object_merge(conn, version, feature_id)
        _, parent, *_ = _version_row(conn, version)
        name, metadata = _looks(conn, version, parent, feature_id)
    k = merge.base.cell_size
    ext = (format or _GOCAD[k]).lower().lstrip(".")
    geotype = _GEOTYPE_OF_K[k]
    try:
        kind = formats.format_for(f"x.{ext}")
    except Exception as exc:  # FileFormatError: unknown extension
        raise InvalidInputError(
            f"no file format has the extension {ext!r}", hint="give ts, pl, vs, so, vtu, vtp or ply"
        ) from exc
    if geotype not in kind.geotypes or kind.writer is None:
        raise InvalidInputError(
            f"{kind.name} files (.{ext}) do not store {geotype.value} (feature {feature_id})",
            hint=f"the GOCAD file of this kind is .{_GOCAD[k]}",
        )
    cell_key = SIMPLEX[geotype][1]
    meshes = {side: _state_mesh(getattr(merge, side), cell_key, name, metadata) for side in _SIDES}
    stem = _file_stem(feature_id, name)
    target = Path(folder)
    # GOCAD files hold no cell values: the cells' ids and values go to a CSV beside each (row j: file cell j)
    sidecar = kind.name in _GOCAD_FORMATS
    files: list[tuple[str, str]] = []  # (what, file name)
    for side in _SIDES:
        files.append((side, f"{stem}_{side}.{ext}"))
        if sidecar:
            files.append((f"{side} cells", f"{stem}_{side}_cells.csv"))
    files.append(("regions", f"{feature_id}_regions.json"))
    if picture:
        files.append(("picture", f"{stem}_overlay.png"))
    names = [n for _, n in files]
    if not overwrite:
        _refuse_existing(target, names)
    target.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=".tgsis-export-", dir=target))
    try:
        for what, file in files:
            if what in _SIDES:
                mesh = meshes[what]
                formats.write(
                    mesh, scratch / file, format=kind.name, **({"drop_cell_properties": True} if sidecar else {})
                )
            elif what.endswith(" cells"):
                _write_cells_csv(meshes[what.split()[0]], scratch / file)
            elif what == "regions":
                (scratch / file).write_text(json.dumps(merge_regions_json(merge), indent=1) + "\n", encoding="utf-8")
            else:
                from tgsis import pictures

                pictures.conflict_overlay(
                    merge,
                    meshes["base"],
                    meshes["parent"],
                    meshes["child"],
                    scratch / file,
                    title=f"feature {feature_id}{f' {name}' if name else ''} in {show_name(version)}: base, parent, child",
                )
        return _move_into(scratch, target, names, overwrite)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _write_cells_csv(mesh: Mesh, path: Path) -> None:
    """The cells' values, one row per file cell in file order; a (m, c) property as columns ``name[0]`` ...

    Floats are written with ``repr`` (the shortest text that reads back bit for bit); NaN (no value) as ``nan``.
    """
    import csv

    header: list[str] = []
    columns: list[npt.NDArray[Any]] = []
    for n, values in mesh.cell_properties.items():
        if values.ndim == 1:
            header.append(n)
            columns.append(values)
        else:
            header += [f"{n}[{i}]" for i in range(values.shape[1])]
            columns += [values[:, i] for i in range(values.shape[1])]
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        for j in range(len(mesh.cells)):
            writer.writerow([repr(c[j].item()) for c in columns])


def _refuse_existing(target: Path, names: list[str]) -> None:
    there = [n for n in names if (target / n).exists()]
    if there:
        raise InvalidInputError(
            f"{len(there)} file(s) already in {target}: {', '.join(there)}; nothing was written",
            hint="remove them, choose another folder, or replace them (overwrite=True; tgsis: --force)",
        )


def _move_into(scratch: Path, target: Path, names: list[str], overwrite: bool) -> list[Path]:
    """Move the written files into place, all or none: without ``overwrite`` a file made meanwhile is kept."""
    placed: list[Path] = []
    try:
        for n in names:
            if overwrite:
                os.replace(scratch / n, target / n)
            else:
                os.link(scratch / n, target / n)  # fails on an existing name (no check-then-replace race)
            placed.append(target / n)
    except FileExistsError:
        for p in placed:
            p.unlink(missing_ok=True)
        _refuse_existing(target, names)
        raise
    return placed
