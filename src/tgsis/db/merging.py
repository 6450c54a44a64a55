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

The merges that write — :func:`merge_version` and :func:`refresh_version`,
the public ``tgsis.merge_version`` / ``tgsis.refresh_version`` — merge such
objects by region in one READ COMMITTED transaction: the versions are
locked (``tgsis.lock_for_region_merge``: the rights and locks of the SQL
merge, without its refusal of unsolved conflicts), each unsolved conflict
that is a model-1 mesh is read in that locked transaction and merged; a
merge whose regions all merge by themselves (or have recorded solutions) is
written into the version's working revision by an id-keyed difference
(:func:`tgsis.db._state_write.write_state_difference`) and recorded
``manual``; then the SQL ``tgsis.merge_version`` / ``tgsis.refresh_version``
run in the same transaction and refuse (TG302) what is still unsolved.
"""

from __future__ import annotations

import json
import logging
import os
import re
import shlex
import shutil
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
import psycopg

from tgsis._merge_slices import apply_sliced, fixed_period_refusal, merge_sliced, slice_text
from tgsis._vertex_metadata import CONTROL_NODES, FLAGS, places_of_ids
from tgsis.arguments import checked
from tgsis.db._attribute_edits import AttributeEdits, attribute_edits, write_attribute_edits
from tgsis.db._continuity import check_continuity
from tgsis.db._merge_states import (
    SLICE_KEYS,
    MergeInputs,
    SlicedInputs,
    feature_time_model,
    read_merge_change,
    read_merge_states,
    read_sliced_states,
    version_row,
)
from tgsis.db._settings import read_version_settings, restore_version_settings
from tgsis.db._state_write import write_sliced_difference, write_state_difference
from tgsis.db._static import SIMPLEX
from tgsis.db._transfer import one_snapshot
from tgsis.db.regions import recorded_solutions, region_solutions, sliced_recorded_solutions, sliced_region_solutions
from tgsis.db.versions import show_name
from tgsis.errors import (
    DiscontinuousPeriodsError,
    InvalidInputError,
    InvalidMergeError,
    MissingPrivilegeError,
    NotFoundError,
    UnsolvedConflictsError,
    VersioningError,
    reraise,
)
from tgsis.merge3 import MeshMerge, MeshState, RegionDiscard, Solution, apply_solutions, three_way_merge
from tgsis.mesh import Geotype, Mesh, mesh_class

__all__ = [
    "MergeResult",
    "MergedObject",
    "export_conflict",
    "merge_regions_json",
    "merge_version",
    "object_merge",
    "refresh_version",
]

Conn = psycopg.Connection[Any]
log = logging.getLogger(__name__)


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
        model = feature_time_model(conn, version, feature_id)
        if model in SLICE_KEYS:
            raise InvalidInputError(
                f"feature {feature_id} is of model {model}: it merges slice by slice (per instant, or per geometry "
                f"instant of a topology period), not as one mesh (version {show_name(version)})",
                hint=f"its regions, each with its slice: tgsis.find_conflicts(conn, {version!r}) finds and records "
                f"them (tgsis version conflicts {shlex.quote(version)})",
            )
        states = read_merge_states(conn, version, feature_id).states
    return three_way_merge(states["base"], states["parent"], states["child"])


# --------------------------------------------------------------------------- export of a conflict's three states

#: GOCAD's file of each kind (what ``tgsis export`` writes by default)
_GOCAD = {1: "vs", 2: "pl", 3: "ts", 4: "so"}
_SIDES = ("base", "parent", "child")
_GOCAD_FORMATS = ("tsurf", "pline", "vset", "tsolid")
#: metadata of the stored object that holds vertex indices of its own state: not valid for the other states
#: (atoms travel as the vertex property ``refid``; flags and control nodes are placed in each state by id)
_INDEXED_METADATA = ("gocad_atoms", "gocad_patoms", FLAGS, CONTROL_NODES)


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
    """A state as a tgsis mesh: file vertex i is the i-th stored id ascending (``vrtxid``), cells likewise.

    The vertex flags and control nodes of ``metadata`` are stored by vertex id (``tgsis._vertex_metadata``):
    each state gets those of its own vertices, at their places in it.
    """
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
        metadata=places_of_ids(metadata, vids, name),
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
            stored = conn.execute("SELECT metadata FROM tgsis.geometry WHERE geoid = %s", (feature_id,)).fetchone()
        if mesh is None:
            continue
        by_id = {k: v for k, v in ((stored or [None])[0] or {}).items() if k in (FLAGS, CONTROL_NODES)}
        return mesh.name, {**{k: v for k, v in mesh.metadata.items() if k not in _INDEXED_METADATA}, **by_id}
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
      edits in blue, the child's in orange, conflict regions boxed in red (violet once solved, the solution
      recorded for each named: :func:`tgsis.db.regions.recorded_solutions`), regions that merge by themselves
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
        sliced = feature_time_model(conn, version, feature_id) in SLICE_KEYS
    if sliced:  # models 2 and 3: the files of each slice that has regions
        return _export_sliced(conn, version, feature_id, Path(folder), format, picture, overwrite)
    with reraise(), _snapshot(conn, version):
        merge = object_merge(conn, version, feature_id)
        _, parent, *_ = version_row(conn, version)
        name, metadata = _looks(conn, version, parent, feature_id)
        # the picture names each region's recorded solution (none, or found on another state: unsolved)
        solutions = recorded_solutions(conn, version, "feature", str(feature_id), merge) or {}
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
                    solutions=solutions,
                )
        return _move_into(scratch, target, names, overwrite)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _slice_tag(key: tuple[float, ...]) -> str:
    """A slice in a file name: ``t2.5`` (an instant), ``m1.0_t2.5`` (a geometry instant of a period)."""
    tag = f"m{key[0]!r}_t{key[1]!r}" if len(key) == 2 else f"t{key[0]!r}"
    return re.sub(r"[^A-Za-z0-9.+-]+", "_", tag)


def _export_sliced(
    conn: Conn,
    version: str,
    feature_id: int,
    target: Path,
    format: str | None,
    picture: bool,
    overwrite: bool,
) -> list[Path]:
    """:func:`export_conflict` of a model-2/3 feature: the three states of each slice with regions, named by slice.

    The slices written are those with a conflicting region (all the merged
    slices when none conflicts); the regions file lists each slice's
    regions under its ``times`` (and ``timem``), numbered in the object,
    and says ``merges_by_region`` false with the ``reason`` when no solution
    can merge it (:func:`tgsis._merge_slices.fixed_period_refusal`).
    """
    from tgsis import formats

    with reraise(), _snapshot(conn, version):
        states = read_sliced_states(conn, version, feature_id).states
        merge = merge_sliced(states["base"], states["parent"], states["child"])
        row = conn.execute("SELECT geoname, zpositive FROM tgsis.geometry WHERE geoid = %s", (feature_id,)).fetchone()
        recorded = sliced_recorded_solutions(conn, version, "feature", str(feature_id), merge) or {}
    name = None if row is None or row[0] is None else str(row[0])
    # the z convention stored beside elevation: a Depth object's files hold depths, as every other export gives them
    metadata = {} if row is None or row[1] is None else {"zpositive": str(row[1])}
    ext = (format or "ts").lower().lstrip(".")
    try:
        kind = formats.format_for(f"x.{ext}")
    except Exception as exc:  # FileFormatError: unknown extension
        raise InvalidInputError(f"no file format has the extension {ext!r}", hint="give ts, vtu, vtp or ply") from exc
    if Geotype.SURFACE not in kind.geotypes or kind.writer is None:
        raise InvalidInputError(
            f"{kind.name} files (.{ext}) do not store surfaces (feature {feature_id})", hint="give ts, vtu, vtp or ply"
        )
    conflicting = sorted({r.key for r in merge.conflicts}) or sorted(merge.merges)
    stem = _file_stem(feature_id, name)
    sidecar = kind.name in _GOCAD_FORMATS
    files: list[tuple[tuple[float, ...] | None, str, str]] = []  # (slice, what, file name)
    for chosen in conflicting:
        tag = _slice_tag(chosen)
        for side in _SIDES:
            files.append((chosen, side, f"{stem}_{tag}_{side}.{ext}"))
            if sidecar:
                files.append((chosen, f"{side} cells", f"{stem}_{tag}_{side}_cells.csv"))
        if picture:
            files.append((chosen, "picture", f"{stem}_{tag}_overlay.png"))
    files.append((None, "regions", f"{feature_id}_regions.json"))
    names = [n for _, _, n in files]
    if not overwrite:
        _refuse_existing(target, names)
    target.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=".tgsis-export-", dir=target))
    slices_json = []
    for merged_key in sorted(merge.merges):
        number = {r.region.index: r.index for r in merge.regions if r.key == merged_key}
        regions = merge_regions_json(merge.merges[merged_key])["regions"]
        for r in regions:
            r["index"] = number[r["index"]]
        slices_json.append({**_slice_json(merged_key), "regions": regions})
    try:
        meshes: dict[tuple[tuple[float, ...], str], Mesh] = {}
        for key, what, file in files:
            if key is None:
                # TG308 whatever the solutions: it merges as a whole only, as find_conflicts says
                refusal = fixed_period_refusal(merge)
                document = {
                    "merges_by_region": refusal is None,
                    "merges_by_itself": refusal is None and not merge.conflicts,
                    **({} if refusal is None else {"reason": refusal}),
                    "slices": slices_json,
                }
                (scratch / file).write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
                continue
            mm = merge.merges[key]
            if what in _SIDES:
                mesh = _state_mesh(getattr(mm, what), "trglid", name, metadata)
                meshes[(key, what)] = mesh
                formats.write(
                    mesh, scratch / file, format=kind.name, **({"drop_cell_properties": True} if sidecar else {})
                )
            elif what.endswith(" cells"):
                _write_cells_csv(meshes[(key, what.split()[0])], scratch / file)
            else:
                from tgsis import pictures

                local = {
                    r.region.index: recorded[r.index] for r in merge.regions if r.key == key and r.index in recorded
                }
                pictures.conflict_overlay(
                    mm,
                    meshes[(key, "base")],
                    meshes[(key, "parent")],
                    meshes[(key, "child")],
                    scratch / file,
                    title=f"feature {feature_id}{f' {name}' if name else ''} in {show_name(version)}, "
                    f"{slice_text(merge.base.kind, key)}: base, parent, child",
                    solutions=local,
                )
        return _move_into(scratch, target, names, overwrite)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _slice_json(key: tuple[float, ...]) -> dict[str, float]:
    return {"times": key[1], "timem": key[0]} if len(key) == 2 else {"times": key[0]}


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
        texts = [[repr(v) for v in c.tolist()] for c in columns]  # tolist: Python numbers, whose repr reads back exact
        writer.writerows(zip(*texts, strict=True) if texts else ([] for _ in range(len(mesh.cells))))


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


# --------------------------------------------------------------------------- merges that write: by region


@dataclass(frozen=True)
class MergedObject:
    """One object a merge or refresh merged by region (written into the version, then recorded ``manual``).

    Attributes
    ----------
    objectclass, objectkey : str
        ``feature`` and the feature id as text (as ``tgsis.conflicts`` names it).
    how : {"automatic", "solutions"}
        Every region merged by itself, or some conflicting regions took their recorded solutions.
    regions : int
        Regions either side changed.
    solved : int
        Conflicting regions solved by a recorded solution (0 for ``automatic``).
    rows_written : int
        Rows the merged mesh wrote into the version (the id-keyed difference from its state).
    discards : tuple of RegionDiscard
        What the solutions threw away of one side's edit (empty for ``automatic``).
    """

    objectclass: str
    objectkey: str
    how: Literal["automatic", "solutions"]
    regions: int
    solved: int
    rows_written: int
    discards: tuple[RegionDiscard, ...] = ()


class MergeResult(int):
    """What a merge or refresh wrote, counted per unit, with the objects it merged by region.

    Three named counts, each in one unit:

    - ``rows_by_region``: rows (vertex, cell, property, atom, part and
      geometry rows, as the face ``tgsis.vrtx``, ... shows them) the merges by
      region wrote into the version, on both storages (the sum of the
      objects' ``rows_written``);
    - ``rows_copied``: rows the SQL ``tgsis.merge_version`` (into the parent)
      or ``tgsis.refresh_version`` (into the version) closed, deleted or
      copied in tables stored as rows (every table of row storage; the
      geometry, property, atom and part rows where model 1 is stored in
      chunks);
    - ``chunk_versions_copied``: chunk versions it closed, deleted or copied
      in tables stored in chunks (``tgsis.stored_in_chunks``; 0 on row
      storage): each a block of up to the chunk size of vertex or cell rows,
      written whole (docs/storage.md, "What differs from rows").

    The value as an ``int`` (and ``str``) is the sum of the three, as before
    these counts existed. **Deprecated**: where model 1 is stored in chunks it
    adds rows to chunk versions; read the named counts instead.

    Attributes
    ----------
    objects : tuple of MergedObject
    rows_by_region, rows_copied, chunk_versions_copied : int
    """

    objects: tuple[MergedObject, ...]
    rows_by_region: int
    rows_copied: int
    chunk_versions_copied: int

    def __new__(
        cls, rows_copied: int, objects: tuple[MergedObject, ...] = (), *, chunk_versions_copied: int = 0
    ) -> MergeResult:
        by_region = sum(o.rows_written for o in objects)
        result = super().__new__(cls, by_region + rows_copied + chunk_versions_copied)
        result.objects = objects
        result.rows_by_region = by_region
        result.rows_copied = rows_copied
        result.chunk_versions_copied = chunk_versions_copied
        return result

    def __repr__(self) -> str:
        return (
            f"MergeResult(rows_copied={self.rows_copied}, chunk_versions_copied={self.chunk_versions_copied}, "
            f"rows_by_region={self.rows_by_region}, objects={self.objects!r})"
        )

    def __str__(self) -> str:
        return str(int(self))  # the sum, as before (deprecated: the named counts say the units)


def _sql_merge(conn: Conn, call: str, args: tuple[Any, ...], objects: tuple[MergedObject, ...]) -> MergeResult:
    """Run the SQL merge or refresh (in the caller's transaction) and split what it wrote by unit.

    ``tgsis.copy_object_state`` adds the chunk versions among the rows it
    returns to the transaction's setting ``tgsis.chunk_versions_written``,
    set to 0 here first.
    """
    conn.execute("SELECT set_config('tgsis.chunk_versions_written', '0', true)")
    row = conn.execute(call, args).fetchone()
    assert row is not None
    chunks = conn.execute("SELECT current_setting('tgsis.chunk_versions_written')").fetchone()
    assert chunks is not None
    chunk_versions = int(chunks[0])
    return MergeResult(int(row[0]) - chunk_versions, objects, chunk_versions_copied=chunk_versions)


#: a region solved by one side's (or the base's) rows
_SIDE_SOLUTIONS: dict[str, Literal["parent", "child", "base"]] = {"parent": "parent", "child": "child", "base": "base"}


def _recorded_solutions(conn: Conn, version: str, key: str, merge: MeshMerge) -> dict[int, Solution]:
    """The recorded solutions of the merge's conflicting regions (:func:`tgsis.db.regions.region_solutions`).

    The store hands back those recorded for the object's current marks and
    these very regions; only conflicting regions' solutions are kept.
    """
    if not merge.conflicts:
        return {}
    conflicting = {r.index for r in merge.conflicts}
    solutions: dict[int, Solution] = {}
    for i, s in region_solutions(conn, version, "feature", key, merge).items():
        if int(i) not in conflicting:
            continue
        if isinstance(s, MeshState):
            solutions[int(i)] = s
        else:
            side = _SIDE_SOLUTIONS.get(s)
            if side is not None:
                solutions[int(i)] = side
    return solutions


def _unsolved_reason(merge: MeshMerge, solutions: Mapping[int, Solution]) -> str:
    """Why a merge with conflicting regions is not written: the regions without a solution, with their boxes."""
    unsolved = [r for r in merge.conflicts if r.index not in solutions]
    parts = []
    for r in unsolved[:5]:
        low, high = r.bounds.tolist()
        parts.append(
            f"region {r.index} unsolved (changed on both sides, differently: parent vertices "
            f"{_ids(r.parent_vertex_ids)}, child vertices {_ids(r.child_vertex_ids)}; box "
            f"{_point(low)}-{_point(high)})"
        )
    more = f"; {len(unsolved) - 5} more regions unsolved" if len(unsolved) > 5 else ""
    return "; ".join(parts) + more


def _in_quotes(text: str) -> str:
    """``text`` as it goes between the quotes of an SQL string literal (for a hint a psql user can paste)."""
    return text.replace("'", "''")


def _ids(ids: npt.NDArray[np.int64]) -> str:
    values = ids.tolist()
    return "[" + ", ".join(str(v) for v in values[:8]) + (", ...]" if len(values) > 8 else "]")


def _point(xyz: list[float]) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in xyz) + ")"


def _discard_text(d: RegionDiscard) -> str:
    return (
        f"region {d.region} solved {d.solution} discards the {d.side}'s edit there: {d.vertices} vertices, "
        f"{d.cells} cells, largest displacement {d.max_displacement:.6g}"
    )


def _merge_object(
    conn: Conn, version: str, key: str, reasons: dict[str, str], may_write: list[bool | None]
) -> MergedObject | None:
    """Merge one conflicting feature by region into the version (locked transaction); None with the reason when not."""
    if feature_time_model(conn, version, int(key)) in SLICE_KEYS:  # models 2 and 3: slice by slice
        return _merge_sliced_object(conn, version, key, reasons, may_write)
    try:
        # the change and its one-ring (docs/merge.md): the same regions and merged rows, read by key
        change = read_merge_change(conn, version, int(key))
        inputs = change[0] if change is not None else read_merge_states(conn, version, int(key))
    except (InvalidInputError, VersioningError) as exc:  # not model 1, deleted on one side, attributes on both
        reasons[key] = exc.message
        return None
    states = inputs.states
    merge = three_way_merge(
        states["base"], states["parent"], states["child"], top_ids=change[1] if change is not None else None
    )
    solutions = _recorded_solutions(conn, version, key, merge)
    if change is not None and any(isinstance(s, MeshState) for s in solutions.values()):
        # a recorded mesh (average, manual) may hold the object's other rows, which must equal the merge's: whole
        change = None
        inputs = read_merge_states(conn, version, int(key))
        states = inputs.states
        merge = three_way_merge(states["base"], states["parent"], states["child"])
        solutions = _recorded_solutions(conn, version, key, merge)
    if any(r.index not in solutions for r in merge.conflicts):
        reasons[key] = _unsolved_reason(merge, solutions)
        return None
    try:
        if merge.merged is not None and not solutions:
            resolved = merge.merged
        else:  # a recorded mesh is named as recorded in what it discards: average or manual
            names = recorded_solutions(conn, version, "feature", key, merge) or {}
            resolved = apply_solutions(merge, solutions, names=names)
    except InvalidMergeError as exc:
        reasons[key] = f"invalid merge: {exc.message}"
        return None
    attributes = _attributes_to_bring(conn, inputs, version, key, reasons)
    if attributes is None:
        return None
    for discard in resolved.discards:  # said before it is written
        log.warning("feature %s of version %s: %s", key, show_name(version), _discard_text(discard))
    _require_write(conn, version, key, may_write)
    settings = read_version_settings(conn)
    try:
        with conn.transaction():  # a savepoint: an object whose rows cannot be written leaves nothing behind
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))  # its working revision, this transaction
            written = write_state_difference(
                conn, inputs.feature_class, int(key), states["child"], resolved.state, whole=change is None
            )
            written += write_attribute_edits(conn, int(key), attributes)
            restore_version_settings(conn, settings, local=True)
            conn.execute("SELECT FROM tgsis.resolve_conflict(%s, 'feature', %s, 'manual')", (version, key))
    except InvalidInputError as exc:  # e.g. an integer property without a value for a row to write
        restore_version_settings(conn, settings, local=True)
        reasons[key] = f"its merged rows cannot be written: {exc.message}"
        return None
    how: Literal["automatic", "solutions"] = "solutions" if solutions else "automatic"
    log.info(
        "feature %s of version %s merged by region (%s, %d regions): %d rows written into the version",
        key,
        show_name(version),
        how,
        len(merge.regions),
        written,
    )
    return MergedObject("feature", key, how, len(merge.regions), len(solutions), written, resolved.discards)


def _merge_sliced_object(
    conn: Conn, version: str, key: str, reasons: dict[str, str], may_write: list[bool | None]
) -> MergedObject | None:
    """:func:`_merge_object` for a model-2 or model-3 feature: per instant, or per geometry instant of each period.

    Raises
    ------
    PeriodTopologyError
        Model 3: merged instant by instant, a period's geometry instants would have other topologies (TG308).
    """
    try:
        # the instants (periods) some side touched: the others are alike on all sides and write nothing
        # and of those the change and its one-ring (docs/merge.md): the same regions and merged rows, read by key
        inputs = read_sliced_states(conn, version, int(key), changed_only=True, ring=True)
        states = inputs.states
        merge = merge_sliced(states["base"], states["parent"], states["child"])
    except (InvalidInputError, VersioningError) as exc:  # a removal against a change, topology on both sides, ...
        reasons[key] = exc.message
        return None
    recorded = sliced_region_solutions(conn, version, "feature", key, merge)
    if any(isinstance(v, MeshState) for v in recorded.values()):
        # a recorded mesh (average, manual) may hold the slice's other rows, which must equal the merge's: whole
        inputs = read_sliced_states(conn, version, int(key), changed_only=True)
        states = inputs.states
        merge = merge_sliced(states["base"], states["parent"], states["child"])
        recorded = sliced_region_solutions(conn, version, "feature", key, merge)
    conflicting = {r.index for r in merge.conflicts}
    solutions: dict[int, Solution] = {}
    for i, value in recorded.items():
        if i in conflicting:
            solutions[i] = value if isinstance(value, MeshState) else _SIDE_SOLUTIONS[value]
    unsolved = [r for r in merge.conflicts if r.index not in solutions]
    if unsolved:
        parts = []
        for r in unsolved[:5]:
            low, high = r.region.bounds.tolist()
            parts.append(
                f"region {r.index} at {slice_text(merge.base.kind, r.key)} unsolved (changed on both sides, "
                f"differently: parent vertices {_ids(r.region.parent_vertex_ids)}, child vertices "
                f"{_ids(r.region.child_vertex_ids)}; box {_point(low)}-{_point(high)})"
            )
        more = f"; {len(unsolved) - 5} more regions unsolved" if len(unsolved) > 5 else ""
        reasons[key] = "; ".join(parts) + more
        return None
    try:
        names = sliced_recorded_solutions(conn, version, "feature", key, merge) or {}
        slices, discards = apply_sliced(merge, solutions, names=names)
    except InvalidMergeError as exc:
        reasons[key] = f"invalid merge: {exc.message}"
        return None
    attributes = _attributes_to_bring(conn, inputs, version, key, reasons)
    if attributes is None:
        return None
    for discard in discards:  # said before it is written
        log.warning("feature %s of version %s: %s", key, show_name(version), _discard_text(discard))
    _require_write(conn, version, key, may_write)
    settings = read_version_settings(conn)
    try:
        with conn.transaction():  # a savepoint: an object whose rows cannot be written leaves nothing behind
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
            written = write_sliced_difference(
                conn,
                inputs.feature_class,
                int(key),
                states["child"].slices,
                slices,
                states["child"].instant_rows,
                merge.instant_rows,
            )
            written += write_attribute_edits(conn, int(key), attributes)
            if merge.base.kind == "EVOLVING" and _stored_periods(conn, int(key)) > 1:  # (slices: the touched only)
                check_continuity(conn, int(key), None)
            restore_version_settings(conn, settings, local=True)
            conn.execute("SELECT FROM tgsis.resolve_conflict(%s, 'feature', %s, 'manual')", (version, key))
    except (InvalidInputError, DiscontinuousPeriodsError) as exc:
        restore_version_settings(conn, settings, local=True)
        reasons[key] = f"its merged rows cannot be written: {exc.message}"
        return None
    how: Literal["automatic", "solutions"] = "solutions" if solutions else "automatic"
    log.info(
        "feature %s of version %s merged slice by slice (%s, %d regions): %d rows written into the version",
        key,
        show_name(version),
        how,
        len(merge.regions),
        written,
    )
    return MergedObject("feature", key, how, len(merge.regions), len(solutions), written, discards)


def _stored_periods(conn: Conn, geoid: int) -> int:
    """How many topology periods the session sees the model-3 object have (after the merge's write)."""
    row = conn.execute("SELECT count(*) FROM tgsis.timem WHERE geoid = %s", (geoid,)).fetchone()
    return int(row[0]) if row else 0


def _attributes_to_bring(
    conn: Conn, inputs: MergeInputs | SlicedInputs, version: str, key: str, reasons: dict[str, str]
) -> AttributeEdits | None:
    """The parent's attribute edits the merge brings into the version; None (the reason given) when both sides
    changed one to other values."""
    attributes = attribute_edits(conn, inputs, version, int(key))
    if attributes.both:
        reasons[key] = (
            f"its attributes were changed both in the version and in its parent, to other values "
            f"({', '.join(attributes.both)}): the merge by region merges the mesh only"
        )
        return None
    return attributes


def _require_write(conn: Conn, version: str, key: str, may_write: list[bool | None]) -> None:
    """Refuse a role that may not write in the version: a merge by region writes the merged object there first."""
    if may_write[0] is None:
        may_write[0] = bool(
            conn.execute("SELECT tgsis.has_version_privilege(%s, 'write')", (version,)).fetchone()[0]  # type: ignore[index]
        )
    if not may_write[0]:
        role = conn.execute("SELECT tgsis.calling_role()").fetchone()[0]  # type: ignore[index]
        raise MissingPrivilegeError(
            f"role {role} may not write in version {show_name(version)}: merging feature {key} by region writes the "
            "merged mesh into the version first, then merges it",
            hint=f"the owner or a tgsis_admin can run SELECT tgsis.grant_version('{_in_quotes(version)}', 'write', "
            f"'{_in_quotes(str(role))}'); else tgsis.resolve_conflict solves it as a whole object (parent, child or "
            "manual)",
        )


def _merge_by_region(
    conn: Conn, version: str, action: Literal["merge", "refresh"], remove: bool, reasons: dict[str, str]
) -> tuple[MergedObject, ...]:
    """Lock (``tgsis.lock_for_region_merge``), then merge every unsolved conflicting mesh that merges by region."""
    conn.execute("SELECT set_config('tgsis.region_detection', 'client', true)")  # merged here: SQL need not find them
    conn.execute("SELECT FROM tgsis.lock_for_region_merge(%s, %s, %s)", (version, action, remove))
    unsolved = conn.execute(
        "SELECT objectkey FROM tgsis.find_conflicts(%s) WHERE solution = 'unsolved' AND objectclass = 'feature' "
        "ORDER BY objectkey::bigint",
        (version,),
    ).fetchall()
    may_write: list[bool | None] = [None]
    merged = []
    for (key,) in unsolved:
        done = _merge_object(conn, version, str(key), reasons, may_write)
        if done is not None:
            merged.append(done)
    return tuple(merged)


def _refusal(exc: UnsolvedConflictsError, reasons: Mapping[str, str]) -> UnsolvedConflictsError:
    """The SQL refusal (TG302) with, per feature it names, why it does not merge by region."""
    if not reasons:
        return exc
    why = "; ".join(f"feature {k}: {r}" for k, r in sorted(reasons.items(), key=lambda kv: int(kv[0])))
    return UnsolvedConflictsError(
        f"{exc.message}. Not merged by region (nothing was written): {why}",
        sqlstate=exc.sqlstate,
        detail=exc.detail,
        hint=exc.hint,
    )


@checked
def merge_version(conn: Conn, version: str, *, remove: bool = False) -> MergeResult:
    """Apply ``version``'s changes to its parent in one transaction, merging conflicting meshes by region.

    In one READ COMMITTED transaction: the version and its parent are locked
    (parent first, waiting for their writers and for other merges); every
    unsolved conflict that is a model-1 feature (point set, line set, surface,
    solid) is merged three ways by region (:func:`tgsis.merge3.three_way_merge`,
    docs/merge.md). When all its regions merge by themselves (one side
    changed them, or both made the same change) or the conflicting ones have
    recorded solutions, the merged mesh is written into the version by
    difference and the conflict recorded ``manual``; then the SQL
    ``tgsis.merge_version`` merges the version as before. Anything still
    unsolved refuses the whole merge and nothing is written.

    Parameters
    ----------
    conn : psycopg.Connection
        Idle, or in a READ COMMITTED transaction.
    version : str
        A version other than DEFAULT.
    remove : bool
        Delete the version after the merge (else it goes on from the merged state).

    Returns
    -------
    MergeResult
        What was written, per unit: ``rows_by_region`` (rows the merges by
        region wrote into the version), ``rows_copied`` and
        ``chunk_versions_copied`` (what the merge wrote into the parent, in
        tables stored as rows and in chunks); ``objects``: the objects merged
        by region. Its ``int`` value, the sum of the three, is deprecated.

    Raises
    ------
    UnsolvedConflictsError
        Objects changed on both sides that do not merge by region and have no
        recorded solution; the message says per object why (regions unsolved
        with their ids and box, an invalid merge, a deletion, ...).
    MissingPrivilegeError
        The role may not merge into the parent, or change (with ``remove``:
        delete) the version; a merge by region also needs the right to write
        in the version (the merged mesh is written there first), even with
        ``remove``; or the role may not change or read the class.
    """
    reasons: dict[str, str] = {}
    try:
        with reraise(), conn.transaction():
            objects = _merge_by_region(conn, version, "merge", remove, reasons)
            result = _sql_merge(conn, "SELECT tgsis.merge_version(%s, %s)", (version, remove), objects)
    except UnsolvedConflictsError as exc:
        raise _refusal(exc, reasons) from exc
    return result


@checked
def refresh_version(conn: Conn, version: str) -> MergeResult:
    """Bring the parent's changes since ``version``'s base into it in one transaction, merging meshes by region.

    As :func:`merge_version`: conflicting model-1 meshes whose regions all
    merge by themselves (or have recorded solutions) are merged into the
    version and recorded ``manual`` in the locked transaction, then the SQL
    ``tgsis.refresh_version`` moves the version's base.

    Returns
    -------
    MergeResult
        As :func:`merge_version`'s: ``rows_by_region``, ``rows_copied`` and
        ``chunk_versions_copied`` (what the refresh wrote into the version
        from the parent), ``objects``.

    Raises
    ------
    UnsolvedConflictsError
        Objects changed on both sides that do not merge by region and have
        no recorded solution; the message says per object why.
    MissingPrivilegeError
        The role may not write in the version, or change or read the class.
    """
    reasons: dict[str, str] = {}
    try:
        with reraise(), conn.transaction():
            objects = _merge_by_region(conn, version, "refresh", False, reasons)
            result = _sql_merge(conn, "SELECT tgsis.refresh_version(%s)", (version,), objects)
    except UnsolvedConflictsError as exc:
        raise _refusal(exc, reasons) from exc
    return result
