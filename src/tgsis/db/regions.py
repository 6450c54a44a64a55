"""Conflicts per region: the regions of conflicting meshes, stored, and their solutions (docs/merge.md).

:func:`find_conflicts` is the region-aware form of
:func:`tgsis.db.versions.find_conflicts`: it (re)computes the conflicting
objects of a version (SQL ``tgsis.find_conflicts``), and for each that is a
model-1 mesh of a feature class (point set, line set, surface, tetrahedral
solid) reads its three states (:func:`~tgsis.db._merge_states.read_merge_states`)
and runs :func:`tgsis.merge3.three_way_merge` on them — all in one
``REPEATABLE READ`` transaction, so that the conflict's marks and the states
agree — and records the regions (``tgsis.record_conflict_regions``, which
refuses marks that are not the conflict's). Recorded solutions of regions
found again alike are kept.

:func:`resolve_region` records the solution of one conflicting region
(``parent``, ``child``, ``base``, ``average``, ``manual``) after computing,
with :func:`tgsis.merge3.apply_solutions`, what it discards of either side;
:func:`region_solutions` gives the merges that write (``tgsis.merge_version``
in Python) the recorded solutions valid for a merge.

The merge itself (writing the merged mesh) is :mod:`tgsis.db.merging`'s.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import shlex
import zipfile
from collections.abc import Callable, Collection, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, TypeVar, cast

import numpy as np
import numpy.typing as npt
import psycopg

from tgsis._merge_slices import SlicedMerge, SliceKey, fixed_period_refusal, merge_sliced
from tgsis.arguments import checked
from tgsis.db._attribute_edits import attribute_edits, write_attribute_edits
from tgsis.db._merge_states import (
    SLICE_KEYS,
    feature_time_model,
    read_merge_change,
    read_merge_states,
    read_sliced_states,
    version_row,
)
from tgsis.db._settings import read_version_settings, restore_version_settings
from tgsis.db._state_write import write_state_difference
from tgsis.db._transfer import repeatable_read
from tgsis.db.classes import class_of_feature
from tgsis.db.copy import SQL_TYPES
from tgsis.db.versions import CONFLICT_COLUMNS, Conflict, ConflictRegion, show_name
from tgsis.db.versions import resolve_conflict as resolve_whole_object
from tgsis.errors import (
    ConcurrentChangeError,
    Error,
    InvalidInputError,
    InvalidMergeError,
    MissingPrivilegeError,
    NotFoundError,
    RegionSolutionError,
    reraise,
)
from tgsis.merge3 import (
    MergeRegion,
    MeshMerge,
    MeshState,
    RegionDiscard,
    Solution,
    apply_solutions,
    state_rows_equal,
    three_way_merge,
)
from tgsis.mesh import Mesh

__all__ = [
    "ConflictRegion",
    "ObjectResolution",
    "RegionResolution",
    "SideDiscard",
    "average_region",
    "discard_text",
    "find_conflicts",
    "recorded_solutions",
    "region_solutions",
    "resolve_all_regions",
    "resolve_conflict",
    "resolve_object_average",
    "resolve_region",
    "side_discard_text",
    "sliced_recorded_solutions",
    "sliced_region_solutions",
    "state_from_npz",
    "state_to_npz",
]

Conn = psycopg.Connection[Any]

_SOLUTIONS = ("parent", "child", "base", "average", "manual", "unsolved")
_T = TypeVar("_T")
_RETRIES = 5  # serialization failures of a transaction of our own (two sessions storing at once) are retried
_REGION_COLUMNS = (
    "region, conflict, changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids, child_vertex_ids,"
    " child_cell_ids, bbox, parent_displacement, child_displacement, solution, childmark, parentmark, solved_at,"
    " solved_by, times, timem"
)
_ID_FIELDS = ("vertex_ids", "cell_ids", "parent_vertex_ids", "parent_cell_ids", "child_vertex_ids", "child_cell_ids")


# --------------------------------------------------------------------------- transactions


@contextmanager
def _consistent(conn: Conn, *, write: bool) -> Iterator[None]:
    """One transaction whose reads agree: a new REPEATABLE READ one, or a savepoint of the caller's.

    In a caller's READ COMMITTED transaction (a merge that holds the locks of
    ``tgsis.lock_for_merge``, where no writer of either side can commit) each
    statement sees its own moment: the marks are checked again after the
    states are read (``tgsis.record_conflict_regions`` refuses marks that are
    no longer the conflict's, and a computed-only answer says the object
    changed meanwhile), so regions of a mixed state are never stored or given.
    """
    with repeatable_read(conn, write=write):
        yield


def _retried(conn: Conn, work: Callable[[], _T]) -> _T:
    """``work`` in one consistent transaction (:func:`_consistent`, writing), tried again after a serialization
    failure (two sessions storing at once) when the transaction is our own; a caller's transaction is tried once."""
    tries = _RETRIES if conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE else 1
    for attempt in range(tries):
        try:
            with reraise(), _consistent(conn, write=True):
                return work()
        except ConcurrentChangeError:
            if attempt == tries - 1:
                raise
    raise AssertionError("unreachable")  # pragma: no cover


# --------------------------------------------------------------------------- rows <-> regions


def _ids(values: Any) -> npt.NDArray[np.int64]:
    return np.asarray(values if values is not None else [], dtype=np.int64)


def _region_of_row(row: tuple[Any, ...]) -> ConflictRegion:
    ids = {name: _ids(value) for name, value in zip(_ID_FIELDS, row[3:9], strict=True)}
    return ConflictRegion(
        region=int(row[0]),
        conflict=bool(row[1]),
        changed_by=str(row[2]),
        **ids,
        bbox=None if row[9] is None else np.asarray(row[9], dtype=np.float64),
        parent_displacement=float(row[10]),
        child_displacement=float(row[11]),
        solution=str(row[12]),
        childmark=str(row[13]),
        parentmark=str(row[14]),
        solved_at=row[15],
        solved_by=row[16],
        times=None if row[17] is None else float(row[17]),
        timem=None if row[18] is None else float(row[18]),
    )


def _region_json(region: MergeRegion, key: SliceKey | None = None) -> dict[str, Any]:
    bounds = np.asarray(region.bounds, dtype=np.float64).ravel()
    return {
        **_slice_json(key),
        "region": region.index,
        "conflict": region.conflict,
        "changed_by": region.sides,
        **{name: [int(i) for i in getattr(region, name)] for name in _ID_FIELDS},
        "bbox": [float(v) for v in bounds] if len(bounds) == 6 and np.all(np.isfinite(bounds)) else None,
        "parent_displacement": float(region.parent_displacement),
        "child_displacement": float(region.child_displacement),
    }


def _computed_region(
    region: MergeRegion, marks: tuple[str, str], stored: ConflictRegion | None, key: SliceKey | None = None
) -> ConflictRegion:
    """A region as found, with the stored solution of the same region (same marks, same ids), if any."""
    as_json = _region_json(region, key)
    solution = "unsolved" if region.conflict else "automatic"
    solved_at = solved_by = None
    if stored is not None and region.conflict and _same_region(stored, region) and _same_slice(stored, key):
        solution, solved_at, solved_by = stored.solution, stored.solved_at, stored.solved_by
    return ConflictRegion(
        region=region.index,
        conflict=region.conflict,
        changed_by=region.sides,
        **{name: getattr(region, name) for name in _ID_FIELDS},
        bbox=None if as_json["bbox"] is None else np.asarray(as_json["bbox"], dtype=np.float64),
        parent_displacement=float(region.parent_displacement),
        child_displacement=float(region.child_displacement),
        solution=solution,
        childmark=marks[0],
        parentmark=marks[1],
        solved_at=solved_at,
        solved_by=solved_by,
        times=as_json.get("times"),
        timem=as_json.get("timem"),
    )


def _slice_json(key: SliceKey | None) -> dict[str, float]:
    """A slice key as the region's ``times`` (and model 3's ``timem``); nothing for a model-1 region."""
    if key is None:
        return {}
    if len(key) == 2:
        return {"times": float(key[1]), "timem": float(key[0])}
    return {"times": float(key[0])}


def _same_slice(stored: ConflictRegion, key: SliceKey | None) -> bool:
    wanted = _slice_json(key)
    return (stored.times, stored.timem) == (wanted.get("times"), wanted.get("timem"))


def _same_region(stored: ConflictRegion, region: MergeRegion) -> bool:
    return stored.conflict == region.conflict and all(
        np.array_equal(getattr(stored, name), getattr(region, name)) for name in _ID_FIELDS
    )


def _stored_regions(conn: Conn, versionid: int, objectclass: str, objectkey: str) -> list[ConflictRegion]:
    rows = conn.execute(
        f"SELECT {_REGION_COLUMNS} FROM tgsis.conflict_regions"
        " WHERE versionid = %s AND objectclass = %s AND objectkey = %s ORDER BY region",
        (versionid, objectclass, objectkey),
        binary=True,  # the instants (times, timem) bit for bit, whatever the session's extra_float_digits
    ).fetchall()
    return [_region_of_row(r) for r in rows]


def _current_marks(conn: Conn, versionid: int, objectclass: str, objectkey: str) -> tuple[str, str] | None:
    """The object's marks as the transaction sees the two sides now (``tgsis.current_conflicts``), or None."""
    row = conn.execute(
        "SELECT childmark, parentmark FROM tgsis.current_conflicts(%s) WHERE objectclass = %s AND objectkey = %s",
        (versionid, objectclass, objectkey),
    ).fetchone()
    return None if row is None else (str(row[0]), str(row[1]))


# --------------------------------------------------------------------------- find_conflicts


@checked
def find_conflicts(conn: Conn, version: str) -> list[Conflict]:
    """(Re)compute the conflicting objects of ``version``, with the regions of the conflicting meshes.

    The objects changed both in the version and in its parent since it was
    based (:func:`tgsis.db.versions.find_conflicts`); for each that is a
    model-1 mesh of a feature class, its regions (docs/merge.md) computed from
    its three states read in the same snapshot as the conflict's marks, and
    recorded (``tgsis.conflict_regions``) when the role stores conflicts (it
    may write in the version or merge into its parent); a region found again
    alike keeps its recorded solution.

    Parameters
    ----------
    conn : psycopg.Connection
        Idle (a REPEATABLE READ transaction of its own, retried when another
        session stored the same conflicts at the same time), or in a
        transaction (a savepoint; under READ COMMITTED the version and its
        parent are locked as a merge locks them).
    version : str
        A version other than DEFAULT.

    Returns
    -------
    list of Conflict
        With ``regions`` for the objects that merge by region, and
        ``region_refusal`` saying why for those that do not (a feature
        property changed on both sides, a deletion, another data model, a
        plain table's row).
    """
    return _retried(conn, lambda: _find(conn, version))


