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
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg

from tgsis.arguments import checked
from tgsis.db._merge_states import read_merge_states, version_row
from tgsis.db._static import SIMPLEX
from tgsis.db._transfer import one_snapshot
from tgsis.db.regions import recorded_solutions
from tgsis.db.versions import show_name
from tgsis.errors import InvalidInputError, NotFoundError, reraise
from tgsis.merge3 import MeshMerge, MeshState, three_way_merge
from tgsis.mesh import Geotype, Mesh, mesh_class

__all__ = ["export_conflict", "merge_regions_json", "object_merge"]

Conn = psycopg.Connection[Any]


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
        states = read_merge_states(conn, version, feature_id).states
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
