"""``tgsis import`` and ``tgsis export``: geometry files in and out."""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import psycopg

from tgsis.cli._arguments import FEATURE_ID, add_command, feature_values
from tgsis.cli._connection import connection
from tgsis.cli._output import out, print_table, render, show_time
from tgsis.cli._progress import busy, progress
from tgsis.cli._render import picture_of, time_unit_suffix
from tgsis.db.features import (
    FeatureClass,
    class_of_feature,
    fetch_feature,
    get_feature_class,
    insert_feature,
)
from tgsis.db.inspect import features_named, lock_feature_name
from tgsis.db.temporal import instants
from tgsis.errors import (
    FileFormatError,
    InvalidGeometryError,
    InvalidInputError,
    PolygonsSplitWarning,
    SkippedObjectWarning,
)
from tgsis.mesh import ORDERS, GeometryCollection, Geotype, Mesh, MeshReport, Surface

# --------------------------------------------------------------------------- features


def _object_label(index: int, mesh: Mesh) -> str:
    """How messages name object ``index`` of a file: its name, else its 1-based position."""
    return f"object {mesh.name!r}" if mesh.name else f"object #{index + 1}"


def _check_flagged(file: str, meshes: Sequence[Mesh], reports: Sequence[MeshReport]) -> None:
    """Refuse the file when any object has flagged defects (``--reject-flagged``)."""
    flagged = [
        f"{_object_label(i, mesh)}: {report.summary()}"
        for i, (mesh, report) in enumerate(zip(meshes, reports))
        if not report.ok
    ]
    if flagged:
        raise InvalidGeometryError(
            f"{file}: refused, nothing imported: " + "; ".join(flagged),
            hint="fix the file, raise --tolerance, or import without --reject-flagged to store it as it is",
        )


def _import_report(mesh: Mesh, tolerance: float) -> MeshReport:
    """:meth:`Mesh.report`, less the duplicates that GOCAD ATOMs make on purpose.

    An ATOM (``metadata["gocad_atoms"]``) is a second vertex at the place of
    another, which is how GOCAD cuts a surface along a line: the two are not a
    defect. Pairs of vertices that repeat the same vertex through ATOMs are
    left out; a vertex that merely happens to lie where another does is still
    flagged.
    """
    report = mesh.report(tolerance)
    pairs = mesh.metadata.get("gocad_atoms")
    if not len(report.duplicate_vertices) or not isinstance(pairs, (list, tuple)):
        return report
    root = np.arange(mesh.n_vertices)
    for pair in pairs:
        if (
            isinstance(pair, (list, tuple))
            and len(pair) == 2
            and all(isinstance(v, int) for v in pair)
            and 0 <= pair[0] < mesh.n_vertices
            and 0 <= pair[1] < mesh.n_vertices
        ):
            root[pair[0]] = pair[1]
    for _ in range(max(1, mesh.n_vertices.bit_length() + 1)):  # follow chains of ATOMs (halving each step)
        root = root[root]
    duplicates = report.duplicate_vertices
    kept = root[duplicates[:, 0]] != root[duplicates[:, 1]]
    return MeshReport(duplicates[kept], report.degenerate_cells)


def _read_for_import(args: argparse.Namespace) -> list[Mesh]:
    """The objects of ``args.file``; objects skipped are one warning line each, or (``--strict``) an error."""
    from tgsis import formats

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SkippedObjectWarning)
        warnings.simplefilter("always", PolygonsSplitWarning)
        meshes = formats.read(args.file, format=args.format)
    for warning in caught:
        if issubclass(warning.category, PolygonsSplitWarning):
            print(f"tgsis: warning: {warning.message}", file=sys.stderr)
        elif not issubclass(warning.category, SkippedObjectWarning):
            warnings.warn_explicit(warning.message, warning.category, warning.filename, warning.lineno)
    skipped = [w.message for w in caught if isinstance(w.message, SkippedObjectWarning)]
    if skipped and args.strict:
        what = "; ".join(
            f"GOCAD {w.object_type} object{f' {w.name!r}' if w.name else ''} at line {w.line}"
            + (f" (its {', '.join(w.skipped)})" if w.skipped else "")
            for w in skipped
        )
        raise FileFormatError(
            f"{args.file}: refused, nothing imported: it holds objects tgsis does not read: {what}",
            hint="import without --strict to store the objects tgsis reads and skip the others",
        )
    for message in skipped:
        print(f"tgsis: warning: {message}", file=sys.stderr)
    empty = [_object_label(i, mesh) for i, mesh in enumerate(meshes) if mesh.n_vertices == 0]
    if empty:
        raise FileFormatError(
            f"{args.file}: refused, nothing imported: {', '.join(empty)} "
            f"{'has' if len(empty) == 1 else 'have'} no vertex",
            hint="an object without vertices would be stored as an empty feature; remove it from the file",
        )
    return meshes