def _find(conn: Conn, version: str) -> list[Conflict]:
    conn.execute("SELECT set_config('tgsis.region_detection', 'client', true)")  # found here: SQL need not
    rows = conn.execute(
        "SELECT objectclass, objectkey, conflicttype, childtables, parenttables, solution, childmark, parentmark"
        "  FROM tgsis.find_conflicts(%s)",
        (version,),
    ).fetchall()
    versionid = version_row(conn, version)[0]
    stores = _stores_conflicts(conn, version)
    result = []
    for row in rows:
        conflict = Conflict.from_row(row)
        marks = (str(row[6]), str(row[7]))
        found, refusal = _object_regions(conn, version, conflict.objectclass, conflict.objectkey)
        if found is None:
            result.append(_with(conflict, (), refusal))
            continue
        payload = json.dumps([_region_json(r, k) for r, k in found])
        if stores:
            conn.execute(
                "SELECT tgsis.record_conflict_regions(%s, %s, %s, %s, %s, %s::jsonb)",
                (version, conflict.objectclass, conflict.objectkey, *marks, payload),
            )
            regions = tuple(_stored_regions(conn, versionid, conflict.objectclass, conflict.objectkey))
        elif _current_marks(conn, versionid, conflict.objectclass, conflict.objectkey) != marks:
            result.append(
                _with(conflict, (), "the object changed while its states were read: find the conflicts again")
            )
            continue
        else:  # computed only, with the solutions recorded for the same regions
            stored = {r.region: r for r in _stored_regions(conn, versionid, conflict.objectclass, conflict.objectkey)}
            regions = tuple(
                _computed_region(r, marks, stored.get(r.index) if _marks_of(stored) == marks else None, k)
                for r, k in found
            )
        result.append(_with(conflict, regions, None))
    return result


def _marks_of(stored: Mapping[int, ConflictRegion]) -> tuple[str, str] | None:
    first = next(iter(stored.values()), None)
    return None if first is None else (first.childmark, first.parentmark)


def _with(conflict: Conflict, regions: tuple[ConflictRegion, ...], refusal: str | None) -> Conflict:
    return dataclasses.replace(conflict, regions=regions, region_refusal=refusal)


def _stores_conflicts(conn: Conn, version: str) -> bool:
    """Whether the role stores the version's conflicts (SQL find_conflicts does for these roles only)."""
    row = conn.execute(
        "SELECT tgsis.holds_version_privilege(v.versionid, 'write', tgsis.calling_role())"
        "    OR tgsis.holds_version_privilege(v.parentid, 'merge', tgsis.calling_role())"
        "  FROM tgsis.versions v WHERE v.versionid = tgsis.version_id(%s)",
        (version,),
    ).fetchone()
    return bool(row and row[0])


def _object_regions(
    conn: Conn, version: str, objectclass: str, objectkey: str
) -> tuple[list[tuple[MergeRegion, SliceKey | None]] | None, str | None]:
    """The regions of a conflicting object (each with its slice: models 2 and 3), or None and why not."""
    if objectclass == "feature":
        try:
            with reraise(), conn.transaction():
                sliced = feature_time_model(conn, version, int(objectkey)) in SLICE_KEYS
        except Error as exc:
            return None, exc.message
        if sliced:
            merge, refusal = _sliced_object_merge(conn, version, objectkey)
            if merge is None:
                return None, refusal
            return [(dataclasses.replace(r.region, index=r.index), r.key) for r in merge.regions], None
    mesh, refusal = _object_merge(conn, version, objectclass, objectkey)
    return (None, refusal) if mesh is None else ([(r, None) for r in mesh.regions], None)


def _sliced_object_merge(conn: Conn, version: str, objectkey: str) -> tuple[SlicedMerge | None, str | None]:
    """:func:`_object_merge` for a model-2 or model-3 feature: its merge slice by slice, or None and why not."""
    try:
        with reraise(), conn.transaction():  # a savepoint: a refused read leaves the transaction usable
            states = read_sliced_states(conn, version, int(objectkey)).states
        merge = merge_sliced(states["base"], states["parent"], states["child"])
    except MissingPrivilegeError as exc:
        return None, f"the role may not read it: {exc.message}"
    except (InvalidInputError, InvalidMergeError, NotFoundError) as exc:
        return None, exc.message
    except Error as exc:
        if exc.code == "TG300":  # VersioningError: not changed on both sides (a conflict of tables only)
            return None, exc.message
        raise
    refusal = fixed_period_refusal(merge)  # TG308 whatever the solutions: said now, not first at the merge
    return (merge, None) if refusal is None else (None, refusal)


def _object_merge(conn: Conn, version: str, objectclass: str, objectkey: str) -> tuple[MeshMerge | None, str | None]:
    """The three-way merge of a conflicting object, or None and why it merges as a whole object only."""
    if objectclass != "feature":
        return None, f"a row of the versioned table(s) of object class {objectclass}: it merges as a whole object"
    try:
        with reraise(), conn.transaction():  # a savepoint: a refused read leaves the transaction usable
            # the change and its one-ring (docs/merge.md): the same regions, read by key
            change = read_merge_change(conn, version, int(objectkey))
            states = change[0].states if change is not None else read_merge_states(conn, version, int(objectkey)).states
        top = change[1] if change is not None else None
        return three_way_merge(states["base"], states["parent"], states["child"], top_ids=top), None
    except MissingPrivilegeError as exc:
        return None, f"the role may not read it: {exc.message}"
    except (InvalidInputError, InvalidMergeError, NotFoundError) as exc:
        return None, exc.message
    except Error as exc:
        if exc.code == "TG300":  # VersioningError: not changed on both sides (a conflict of tables only)
            return None, exc.message
        raise


# --------------------------------------------------------------------------- region_solutions


@checked
def region_solutions(
    conn: Conn, version: str, objectclass: str, objectkey: str, merge: MeshMerge
) -> dict[int, str | MeshState]:
    """The solutions recorded for the conflicting regions of ``merge``, when they hold for it.

    They hold when the stored regions were found on the object's current marks
    (as the caller's transaction sees the two sides) and are the regions of
    ``merge`` (same count, same six id arrays each). Otherwise, or when none
    is recorded, ``{}``: a merge then treats every conflicting region as
    unsolved.

    Parameters
    ----------
    conn : psycopg.Connection
        In the merge's transaction (the states of ``merge`` read in it).
    version, objectclass, objectkey : str
        The conflict (``objectkey`` as ``tgsis.conflicts`` names it: a feature's geoid).
    merge : MeshMerge
        The three-way merge of the object's states.

    Returns
    -------
    dict of int to str or MeshState
        Region index to ``"parent"``, ``"child"``, ``"base"`` or a
        :class:`~tgsis.merge3.MeshState` (the rows of an ``average`` or
        ``manual`` solution), for the solved conflicting regions only.
    """
    with reraise():
        versionid = version_row(conn, version)[0]
        marks = _current_marks(conn, versionid, objectclass, objectkey)
        stored = _stored_regions(conn, versionid, objectclass, objectkey)
        if marks is None or not _holds(stored, marks, merge):
            return {}
    return _solutions_of(conn, versionid, objectclass, objectkey, stored, merge.base.name)


def _solutions_of(
    conn: Conn, versionid: int, objectclass: str, objectkey: str, stored: list[ConflictRegion], name: str
) -> dict[int, str | MeshState]:
    """The recorded solutions of the stored regions that hold: a side's name, or the rows of average/manual."""
    with reraise():
        meshes = {
            row[0]: row[1:]
            for row in conn.execute(
                "SELECT region, solution_mesh, solution_vertex_ids, solution_vertices, solution_cell_ids, solution_cells,"
                " solution_vertex_columns, solution_vertex_values, solution_cell_columns, solution_cell_values"
                " FROM tgsis.conflict_regions WHERE versionid = %s AND objectclass = %s"
                " AND objectkey = %s AND solution_mesh IS NOT NULL",
                (versionid, objectclass, objectkey),
                binary=True,  # the float8 rows bit for bit, whatever the session's extra_float_digits
            ).fetchall()
        }
    solutions: dict[int, str | MeshState] = {}
    for region in stored:
        if not region.conflict or region.solution == "unsolved":
            continue
        if region.solution in ("average", "manual"):
            mesh, *rows = meshes[region.region]
            state = state_from_npz(bytes(mesh), name)
            _require_same_rows(state, rows, region, objectkey)
            solutions[region.region] = state
        else:
            solutions[region.region] = region.solution
    return solutions


def _require_same_rows(state: MeshState, rows: list[Any], region: ConflictRegion, objectkey: str) -> None:
    """Refuse a solution whose rows for the psql merge (``solution_*``) are not those of its .npz.

    A psql user records both, and nothing in SQL ties them: the psql merge
    would apply the rows and this merge the .npz, two results of one
    solution. Compared bit for bit (NaN with NaN: a value of none).
    """
    if rows[0] is None:  # recorded with the .npz only: the psql merge refuses it, no second reading
        return
    expected = _sql_rows(state)
    same = expected is not None and all(_same_array(a, b) for a, b in zip(expected, rows, strict=True))
    if not same:
        raise InvalidInputError(
            f"feature {objectkey}: region {region.region}: the rows recorded with its {region.solution} solution "
            "(tgsis.conflict_regions.solution_*) are not those of its mesh (solution_mesh): they were recorded apart",
            hint="record the solution again, both from one mesh: tgsis version resolve VERSION ID average|manual "
            "--region N [--mesh FILE], or tgsis.resolve_region in Python",
        )


def _same_array(a: list[Any], b: list[Any] | None) -> bool:
    """Two arrays of ids, names or float8 values the same, floats bit for bit with NaN equal to NaN."""
    if b is None or len(a) != len(b):
        return False
    if not a or not isinstance(a[0], float):
        return list(a) == list(b)
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return bool(np.all((x.view(np.int64) == y.view(np.int64)) | (np.isnan(x) & np.isnan(y))))


def _holds(stored: list[ConflictRegion], marks: tuple[str, str], merge: MeshMerge) -> bool:
    return (
        len(stored) == len(merge.regions)
        and len(stored) > 0
        and all((r.childmark, r.parentmark) == marks for r in stored)
        and all(_same_region(s, m) for s, m in zip(stored, merge.regions, strict=True))
    )


def _holds_sliced(stored: list[ConflictRegion], marks: tuple[str, str], merge: SlicedMerge) -> bool:
    return (
        len(stored) == len(merge.regions)
        and len(stored) > 0
        and all((r.childmark, r.parentmark) == marks for r in stored)
        and all(
            _same_region(s, dataclasses.replace(m.region, index=m.index)) and _same_slice(s, m.key)
            for s, m in zip(stored, merge.regions, strict=True)
        )
    )


@checked
def sliced_region_solutions(
    conn: Conn, version: str, objectclass: str, objectkey: str, merge: SlicedMerge
) -> dict[int, str | MeshState]:
    """:func:`region_solutions` for a model-2 or model-3 object merged slice by slice (regions numbered in the object).

    The stored regions hold when found on the current marks and they are the
    merge's, slice and ids alike; otherwise ``{}``.
    """
    with reraise():
        versionid = version_row(conn, version)[0]
        marks = _current_marks(conn, versionid, objectclass, objectkey)
        stored = _stored_regions(conn, versionid, objectclass, objectkey)
        if marks is None or not _holds_sliced(stored, marks, merge):
            return {}
    return _solutions_of(conn, versionid, objectclass, objectkey, stored, merge.base.name)


@checked
def sliced_recorded_solutions(
    conn: Conn, version: str, objectclass: str, objectkey: str, merge: SlicedMerge
) -> dict[int, str] | None:
    """:func:`recorded_solutions` for a model-2 or model-3 object merged slice by slice."""
    with reraise():
        versionid = version_row(conn, version)[0]
        stored = _stored_regions(conn, versionid, objectclass, objectkey)
        if not stored:
            return {}
        marks = _current_marks(conn, versionid, objectclass, objectkey)
        if marks is None or not _holds_sliced(stored, marks, merge):
            return None
    return {r.region: r.solution for r in stored}


# --------------------------------------------------------------------------- a MeshState as .npz bytes


def state_to_npz(state: MeshState) -> bytes:
    """A state as the bytes of an ``.npz`` (numpy arrays only: read back without pickles)."""
    arrays: dict[str, npt.NDArray[Any]] = {
        "cell_size": np.asarray(state.cell_size, dtype=np.int64),
        "vertex_ids": state.vertex_ids,
        "vertices": state.vertices,
        "cell_ids": state.cell_ids,
        "cells": state.cells,
    }
    for prefix, props in (("vertex:", state.vertex_properties), ("cell:", state.cell_properties)):
        for name, values in props.items():
            arrays[prefix + name] = np.asarray(values)
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)  # type: ignore[arg-type]
    return buffer.getvalue()


def state_from_npz(data: bytes, name: str = "mesh") -> MeshState:
    """The state of :func:`state_to_npz` bytes (``allow_pickle=False``); a bad file is :class:`InvalidInputError`."""
    try:
        arrays = _npz_arrays(data)
        return MeshState(
            int(arrays["cell_size"]),
            arrays["vertex_ids"],
            arrays["vertices"],
            arrays["cell_ids"],
            arrays["cells"],
            {k.split(":", 1)[1]: v for k, v in arrays.items() if k.startswith("vertex:")},
            {k.split(":", 1)[1]: v for k, v in arrays.items() if k.startswith("cell:")},
            name,
        )
    except Error:
        raise
    except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile) as exc:
        raise InvalidInputError(f"{name}: the stored mesh of a solution is no .npz of a mesh state: {exc}") from exc


def _npz_arrays(data: bytes) -> dict[str, npt.NDArray[Any]]:
    """The arrays of .npz ``data``, each checked before it is made: a forged file is refused, not inflated.

    The bytes are written by any role that may resolve a conflict and read by
    the merge of another: only members stored uncompressed (as
    :func:`numpy.savez` writes them; a deflated member could expand a few
    bytes into gigabytes), no object arrays (pickles), and a header whose
    shape and type hold exactly the member's bytes. ValueError names the member.
    """
    arrays: dict[str, npt.NDArray[Any]] = {}
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        for info in archive.infolist():
            if info.compress_type != zipfile.ZIP_STORED:
                raise ValueError(
                    f"member {info.filename} is compressed; .npz of numpy.savez stores its arrays as they are"
                )
            payload = archive.read(info)  # stored: as long as it is in data, CRC checked
            stream = io.BytesIO(payload)
            version = np.lib.format.read_magic(stream)
            read_header = (
                np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            )
            shape, fortran, dtype = read_header(stream)
            if dtype.hasobject:
                raise ValueError(f"member {info.filename} holds Python objects (pickles are not read)")
            count = int(np.prod(shape, dtype=object))
            held = len(payload) - stream.tell()
            if count * dtype.itemsize != held:
                raise ValueError(f"member {info.filename} declares shape {shape} of {dtype} but holds {held} bytes")
            values = np.frombuffer(payload, dtype=dtype, count=count, offset=stream.tell())
            arrays[info.filename.removesuffix(".npy")] = values.reshape(shape, order="F" if fortran else "C").copy()
    return arrays


# --------------------------------------------------------------------------- resolve_region


@dataclass(frozen=True)
class RegionResolution:
    """What :func:`resolve_region` recorded.

    Attributes
    ----------
    region : ConflictRegion
        The stored region with its solution.
    discards : tuple of RegionDiscard
        What the solution throws away of each side's edit in the region
        (counted against the merge with the other regions' recorded
        solutions, ``parent`` for those still unsolved).
    state : MeshState or None
        The rows of an ``average`` or ``manual`` solution as recorded.
    """

    region: ConflictRegion
    discards: tuple[RegionDiscard, ...]
    state: MeshState | None = None

    def summary(self) -> str:
        """One line per discard, or that nothing is discarded."""
        if not self.discards:
            return f"region {self.region.region}: {self.region.solution} discards nothing"
        return "\n".join(discard_text(d) for d in self.discards)


def discard_text(d: RegionDiscard) -> str:
    """What a region's solution discards, in one line."""
    return (
        f"region {d.region}: {d.solution} discards the {'version' if d.side == 'child' else 'parent'}'s edit of "
        f"{d.vertices} vertices and {d.cells} cells (largest displacement {d.max_displacement:.6g})"
    )


@checked
def resolve_region(
    conn: Conn,
    version: str,
    feature_id: int,
    region: int,
    solution: str,
    mesh: MeshState | Mesh | None = None,
    *,
    discard_other: bool = True,
) -> RegionResolution:
    """Record the solution of one conflicting region of a mesh (docs/merge.md, "Solutions per region").

    The regions must have been found on the object's current state
    (:func:`find_conflicts`); what the solution discards of either side's
    edit in the region is computed first (:func:`tgsis.merge3.apply_solutions`
    with the other regions' recorded solutions) and returned.

    Parameters
    ----------
    version : str
    feature_id : int
        The conflicting feature (geoid).
    region : int
        The region's index (:attr:`ConflictRegion.region`).
    solution : {"parent", "child", "base", "average", "manual", "unsolved"}
        ``parent``, ``child``, ``base``: that state's rows of the region;
        ``average``: each vertex of the region at the middle of its parent
        and child positions (docs/merge.md says the rule); ``manual``: the
        rows of ``mesh``; ``unsolved`` takes a solution back.
    mesh : MeshState or Mesh, optional
        ``manual`` only. A :class:`~tgsis.merge3.MeshState` keyed by the
        stored ids, or a :class:`~tgsis.mesh.Mesh` whose vertex property
        ``vrtxid`` holds them (what ``tgsis version conflicts --export``
        writes: a vertex without an id, NaN or negative, is a new vertex). Its
        rows of the region's ids, and of ids no state has, are the region's;
        its other rows must be those of a state (base, parent or version).
        An ``average`` or ``manual`` solution is recorded with its rows also
        in a form SQL reads (``tgsis.conflict_regions.solution_*``), so that
        a psql ``SELECT tgsis.merge_version(v)`` applies it as well.
    discard_other : bool
        When False, a solution that discards anything is refused.

    Returns
    -------
    RegionResolution

    Raises
    ------
    RegionSolutionError
        The region is no conflict; the regions were found on a state that
        changed since (find them again); ``discard_other=False`` and the
        solution discards something.
    InvalidInputError
        An unknown solution; a mesh for parent/child/base or none for manual;
        a mesh that changes rows outside the region.
    InvalidMergeError
        The solution gives no valid mesh.
    MissingPrivilegeError
        The role may not write in the version (nothing recorded).
    """
    wanted = solution.lower() if isinstance(solution, str) else solution
    name = f"region {region} of feature {feature_id} in version {show_name(version)}"
    if wanted not in _SOLUTIONS:
        raise InvalidInputError(
            f"{name}: solution {solution!r} is not parent, child, base, average, manual or unsolved",
            hint="automatic is no choice: regions that are no conflict merge by themselves"
            if wanted == "automatic"
            else None,
        )
    if wanted == "manual" and mesh is None:
        raise InvalidInputError(f"{name}: solution manual needs the region's mesh", hint="give mesh=")
    if wanted != "manual" and mesh is not None:
        raise InvalidInputError(
            f"{name}: solution {wanted} takes no mesh: one was given",
            hint="leave mesh out, or give solution='manual'"
            + (" (average is computed)" if wanted == "average" else ""),
        )
    return _retried(conn, lambda: _resolve(conn, version, feature_id, region, wanted, mesh, discard_other, name))