def _features_named(conn: Any, fc: FeatureClass, name: str) -> list[int]:
    """The features of class ``fc`` named ``name`` (as the session's version sees them), after taking the name's lock.

    The lock (a transaction-level advisory lock on class and name) makes two
    imports of one name take turns: the second sees the first's feature once
    it is committed, so that it warns, or replaces it with ``--replace``,
    instead of both adding a feature of that name.
    """
    lock_feature_name(conn, fc, name, "tgsis import")
    return features_named(conn, fc, name)


def _replaced_one(fc: FeatureClass, name: str, same: Sequence[int]) -> int | None:
    """The feature ``--replace`` replaces: the one of that name, none, or an error when there are several."""
    if len(same) > 1:
        raise InvalidInputError(
            f"--replace: class {fc.name} has {len(same)} features named {name!r} "
            f"({', '.join(map(str, same))}): which one to replace is not clear",
            hint=f"tgsis ls --class {fc.name} lists them; import with --name to store it under another name",
        )
    return same[0] if same else None


def _warn_same_name(fc: FeatureClass, name: str, same: Sequence[int]) -> None:
    ids = ", ".join(map(str, same))
    print(
        f"tgsis: warning: class {fc.name} already has a feature named {name!r} ({'id' if len(same) == 1 else 'ids'} "
        f"{ids}): this import adds another one; --replace replaces it",
        file=sys.stderr,
    )


def _report_json(report: MeshReport) -> dict[str, Any]:
    return {
        "duplicate_vertices": len(report.duplicate_vertices),
        "degenerate_cells": len(report.degenerate_cells),
        "summary": report.summary(),
    }


def _import_instant(
    args: argparse.Namespace,
    conn: psycopg.Connection[Any],
    fc: FeatureClass,
    meshes: list[Mesh],
    values: dict[str, Any],
) -> int:
    """``tgsis import FILE --class C --at T [--feature ID]``: a surface of a model-2 class at model time T."""
    from tgsis.db.temporal import add_instant
    from tgsis.temporal import SurfaceSeries

    if fc.time_model != "INSTANTS":
        raise InvalidInputError(
            f"--at and --feature take a class of surfaces at instants (INSTANTS); {fc.name} is {fc.time_model}",
            hint="tgsis interpolate --class CLASS builds evolving surfaces",
        )
    if args.order == "spatial":
        raise InvalidInputError(
            f"--order spatial renumbers static features only (model 1); a surface at an instant of class {fc.name} "
            f"({fc.time_model}) keeps the file's order"
        )
    if args.at is None:
        raise InvalidInputError(
            f"feature class {fc.name} holds surfaces at instants: give --at T, the model time of the file's surface"
        )
    if not math.isfinite(args.at):
        raise InvalidInputError(f"--at must be a finite model time, got {args.at!r}")
    if args.replace:
        raise InvalidInputError(
            "--replace does not go with --at: the instant is new (tgsis import --at T --feature ID adds it)"
        )
    if len(meshes) != 1 or not isinstance(meshes[0], Surface):
        raise InvalidInputError(
            f"{args.file} holds {len(meshes)} object(s) ({', '.join(type(m).__name__ for m in meshes)}): "
            "an instant is one surface",
            hint="write the surface of that instant to a file of its own",
        )
    surface = meshes[0]
    if args.feature is not None:
        if values:
            raise InvalidInputError("--set does not go with --feature: the feature's properties stay")
        if args.alive:
            raise InvalidInputError(
                "--alive does not go with --feature: the feature keeps whether it is alive (set when it was stored)"
            )
        with conn.transaction():
            add_instant(conn, fc, args.feature, args.at, surface, drop_extra_properties=args.drop_extra_properties)
        fid, known = args.feature, [t for t, _ in instants(conn, args.feature)]
    else:
        name = args.name or surface.name or Path(args.file).stem
        # not alive unless --alive, as SurfaceSeries from Python: a surface known at T is not claimed after T
        series = SurfaceSeries([args.at], [surface], alive=args.alive, name=name)
        with conn.transaction():
            fid = insert_feature(conn, fc, series, values, name=name, drop_extra_properties=args.drop_extra_properties)
        known = [args.at]
    return render(args, ImportedInstant(args.file, fc, fid, args.at, known, surface), instant_text, instant_json)