def _resolve(
    conn: Conn,
    version: str,
    feature_id: int,
    index: int,
    solution: str,
    mesh: MeshState | Mesh | None,
    discard_other: bool,
    name: str,
) -> RegionResolution:
    key, stored = _regions_of_now(conn, version, feature_id, name)
    if solution == "unsolved" or not 0 <= index < len(stored) or not stored[index].conflict:
        # nothing to compute: the SQL function records it or refuses (not a region, no conflict)
        return RegionResolution(_record(conn, version, key, index, solution, None), ())
    if stored[index].times is not None:  # a region of one slice of a temporal surface (models 2, 3)
        return _resolve_sliced(conn, version, feature_id, key, stored, index, solution, mesh, discard_other, name)
    merge = _checked_merge(conn, version, feature_id, stored, name)
    target = merge.regions[index]
    given: Solution
    if solution == "average":
        given = average_region(merge, target, _real_properties(conn, feature_id))
    elif solution == "manual":
        assert mesh is not None
        given = _manual_state(merge, target, mesh, name)
    else:
        given = cast(Solution, solution)
    others = cast(dict[int, Solution], region_solutions(conn, version, "feature", key, merge))
    others.pop(index, None)
    placeholders: dict[int, Solution] = {r.index: "parent" for r in merge.conflicts if r.index not in others}
    placeholders.pop(index, None)
    resolved = apply_solutions(merge, {**placeholders, **others, index: given}, names={index: solution})
    discards = tuple(d for d in resolved.discards if d.region == index)
    if discards and not discard_other:
        raise RegionSolutionError(
            f"{name}: solution {solution} discards edits: " + "; ".join(discard_text(d) for d in discards),
            hint="call again with discard_other=True to discard them, or choose another solution",
        )
    state = given if isinstance(given, MeshState) else None
    row = _record(conn, version, key, index, solution, state)
    return RegionResolution(row, discards, state)


def _checked_sliced_merge(
    conn: Conn, version: str, feature_id: int, stored: list[ConflictRegion], name: str
) -> SlicedMerge:
    """:func:`_checked_merge` of a model-2/3 object: its merge slice by slice, refused when other than stored."""
    states = read_sliced_states(conn, version, feature_id).states
    merge = merge_sliced(states["base"], states["parent"], states["child"])
    if len(stored) != len(merge.regions) or not all(
        _same_region(s, dataclasses.replace(m.region, index=m.index)) and _same_slice(s, m.key)
        for s, m in zip(stored, merge.regions, strict=True)
    ):
        raise RegionSolutionError(
            f"{name}: the stored regions are not those of the object's states now",
            hint=f"find the regions again: tgsis.find_conflicts(conn, {version!r})",
        )
    return merge


def _slice_solution(
    conn: Conn,
    version: str,
    key: str,
    merge: SlicedMerge,
    given: Mapping[int, Solution],
    names: Mapping[int, str],
) -> tuple[RegionDiscard, ...]:
    """Check the solutions ``given`` (object region numbers) on their slices with the other recorded ones there.

    Each slice of a given region takes :func:`apply_solutions` with the
    recorded solutions of its other conflicting regions (``parent`` for those
    still unsolved) and the given ones; what the given ones discard is
    returned, numbered in the object.
    """
    recorded = sliced_region_solutions(conn, version, "feature", key, merge)
    discards: list[RegionDiscard] = []
    for slice_key in sorted({merge.region(i).key for i in given}):
        mine = [r for r in merge.regions if r.key == slice_key]
        number = {r.region.index: r.index for r in mine}
        local: dict[int, Solution] = {}
        for r in mine:
            if not r.region.conflict:
                continue
            if r.index in given:
                local[r.region.index] = given[r.index]
            elif r.index in recorded:
                value = recorded[r.index]
                local[r.region.index] = value if isinstance(value, MeshState) else cast(Solution, value)
            else:
                local[r.region.index] = "parent"
        local_names = {r.region.index: names[r.index] for r in mine if r.index in names}
        resolved = apply_solutions(merge.merges[slice_key], local, names=local_names)
        discards += [
            dataclasses.replace(d, region=number[d.region]) for d in resolved.discards if number[d.region] in given
        ]
    return tuple(sorted(discards, key=lambda d: (d.region, d.side)))


def _resolve_sliced(
    conn: Conn,
    version: str,
    feature_id: int,
    key: str,
    stored: list[ConflictRegion],
    index: int,
    solution: str,
    mesh: MeshState | Mesh | None,
    discard_other: bool,
    name: str,
) -> RegionResolution:
    """:func:`_resolve` for a region of one slice of a model-2/3 object: solved on that slice's merge."""
    merge = _checked_sliced_merge(conn, version, feature_id, stored, name)
    target = merge.region(index)
    mm = merge.merges[target.key]
    given: Solution
    if solution == "average":
        given = average_region(mm, target.region, _real_properties(conn, feature_id))
    elif solution == "manual":
        assert mesh is not None
        given = _manual_state(mm, target.region, mesh, name)
    else:
        given = cast(Solution, solution)
    discards = _slice_solution(conn, version, key, merge, {index: given}, {index: solution})
    if discards and not discard_other:
        raise RegionSolutionError(
            f"{name}: solution {solution} discards edits: " + "; ".join(discard_text(d) for d in discards),
            hint="call again with discard_other=True to discard them, or choose another solution",
        )
    state = given if isinstance(given, MeshState) else None
    # with its rows, keyed by the slice's ids, which the psql merge applies
    row = _record(conn, version, key, index, solution, state)
    return RegionResolution(row, discards, state)


def _regions_of_now(conn: Conn, version: str, feature_id: int, name: str) -> tuple[str, list[ConflictRegion]]:
    """The feature's key and its stored regions, on the marks of now (stale ones dropped); refused without regions.

    The right first: a role that may not resolve learns that, whatever else is wrong.
    """
    versionid = version_row(conn, version)[0]
    conn.execute("SELECT tgsis.require_version_privilege(%s, 'write', 'resolve conflicts of')", (versionid,))
    key = str(feature_id)
    stored_before = _stored_regions(conn, versionid, "feature", key)
    conn.execute("SELECT FROM tgsis.find_conflicts(%s)", (version,))  # the marks of now; stale regions go
    stored = _stored_regions(conn, versionid, "feature", key)
    _require_regions(stored, stored_before, version, name)
    return key, stored


def _require_regions(
    stored: list[ConflictRegion], stored_before: list[ConflictRegion], version: str, name: str
) -> None:
    """Refuse when no regions are stored now: stale ones (gone with the marks, or found again on new marks by SQL
    tgsis.find_conflicts) or none ever found."""
    again = bool(stored and stored_before) and (stored[0].childmark, stored[0].parentmark) != (
        stored_before[0].childmark,
        stored_before[0].parentmark,
    )
    if stored and not again:
        return
    if stored_before:
        raise RegionSolutionError(
            f"{name}: the regions were found on a state that changed since: the object changed in the version "
            "or its parent",
            hint=f"find the regions again: tgsis.find_conflicts(conn, {version!r}), or tgsis version conflicts "
            f"{shlex.quote(version)}",
        )
    raise NotFoundError(
        f"{name}: no regions of the feature are stored",
        hint=f"tgsis.find_conflicts(conn, {version!r}) finds and records them (tgsis version conflicts {shlex.quote(version)})",
    )


def _sql_rows(state: MeshState) -> tuple[Any, ...] | None:
    """A solution's rows as the eight arrays ``tgsis.resolve_region`` keeps for the psql merge, or None.

    Ids, coordinates (x, y, z per vertex), cells (k vertex ids per cell) and
    the scalar property values column after column per row (float64: exact for
    every float and for integers up to 2**53). None when a value does not fit
    (a vector property, an integer beyond 2**53): the psql merge then refuses
    the solution and the Python merge applies it.
    """
    columns: list[list[str]] = []
    values: list[list[float]] = []
    for props, count in (
        (state.vertex_properties, len(state.vertex_ids)),
        (state.cell_properties, len(state.cell_ids)),
    ):
        names = sorted(props)
        table = np.empty((count, len(names)), dtype=np.float64)
        for j, prop in enumerate(names):
            column = np.asarray(props[prop])
            if column.ndim != 1 or column.dtype.kind not in "biuf":
                return None
            if column.dtype.kind in "iu" and len(column) and np.abs(column.astype(np.float64)).max() > 2.0**53:
                return None
            table[:, j] = column.astype(np.float64)
        columns.append(names)
        values.append(table.ravel().tolist())
    return (
        state.vertex_ids.tolist(),
        np.asarray(state.vertices, dtype=np.float64).ravel().tolist(),
        state.cell_ids.tolist(),
        state.cells.ravel().tolist(),
        columns[0],
        values[0],
        columns[1],
        values[1],
    )


def _record(conn: Conn, version: str, key: str, index: int, solution: str, state: MeshState | None) -> ConflictRegion:
    """Record a region's solution; an average or manual one with its .npz and its rows for the psql merge.

    A region of a slice (an instant of model 2, a geometry instant of a
    model-3 period) too: its rows keyed by the slice's ids (vertex or node ids,
    triangle ids).
    """
    mesh = None if state is None else state_to_npz(state)
    rows = None if state is None else _sql_rows(state)
    row = conn.execute(
        f"SELECT {_REGION_COLUMNS} FROM tgsis.resolve_region(%s, 'feature', %s, %s, %s, %s,"
        " %s, %s::float8[], %s, %s, %s::text[], %s::float8[], %s::text[], %s::float8[])",
        (version, key, index, solution, mesh, *(rows or (None,) * 8)),
        binary=True,  # the instants (times, timem) bit for bit, whatever the session's extra_float_digits
    ).fetchone()
    assert row is not None
    return _region_of_row(row)


def _checked_merge(conn: Conn, version: str, feature_id: int, stored: list[ConflictRegion], name: str) -> MeshMerge:
    states = read_merge_states(conn, version, feature_id).states
    merge = three_way_merge(states["base"], states["parent"], states["child"])
    if len(stored) != len(merge.regions) or not all(
        _same_region(s, m) for s, m in zip(stored, merge.regions, strict=True)
    ):
        raise RegionSolutionError(  # marks unchanged but other regions: found by another client or rules
            f"{name}: the stored regions are not those of the object's states now",
            hint=f"find the regions again: tgsis.find_conflicts(conn, {version!r})",
        )
    return merge


# --------------------------------------------------------------------------- resolve_all_regions: one solution per object

_OBJECT_SOLUTIONS = ("parent", "child", "base", "average", "unsolved")


@dataclass(frozen=True)
class SideDiscard:
    """What an object's solution throws away of one side's edits, summed over its conflicting regions.

    Attributes
    ----------
    solution : str
        ``parent``, ``child``, ``base`` or ``average``.
    side : str
        ``parent`` or ``child``: whose edits are lost.
    vertices, cells : int
        The sums of the regions' :class:`~tgsis.merge3.RegionDiscard` counts.
    max_displacement : float
        The largest of the regions' largest displacements.
    regions : tuple of int
        The regions where that side loses something.
    """

    solution: str
    side: str
    vertices: int
    cells: int
    max_displacement: float
    regions: tuple[int, ...]


def side_discard_text(d: SideDiscard) -> str:
    """What an object's solution discards of one side, in one line."""
    return (
        f"{d.solution} discards the {'version' if d.side == 'child' else 'parent'}'s edit of {d.vertices} vertices "
        f"and {d.cells} cells in {len(d.regions)} region(s) (largest displacement {d.max_displacement:.6g})"
    )


@dataclass(frozen=True)
class ObjectResolution:
    """What :func:`resolve_all_regions` recorded.

    Attributes
    ----------
    regions : tuple of ConflictRegion
        The conflicting regions with their solution, as stored (the regions
        that merge by themselves are not among them: they stay automatic).
    discards : tuple of RegionDiscard
        What the solution throws away, per region and side.
    totals : tuple of SideDiscard
        The same summed per side (``parent`` first); empty when nothing is discarded.
    """

    regions: tuple[ConflictRegion, ...]
    discards: tuple[RegionDiscard, ...]
    totals: tuple[SideDiscard, ...]

    def summary(self) -> str:
        """One line per side (the sums), then one per region's discard; or that nothing is discarded."""
        if not self.discards:
            solutions = sorted({r.solution for r in self.regions})
            return f"{', '.join(solutions) or 'the solution'} discards nothing"
        return "\n".join([*(side_discard_text(t) for t in self.totals), *(discard_text(d) for d in self.discards)])


def _totals(discards: tuple[RegionDiscard, ...], solution: str) -> tuple[SideDiscard, ...]:
    totals = []
    for side in ("parent", "child"):
        mine = [d for d in discards if d.side == side]
        if mine:
            totals.append(
                SideDiscard(
                    solution,
                    side,
                    sum(d.vertices for d in mine),
                    sum(d.cells for d in mine),
                    max(d.max_displacement for d in mine),
                    tuple(sorted({d.region for d in mine})),
                )
            )
    return tuple(totals)


@checked
def resolve_all_regions(
    conn: Conn, version: str, feature_id: int, solution: str, *, discard_other: bool = True
) -> ObjectResolution:
    """Record one solution for every conflicting region of a mesh at once (docs/merge.md, "Solutions per object").

    All or nothing, in one transaction: each conflicting region gets
    ``solution`` (replacing a solution recorded before), or, if one region
    refuses it (``average`` where the two sides' meshings of the region
    have no average shape), none is recorded and the error names the region. The
    regions that are no conflict are not touched: they merge by themselves,
    so a per-object ``parent`` never drops the version's edits outside the
    conflicts (unlike ``resolve_conflict(..., 'parent')``, which is refused
    for such an object).

    Parameters
    ----------
    version : str
    feature_id : int
        The conflicting feature (geoid); its regions must have been found on
        its current state (:func:`find_conflicts`).
    solution : {"parent", "child", "base", "average", "unsolved"}
        As for :func:`resolve_region`, for each conflicting region;
        ``unsolved`` takes every region's solution back. ``manual`` is per
        region only (its mesh is a region's rows).
    discard_other : bool
        When False, a solution that discards anything is refused.

    Returns
    -------
    ObjectResolution
        The regions recorded and what the solution discards, per region and
        summed per side (:attr:`ObjectResolution.totals`).

    Raises
    ------
    RegionSolutionError
        The object has no conflicting region; the regions were found on a
        state that changed since; a region refuses the solution (named);
        ``discard_other=False`` and the solution discards something.
    InvalidInputError
        An unknown solution, or ``manual``.
    NotFoundError
        No regions of the feature are stored.
    InvalidMergeError
        The solutions give no valid mesh.
    MissingPrivilegeError
        The role may not write in the version (nothing recorded).
    """
    wanted = solution.lower()
    name = f"feature {feature_id} in version {show_name(version)}"
    if wanted not in _OBJECT_SOLUTIONS:
        raise InvalidInputError(
            f"{name}: solution {solution!r} of all its regions is not parent, child, base, average or unsolved",
            hint="manual is a region's: resolve_region(conn, version, feature_id, N, 'manual', mesh)"
            if wanted == "manual"
            else None,
        )
    return _retried(conn, lambda: _resolve_all(conn, version, feature_id, wanted, discard_other, name))


def _resolve_all(
    conn: Conn, version: str, feature_id: int, solution: str, discard_other: bool, name: str
) -> ObjectResolution:
    key, stored = _regions_of_now(conn, version, feature_id, name)
    conflicting = [r.region for r in stored if r.conflict]
    if not conflicting:
        raise RegionSolutionError(
            f"{name}: no region of the feature is a conflict: nothing to choose, it merges by itself",
            hint=f"merge the version: tgsis version merge {shlex.quote(version)}",
        )
    if solution == "unsolved":
        return ObjectResolution(tuple(_record(conn, version, key, i, solution, None) for i in conflicting), (), ())
    if any(r.times is not None for r in stored):  # a model-2/3 object: its regions lie in its slices
        return _resolve_all_sliced(conn, version, feature_id, key, stored, solution, discard_other, name)
    merge = _checked_merge(conn, version, feature_id, stored, name)
    given: dict[int, Solution] = {}
    real = _real_properties(conn, feature_id)
    for region in merge.conflicts:
        if solution == "average":
            try:
                given[region.index] = average_region(merge, region, real)
            except RegionSolutionError as exc:  # the whole solution is refused: say which region refused it
                raise RegionSolutionError(
                    f"{name}: average of all its regions refused, nothing recorded: {exc.message}", hint=exc.hint
                ) from exc
        else:
            given[region.index] = cast(Solution, solution)
    resolved = apply_solutions(merge, given, names=dict.fromkeys(given, solution))
    discards = tuple(sorted((d for d in resolved.discards if d.region in given), key=lambda d: (d.region, d.side)))
    return _record_all(conn, version, key, given, solution, discards, discard_other, name)


def _record_all(
    conn: Conn,
    version: str,
    key: str,
    given: Mapping[int, Solution],
    solution: str,
    discards: tuple[RegionDiscard, ...],
    discard_other: bool,
    name: str,
) -> ObjectResolution:
    """Record one solution for every given region, after saying what it discards (refused, nothing recorded,
    when it discards and ``discard_other`` is False)."""
    totals = _totals(discards, solution)
    if discards and not discard_other:
        raise RegionSolutionError(
            f"{name}: solution {solution} of all its regions discards edits: "
            + "; ".join([*(side_discard_text(t) for t in totals), *(discard_text(d) for d in discards)]),
            hint="call again with discard_other=True to discard them, or choose another solution",
        )
    rows = []
    for index in sorted(given):
        value = given[index]
        state = value if isinstance(value, MeshState) else None
        rows.append(_record(conn, version, key, index, solution, state))
    return ObjectResolution(tuple(rows), discards, totals)


def _resolve_all_sliced(
    conn: Conn,
    version: str,
    feature_id: int,
    key: str,
    stored: list[ConflictRegion],
    solution: str,
    discard_other: bool,
    name: str,
) -> ObjectResolution:
    """:func:`_resolve_all` for a model-2/3 object: every conflicting region of every slice, all or nothing."""
    merge = _checked_sliced_merge(conn, version, feature_id, stored, name)
    given: dict[int, Solution] = {}
    real = _real_properties(conn, feature_id)
    for r in merge.conflicts:
        if solution == "average":
            try:
                given[r.index] = average_region(merge.merges[r.key], r.region, real)
            except RegionSolutionError as exc:
                raise RegionSolutionError(
                    f"{name}: average of all its regions refused, nothing recorded: region {r.index}: {exc.message}",
                    hint=exc.hint,
                ) from exc
        else:
            given[r.index] = cast(Solution, solution)
    discards = _slice_solution(conn, version, key, merge, given, dict.fromkeys(given, solution))
    return _record_all(conn, version, key, given, solution, discards, discard_other, name)


# --------------------------------------------------------------------------- average of a whole object


@checked
def resolve_conflict(
    conn: Conn, version: str, objectclass: str, objectkey: object, solution: str, *, discard_other: bool = True
) -> Conflict:
    """Record how a conflicting object is merged; ``average`` of a feature's mesh computed here (docs/merge.md).

    The public ``tgsis.resolve_conflict``: ``parent``, ``child``, ``base``,
    ``manual`` and ``unsolved`` are :func:`tgsis.db.versions.resolve_conflict`'s
    (``base`` writes the object as the version was based on it into the
    version and records ``manual``); ``average`` of a feature writes the
    average of the two sides' meshes into the version and records ``manual``
    (:func:`resolve_object_average`; what it discards in
    :attr:`Conflict.region_discards`).

    Parameters
    ----------
    version, objectclass : str
    objectkey : object
        The object's key (a feature's geoid for class ``feature``).
    solution : {"parent", "child", "base", "average", "manual", "unsolved"}
    discard_other : bool
        When False, a solution that discards the other side's edits (for
        ``base`` and ``average``: either side's) is refused.

    Returns
    -------
    Conflict
        The recorded row (``manual`` for ``base`` and ``average``).

    Raises
    ------
    InvalidInputError
        An unknown solution; ``average`` of a row of a versioned table (no mesh).
    RegionSolutionError, VersioningError, NotFoundError, MissingPrivilegeError
        As :func:`tgsis.db.versions.resolve_conflict` and :func:`resolve_object_average` say.
    """
    if isinstance(solution, str) and solution.lower() == "average":
        if objectclass != "feature":
            raise InvalidInputError(
                f"solution average is the average shape of a feature's two meshes: object {objectkey} of class "
                f"{objectclass} in version {show_name(version)} is a row of a versioned table",
                hint="solve it with parent, child, base or manual",
            )
        try:
            feature_id = int(str(objectkey).strip())
        except ValueError:
            raise InvalidInputError(
                f"key {str(objectkey)!r} of class feature is not a feature id",
                hint="give the feature's id (tgsis version conflicts VERSION lists the conflicting objects)",
            ) from None
        conflict, discards = resolve_object_average(conn, version, feature_id, discard_other=discard_other)
        return dataclasses.replace(conflict, region_discards=discards)
    return resolve_whole_object(conn, version, objectclass, objectkey, solution, discard_other=discard_other)