@dataclass(frozen=True)
class ImportedInstant:
    """A surface stored as feature ``id``'s instant ``at``; ``instants``: the feature's instants now."""

    file: str
    fc: FeatureClass
    id: int
    at: float
    instants: list[float]
    surface: Surface


def instant_text(args: argparse.Namespace, result: ImportedInstant) -> None:
    fc, surface = result.fc, result.surface
    out(
        f"stored feature {result.id} ({fc.name}) at t = {show_time(result.at)}{time_unit_suffix(fc)}: "
        f"{surface.n_vertices} vertices, {surface.n_cells} triangles; "
        f"its instants: {', '.join(show_time(t) for t in result.instants)}"
    )


def instant_json(result: ImportedInstant) -> dict[str, Any]:
    return {
        "file": result.file,
        "class": result.fc.name,
        "id": result.id,
        "at": result.at,
        "instants": result.instants,
        "vertices": result.surface.n_vertices,
        "cells": result.surface.n_cells,
    }


@dataclass(frozen=True)
class ImportedCollection:
    """A file stored as one feature ``id`` (a geometry collection of its objects); ``replaced``: the feature it
    replaced (``--replace``); ``same_name``: features of that name it did not replace."""

    file: str
    feature_class: str
    id: int
    collection: GeometryCollection
    replaced: int | None
    same_name: list[int]
    members: list[Mesh]
    reports: list[MeshReport]


def _members_json(result: ImportedCollection) -> list[dict[str, Any]]:
    return [
        {
            "index": i,
            "name": mesh.name,
            "geotype": mesh.geotype.value,
            "vertices": mesh.n_vertices,
            "cells": mesh.n_cells,
            "cell_name": type(mesh).cell_name,
            "defects": _report_json(report),
        }
        for i, (mesh, report) in enumerate(zip(result.members, result.reports))
    ]


def collection_text(args: argparse.Namespace, result: ImportedCollection) -> None:
    collection, old = result.collection, result.replaced
    print_table(
        args,
        IMPORT_HEADER,
        [
            (
                result.id,
                collection.name,
                collection.geotype.value,
                collection.n_vertices,
                collection.n_cells,
                old if old is not None else "",
                f"{len(collection)} members",
            )
        ],
    )
    for m in _members_json(result):  # under the collection's line, one per member
        out(
            f"\tmember {m['index']}\t{m['name'] or ''}\t{m['geotype']}\t{m['vertices']}\t{m['cells']}\t"
            f"\t{m['defects']['summary']}"
        )


def collection_json(result: ImportedCollection) -> dict[str, Any]:
    collection = result.collection
    return {
        "file": result.file,
        "class": result.feature_class,
        "features": [
            {
                "id": result.id,
                "name": collection.name,
                "geotype": collection.geotype.value,
                "vertices": collection.n_vertices,
                "cells": collection.n_cells,
                "replaced": result.replaced,
                "same_name": result.same_name,
                "members": _members_json(result),
            }
        ],
    }


@dataclass(frozen=True)
class ImportedObject:
    """An object of a file stored as feature ``id``, or over feature ``replaced`` (``--replace``); ``same_name``:
    features of that name it did not replace."""

    id: int
    name: str
    mesh: Mesh
    report: MeshReport
    replaced: int | None
    same_name: list[int]


@dataclass(frozen=True)
class ImportedObjects:
    """The objects of a file, each stored as a feature of ``feature_class``."""

    file: str
    feature_class: str
    features: list[ImportedObject]


def objects_text(args: argparse.Namespace, result: ImportedObjects) -> None:
    print_table(
        args,
        IMPORT_HEADER,
        [
            (
                f.id,
                f.name,
                f.mesh.geotype.value,
                f.mesh.n_vertices,
                f.mesh.n_cells,
                f.replaced if f.replaced is not None else "",
                f.report.summary(),
            )
            for f in result.features
        ],
    )


def objects_json(result: ImportedObjects) -> dict[str, Any]:
    return {
        "file": result.file,
        "class": result.feature_class,
        "features": [
            {
                "id": f.id,
                "name": f.name,
                "geotype": f.mesh.geotype.value,
                "vertices": f.mesh.n_vertices,
                "cells": f.mesh.n_cells,
                "cell_name": type(f.mesh).cell_name,
                "defects": _report_json(f.report),
                "replaced": f.replaced,
                "same_name": f.same_name,
            }
            for f in result.features
        ],
    }