@checked
def resolve_object_average(
    conn: Conn, version: str, feature_id: int, *, discard_other: bool = True
) -> tuple[Conflict, tuple[RegionDiscard, ...]]:
    """The object-level ``average`` of a conflicting mesh: written into the version, the conflict recorded ``manual``.

    :func:`tgsis.resolve_conflict` with ``average`` calls it (docs/merge.md,
    "Whole-object solutions"). The average of the two sides' whole meshes:
    where they are the same (everything neither side changed) it is that
    mesh, bit for bit; each conflicting region is averaged as
    :func:`average_region` does (the exact midpoint for one meshing,
    :func:`tgsis.interpolation.average_shape` of the two patches for two
    meshings of a surface), attached to the unchanged rest. The merged mesh
    is written into the version by difference and the conflict recorded
    ``manual``, in one READ COMMITTED transaction holding the locks of a
    refresh (the version and its parent, so that no writer of either side
    commits between the read and the write); what it discards of each side
    is computed first. A mesh with a region that merges by itself is refused: averaging
    it would halve the one side's edit there, which
    :func:`resolve_all_regions` with ``average`` keeps.

    Returns
    -------
    (Conflict, tuple of RegionDiscard)
        The recorded conflict (solution ``manual``) and, per region and side,
        what the average discards.

    Raises
    ------
    RegionSolutionError
        A region that merges by itself (the hint: ``--region all``); no
        conflicting region; a region whose average is refused (named);
        ``discard_other=False`` and the average discards something.
    InvalidInputError
        Not a model-1 feature mesh, deleted on one side, attributes changed
        on both sides (the merge reader's refusals).
    MissingPrivilegeError
        The role may not write in the version or change the feature.
    """
    fresh = conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
    with reraise(), conn.transaction():  # READ COMMITTED, the pair locked: the write by difference needs it
        if fresh:
            conn.execute("SET TRANSACTION ISOLATION LEVEL READ COMMITTED")
        return _average_object(conn, version, feature_id, discard_other)


def _average_object(
    conn: Conn, version: str, feature_id: int, discard_other: bool
) -> tuple[Conflict, tuple[RegionDiscard, ...]]:
    name = f"feature {feature_id} in version {show_name(version)}"
    versionid = version_row(conn, version)[0]
    conn.execute("SELECT tgsis.require_version_privilege(%s, 'write', 'resolve conflicts of')", (versionid,))
    # the locks of a refresh (which writes into the version too): no writer of either side commits meanwhile
    conn.execute("SELECT FROM tgsis.lock_for_region_merge(%s, 'refresh')", (version,))
    inputs = read_merge_states(conn, version, feature_id)
    states = inputs.states
    merge = three_way_merge(states["base"], states["parent"], states["child"])
    by_itself = [r.index for r in merge.regions if not r.conflict]
    if by_itself or not merge.conflicts:
        from tgsis.merge3 import ids_text

        raise RegionSolutionError(
            f"{name}: the average of the whole object would halve the edits of regions {ids_text(by_itself)}, which "
            "merge by themselves"
            if by_itself
            else f"{name}: no region of it conflicts: it merges by itself",
            hint=f"average its conflicting regions only: tgsis version resolve {shlex.quote(version)} {feature_id} average "
            "--region "
            "all; the merge takes the rest by itself"
            if by_itself
            else f"merge it: tgsis version merge {shlex.quote(version)}",
        )
    averages: dict[int, Solution] = {}
    real = _real_properties(conn, feature_id)
    for region in merge.conflicts:
        try:
            averages[region.index] = average_region(merge, region, real)
        except RegionSolutionError as exc:
            raise RegionSolutionError(
                f"{name}: average refused, nothing written: {exc.message}", hint=exc.hint
            ) from exc
    resolved = apply_solutions(merge, averages, names=dict.fromkeys(averages, "average"))
    # the version's object replaces the parent's at the merge: an attribute only the parent changed goes into it
    # too, as the merge by region brings it (read_merge_states refused attributes both sides changed)
    attributes = attribute_edits(conn, inputs, version, feature_id)
    if attributes.both:
        raise RegionSolutionError(
            f"{name}: its attributes were changed both in the version and in its parent, to other values "
            f"({', '.join(attributes.both)}): the average is of the mesh only",
            hint="solve it with parent, child or base, or write the merged object into the version and record manual",
        )
    if resolved.discards and not discard_other:
        raise RegionSolutionError(
            f"{name}: solution average discards edits: " + "; ".join(discard_text(d) for d in resolved.discards),
            hint="call again with discard_other=True to discard them, or choose another solution",
        )
    settings = read_version_settings(conn)
    try:
        conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))  # its working revision, this transaction
        write_state_difference(conn, inputs.feature_class, feature_id, states["child"], resolved.state)
        write_attribute_edits(conn, feature_id, attributes)
    finally:
        if conn.info.transaction_status != psycopg.pq.TransactionStatus.INERROR:
            restore_version_settings(conn, settings, local=True)
    row = conn.execute(
        f"SELECT {CONFLICT_COLUMNS} FROM tgsis.resolve_conflict(%s, 'feature', %s, 'manual')",
        (version, str(feature_id)),
    ).fetchone()
    assert row is not None
    return Conflict.from_row(row), resolved.discards


# --------------------------------------------------------------------------- average and manual


def _closure(merge: MeshMerge, vids: npt.NDArray[np.int64], cells: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
    """The vertex ids the region's cells use that are not region rows (unchanged everywhere: the rest)."""
    used = np.unique(cells)
    return used[~np.isin(used, vids)]


def _rows_state(
    merge: MeshMerge,
    source: MeshState,
    vids: npt.NDArray[np.int64],
    cids: npt.NDArray[np.int64],
    name: str,
) -> MeshState:
    """``source``'s rows of these ids, with the rest's vertices its cells use, as the merge gives the rest."""
    at_v = np.flatnonzero(np.isin(source.vertex_ids, vids))
    at_c = np.flatnonzero(np.isin(source.cell_ids, cids))
    cells = source.cells[at_c]
    extra = _closure(merge, source.vertex_ids[at_v], cells)
    # the rest's vertices the region's cells use, as the merge gives the rest: the version's row where only the
    # version changed it (a region of its own the merge takes from the version: a value changed beside the
    # region, which puts no cell in a footprint), else the parent's (the merge keeps them), else the version's
    none = np.empty(0, np.int64)
    parent_same = state_rows_equal(merge.parent, merge.base, extra, none)[0]
    child_same = state_rows_equal(merge.child, merge.base, extra, none)[0]
    versions_own = extra[parent_same & ~child_same & np.isin(extra, merge.child.vertex_ids)]
    parts = [(source, at_v), (merge.child, np.flatnonzero(np.isin(merge.child.vertex_ids, versions_own)))]
    extra = extra[~np.isin(extra, versions_own)]
    for state in (merge.parent, merge.child):
        at_e = np.flatnonzero(np.isin(state.vertex_ids, extra))
        parts.append((state, at_e))
        extra = extra[~np.isin(extra, state.vertex_ids)]
    return MeshState(
        source.cell_size,
        np.concatenate([s.vertex_ids[a] for s, a in parts]),
        np.concatenate([s.vertices[a] for s, a in parts]),
        source.cell_ids[at_c],
        cells,
        {
            n: np.concatenate([np.asarray(s.vertex_properties[n])[a] for s, a in parts])
            for n in source.vertex_properties
        },
        {n: np.asarray(v)[at_c] for n, v in source.cell_properties.items()},
        name,
    )


def _real_properties(conn: Conn, feature_id: int) -> tuple[frozenset[str], frozenset[str]]:
    """The names of the feature's real-valued vertex and cell properties (columns real or double precision)."""
    fc = class_of_feature(conn, feature_id)
    vertex, cell = (
        frozenset(p.name for p in fc.aligned(a) if SQL_TYPES.get(p.type) in ("float4", "float8"))
        for a in ("VERTEX", "CELL")
    )
    return vertex, cell


def average_region(
    merge: MeshMerge, region: MergeRegion, real: tuple[Collection[str], Collection[str]] | None = None
) -> MeshState:
    """The ``average`` solution of a conflicting region: its rows at the middle of the two sides.

    The rule (docs/merge.md): when the region's rows are the parent's and
    the child's with the same ids and the same cells (the two sides moved or
    re-valued the region's vertices, neither re-meshed it), each vertex takes
    the middle of its parent and child positions, ``(p + c) / 2``, which is
    the average shape of two meshes of one topology (every vertex halfway
    along its straight trajectory); a real-valued property the middle of the
    two values, any other the parent's. Vertices of the rest that the
    region's cells use are not moved: their rows are those the merge gives
    the rest (the version's where only the version changed them, else the
    parent's).

    When the two sides meshed the region differently (a surface only), the
    average is :func:`tgsis.interpolation.average_shape` of the two sides'
    triangles of the region, the finer meshing carrying it and the border
    vertices both sides share as control vertices (see
    :func:`_average_of_meshings`): attached to the unchanged rest without a
    seam, with the finer side's ids (no new id, so none clashes).

    ``real`` names the vertex and the cell properties whose column is
    real-valued (``real``, ``double precision``): an integer column read as
    floats (NaN where a row is missing) is no real-valued property and keeps
    the parent's values. None: every float array is taken for one.

    Raises
    ------
    RegionSolutionError
        The sides meshed the region differently and its average shape is not
        defined (points, segments, tetrahedra; a side's triangles of the
        region that are no disk; fewer than three shared border vertices) or
        not valid (folds, or a mesh the merge refuses); the message says why.
    """
    parent, child = merge.parent, merge.child
    vids, cids = region.vertex_ids, region.cell_ids
    pv, cv = np.isin(parent.vertex_ids, vids), np.isin(child.vertex_ids, vids)
    pc, cc = np.isin(parent.cell_ids, cids), np.isin(child.cell_ids, cids)
    same_topology = (
        np.array_equal(parent.vertex_ids[pv], child.vertex_ids[cv])
        and np.array_equal(parent.cell_ids[pc], child.cell_ids[cc])
        and np.array_equal(np.sort(parent.cells[pc], axis=1), np.sort(child.cells[cc], axis=1))
    )
    if not same_topology:
        return _average_of_meshings(merge, region, real)
    rows = _rows_state(merge, parent, vids, cids, merge.base.name)
    at_p = np.flatnonzero(np.isin(rows.vertex_ids, parent.vertex_ids[pv]))  # the region's own vertices
    middle = 0.5 * parent.vertices[pv] + 0.5 * child.vertices[cv]
    vertices = rows.vertices.copy()
    vertices[at_p] = middle
    vprops = {n: np.asarray(v).copy() for n, v in rows.vertex_properties.items()}
    for n, values in vprops.items():
        if values.dtype.kind == "f" and (real is None or n in real[0]):
            values[at_p] = (
                0.5 * np.asarray(parent.vertex_properties[n])[pv] + 0.5 * np.asarray(child.vertex_properties[n])[cv]
            )
    cprops = {n: np.asarray(v).copy() for n, v in rows.cell_properties.items()}
    for n, values in cprops.items():
        if values.dtype.kind == "f" and (real is None or n in real[1]):
            values[:] = 0.5 * np.asarray(parent.cell_properties[n])[pc] + 0.5 * np.asarray(child.cell_properties[n])[cc]
    return MeshState(
        rows.cell_size,
        rows.vertex_ids,
        vertices,
        rows.cell_ids,
        rows.cells,
        vprops,
        cprops,
        f"{merge.base.name} average",
    )


_MESHING_WORDS = {1: "points", 2: "segments", 3: "triangles", 4: "tetrahedra"}
_NOT_AVERAGED = "solve it with parent, child or base, or give a manual mesh (e.g. an edited export)"


@dataclass(frozen=True)
class _Patch:
    """One side's cells of a region as a surface of its own: vertex ids (ascending), their rows, local triangles."""

    side: str  # "parent" or "child"
    state: MeshState
    vertex_ids: npt.NDArray[np.int64]
    at_vertices: npt.NDArray[np.int64]  # rows of state
    at_cells: npt.NDArray[np.int64]  # rows of state
    triangles: npt.NDArray[np.int64]  # local indices into vertex_ids

    @property
    def words(self) -> str:
        return "the version" if self.side == "child" else "the parent"


def _patch(side: str, state: MeshState, region: MergeRegion) -> _Patch:
    at_c = np.flatnonzero(np.isin(state.cell_ids, region.cell_ids))
    ids = np.unique(state.cells[at_c])
    return _Patch(
        side, state, ids, np.searchsorted(state.vertex_ids, ids), at_c, np.searchsorted(ids, state.cells[at_c])
    )


def _patch_surface(patch: _Patch) -> Any:
    """The patch as a Surface, with its one-valued real vertex properties (atoms' ``refid`` is an id, not a value)."""
    from tgsis.mesh import Surface

    props = {
        n: np.asarray(v, dtype=np.float64)[patch.at_vertices]
        for n, v in patch.state.vertex_properties.items()
        if np.asarray(v).dtype.kind == "f" and np.asarray(v).ndim == 1 and n != "refid"
    }
    return Surface(patch.state.vertices[patch.at_vertices], patch.triangles, vertex_properties=props)


def _average_of_meshings(
    merge: MeshMerge, region: MergeRegion, real: tuple[Collection[str], Collection[str]] | None = None
) -> MeshState:
    """``average`` of a region the two sides meshed differently: the morphological average shape of their patches.

    Each side's triangles of the region (its patch: the region's own
    vertices and the rest's vertices its triangles use) must be a
    topological disk. The patch with more vertices (the parent's on a tie)
    is the source of :func:`tgsis.interpolation.average_shape`, the other the
    target; the control vertices are the source's border vertices that are
    on the target's border too (same ids: the unchanged rest around the
    region, and the mesh-border vertices both sides kept), in the source's
    border order, so each border edge of the rest is a border edge of both
    patches and maps onto itself. With an infinite tolerance nothing is
    refined: the average has the source's triangles and ids, each vertex
    halfway between its place and its image on the target (the common
    parameterisation of the two disks), the real vertex properties halfway
    as well; cell values are the source's. Shared border vertices that are
    region rows take ``(p + c) / 2`` exactly (their own straight path; those
    both sides left alone stay bit for bit) and the rest's vertices are the
    rest's rows. The result is checked: no triangle turned over against the
    source, and the merge with it (the other conflicts solved ``parent``)
    valid — else refused, saying why.
    """
    from tgsis.interpolation import InterpolationSetup, average_shape, border_loops, border_vertices, check_disk

    name = f"{merge.base.name}: region {region.index}"
    k = merge.base.cell_size
    if k != 3:
        raise RegionSolutionError(
            f"{name} has other {_MESHING_WORDS[k]} in the parent and in the version: the average of two meshings "
            "(tgsis.interpolation.average_shape) is defined for triangulated surfaces only",
            hint=_NOT_AVERAGED,
        )
    patches = [_patch("parent", merge.parent, region), _patch("child", merge.child, region)]
    for patch in patches:
        if len(patch.triangles) == 0:
            raise RegionSolutionError(
                f"{name}: {patch.words} has no triangle in the region: there is no shape of it to average",
                hint=_NOT_AVERAGED,
            )
    source, target = patches if len(patches[0].vertex_ids) >= len(patches[1].vertex_ids) else patches[::-1]
    surfaces = [_patch_surface(p) for p in (source, target)]
    for patch, surface in zip((source, target), surfaces, strict=True):
        disk = check_disk(surface, vertex_ids=patch.vertex_ids)
        if not disk.ok:
            raise RegionSolutionError(
                f"{name}: {patch.words}'s triangles of the region are no topological disk ({disk.summary()}): "
                "average_shape maps one disk onto another",
                hint=_NOT_AVERAGED,
            )
    loop = source.vertex_ids[border_loops(surfaces[0])[0]]
    controls = loop[np.isin(loop, target.vertex_ids[border_vertices(surfaces[1])])]
    if len(controls) < 3:
        raise RegionSolutionError(
            f"{name}: the two sides' triangles of the region share {len(controls)} border vertices: average_shape "
            "needs three or more to pair the two borders",
            hint=_NOT_AVERAGED,
        )
    setup = InterpolationSetup(
        tuple(np.searchsorted(source.vertex_ids, controls).tolist()),
        tuple(np.searchsorted(target.vertex_ids, controls).tolist()),
        steps=3,  # the middle is a sample
    )
    try:
        middle = average_shape(surfaces[0], surfaces[1], setup)
    except InvalidInputError as exc:  # the interpolation's set-up, parameterisation or trajectory errors
        raise RegionSolutionError(
            f"{name}: the average shape of the two sides' meshings of the region failed: {exc.message}",
            hint=_NOT_AVERAGED,
        ) from exc
    if middle.n_vertices != len(source.vertex_ids) or not np.array_equal(middle.cells, source.triangles):
        raise RegionSolutionError(f"{name}: the average shape re-meshed the region", hint=_NOT_AVERAGED)
    state = _averaged_rows(merge, region, source, middle, controls, name, real)
    _check_average(merge, region, source, state, name)
    return state


def _averaged_rows(
    merge: MeshMerge,
    region: MergeRegion,
    source: _Patch,
    middle: Any,
    controls: npt.NDArray[np.int64],
    name: str,
    real: tuple[Collection[str], Collection[str]] | None = None,
) -> MeshState:
    """The source's rows of the region at the average shape; the rest's rows as they are (see _average_of_meshings)."""
    own = source.vertex_ids[np.isin(source.vertex_ids, region.vertex_ids)]
    rows = _rows_state(merge, source.state, own, source.state.cell_ids[source.at_cells], name)
    at_rows, at_mid = np.searchsorted(rows.vertex_ids, own), np.searchsorted(source.vertex_ids, own)
    vertices = rows.vertices.copy()
    vertices[at_rows] = middle.vertices[at_mid]
    vprops = {n: np.asarray(v).copy() for n, v in rows.vertex_properties.items()}
    carried = [n for n in middle.vertex_properties if real is None or n in real[0]]  # (not an integer column's)
    for n in carried:
        values = middle.vertex_properties[n]
        vprops[n] = vprops[n].astype(np.float64)
        vprops[n][at_rows] = np.asarray(values)[at_mid]
    # the shared border's region rows: their own straight path, exactly as for one meshing
    paired = controls[np.isin(controls, region.vertex_ids)]
    at_p = np.searchsorted(merge.parent.vertex_ids, paired)
    at_c = np.searchsorted(merge.child.vertex_ids, paired)
    at_s = np.searchsorted(rows.vertex_ids, paired)
    vertices[at_s] = 0.5 * merge.parent.vertices[at_p] + 0.5 * merge.child.vertices[at_c]
    for n in carried:
        vprops[n][at_s] = (
            0.5 * np.asarray(merge.parent.vertex_properties[n])[at_p]
            + 0.5 * np.asarray(merge.child.vertex_properties[n])[at_c]
        )
    return MeshState(
        rows.cell_size,
        rows.vertex_ids,
        vertices,
        rows.cell_ids,
        rows.cells,
        vprops,
        rows.cell_properties,
        f"{merge.base.name} average",
    )


def _check_average(merge: MeshMerge, region: MergeRegion, source: _Patch, state: MeshState, name: str) -> None:
    """Refuse (TG307, saying why) an average with triangles turned over, or whose merge would be no valid mesh."""
    from tgsis.merge3 import ids_text

    def normals(xyz: npt.NDArray[np.float64], ids: npt.NDArray[np.int64], cells: npt.NDArray[np.int64]) -> Any:
        corners = xyz[np.searchsorted(ids, cells)]
        return np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])

    cells = source.state.cells[source.at_cells]
    before = normals(source.state.vertices, source.state.vertex_ids, cells)
    after = normals(state.vertices, state.vertex_ids, cells)
    turned = np.einsum("ij,ij->i", before, after) <= 0.0
    if turned.any():
        raise RegionSolutionError(
            f"{name}: the average shape of the two sides' meshings turns triangles "
            f"{ids_text(source.state.cell_ids[source.at_cells][turned])} over (a fold)",
            hint=_NOT_AVERAGED,
        )
    others: dict[int, Solution] = {r.index: "parent" for r in merge.conflicts}
    try:
        apply_solutions(merge, {**others, region.index: state}, names={region.index: "average"})
    except (InvalidMergeError, InvalidInputError) as exc:
        raise RegionSolutionError(
            f"{name}: the average shape of the two sides' meshings would not merge into a valid mesh: {exc.message}",
            hint=_NOT_AVERAGED,
        ) from exc