IMPORT_HEADER = ("id", "name", "geotype", "vertices", "cells", "replaced", "defects")


def cmd_import(args: argparse.Namespace) -> int:
    from tgsis.db.checkin import save_feature
    from tgsis.db.features import delete_feature

    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise InvalidInputError(f"--tolerance must be a finite number >= 0, got {args.tolerance}")
    meshes = _read_for_import(args)
    reports = [_import_report(mesh, args.tolerance) for mesh in meshes]
    if args.reject_flagged:
        _check_flagged(args.file, meshes, reports)
    values = feature_values(args.set)
    stem = Path(args.file).stem
    with connection(args) as conn:
        fc = get_feature_class(conn, args.feature_class)
        if args.at is not None or args.feature is not None or fc.time_model == "INSTANTS":
            return _import_instant(args, conn, fc, meshes, values)
        if args.alive:
            raise InvalidInputError("--alive goes with --at T: a static feature exists at every time")
        if fc.geotype is Geotype.GEOMETRYCOLLECTION:  # the whole file is one feature
            collection = GeometryCollection(meshes, name=args.name or stem)
            with conn.transaction():
                same = _features_named(conn, fc, collection.name or "")
                old = _replaced_one(fc, collection.name or "", same) if args.replace else None
                with busy(f"uploading {collection.n_vertices} vertices"):
                    if old is not None:
                        delete_feature(conn, fc, old)
                    fid = insert_feature(
                        conn,
                        fc,
                        collection,
                        values,
                        drop_extra_properties=args.drop_extra_properties,
                        order=args.order,
                    )
            if same and not args.replace:
                _warn_same_name(fc, collection.name or "", same)
            result = ImportedCollection(
                args.file, fc.name, fid, collection, old, [] if args.replace else same, list(meshes), list(reports)
            )
            return render(args, result, collection_text, collection_json)
        if args.replace and args.order == "spatial":
            raise InvalidInputError(
                "--order spatial does not go with --replace: a replaced feature is written by difference and keeps "
                "the ids of the vertices it still has, so it cannot be renumbered (delete it and import the file)"
            )
        if args.name and len(meshes) > 1:
            raise InvalidInputError(
                f"{args.file} holds {len(meshes)} objects: --name names only one",
                hint="import into a GEOMETRYCOLLECTION class to store them as one feature",
            )
        names = [args.name or mesh.name or stem for mesh in meshes]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice and args.replace:
            raise InvalidInputError(
                f"--replace: {args.file} holds several objects named {twice[0]!r}, so which one "
                "replaces the stored feature is not clear",
                hint="import without --replace",
            )
        ids: list[int] = []
        replaced: list[int | None] = []
        warned: list[tuple[str, list[int]]] = []
        with conn.transaction(), progress("uploading objects", len(meshes), "object") as moved:
            for i, (mesh, name) in enumerate(zip(meshes, names)):  # all objects of the file, or none
                same = _features_named(conn, fc, name)
                old = _replaced_one(fc, name, same) if args.replace else None
                if old is not None:
                    save_feature(
                        conn, fc, old, mesh, values or None, name=name, drop_extra_properties=args.drop_extra_properties
                    )
                    ids.append(old)
                else:
                    ids.append(
                        insert_feature(
                            conn,
                            fc,
                            mesh,
                            values,
                            name=name,
                            drop_extra_properties=args.drop_extra_properties,
                            order=args.order,
                        )
                    )
                    if same:
                        warned.append((name, same))
                replaced.append(old)
                moved(i + 1, len(meshes))
    for name, same in warned:
        _warn_same_name(fc, name, same)
    features = [
        ImportedObject(fid, name, mesh, report, old, next((same for n, same in warned if n == name), []))
        for fid, name, mesh, report, old in zip(ids, names, meshes, reports, replaced)
    ]
    return render(args, ImportedObjects(args.file, fc.name, features), objects_text, objects_json)