def _file_ids(
    mesh: Mesh, name: str, stored: npt.NDArray[np.int64]
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.bool_]]:
    """Per file vertex, its stored id from the vertex property ``vrtxid``, and whether it is a new vertex.

    A vertex is new when its ``vrtxid`` is NaN, or negative and no id of ``stored`` (the three states'
    vertex ids): a psql user may store negative ids, which the export writes as they are, so a negative
    value that is a stored id is that vertex, not a tool's mark of a vertex it added.
    """
    if "vrtxid" not in mesh.vertex_properties:
        raise InvalidInputError(
            f"{name}: the mesh has no vertex property 'vrtxid': its vertices cannot be matched to the stored ones",
            hint="edit a file written by tgsis version conflicts --export (it keeps the ids as the vertex property "
            "vrtxid), or give a MeshState",
        )
    given = np.asarray(mesh.vertex_properties["vrtxid"]).ravel()
    if given.dtype.kind in "iu":  # integers as they are: through float64 an id past 2**53 would become another
        if given.dtype.kind == "u" and given.size and int(given.max()) > np.iinfo(np.int64).max:
            raise InvalidInputError(f"{name}: vertex property 'vrtxid' holds values past the largest id (bigint)")
        values = given.astype(np.int64)
        known = (values >= 0) | np.isin(values, stored)
    else:
        raw = given.astype(np.float64)
        finite = np.isfinite(raw)
        whole = finite & (raw == np.round(raw)) & (np.abs(raw) < 2.0**63)
        known = finite & (raw >= 0)
        known[whole] |= np.isin(raw[whole].astype(np.int64), stored)  # a stored negative id
        if np.any(raw[known] != np.round(raw[known])):
            raise InvalidInputError(f"{name}: vertex property 'vrtxid' holds values that are no ids (not integers)")
        exact = 2 ** (np.finfo(given.dtype).nmant + 1) if given.dtype.kind == "f" else 2**53
        if np.any(np.abs(raw[known]) >= exact):  # from there on, neighbouring integers share one value
            raise InvalidInputError(
                f"{name}: vertex property 'vrtxid' is stored as {given.dtype} and holds ids of {exact} or more, "
                f"which {given.dtype} cannot tell apart from their neighbours",
                hint="write vrtxid as an integer (or float64) property, as tgsis version conflicts --export does",
            )
        values = np.where(known, raw, -1).astype(np.int64)
    ids = np.full(len(given), -1, dtype=np.int64)
    ids[known] = values[known]
    if len(np.unique(ids[known])) != int(known.sum()):
        raise InvalidInputError(
            f"{name}: two vertices of the mesh have the same 'vrtxid'", hint="give each vertex its own id"
        )
    return ids, ~known


def _manual_state(merge: MeshMerge, region: MergeRegion, mesh: MeshState | Mesh, name: str) -> MeshState:
    """The region's rows of a manual mesh, checked: its rows outside the region must be a state's."""
    states = (merge.base, merge.parent, merge.child)
    if isinstance(mesh, MeshState):
        given = mesh
    else:
        given = _state_of_file(merge, mesh, name)
    known_v = np.unique(np.concatenate([s.vertex_ids for s in states]))
    known_c = np.unique(np.concatenate([s.cell_ids for s in states]))
    take_v = np.isin(given.vertex_ids, region.vertex_ids) | ~np.isin(given.vertex_ids, known_v)
    take_c = np.isin(given.cell_ids, region.cell_ids) | ~np.isin(given.cell_ids, known_c)
    # the rest: every row must be one of the three states' (an export of any side, unedited there)
    outside_v = given.vertex_ids[~take_v]
    outside_c = given.cell_ids[~take_c]
    changed_v = np.ones(len(outside_v), dtype=bool)
    changed_c = np.ones(len(outside_c), dtype=bool)
    for state in states:
        same_v, same_c = _rows_equal(given, state, outside_v, outside_c)
        changed_v &= ~same_v
        changed_c &= ~same_c
    if changed_v.any() or changed_c.any():
        from tgsis.merge3 import ids_text

        raise InvalidInputError(
            f"{name}: the manual mesh changes rows outside the region: vertices "
            f"{ids_text(outside_v[changed_v]) or 'none'}, cells {ids_text(outside_c[changed_c]) or 'none'}",
            hint="edit only the region's vertices and cells (its vertex_ids and cell_ids), or solve the other "
            "regions on their own",
        )
    return _rows_state(merge, given, given.vertex_ids[take_v], given.cell_ids[take_c], f"{merge.base.name} manual")


def _rows_equal(
    a: MeshState, b: MeshState, vids: npt.NDArray[np.int64], cids: npt.NDArray[np.int64]
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Per id, whether both states have the row and it is the same (coordinates, values; a rotated cell alike)."""
    same_v, same_c = state_rows_equal(a, b, vids, cids)
    return same_v & np.isin(vids, b.vertex_ids), same_c & np.isin(cids, b.cell_ids)


def _state_of_file(merge: MeshMerge, mesh: Mesh, name: str) -> MeshState:
    """A mesh read from a file as a state of the stored ids (vertex property ``vrtxid``; see docs/merge.md).

    New vertices get ids above every state's; a cell takes the id of the
    child's (else parent's, base's) cell on the same vertices, a new one
    otherwise. Property columns the file lacks (GOCAD files hold no cell
    values) are those of the matched rows (NaN for new rows); columns of the
    file the object does not have are dropped.
    """
    states = (merge.child, merge.parent, merge.base)
    base = merge.base
    if mesh.cell_size != base.cell_size:
        raise InvalidInputError(
            f"{name}: the mesh has cells of {mesh.cell_size} vertices, the object of {base.cell_size}"
        )
    ids, new = _file_ids(mesh, name, np.concatenate([s.vertex_ids for s in states]))
    top_v = max(int(s.vertex_ids.max()) for s in states if s.n_vertices) if any(s.n_vertices for s in states) else -1
    if (~new).any():  # above the ids the file gives too (a whole vrtxid no state has is taken as given)
        top_v = max(top_v, int(ids[~new].max()))
    ids[new] = np.arange(top_v + 1, top_v + 1 + int(new.sum()))
    vertices = np.asarray(mesh.vertices, dtype=np.float64).copy()
    if str(mesh.metadata.get("zpositive", "")).lower() == "depth":
        vertices[:, 2] = -vertices[:, 2]  # the export wrote depths for a Depth object; stored z is elevation
    cells = ids[np.asarray(mesh.cells, dtype=np.int64)]
    # cell ids: the same vertices (any order) as a stored cell
    lookup: dict[tuple[int, ...], int] = {}
    for state in reversed(states):  # the child's win
        for cid, row in zip(state.cell_ids.tolist(), np.sort(state.cells, axis=1).tolist()):
            lookup[tuple(row)] = cid
    top_c = max(int(s.cell_ids.max()) for s in states if s.n_cells) if any(s.n_cells for s in states) else -1
    cell_ids = np.empty(len(cells), dtype=np.int64)
    fresh = top_c + 1
    for i, row in enumerate(np.sort(cells, axis=1).tolist()):
        cid = lookup.get(tuple(row))
        if cid is None:
            cid, fresh = fresh, fresh + 1
        cell_ids[i] = cid
    if len(np.unique(cell_ids)) != len(cell_ids):
        raise InvalidInputError(f"{name}: the mesh has two cells on the same vertices")
    vprops = _columns(mesh.vertex_properties, base.vertex_properties, ids, states, "vertex")
    cprops = _columns(mesh.cell_properties, base.cell_properties, cell_ids, states, "cell")
    return MeshState(base.cell_size, ids, vertices, cell_ids, cells, vprops, cprops, name)


def _columns(
    given: Mapping[str, Any],
    wanted: Mapping[str, npt.NDArray[Any]],
    ids: npt.NDArray[np.int64],
    states: tuple[MeshState, ...],
    what: str,
) -> dict[str, npt.NDArray[Any]]:
    """The object's property columns for these rows: the file's values, else the stored rows' (NaN for new ones)."""
    result: dict[str, npt.NDArray[Any]] = {}
    for column, like in wanted.items():
        if column in given:
            result[column] = np.asarray(given[column]).astype(like.dtype if like.dtype.kind == "f" else np.float64)
            continue
        values = np.full((len(ids), *like.shape[1:]), math.nan)
        filled = np.zeros(len(ids), dtype=bool)
        for state in states:
            table_ids = state.vertex_ids if what == "vertex" else state.cell_ids
            props = state.vertex_properties if what == "vertex" else state.cell_properties
            pos = np.searchsorted(table_ids, ids)
            pos = np.minimum(pos, max(len(table_ids) - 1, 0))
            hit = ~filled & (len(table_ids) > 0) & (table_ids[pos] == ids if len(table_ids) else False)
            values[hit] = np.asarray(props[column])[pos[hit]]
            filled |= hit
        if filled.all() and like.dtype.kind != "f":
            result[column] = values.astype(like.dtype)
        else:
            result[column] = values
    return result


# --------------------------------------------------------------------------- issue39-view: the names of the solutions


@checked
def recorded_solutions(
    conn: Conn, version: str, objectclass: str, objectkey: str, merge: MeshMerge
) -> dict[int, str] | None:
    """The solution recorded for each region of ``merge``, by name, when the stored regions hold for it (read-only).

    What the browser view and the PNG overlay show: ``automatic`` for a region
    that is no conflict, ``unsolved``, ``parent``, ``child``, ``base``,
    ``average`` or ``manual`` for a conflicting one (:func:`region_solutions`
    gives the rows of the last two, not their names).

    Parameters
    ----------
    conn : psycopg.Connection
        In the transaction ``merge`` was read in.
    version, objectclass, objectkey : str
        The conflict (``objectkey`` a feature's geoid).
    merge : MeshMerge

    Returns
    -------
    dict of int to str, or None
        Region index to solution name; ``{}`` when no region is stored for
        the object; None when the stored regions were found on another
        state (other marks, or other regions): their solutions do not hold
        until the conflicts are found again (:func:`find_conflicts`).
    """
    with reraise():
        versionid = version_row(conn, version)[0]
        stored = _stored_regions(conn, versionid, objectclass, objectkey)
        if not stored:
            return {}
        marks = _current_marks(conn, versionid, objectclass, objectkey)
        if marks is None or not _holds(stored, marks, merge):
            return None
    return {r.region: r.solution for r in stored}