def cmd_export(args: argparse.Namespace) -> int:
    from tgsis import formats

    with connection(args) as conn:
        fc = get_feature_class(conn, args.feature_class) if args.feature_class else class_of_feature(conn, args.id)
        with busy(f"downloading feature {args.id}"):
            feature = fetch_feature(conn, fc, args.id)
        assert feature.mesh is not None
        if args.png and not isinstance(feature.mesh, Surface):  # refused before any file is written
            raise InvalidInputError(f"feature {args.id} is no surface: --png draws surfaces")
        with busy(f"writing {args.file}"):
            formats.write(feature.mesh, args.file, format=args.format)
        members = f" in {len(feature.mesh)} members" if isinstance(feature.mesh, GeometryCollection) else ""
        out(f"wrote feature {feature.id} ({fc.name}, {feature.mesh.n_vertices} vertices{members}) to {args.file}")
        if args.png:
            picture_of(
                conn, [args.id], None, args.png, title=f"feature {args.id} ({fc.name}) {feature.mesh.name or ''}"
            )
    return 0


def add_import_parser(commands: Any) -> None:
    """``tgsis import``."""
    imp = add_command(
        commands,
        "import",
        "store the objects of a geometry file as features of a class (as one feature in a GEOMETRYCOLLECTION class)",
        [
            "tgsis import Garlock.ts --class faults --set release=6.1 --drop-extra-properties",
            "tgsis import Garlock.ts --class faults --replace   # a new version of the same fault",
            "tgsis import model.vtu --class models --json",
            "tgsis import top_2024.ts --class horizons --at 2024 --feature 7   # a model-2 instant",
        ],
        cmd_import,
        tabular=True,
    )
    imp.add_argument(
        "file", help="the geometry file (.ts, .pl, .vs, .so, .lso, .gp, .ml, .vtu, .obj, .ply, .off, .stl)"
    )
    imp.add_argument("--class", dest="feature_class", required=True, help="the feature class to store them in")
    imp.add_argument(
        "--name",
        help="feature name (default: the name in the file, else the file name; "
        "for a GEOMETRYCOLLECTION class the file name)",
    )
    imp.add_argument("--format", help="file format (default: from the extension)")
    imp.add_argument("--set", action="append", metavar="NAME=VALUE", help="a feature property value (repeatable)")
    imp.add_argument(
        "--drop-extra-properties",
        action="store_true",
        help="ignore properties of the file that the class does not store",
    )
    imp.add_argument(
        "--replace",
        action="store_true",
        help="replace the feature of the same name in the class (written by difference, keeping its "
        "id; in a version, a change of that version) instead of adding a second one",
    )
    imp.add_argument(
        "--reject-flagged",
        action="store_true",
        help="refuse the whole file if any object has duplicate vertices (other than GOCAD ATOMs) or degenerate cells",
    )
    imp.add_argument(
        "--strict",
        action="store_true",
        help="refuse the whole file if it holds objects tgsis cannot read (a GOCAD SGrid beside "
        "surfaces), instead of skipping them with a warning",
    )
    imp.add_argument(
        "--tolerance",
        type=float,
        default=0.0,
        metavar="T",
        help="cells of length/area/volume at most T count as degenerate (default 0: exactly zero)",
    )
    imp.add_argument(
        "--at",
        type=float,
        metavar="T",
        help="a class of surfaces at instants (INSTANTS): the surface is the shape at model time T, of a "
        "new feature (known from T on) or, with --feature, of an existing one",
    )
    imp.add_argument(
        "--feature",
        type=FEATURE_ID,
        metavar="ID",
        help="with --at: add the instant T to this feature instead of storing a new one",
    )
    imp.add_argument(
        "--alive",
        action="store_true",
        help="with --at, for a new feature: it still exists after its last instant (keeps its last shape; "
        "default: it exists only from its first to its last instant, as from Python)",
    )
    imp.add_argument(
        "--order",
        choices=ORDERS,
        default="file",
        help="the order of the stored vertex and cell ids: the file's (default), or spatial (vertices along a "
        "Morton curve, cells by part and smallest corner; recorded as vertex_order in the geometry's metadata, "
        "and an export gives that order back); static classes only",
    )


def add_export_parser(commands: Any) -> None:
    """``tgsis export``."""
    exp = add_command(
        commands,
        "export",
        "write a feature to a geometry file",
        ["tgsis export 3 garlock.ts", "tgsis export 3 garlock.vtu --png garlock.png"],
        cmd_export,
    )
    exp.add_argument("id", type=FEATURE_ID, help="the feature's id (tgsis ls lists them)")
    exp.add_argument("file", help="the file to write; its extension gives the format")
    exp.add_argument("--class", dest="feature_class", help="its feature class (default: looked up)")
    exp.add_argument("--format", help="file format (default: from the extension)")
    exp.add_argument("--png", metavar="PNG", help="also draw the feature (a surface) to this PNG file")
