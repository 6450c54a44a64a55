"""The ``tgsis`` command line (see docs/cli.md).

Every command that needs a database takes ``--dsn``; without it the database
comes from ``$TGSIS_DSN``, libpq's ``PG*`` variables, or the local server that
tgsis starts for the command and stops afterwards (``tgsis local start`` keeps
one running).
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import logging
import math
import os
import signal
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import psycopg

from psycopg import sql as psycopg_sql

import tgsis
from tgsis.db.connect import connect, release_local_server, resolve_target
from tgsis.db.install import install, installed_version, uninstall
from tgsis.db.local import LocalServer, find_binaries
from tgsis import clistate
from tgsis.db import versions as V
from tgsis.db.features import (
    FeatureClass,
    Property,
    class_of_feature,
    create_feature_class,
    drop_feature_class,
    fetch_feature,
    get_feature_class,
    insert_feature,
    list_feature_classes,
)
from tgsis.db.temporal import export_series, get_at, instants, lifespan
from tgsis.errors import (Error, FileFormatError, InvalidGeometryError, InvalidInputError, NotFoundError,
                          NotVersionedError, SkippedObjectWarning)
from tgsis.mesh import GeometryCollection, Geotype, Mesh, MeshReport, Surface
from tgsis.temporal import even_times

__all__ = ["main", "build_parser"]

Handler = Callable[[argparse.Namespace], int]


def _out(text: str) -> None:
    print(text, flush=True)


def _integer(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: an integer from ``low`` to ``high`` (the range of its SQL column), else a usage error."""
    def integer(text: str) -> int:
        value = int(text)  # ValueError: argparse says "invalid integer value"
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{value} is out of range: from {low} to {high}")
        return value
    return integer


_ID = _integer(-(2**63), 2**63 - 1)     # feature ids (bigint)
_INT4 = _integer(-(2**31), 2**31 - 1)   # SRS ids, orders (integer)


# --------------------------------------------------------------------------- db


def cmd_db_install(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        result = install(conn, method=args.method)
    if result.action == "unchanged":
        _out(f"tgsis {result.version} is already installed ({result.method}): nothing to do")
    elif result.action == "upgraded":
        _out(f"upgraded tgsis {result.previous_version} -> {result.version} ({result.method})")
    else:
        _out(f"installed tgsis {result.version} ({result.method})")
    return 0


def cmd_db_uninstall(args: argparse.Namespace) -> int:
    if not args.yes:
        raise Error("uninstall removes every tgsis object and its data from the database",
                    hint="repeat with --yes to do it")
    with connect(args.dsn) as conn:
        removed = uninstall(conn, cascade=args.cascade)
    _out(f"removed tgsis {removed.version} ({removed.method})" if removed else "tgsis was not installed")
    return 0


def cmd_db_status(args: argparse.Namespace) -> int:
    target = resolve_target(args.dsn)
    with connect(args.dsn) as conn:
        current = installed_version(conn)
        server = conn.execute("SELECT version()").fetchone()
        db = conn.info.dbname
    _out(f"database: {db} (from {target.source})")
    _out(f"server:   {server[0] if server else '?'}")
    _out(f"tgsis:    {f'{current.version} ({current.method})' if current else 'not installed'}")
    _out(f"client:   {tgsis.__version__}")
    return 0


# --------------------------------------------------------------------------- working version


def _target_key(args: argparse.Namespace) -> str:
    target = resolve_target(args.dsn)
    return target.dsn if target.dsn is not None else "local"


def _chosen_version(args: argparse.Namespace) -> str | None:
    """--in, else $TGSIS_VERSION, else what `tgsis version goto` remembered for this database."""
    return args.in_version or os.environ.get("TGSIS_VERSION") or clistate.remembered_version(_target_key(args))


def _split_version(text: str) -> tuple[str, int | None]:
    """``VERSION`` or ``VERSION@REVISION``."""
    name, sep, revision = text.partition("@")
    if not sep:
        return name, None
    if not (revision.isascii() and revision.isdigit()):  # '²' is a digit to str.isdigit, not to int()
        raise InvalidInputError(f"{text!r} is not VERSION or VERSION@REVISION")
    if int(revision) > 2**31 - 1:
        raise InvalidInputError(f"revision {revision} of {text!r} is out of range: revisions go up to {2**31 - 1}")
    return name, int(revision)


@contextlib.contextmanager
def _connect(args: argparse.Namespace) -> Iterator[psycopg.Connection[Any]]:
    """A connection working in the chosen version, or looking at VERSION@REVISION (DEFAULT when none is chosen)."""
    with connect(args.dsn) as conn:
        chosen = _chosen_version(args)
        if chosen is not None:
            name, revision = _split_version(chosen)
            if revision is None:
                V.goto_version(conn, name)
            else:
                V.goto_revision(conn, name, revision)
        yield conn


# --------------------------------------------------------------------------- local


def _local_server() -> LocalServer:
    return LocalServer.persistent(find_binaries())


def cmd_local_start(args: argparse.Namespace) -> int:
    server = _local_server()
    started = server.start_explicitly()
    server.ensure_database("tgsis")
    with connect(server.dsn("tgsis")) as conn:
        install(conn)
    _out(("started" if started else "already running:") + f" {server.binaries.describe()} in {server.root}")
    _out(server.dsn("tgsis"))
    return 0


def cmd_local_stop(args: argparse.Namespace) -> int:
    server = _local_server()
    stopped = server.stop_explicitly(force=args.force)
    _out(f"stopped the server in {server.root}" if stopped else f"no server was running in {server.root}")
    return 0


def cmd_local_status(args: argparse.Namespace) -> int:
    server = _local_server()
    running = server.is_running()
    _out(f"cluster:  {server.root}")
    _out(f"binaries: {server.binaries.describe()}")
    if running:
        _out(f"status:   running (pid {server.pid()}, started {server.started_by() or 'outside tgsis'})")
        _out(f"dsn:      {server.dsn('tgsis')}")
    else:
        _out("status:   " + ("stopped" if server.is_initialized() else "not created yet"))
    return 0 if running else 3


def cmd_local_dsn(args: argparse.Namespace) -> int:
    server = _local_server()
    _out(server.dsn("tgsis"))
    if not server.is_running():
        print("note: the server is not running; `tgsis local start` starts it", file=sys.stderr)
    return 0


# --------------------------------------------------------------------------- feature classes


def _pairs(items: Sequence[str] | None, what: str) -> list[tuple[str, str]]:
    pairs = []
    for item in items or []:
        name, sep, value = item.partition(":")
        if not sep or not name or not value:
            raise InvalidInputError(f"{what} {item!r} must be NAME:TYPE, e.g. porosity:float8")
        pairs.append((name, value))
    return pairs


def _cell_properties(items: Sequence[str] | None) -> list[Property]:
    """``--property NAME:TYPE[:SIZE][:VERTEX|CELL]`` items: a vector of SIZE components, an alignment of its own."""
    result = []
    for item in items or []:
        name, _, rest = item.partition(":")
        words = rest.split(":") if rest else []
        if not name or not words or not words[0] or len(words) > 3:
            raise InvalidInputError(f"--property {item!r} must be NAME:TYPE[:SIZE][:VERTEX|CELL], e.g. porosity:float8, "
                                    "slip:float8:3 or facies:int:CELL")
        size, alignment = 1, None
        for word in words[1:]:
            if word.upper() in ("VERTEX", "CELL") and alignment is None:
                alignment = word.upper()
            elif word.isdigit() and size == 1:
                size = int(word)
            else:
                raise InvalidInputError(f"--property {item!r}: {word!r} is neither a number of components nor "
                                        "VERTEX or CELL", hint="e.g. --property slip:float8:3:CELL")
        result.append(Property(name, words[0], size, alignment))  # type: ignore[arg-type]
    return result


def cmd_class_create(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        fc = create_feature_class(
            conn, args.name, args.geotype, feature_properties=_pairs(args.feature_property, "--feature-property"),
            cell_properties=_cell_properties(args.property), alignment=args.alignment.upper(), srs=args.srs,
            schema=args.schema, description=args.description, time_model=args.time_model, time_unit=args.time_unit,
            instant_properties=_pairs(args.instant_property, "--instant-property"))
    pros = f", {fc.protable}" if fc.protable else ""
    other = f", {fc.otherprotable}" if fc.otherprotable else ""
    _out(f"created feature class {fc.name} ({fc.geotype.value}{_time_label(fc)}) in schema {fc.schema}: "
         f"tables {fc.featuretable}, {fc.cellprotable}{other}{pros}, view {fc.viewname}")
    return 0


def _unit(fc: FeatureClass) -> str:
    """`` Ma``: the class's unit of model time for messages (empty when it records none)."""
    return f" {fc.time_unit}" if fc.time_unit else ""


def _time_label(fc: FeatureClass) -> str:
    """``, EVOLVING in Ma``-like suffix naming the time model of a temporal class ('' for static ones)."""
    if fc.time_model == "STATIC":
        return ""
    return f", {fc.time_model}" + (f" in{_unit(fc)}" if fc.time_unit else "")


def cmd_class_list(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        classes = list_feature_classes(conn)
    for fc in classes:
        fprops = ", ".join(f"{p.name} {p.type}" for p in fc.feature_properties) or "-"
        cprops = ", ".join(f"{p.name} {p.type}{f'[{p.size}]' if p.size > 1 else ''}"
                           f"{f' ({p.alignment.lower()})' if p.alignment else ''}" for p in fc.cell_properties) or "-"
        iprops = ", ".join(f"{p.name} {p.type}" for p in fc.instant_properties) or "-"
        temporal = f"\ttime: {_time_label(fc)[2:]}\tper instant: {iprops}" if fc.time_model != "STATIC" else ""
        _out(f"{fc.name}\t{fc.geotype.value}\tsrs {fc.srs}\t{fc.schema}\tfeature: {fprops}\t"
             f"{fc.alignment.lower()}: {cprops}{temporal}")
    if not classes:
        print("no feature classes", file=sys.stderr)
    return 0


def cmd_class_drop(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        deleted = drop_feature_class(conn, args.name, force=args.force)
    _out(f"dropped feature class {args.name}" + (f" and its {deleted} feature(s)" if deleted else ""))
    return 0


# --------------------------------------------------------------------------- features


def _feature_values(items: Sequence[str] | None) -> dict[str, str]:
    values = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InvalidInputError(f"--set {item!r} must be NAME=VALUE")
        values[name] = value
    return values


def _object_label(index: int, mesh: Mesh) -> str:
    """How messages name object ``index`` of a file: its name, else its 1-based position."""
    return f"object {mesh.name!r}" if mesh.name else f"object #{index + 1}"


def _check_flagged(file: str, meshes: Sequence[Mesh], reports: Sequence[MeshReport]) -> None:
    """Refuse the file when any object has flagged defects (``--reject-flagged``)."""
    flagged = [f"{_object_label(i, mesh)}: {report.summary()}"
               for i, (mesh, report) in enumerate(zip(meshes, reports)) if not report.ok]
    if flagged:
        raise InvalidGeometryError(f"{file}: refused, nothing imported: " + "; ".join(flagged),
                                   hint="fix the file, raise --tolerance, or import without --reject-flagged "
                                        "to store it as it is")


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
        if (isinstance(pair, (list, tuple)) and len(pair) == 2 and all(isinstance(v, int) for v in pair)
                and 0 <= pair[0] < mesh.n_vertices and 0 <= pair[1] < mesh.n_vertices):
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
        meshes = formats.read(args.file, format=args.format)
    for warning in caught:
        if not issubclass(warning.category, SkippedObjectWarning):
            warnings.warn_explicit(warning.message, warning.category, warning.filename, warning.lineno)
    skipped = [w.message for w in caught if isinstance(w.message, SkippedObjectWarning)]
    if skipped and args.strict:
        what = "; ".join(f"GOCAD {w.object_type} object{f' {w.name!r}' if w.name else ''} at line {w.line}"
                         for w in skipped)
        raise FileFormatError(f"{args.file}: refused, nothing imported: it holds objects tgsis does not read: {what}",
                              hint="import without --strict to store the objects tgsis reads and skip the others")
    for message in skipped:
        print(f"tgsis: warning: {message}", file=sys.stderr)
    empty = [_object_label(i, mesh) for i, mesh in enumerate(meshes) if mesh.n_vertices == 0]
    if empty:
        raise FileFormatError(f"{args.file}: refused, nothing imported: {', '.join(empty)} "
                              f"{'has' if len(empty) == 1 else 'have'} no vertex",
                              hint="an object without vertices would be stored as an empty feature; "
                                   "remove it from the file")
    return meshes


def cmd_import(args: argparse.Namespace) -> int:
    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise InvalidInputError(f"--tolerance must be a finite number >= 0, got {args.tolerance}")
    meshes = _read_for_import(args)
    reports = [_import_report(mesh, args.tolerance) for mesh in meshes]
    if args.reject_flagged:
        _check_flagged(args.file, meshes, reports)
    values = _feature_values(args.set)
    stem = Path(args.file).stem
    with _connect(args) as conn:
        fc = get_feature_class(conn, args.feature_class)
        if fc.geotype is Geotype.GEOMETRYCOLLECTION:  # the whole file is one feature
            collection = GeometryCollection(meshes, name=args.name or stem)
            fid = insert_feature(conn, fc, collection, values, drop_extra_properties=args.drop_extra_properties)
            _out(f"{fid}\t{collection.name}\t{collection.geotype.value}\t{len(collection)} members\t"
                 f"{collection.n_vertices} vertices\t{collection.n_cells} cells")
            for i, (mesh, report) in enumerate(zip(meshes, reports)):
                _out(f"\tmember {i}\t{mesh.name or ''}\t{mesh.n_vertices} vertices\t"
                     f"{mesh.n_cells} {type(mesh).cell_name}s\t{report.summary()}")
            return 0
        if args.name and len(meshes) > 1:
            raise InvalidInputError(f"{args.file} holds {len(meshes)} objects: --name names only one",
                                    hint="import into a GEOMETRYCOLLECTION class to store them as one feature")
        with conn.transaction():  # all objects of the file, or none
            ids = [insert_feature(conn, fc, mesh, values, name=args.name or mesh.name or stem,
                                  drop_extra_properties=args.drop_extra_properties) for mesh in meshes]
    for fid, mesh, report in zip(ids, meshes, reports):
        _out(f"{fid}\t{args.name or mesh.name or stem}\t{mesh.n_vertices} vertices\t"
             f"{mesh.n_cells} {type(mesh).cell_name}s\t{report.summary()}")
    return 0


def _picture_of(conn: Any, ids: Sequence[int], t: float | None, path: str, title: str) -> None:
    """A PNG of features (at t, or static) in one scene; the first coloured by how far it moved since its start."""
    from tgsis import pictures

    shapes = [get_at(conn, fid, t) if t is not None else fetch_feature(conn, class_of_feature(conn, fid), fid).mesh
              for fid in ids]
    others = [fid for fid, mesh in zip(ids, shapes) if mesh is not None and not isinstance(mesh, Surface)]
    if others:
        raise InvalidInputError(f"feature {others[0]} is no surface: --png draws surfaces")
    meshes = [mesh for mesh in shapes if isinstance(mesh, Surface)]
    if not meshes:
        raise NotFoundError("none of the features exists then: nothing to draw")
    colour: list[Any] = [None] * len(meshes)
    span = lifespan(conn, ids[0]) if t is not None else None
    first = shapes[0]
    if span is not None and t is not None and isinstance(first, Surface):
        # coloured by displacement only within the first topology period: later ones have other vertices
        changes = [s for s, starts in instants(conn, ids[0]) if starts and span[0] < s <= t]
        start = get_at(conn, ids[0], span[0])
        if not changes and start is not None and start.vertices.shape == first.vertices.shape:
            colour[0] = pictures.displacement(first, start)
    pictures.scene(meshes, path, title=title, colour=colour, colour_label=f"moved since t = {span[0]!r} (m)"
                   if span is not None else "")
    _out(f"drew {len(meshes)} surface(s) to {path}")


def cmd_export(args: argparse.Namespace) -> int:
    from tgsis import formats

    with _connect(args) as conn:
        fc = get_feature_class(conn, args.feature_class) if args.feature_class else class_of_feature(conn, args.id)
        feature = fetch_feature(conn, fc, args.id)
        assert feature.mesh is not None
        if args.png and not isinstance(feature.mesh, Surface):     # refused before any file is written
            raise InvalidInputError(f"feature {args.id} is no surface: --png draws surfaces")
        formats.write(feature.mesh, args.file, format=args.format)
        members = f" in {len(feature.mesh)} members" if isinstance(feature.mesh, GeometryCollection) else ""
        _out(f"wrote feature {feature.id} ({fc.name}, {feature.mesh.n_vertices} vertices{members}) to {args.file}")
        if args.png:
            _picture_of(conn, [args.id], None, args.png, title=f"feature {args.id} ({fc.name}) {feature.mesh.name or ''}")
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    from tgsis.db.versions import diff_versions, list_versions, working_version

    with _connect(args) as conn:
        fc = class_of_feature(conn, args.id)
        row = conn.execute(
            "SELECT geoname, geotype, nvrtx, ncell, cardinality(geoids), timemodel, alive, "
            "cube_ll_coord(bbox, 1), cube_ur_coord(bbox, 1), cube_ll_coord(bbox, 2), cube_ur_coord(bbox, 2), "
            "cube_ll_coord(bbox, 3), cube_ur_coord(bbox, 3) FROM tgsis.geometry WHERE geoid = %s", (args.id,)).fetchone()
        assert row is not None
        feature = fetch_feature(conn, fc, args.id) if fc.time_model == "STATIC" else None
        values = conn.execute(psycopg_sql.SQL("SELECT * FROM {}.{} WHERE _geoid = %s").format(
            psycopg_sql.Identifier(fc.schema), psycopg_sql.Identifier(fc.featuretable)), (args.id,))
        names = [d.name for d in values.description or []]
        properties = {n: v for n, v in zip(names, values.fetchone() or ()) if not n.startswith("_")}
        span = lifespan(conn, args.id)
        steps = instants(conn, args.id) if span is not None else []
        here = working_version(conn)
        versioned = conn.execute("SELECT EXISTS (SELECT FROM tgsis.versioned_tables WHERE objectclass = 'feature')"
                                 ).fetchone() == (True,)
        differs = []
        if versioned:
            for version in list_versions(conn):
                if version.name != here:
                    changed = [d for d in diff_versions(conn, here, version.name)
                               if d.objectclass == "feature" and d.objectkey == str(args.id)]
                    if changed:
                        added, removed = sum(d.added for d in changed), sum(d.removed for d in changed)
                        what = ("only there" if removed == 0 and sum(d.changed for d in changed) == 0 and added
                                else "not there" if added == 0 and sum(d.changed for d in changed) == 0 and removed
                                else f"{sum(d.added + d.removed + d.changed for d in changed)} rows differ")
                        differs.append(f"{version.name} ({what})")
        conn.rollback()
    name, geotype, nvrtx, ncell, members, timemodel, alive = row[:7]
    _out(f"feature {args.id}: {name or '(no name)'}, class {fc.name} ({geotype}{_time_label(fc)}), in version {here}")
    _out(f"  {nvrtx} vertices, {ncell} cells" + (f", {members} members" if members is not None else ""))
    if row[7] is not None:
        _out("  box: " + ", ".join(f"{axis} [{row[7 + 2 * i]!r}, {row[8 + 2 * i]!r}]" for i, axis in enumerate("xyz")))
    if span is None:
        _out("  static: the same at every time")
    else:
        topology = [t for t, starts in steps if starts]
        _out(f"  exists from t = {span[0]!r} to {span[1]!r}{_unit(fc)}" + (" and after (alive)" if span[2] else "")
             + f"; {len(steps)} instants, topology (re)defined at {', '.join(repr(t) for t in topology)}")
    if properties:
        _out("  properties: " + ", ".join(f"{k} = {v!r}" for k, v in properties.items()))
    if fc.instant_properties:
        _out("  per-instant properties: " + ", ".join(p.name for p in fc.instant_properties))
    mesh = feature.mesh if feature is not None else None
    if mesh is not None and not isinstance(mesh, GeometryCollection):
        if mesh.vertex_properties:
            _out("  vertex properties: " + ", ".join(mesh.vertex_properties))
        if mesh.cell_properties:
            _out("  cell properties: " + ", ".join(mesh.cell_properties))
    if versioned:
        _out("  versions where it differs from " + here + ": " + (", ".join(differs) if differs else "none"))
    return 0


def cmd_query(args: argparse.Namespace) -> int:
    from tgsis.db.temporal import class_property_periods

    if math.isnan(args.value):
        raise InvalidInputError("VALUE must be a number, got nan", hint="-inf and inf are allowed")
    with _connect(args) as conn:
        found = class_property_periods(conn, args.feature_class, args.property, args.op, args.value,
                                       convention=args.convention)
    for fid, periods in found.items():
        if args.first:
            first = periods[0]
            _out(f"{fid}\t{first.start!r}" + ("" if first.start_closed else "\t(right after it)"))
        else:
            _out(f"{fid}\t" + " ".join(str(p) for p in periods))
    if not found:
        print(f"no feature of {args.feature_class} has {args.property} {args.op} {args.value!r} at any time",
              file=sys.stderr)
    return 0


def cmd_ls(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        classes = [get_feature_class(conn, args.feature_class)] if args.feature_class else list_feature_classes(conn)
        rows = []
        for fc in classes:
            rows += [(fc.name, *r) for r in conn.execute(
                psycopg_sql.SQL("SELECT g.geoid, g.geoname, g.geotype, g.nvrtx, g.ncell, cardinality(g.geoids) "
                                "FROM {}.{} f JOIN tgsis.geometry g ON g.geoid = f._geoid ORDER BY g.geoid").format(
                    psycopg_sql.Identifier(fc.schema), psycopg_sql.Identifier(fc.featuretable))).fetchall()]
    for cls, geoid, name, geotype, nvrtx, ncell, nmembers in rows:
        members = f"\t{nmembers} members" if nmembers is not None else ""
        _out(f"{geoid}\t{cls}\t{name or ''}\t{geotype}\t{nvrtx} vertices\t{ncell} cells{members}")
    if not rows:
        print("no features", file=sys.stderr)
    return 0


# --------------------------------------------------------------------------- check-out / check-in


def _checkout_file(path: str) -> Path:
    """Where ``tgsis checkout`` keeps the token and base of the mesh it wrote to ``path``."""
    return Path(f"{path}.tgsis-checkout.npz")


def cmd_checkout(args: argparse.Namespace) -> int:
    from tgsis import formats
    from tgsis.db.checkin import checkout

    with _connect(args) as conn:
        co = checkout(conn, args.id, args.feature_class)
    formats.write(co.mesh, args.file, format=args.format)
    written = formats.read_one(args.file, format=args.format)
    if not np.array_equal(written.vertices, co.mesh.vertices):  # the format must keep every bit of the base
        raise InvalidInputError(f"{args.file}: the format does not keep the coordinates exactly, so a check-in "
                                "would see every vertex as moved", hint="use .ts (GOCAD) or .vtu (VTK)")
    side = co.save(_checkout_file(args.file))
    _out(f"checked out feature {co.token.feature_id} ({co.token.feature_class}, {co.mesh.n_vertices} vertices, "
         f"{co.mesh.n_cells} {type(co.mesh).cell_name}s) of version {co.token.version} at revision "
         f"{co.token.revision} to {args.file} (check-out record: {side})")
    return 0


def cmd_checkin(args: argparse.Namespace) -> int:
    from tgsis import formats
    from tgsis.db.checkin import Checkout, checkin

    side = _checkout_file(args.file)
    if not side.is_file():
        raise NotFoundError(f"{args.file} was not checked out here: {side} is missing",
                            hint="tgsis checkout ID FILE writes the file and its check-out record")
    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise InvalidInputError(f"--tolerance must be a finite number >= 0, got {args.tolerance}")
    co = Checkout.load(side)
    edited = formats.read_one(args.file, format=args.format)
    if args.png and not isinstance(edited, Surface):             # refused before anything is checked in
        raise InvalidInputError(f"{args.file} holds a {type(edited).__name__}: --png draws surfaces")
    with connect(args.dsn) as conn:  # the check-out's version, whatever version commands work in now
        result = checkin(conn, co, edited, _feature_values(args.set) or None, name=args.name,
                         tolerance=args.tolerance, on_conflict=args.on_conflict, child_version=args.child_version,
                         keep=not args.no_keep, drop_extra_properties=args.drop_extra_properties)
    save = result.save
    counts = save.diff.counts()
    _out(f"checked in feature {save.feature_id} into version {save.version}"
         + (" (a new child version: the feature had changed since check-out)" if result.conflict else ""))
    _out(f"  vertices: {counts['vertices_kept']} kept, {save.vertices_moved} moved, "
         f"{counts['vertices_removed'] - save.vertices_moved} removed, {counts['vertices_added'] - save.vertices_moved} "
         f"added; {type(edited).cell_name}s: {counts['cells_kept']} kept by definition, "
         f"{counts['cells_removed']} removed, {counts['cells_added']} added")
    _out(f"  rows written: {save.rows_written} ({save.rows_deleted} deleted, {save.rows_inserted} inserted, "
         f"{save.rows_updated} updated)")
    if args.png and isinstance(edited, Surface):
        from scipy.spatial import cKDTree

        from tgsis import pictures

        # how far each vertex lies from the checked-out shape: 0 for the ones kept
        moved = cKDTree(co.mesh.vertices).query(edited.vertices)[0]
        moved[save.diff.vertex_map >= 0] = 0.0
        pictures.scene([edited], args.png, colour=[moved], colour_label="moved from the check-out (m)",
                       title=f"feature {save.feature_id} checked in to {save.version}")
        _out(f"  drew the edit to {args.png}")
    if result.checkout is not None and not result.conflict:
        result.checkout.save(side)
    elif result.conflict:
        _out(f"  both edits meet as a conflict of {save.version}: tgsis version conflicts {save.version} --rows; "
             f"tgsis version resolve {save.version} feature {save.feature_id} parent|child|manual; "
             f"tgsis version merge {save.version} --remove")
    return 0


# --------------------------------------------------------------------------- interpolation


def _read_surface(path: str, what: str) -> tgsis.Surface:
    from tgsis import formats

    mesh = formats.read_one(path)
    if not isinstance(mesh, tgsis.Surface):
        raise InvalidInputError(f"the {what} {path} holds a {type(mesh).__name__}: interpolation morphs surfaces")
    return mesh


#: Most PNG views ``tgsis interpolate --preview`` writes.
MAX_PREVIEWS = 1000


def cmd_interpolate(args: argparse.Namespace) -> int:
    from tgsis.interpolation import InterpolationSetup, interpolate
    from tgsis.interpolation.preview import write_previews

    if args.preview and not 1 <= args.frames <= MAX_PREVIEWS:
        raise InvalidInputError(f"--frames must be from 1 to {MAX_PREVIEWS}, got {args.frames}")
    source, target = _read_surface(args.source, "source"), _read_surface(args.target, "target")
    setup = InterpolationSetup.load(args.setup)
    name = args.name or source.name or Path(args.source).stem
    result = interpolate(source, target, setup, args.t0, args.t1, name=name, alive=args.alive)
    _out(f"interpolated {name}: {result.source.n_vertices} vertices, {result.source.n_cells} triangles "
         f"({result.source.n_vertices - source.n_vertices} added by cutting and refinement), m = {setup.steps}, "
         f"error to the target {result.error:.3g}")
    _out("  " + ", ".join(f"{stage} {seconds:.2f} s" for stage, seconds in result.timings.items()))
    if args.preview:
        times = np.linspace(args.t0, args.t1, args.frames).tolist()
        paths = write_previews(result.evolving, times, args.preview, stem=Path(args.source).stem)
        _out(f"  {len(paths)} previews in {args.preview}")
    if args.feature_class:
        with _connect(args) as conn:
            fid = insert_feature(conn, args.feature_class, result.evolving)
        _out(f"stored as feature {fid} of class {args.feature_class} from t = {args.t0:g} to {args.t1:g}")
    return 0


def cmd_corners(args: argparse.Namespace) -> int:
    from tgsis.interpolation import propose_corners

    if args.count is not None and args.count < 1:
        raise InvalidInputError(f"--count must be >= 1, got {args.count}", hint="leave --count out for every corner")
    if not 0 <= args.min_angle <= 180:  # NaN too
        raise InvalidInputError(f"--min-angle must be from 0 to 180 degrees, got {args.min_angle}")
    surface = _read_surface(args.file, "surface")
    corners = propose_corners(surface, min_angle=args.min_angle, count=args.count)
    _out(json.dumps(corners.tolist()))
    for vertex in corners.tolist():
        x, y, z = surface.vertices[vertex]
        print(f"vertex {vertex}: {x:.6g} {y:.6g} {z:.6g}", file=sys.stderr)
    return 0


def _vertex_path(text: str) -> list[int]:
    try:
        path = [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"a path is vertex indices separated by commas (e.g. 3,7,12), got {text!r}") from None
    if len(path) < 2 or min(path) < 0:
        raise argparse.ArgumentTypeError(f"a path has at least two vertex indices >= 0, got {text!r}")
    return path


def cmd_cut(args: argparse.Namespace) -> int:
    from tgsis import formats
    from tgsis.interpolation.cutting import cut_along_paths

    target = formats.format_for(args.output, args.format)  # an unknown format fails before any work
    surface = _read_surface(args.file, "surface")
    cut = cut_along_paths(surface, args.path, names=[f"--path {','.join(map(str, p))}" for p in args.path])
    target.write(cut.surface, args.output)
    _out(f"cut {args.file} along {len(args.path)} path(s): {surface.n_vertices} vertices, {cut.n_copies} copied "
         f"({cut.surface.n_vertices} now), {surface.n_cells} triangles; wrote {args.output}")
    return 0


# --------------------------------------------------------------------------- time


def _life(span: tuple[float, float, bool] | None, fc: FeatureClass) -> str:
    """When a feature exists, for messages."""
    if span is None:
        return "it is static: it exists at every time"
    first, last, alive = span
    return (f"it exists from t = {first!r}{_unit(fc)} on (alive)" if alive
            else f"it exists from t = {first!r} to {last!r}{_unit(fc)}")


def cmd_at(args: argparse.Namespace) -> int:
    from tgsis import formats

    if not math.isfinite(args.time):
        raise InvalidInputError(f"T must be a finite number, got {args.time!r}")
    if (args.format or Path(args.file).suffix).lower().lstrip(".") == "pvd":
        raise InvalidInputError(f"{args.file}: tgsis at writes one surface; a .pvd is a time series",
                                hint="tgsis series writes a .pvd")
    target = formats.format_for(args.file, args.format)  # an unknown format fails before connecting
    with _connect(args) as conn:
        fc = class_of_feature(conn, args.id)
        surface = get_at(conn, args.id, args.time, convention=args.convention, properties=True)
        if surface is None:
            raise NotFoundError(f"feature {args.id} ({fc.name}) does not exist at t = {args.time!r}{_unit(fc)}",
                                hint=_life(lifespan(conn, args.id), fc))
        target.write(surface, args.file)
        _out(f"wrote feature {args.id} ({fc.name}) at t = {args.time!r}{_unit(fc)}: {surface.n_vertices} vertices, "
             f"{surface.n_cells} triangles, to {args.file}")
        if args.png:
            _picture_of(conn, [args.id, *args.with_ids], args.time, args.png,
                        title=f"feature {args.id} ({fc.name}) at t = {args.time!r}{_unit(fc)} (SQL snapshot)")
    return 0


def _series_name(name: str) -> str:
    """The stem of the .pvd file (a trailing .pvd dropped); no folders."""
    stem = name[:-4] if name.lower().endswith(".pvd") else name
    if not stem or stem in (".", "..") or "/" in stem or os.sep in stem:
        raise InvalidInputError(f"--name {name!r} must be a file name without folders, e.g. fault_history")
    return stem


def cmd_series(args: argparse.Namespace) -> int:
    sampling = (args.start, args.end, args.steps)
    if any(v is not None for v in sampling):
        if any(v is None for v in sampling):
            raise InvalidInputError("--from, --to and --steps go together",
                                    hint="without all three, the frames are at the feature's own instants")
        even_times(args.start, args.end, args.steps, labels=("--from", "--to", "--steps"))  # clear messages
    stem = _series_name(args.name or f"feature_{args.id}")
    folder = Path(args.dir)
    with _connect(args) as conn:
        fc = class_of_feature(conn, args.id)
        if args.steps is None and lifespan(conn, args.id) is None:
            raise InvalidInputError(f"feature {args.id} ({fc.name}) is static: it has no instants of its own",
                                    hint="give --from, --to and --steps")
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InvalidInputError(f"cannot create the folder {folder}: {exc.strerror or exc}") from exc
        written = export_series(conn, args.id, folder / f"{stem}.pvd", start=args.start, end=args.end,
                                steps=args.steps, convention=args.convention)
    if args.gif:
        from tgsis import pictures

        shown = [(t, [surface]) for t, surface in written.frames if surface is not None]
        first = shown[0][1][0] if shown else None
        same = first is not None and all(s[0].vertices.shape == first.vertices.shape for _, s in shown)
        pictures.animation(shown, args.gif, title=f"feature {args.id} ({fc.name})", time_unit=fc.time_unit or "",
                           reference=[first] if same and first is not None else None,
                           colour_label=f"moved since t = {shown[0][0]!r} (m)" if shown else "")
    for (t, surface), file in zip(written.frames, written.files):
        _out(f"{t!r}\t{file}\t" + (f"{surface.n_vertices} vertices\t{surface.n_cells} triangles" if surface
                                     else "no object (empty grid)"))
    times = [t for t, _ in written.frames]
    missing = f", {len(written.missing)} without the object" if written.missing else ""
    _out(f"wrote {written.pvd}: feature {args.id} ({fc.name}) at {len(times)} times from {times[0]!r} "
         f"to {times[-1]!r}{_unit(fc)}{missing}")
    if args.gif:
        _out(f"drew {len(times)} frames to {args.gif}")
    return 0


# --------------------------------------------------------------------------- versions


def cmd_version_create(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        revision = V.create_version(conn, args.name, args.parent, description=args.description)
    _out(f"created version {args.name} (parent {args.parent}), working revision {revision}")
    return 0


def cmd_version_list(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        versions = V.list_versions(conn)
        current = V.working_version(conn)
    for v in versions:
        mark = "*" if v.name == current else " "
        _out(f"{mark} {v.name}\tparent {v.parent or '-'}\tinitrevision {v.initrevision if v.initrevision is not None else '-'}"
             f"\tworking {v.workingrevision}\towner {v.owner}\t{v.created_at:%Y-%m-%d %H:%M}\t{v.description or ''}")
    return 0


def cmd_version_tree(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        _out(V.format_tree(V.list_versions(conn)))
    return 0


def cmd_version_goto(args: argparse.Namespace) -> int:
    name, revision = _split_version(args.name)
    with connect(args.dsn) as conn:
        if revision is None:
            V.goto_version(conn, name)  # checks that it exists
            working = V.working_revision(conn)
        else:
            V.goto_revision(conn, name, revision)
    clistate.remember_version(_target_key(args), args.name)
    if revision is None:
        _out(f"commands on this database now work in version {name} (working revision {working})")
    else:
        _out(f"commands on this database now look at revision {revision} of version {name} (read-only)")
    return 0


def cmd_version_current(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        name, working, viewing = V.working_version(conn), V.working_revision(conn), V.viewing_revision(conn)
    source = ("--in" if args.in_version else "$TGSIS_VERSION" if os.environ.get("TGSIS_VERSION")
              else "tgsis version goto" if clistate.remembered_version(_target_key(args)) else "default")
    looking = f"\tviewing revision {viewing} (read-only)" if viewing is not None else ""
    _out(f"{name}\tworking revision {working}{looking}\t(from {source})")
    return 0


def cmd_version_save(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        saved = V.save_revision(conn, args.name)
        version, working = V.working_version(conn), V.working_revision(conn)
    _out(f"saved revision {saved} of {version} as {args.name}; new working revision {working}")
    return 0


def cmd_version_delete(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        removed = V.delete_version(conn, args.name)
    if clistate.remembered_version(_target_key(args)) == args.name:
        clistate.remember_version(_target_key(args), None)
    _out(f"deleted version {args.name} and {removed} row version(s)")
    return 0


def cmd_version_conflicts(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        conflicts = V.find_conflicts(conn, args.name)
        details = {(c.objectclass, c.objectkey): V.conflict_rows(conn, args.name, c.objectclass, c.objectkey)
                   for c in conflicts} if args.rows else {}
    for c in conflicts:
        both = ", ".join(c.conflicttype) or "different tables"
        _out(f"{c.objectclass}\t{c.objectkey}\t{c.solution}\tboth changed: {both}\t"
             f"{args.name}: {', '.join(c.childtables)}\tparent: {', '.join(c.parenttables)}")
        for table, side, key, row in details.get((c.objectclass, c.objectkey), []):
            _out(f"\t{table}\t{side}\t{json.dumps(key)}\t{json.dumps(row)}")
    if not conflicts:
        print(f"version {args.name} has no conflicts with its parent", file=sys.stderr)
    return 0


def cmd_version_resolve(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        c = V.resolve_conflict(conn, args.name, args.objectclass, args.objectkey, args.solution)
    _out(f"{c.objectclass} {c.objectkey} in {args.name}: {c.solution}")
    return 0


def cmd_version_merge(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        written = V.merge_version(conn, args.name, remove=args.remove)
    _out(f"merged {args.name} into its parent: {written} row(s) written" + ("; version removed" if args.remove else ""))
    if args.remove and clistate.remembered_version(_target_key(args)) == args.name:
        clistate.remember_version(_target_key(args), None)
    return 0


def cmd_version_refresh(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        written = V.refresh_version(conn, args.name)
    _out(f"refreshed {args.name} from its parent: {written} row(s) written")
    return 0


def _feature_as(conn: Any, fid: int, version: str, revision: int | None) -> Mesh | GeometryCollection | None:
    """Feature ``fid`` as a version (at a revision) sees it, or None where it does not exist there."""
    context = V.at_revision(conn, revision, version) if revision is not None else V.in_version(conn, version)
    with context:
        try:
            return fetch_feature(conn, class_of_feature(conn, fid), fid).mesh
        except NotFoundError:
            return None
        finally:
            conn.rollback()


def _draw_differences(conn: Any, args: argparse.Namespace, differences: Sequence[Any],
                      sides: tuple[tuple[str, int | None], tuple[str, int | None]]) -> None:
    """One PNG per changed surface feature: the new side coloured by how far each vertex moved, or both sides."""
    from tgsis import pictures

    folder = Path(args.png)
    folder.mkdir(parents=True, exist_ok=True)
    for fid in sorted({int(d.objectkey) for d in differences if d.objectclass == "feature"}):
        old, new = (_feature_as(conn, fid, version, revision) for version, revision in sides)
        shown = [m for m in (old, new) if isinstance(m, Surface)]
        if not shown:
            continue
        path = folder / f"diff_{fid}.png"
        title = f"feature {fid}: {args.a} -> {args.b}"
        if isinstance(old, Surface) and isinstance(new, Surface) and old.vertices.shape == new.vertices.shape:
            pictures.scene([new], path, title=title, colour=[pictures.displacement(new, old)],
                           colour_label=f"moved from {args.a} (m)")
        else:
            if isinstance(old, Surface):
                old.name = f"{old.name or fid} in {args.a}"
            if isinstance(new, Surface):
                new.name = f"{new.name or fid} in {args.b}"
            pictures.scene(shown, path, title=title)
        _out(f"drew feature {fid} to {path}")


def cmd_version_diff(args: argparse.Namespace) -> int:
    a, a_rev = _split_version(args.a)
    b, b_rev = _split_version(args.b)
    with _connect(args) as conn:
        differences = V.diff_versions(conn, a, b, a_revision=a_rev, b_revision=b_rev)
        if args.png:
            _draw_differences(conn, args, differences, ((a, a_rev), (b, b_rev)))
    for d in differences:
        _out(f"{d.objectclass}\t{d.objectkey}\t{d.table}\t+{d.added}\t-{d.removed}\t~{d.changed}")
    if not differences:
        print(f"{args.a} and {args.b} hold the same rows", file=sys.stderr)
    return 0


def _moment(text: str) -> datetime.datetime:
    try:
        moment = datetime.datetime.fromisoformat(text)
    except ValueError:
        raise InvalidInputError(f"{text!r} is not a date or time (ISO 8601, e.g. 2026-03-01 or 2026-03-01T12:00+01:00)"
                                ) from None
    return moment if moment.tzinfo else moment.replace(tzinfo=datetime.timezone.utc)


def cmd_version_valid(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        V.set_version_validity(conn, args.name, _moment(args.valid_from), _moment(args.valid_to) if args.valid_to else None)
    _out(f"version {args.name} believed from {args.valid_from}" + (f" to {args.valid_to}" if args.valid_to else " on"))
    return 0


def cmd_version_chain(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        if args.at:
            believed = V.version_believed_at(conn, _moment(args.at), args.root)
            _out(believed if believed is not None else "-")
            return 0 if believed is not None else 3
        chain = V.version_chain(conn, args.root)
    for name, start, end in chain:
        _out(f"{name}\t{start.isoformat()}\t{end.isoformat() if end else 'still believed'}")
    return 0


def cmd_version_lock(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        taken = V.lock_objects(conn, args.name, args.objectclass, args.keys, exclusive=args.exclusive)
    _out(f"{args.name} holds {len(set(args.keys))} {args.objectclass} object(s) ({taken} newly locked"
         + (", exclusive" if args.exclusive else "") + ")")
    return 0


def cmd_version_unlock(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        released = V.unlock_objects(conn, args.name, args.objectclass, args.keys or None)
    _out(f"released {released} lock(s) of {args.name}")
    return 0


def cmd_version_locks(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        locks = V.object_locks(conn, args.name)
    for lk in locks:
        _out(f"{lk.objectclass}\t{lk.objectkey}\t{lk.version}\t{lk.locked_by}\t"
             f"{'exclusive' if lk.exclusive else 'version'}\t{lk.locked_at.isoformat()}")
    if not locks:
        print("no object locks" + (f" in {args.name}" if args.name else ""), file=sys.stderr)
    return 0


def cmd_version_grant(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        (V.revoke_version if args.revoke else V.grant_version)(conn, args.name, args.privilege, args.role)
    _out(f"{'revoked' if args.revoke else 'granted'} {args.privilege} on {args.name} "
         f"{'from' if args.revoke else 'to'} {args.role}")
    return 0


def cmd_version_owner(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        V.set_version_owner(conn, args.name, args.role)
    _out(f"version {args.name} is owned by {args.role}")
    return 0


def cmd_version_privileges(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        owners = {v.name: v.owner for v in V.list_versions(conn) if args.name in (None, v.name)}
        grants = V.version_privileges(conn, args.name)
    if args.name is not None and not owners:
        raise NotFoundError(f"version {args.name!r} does not exist")
    for name, owner in owners.items():
        _out(f"{name}\t{owner}\towner (every right)")
        for g in (g for g in grants if g.version == name):
            _out(f"{name}\t{g.grantee}\t{g.privilege}\tgranted by {g.granted_by}")
    return 0


def cmd_version_compress(args: argparse.Namespace) -> int:
    remembered = clistate.remembered_version(_target_key(args))
    looked_at = _split_version(remembered)[1] if remembered else None
    with connect(args.dsn) as conn:
        report = V.compress_versions(conn, dry_run=args.dry_run)
        gone = looked_at is not None and not args.dry_run and conn.execute(
            "SELECT NOT EXISTS (SELECT FROM tgsis.revisions WHERE revision = %s)", (looked_at,)).fetchone() == (True,)
    for item in report:
        _out(f"{item.what}\t{item.name}\t{item.removed}")
    totals = {what: sum(i.removed for i in report if i.what == what)
              for what in ("rows", "lastrevs", "revisions", "set entries")}
    summary = (f"{totals['rows']} row version(s), {totals['lastrevs']} lastrevs entr(ies), "
               f"{totals['revisions']} revision(s), {totals['set entries']} revision set entr(ies)")
    if args.dry_run:
        _out(f"compress would remove {summary} (dry run: nothing changed)" if report
             else "compress would remove nothing (dry run)")
    else:
        _out(f"compress removed {summary}" if report else "compress removed nothing")
    if gone:
        clistate.remember_version(_target_key(args), None)
        _out(f"revision {looked_at} is gone: commands on this database work in DEFAULT again (was {remembered})")
    return 0


def cmd_versioning_enable(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        if args.table == "features":
            count = V.enable_feature_versioning(conn)
            _out(f"model 1 and the feature classes are versioned (object class feature): {count} table(s) newly versioned")
            return 0
        if not (args.key and args.object_class):
            raise InvalidInputError("versioning a table needs --key and --class",
                                    hint="e.g. tgsis versioning enable wells --key id --class well")
        t = V.enable_versioning(conn, args.table, args.key, args.object_class, args.order, args.shortname)
    _out(f"{t.schema}.{t.table} is versioned (object class {t.objectclass}, key {t.objectkeyfield}, "
         f"storage {t.table}_ver)")
    return 0


def cmd_versioning_disable(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        if args.table == "features":
            removed = V.disable_feature_versioning(conn, force=args.force)
        else:
            removed = V.disable_versioning(conn, args.table, force=args.force)
    _out(f"{args.table}: versioning disabled, DEFAULT's rows kept, {removed} row version(s) removed")
    return 0


def cmd_versioning_list(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        tables = V.versioned_tables(conn)
    for t in tables:
        _out(f"{t.schema}.{t.table}\t{t.objectclass}\tkey {t.objectkeyfield}\torder {t.iudorder}\t"
             f"short {t.shortname}\trow key ({', '.join(t.keycolumns)})")
    if not tables:
        print("no versioned tables", file=sys.stderr)
    return 0


# --------------------------------------------------------------------------- demo


def cmd_demo(args: argparse.Namespace) -> int:
    from tgsis.scenarios import SCENARIOS, run_scenario

    if args.list:
        for scenario in SCENARIOS.values():
            _out(f"{scenario.name}\t{scenario.summary}")
        return 0
    run_scenario(args.name, args.dsn, out=_out, folder=args.dir, size=args.size)
    return 0


# --------------------------------------------------------------------------- parser


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``tgsis`` command."""
    parser = argparse.ArgumentParser(
        prog="tgsis",
        description="tgsis: spatio-temporal geoscience information system on PostgreSQL",
    )
    parser.add_argument("--version", action="version", version=f"tgsis {tgsis.__version__}")
    parser.add_argument("--dsn", help="libpq connection string (default: $TGSIS_DSN, PG* variables, "
                                      "else the local server tgsis runs itself)")
    parser.add_argument("--in", dest="in_version", metavar="VERSION[@REVISION]",
                        help="work in this version, or look at one of its revisions (default: $TGSIS_VERSION, "
                             "else what `tgsis version goto` chose, else DEFAULT)")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output (-vv: debug)")
    parser.add_argument("-q", "--quiet", action="store_true", help="errors only")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    demo = commands.add_parser("demo", help="run a sample application end to end (default: cfm, the release story)",
                               epilog="example: tgsis demo saltdome --dir out  (then look at out/*.png, out/saltdome.gif)")
    demo.add_argument("name", nargs="?", default="cfm", metavar="NAME",
                      help="the scenario (tgsis demo --list names them; default: cfm)")
    demo.add_argument("--list", action="store_true", help="list the scenarios and what each shows")
    demo.add_argument("--dir", metavar="DIR", help="folder for the files it writes (default: a new temporary folder)")
    demo.add_argument("--size", choices=("small", "large"), default="small",
                      help="how much data the scenario makes (default: small, under a minute)")
    demo.set_defaults(handler=cmd_demo)

    db = commands.add_parser("db", help="install, upgrade or inspect tgsis in a database")
    db_commands = db.add_subparsers(dest="db_command", metavar="ACTION", required=True)
    db_install = db_commands.add_parser("install", help="install or upgrade tgsis (a no-op when up to date)")
    db_install.add_argument("--method", choices=("auto", "extension", "sql"), default="auto",
                            help="extension: CREATE EXTENSION (needs the files on the server); "
                                 "sql: run the script from the client; auto: extension when available")
    db_install.set_defaults(handler=cmd_db_install)
    db_uninstall = db_commands.add_parser("uninstall", help="remove tgsis and all its data from the database")
    db_uninstall.add_argument("--yes", action="store_true", help="really do it")
    db_uninstall.add_argument("--cascade", action="store_true", help="also drop objects that depend on tgsis")
    db_uninstall.set_defaults(handler=cmd_db_uninstall)
    db_status = db_commands.add_parser("status", help="server and tgsis versions")
    db_status.set_defaults(handler=cmd_db_status)

    cls = commands.add_parser("class", help="feature classes: create, list, drop")
    cls_commands = cls.add_subparsers(dest="class_command", metavar="ACTION", required=True)
    cls_create = cls_commands.add_parser("create", help="register a feature class")
    cls_create.add_argument("name")
    cls_create.add_argument("--geotype", required=True, type=str.upper,
                            choices=("MULTIPOINT", "MULTILINESTRING", "SURFACE", "MULTITETRA", "GEOMETRYCOLLECTION"))
    cls_create.add_argument("--feature-property", action="append", metavar="NAME:TYPE",
                            help="a property of the whole feature (repeatable), e.g. creator:text")
    cls_create.add_argument("--property", action="append", metavar="NAME:TYPE[:SIZE][:VERTEX|CELL]",
                            help="a per-vertex (or per-cell) property (repeatable), e.g. porosity:float8; SIZE: a "
                                 "vector of SIZE components (slip:float8:3); VERTEX or CELL: an alignment other "
                                 "than --alignment (facies:int:CELL)")
    cls_create.add_argument("--alignment", default="VERTEX", type=str.upper, choices=("VERTEX", "CELL"))
    cls_create.add_argument("--srs", type=_INT4, default=0, help="spatial reference id (EPSG), 0 = undefined")
    cls_create.add_argument("--schema", default="public")
    cls_create.add_argument("--description")
    cls_create.add_argument("--time-model", default="STATIC", type=str.upper, choices=("STATIC", "INSTANTS", "EVOLVING"),
                            help="STATIC (model 1), INSTANTS: surfaces at instants (model 2), "
                                 "EVOLVING: continuously evolving surfaces (model 3)")
    cls_create.add_argument("--time-unit", help="unit of model time of a temporal class, e.g. Ma")
    cls_create.add_argument("--instant-property", action="append", metavar="NAME:TYPE",
                            help="per-instant feature property of a temporal class (repeatable)")
    cls_create.set_defaults(handler=cmd_class_create)
    cls_list = cls_commands.add_parser("list", help="list the feature classes")
    cls_list.set_defaults(handler=cmd_class_list)
    cls_drop = cls_commands.add_parser("drop", help="drop a feature class (refused while it has features)")
    cls_drop.add_argument("name")
    cls_drop.add_argument("--force", action="store_true", help="also delete its features and their geometries")
    cls_drop.set_defaults(handler=cmd_class_drop)

    imp = commands.add_parser("import", help="store the objects of a geometry file as features of a class "
                                             "(as one feature in a GEOMETRYCOLLECTION class)")
    imp.add_argument("file")
    imp.add_argument("--class", dest="feature_class", required=True)
    imp.add_argument("--name", help="feature name (default: the name in the file, else the file name; "
                                    "for a GEOMETRYCOLLECTION class the file name)")
    imp.add_argument("--format", help="file format (default: from the extension)")
    imp.add_argument("--set", action="append", metavar="NAME=VALUE", help="a feature property value (repeatable)")
    imp.add_argument("--drop-extra-properties", action="store_true",
                     help="ignore properties of the file that the class does not store")
    imp.add_argument("--reject-flagged", action="store_true",
                     help="refuse the whole file if any object has duplicate vertices (other than GOCAD ATOMs) "
                          "or degenerate cells")
    imp.add_argument("--strict", action="store_true",
                     help="refuse the whole file if it holds objects tgsis cannot read (a GOCAD SGrid beside "
                          "surfaces), instead of skipping them with a warning")
    imp.add_argument("--tolerance", type=float, default=0.0, metavar="T",
                     help="cells of length/area/volume at most T count as degenerate (default 0: exactly zero)")
    imp.set_defaults(handler=cmd_import)

    exp = commands.add_parser("export", help="write a feature to a geometry file")
    exp.add_argument("id", type=_ID)
    exp.add_argument("file")
    exp.add_argument("--class", dest="feature_class", help="its feature class (default: looked up)")
    exp.add_argument("--format", help="file format (default: from the extension)")
    exp.add_argument("--png", metavar="PNG", help="also draw the feature (a surface) to this PNG file")
    exp.set_defaults(handler=cmd_export)

    at = commands.add_parser("at", help="write the surface of a feature at model time T to a file")
    at.add_argument("id", type=_ID)
    at.add_argument("time", type=float, metavar="T", help="model time (in the class's unit)")
    at.add_argument("file")
    at.add_argument("--format", help="file format (default: from the extension)")
    at.add_argument("--convention", type=str.lower, choices=("left", "right"), default="left",
                    help="step convention of a surface known at instants (default: left)")
    at.add_argument("--png", metavar="PNG", help="also draw the surface at T to this PNG file, coloured by how far "
                                                  "it moved since its first instant")
    at.add_argument("--with", dest="with_ids", type=_ID, nargs="+", default=[], metavar="ID",
                    help="with --png: other features drawn at T in the same scene (the structure at T)")
    at.set_defaults(handler=cmd_at)

    series = commands.add_parser("series", help="write a feature over model time as a ParaView .pvd time series")
    series.add_argument("id", type=_ID)
    series.add_argument("dir", metavar="DIR", help="folder of the .pvd and its frames (created if missing)")
    series.add_argument("--from", dest="start", type=float, metavar="T0", help="first time")
    series.add_argument("--to", dest="end", type=float, metavar="T1", help="last time")
    series.add_argument("--steps", type=_INT4, metavar="N",
                        help="N frames evenly spaced from T0 to T1, both included (without --from/--to/--steps: "
                             "one frame at each of the feature's own instants)")
    series.add_argument("--name", help="name of the .pvd file (default: feature_ID)")
    series.add_argument("--convention", type=str.lower, choices=("left", "right"), default="left",
                        help="step convention of a surface known at instants (default: left)")
    series.add_argument("--gif", metavar="GIF", help="also draw the frames as an animated GIF, coloured by how far "
                                                     "the surface moved since the first frame")
    series.set_defaults(handler=cmd_series)

    co = commands.add_parser("checkout", help="write a feature to a file for editing, recording what it was")
    co.add_argument("id", type=_ID)
    co.add_argument("file", help="the file to edit (.ts, .vtk, .vtu, ...); the record goes to FILE.tgsis-checkout.npz")
    co.add_argument("--class", dest="feature_class", help="its feature class (default: looked up)")
    co.add_argument("--format", help="file format (default: from the extension)")
    co.set_defaults(handler=cmd_checkout)

    ci = commands.add_parser("checkin", help="write an edited file back by difference, unless the feature changed "
                                             "since check-out")
    ci.add_argument("file", help="a file written by tgsis checkout, edited")
    ci.add_argument("--format", help="file format (default: from the extension)")
    ci.add_argument("--tolerance", type=float, default=0.0, metavar="T",
                    help="vertices within distance T of a checked-out vertex are unchanged (default 0: equal "
                         "coordinates)")
    ci.add_argument("--on-conflict", choices=("raise", "child"), default="raise",
                    help="when the feature changed since check-out: fail (default) or write the edit into a new "
                         "child version")
    ci.add_argument("--child-version", metavar="NAME", help="name of that child version (default checkin_ID)")
    ci.add_argument("--name", help="new feature name")
    ci.add_argument("--set", action="append", metavar="NAME=VALUE", help="a feature property value (repeatable)")
    ci.add_argument("--drop-extra-properties", action="store_true",
                    help="ignore properties of the file that the class does not store")
    ci.add_argument("--no-keep", dest="no_keep", action="store_true",
                    help="do not update the check-out record (by default it follows the new state, so that the "
                         "file can be edited and checked in again)")
    ci.add_argument("--png", metavar="PNG", help="also draw the edited surface, coloured by how far each vertex lies "
                                                  "from the checked-out shape (0 for the kept ones)")
    ci.set_defaults(handler=cmd_checkin)

    interp = commands.add_parser("interpolate", help="the surface evolving from SOURCE (at T0) to TARGET (at T1): "
                                                     "morphological interpolation, stored as a model-3 feature")
    interp.add_argument("source", help="surface file at T0")
    interp.add_argument("target", help="surface file at T1")
    interp.add_argument("--setup", required=True, help="JSON set-up: control vertices, fences, cuts, attachments, "
                                                       "steps, tolerance (see docs/interpolation.md)")
    interp.add_argument("--t0", type=float, required=True, help="time of the source")
    interp.add_argument("--t1", type=float, required=True, help="time of the target")
    interp.add_argument("--class", dest="feature_class", help="EVOLVING feature class to store it in "
                                                               "(without: computed and previewed only)")
    interp.add_argument("--name", help="feature name (default: the source's)")
    interp.add_argument("--alive", action="store_true",
                        help="the surface goes on existing after its last instant, in its last shape")
    interp.add_argument("--preview", metavar="DIR", help="write PNG views of a few instants to DIR")
    interp.add_argument("--frames", type=_INT4, default=5, help="number of preview instants (default 5)")
    interp.set_defaults(handler=cmd_interpolate)

    corners = commands.add_parser("corners", help="propose control vertices: the sharp corners of a surface's border")
    corners.add_argument("file")
    corners.add_argument("--count", type=_INT4, help="exactly this many corners")
    corners.add_argument("--min-angle", type=float, default=35.0, help="smallest turn of a corner, degrees (35)")
    corners.set_defaults(handler=cmd_corners)

    info = commands.add_parser("info", help="what a feature is: class, counts, box, lifespan and instants, properties, "
                                            "the versions where it differs", epilog="example: tgsis info 3")
    info.add_argument("id", type=_ID, help="the feature's id")
    info.set_defaults(handler=cmd_info)

    query = commands.add_parser(
        "query", help="the features of a temporal class whose per-instant property satisfies PROPERTY OP VALUE, and when",
        epilog="example: tgsis query faults throw '>=' 100 --first   (when each fault's throw first reaches 100)")
    query.add_argument("feature_class", metavar="CLASS", help="an INSTANTS or EVOLVING feature class")
    query.add_argument("property", metavar="PROPERTY", help="a numeric per-instant property of the class")
    query.add_argument("op", metavar="OP", choices=("<", "<=", "=", "<>", ">=", ">"), help="one of < <= = <> >= >")
    query.add_argument("value", metavar="VALUE", type=float, help="the number compared with (-inf, inf allowed)")
    query.add_argument("--first", action="store_true", help="only when the condition first holds, per feature")
    query.add_argument("--convention", type=str.lower, choices=("left", "right"), default="left",
                       help="step convention of features known at instants (default: left)")
    query.set_defaults(handler=cmd_query)

    cut = commands.add_parser("cut", help="cut a surface along vertex paths (its edges become borders on both sides)",
                              epilog="example: tgsis cut horizon.ts horizon_cut.ts --path 12,13,14,15")
    cut.add_argument("file", metavar="FILE", help="a file holding one surface")
    cut.add_argument("output", metavar="OUTPUT", help="the cut surface is written here")
    cut.add_argument("--path", type=_vertex_path, action="append", required=True, metavar="V1,V2,...",
                     help="a cutting path: vertex indices of FILE along interior edges, only its ends on the border "
                          "(repeat for several paths)")
    cut.add_argument("--format", help="format of OUTPUT (default: from its extension)")
    cut.set_defaults(handler=cmd_cut)

    ls = commands.add_parser("ls", help="list features")
    ls.add_argument("--class", dest="feature_class", help="only this feature class")
    ls.set_defaults(handler=cmd_ls)

    ver = commands.add_parser("version", help="versions (long transactions): create, goto, save, merge, lock, grant, ...")
    ver_commands = ver.add_subparsers(dest="version_command", metavar="ACTION", required=True)
    ver_create = ver_commands.add_parser("create", help="create a child version")
    ver_create.add_argument("name")
    ver_create.add_argument("--parent", default="DEFAULT", help="parent version (default: DEFAULT)")
    ver_create.add_argument("--description")
    ver_create.set_defaults(handler=cmd_version_create)
    ver_list = ver_commands.add_parser("list", help="list the versions (* marks the one commands work in)")
    ver_list.set_defaults(handler=cmd_version_list)
    ver_tree = ver_commands.add_parser("tree", help="print the version tree with revisions")
    ver_tree.set_defaults(handler=cmd_version_tree)
    ver_goto = ver_commands.add_parser("goto", help="work in a version from now on (remembered per database)")
    ver_goto.add_argument("name", metavar="VERSION[@REVISION]",
                          help="a version, or a revision of its history to look at read-only")
    ver_goto.set_defaults(handler=cmd_version_goto)
    ver_current = ver_commands.add_parser("current", help="the version commands work in, and its working revision")
    ver_current.set_defaults(handler=cmd_version_current)
    ver_save = ver_commands.add_parser("save", help="freeze the working revision under a name, start a new one")
    ver_save.add_argument("name")
    ver_save.set_defaults(handler=cmd_version_save)
    ver_delete = ver_commands.add_parser("delete", help="delete a version without children, with its changes")
    ver_delete.add_argument("name")
    ver_delete.set_defaults(handler=cmd_version_delete)

    ver_conflicts = ver_commands.add_parser("conflicts", help="objects changed both in a version and in its parent")
    ver_conflicts.add_argument("name")
    ver_conflicts.add_argument("--rows", action="store_true", help="also print the rows that differ, per side")
    ver_conflicts.set_defaults(handler=cmd_version_conflicts)
    ver_resolve = ver_commands.add_parser("resolve", help="record how a conflicting object is merged")
    ver_resolve.add_argument("name")
    ver_resolve.add_argument("objectclass")
    ver_resolve.add_argument("objectkey")
    ver_resolve.add_argument("solution", type=str.lower, choices=("parent", "child", "manual", "unsolved"))
    ver_resolve.set_defaults(handler=cmd_version_resolve)

    ver_merge = ver_commands.add_parser("merge", help="apply a version's changes to its parent (one transaction)")
    ver_merge.add_argument("name")
    ver_merge.add_argument("--remove", action="store_true", help="delete the version after merging it")
    ver_merge.set_defaults(handler=cmd_version_merge)
    ver_refresh = ver_commands.add_parser("refresh", help="bring the parent's changes into a version")
    ver_refresh.add_argument("name")
    ver_refresh.set_defaults(handler=cmd_version_refresh)

    ver_diff = ver_commands.add_parser("diff", help="objects whose rows differ between two versions or revisions")
    ver_diff.add_argument("a", metavar="A[@REVISION]")
    ver_diff.add_argument("b", metavar="B[@REVISION]")
    ver_diff.add_argument("--png", metavar="DIR", help="also draw each changed surface feature to DIR/diff_ID.png, "
                                                       "coloured by how far its vertices moved from A")
    ver_diff.set_defaults(handler=cmd_version_diff)

    ver_valid = ver_commands.add_parser("valid", help="set the period in which a version was believed true")
    ver_valid.add_argument("name")
    ver_valid.add_argument("valid_from", metavar="FROM", help="ISO date or time")
    ver_valid.add_argument("valid_to", metavar="TO", nargs="?", help="ISO date or time (omitted: still believed)")
    ver_valid.set_defaults(handler=cmd_version_valid)
    ver_chain = ver_commands.add_parser("chain", help="the chain of believed versions, or the one believed --at a time")
    ver_chain.add_argument("--root", default="DEFAULT")
    ver_chain.add_argument("--at", help="ISO date or time: print the version believed then (exit 3: none)")
    ver_chain.set_defaults(handler=cmd_version_chain)

    ver_compress = ver_commands.add_parser(
        "compress", help="remove revisions and row versions no version, named revision or child can reach")
    ver_compress.add_argument("--dry-run", action="store_true", help="only report what would be removed")
    ver_compress.set_defaults(handler=cmd_version_compress)

    ver_lock = ver_commands.add_parser("lock", help="lock objects for a version: no other version may change them")
    ver_lock.add_argument("name")
    ver_lock.add_argument("objectclass", help="object class ('feature' for features)")
    ver_lock.add_argument("keys", nargs="+", metavar="KEY", help="object keys (feature ids)")
    ver_lock.add_argument("--exclusive", action="store_true", help="also keep other roles from changing them in the version")
    ver_lock.set_defaults(handler=cmd_version_lock)
    ver_unlock = ver_commands.add_parser("unlock", help="release a version's object locks (all, of a class, or some keys)")
    ver_unlock.add_argument("name")
    ver_unlock.add_argument("objectclass", nargs="?")
    ver_unlock.add_argument("keys", nargs="*", metavar="KEY")
    ver_unlock.set_defaults(handler=cmd_version_unlock)
    ver_locks = ver_commands.add_parser("locks", help="list object locks (of one version, or all)")
    ver_locks.add_argument("name", nargs="?")
    ver_locks.set_defaults(handler=cmd_version_locks)

    privileges = ("write", "create", "merge", "delete", "all")
    for verb in ("grant", "revoke"):
        ver_grant = ver_commands.add_parser(verb, help=f"{verb} a right on a version (owner or tgsis_admin only)")
        ver_grant.add_argument("name")
        ver_grant.add_argument("privilege", type=str.lower, choices=privileges)
        ver_grant.add_argument("role", help="a role, or public")
        ver_grant.set_defaults(handler=cmd_version_grant, revoke=verb == "revoke")
    ver_owner = ver_commands.add_parser("owner", help="hand a version to another role")
    ver_owner.add_argument("name")
    ver_owner.add_argument("role")
    ver_owner.set_defaults(handler=cmd_version_owner)
    ver_privileges = ver_commands.add_parser("privileges", help="owners and granted rights (of one version, or all)")
    ver_privileges.add_argument("name", nargs="?")
    ver_privileges.set_defaults(handler=cmd_version_privileges)

    vt = commands.add_parser("versioning", help="turn versioning of tables on or off")
    vt_commands = vt.add_subparsers(dest="versioning_command", metavar="ACTION", required=True)
    vt_enable = vt_commands.add_parser("enable", help="version a table (or 'features': model 1 and all feature classes)")
    vt_enable.add_argument("table", help="name or schema.name, or 'features'")
    vt_enable.add_argument("--key", help="column holding the object key")
    vt_enable.add_argument("--class", dest="object_class", help="object class")
    vt_enable.add_argument("--order", type=_INT4, default=0, help="iudorder within the object class (default 0)")
    vt_enable.add_argument("--shortname", help="name in conflict reports (default: the table name)")
    vt_enable.set_defaults(handler=cmd_versioning_enable)
    vt_disable = vt_commands.add_parser("disable", help="make a versioned table plain again with DEFAULT's rows")
    vt_disable.add_argument("table", help="name or schema.name, or 'features'")
    vt_disable.add_argument("--force", action="store_true", help="even if versions other than DEFAULT changed it")
    vt_disable.set_defaults(handler=cmd_versioning_disable)
    vt_list = vt_commands.add_parser("list", help="list the versioned tables")
    vt_list.set_defaults(handler=cmd_versioning_list)

    local = commands.add_parser("local", help="the local PostgreSQL server tgsis runs by itself")
    local_commands = local.add_subparsers(dest="local_command", metavar="ACTION", required=True)
    local_start = local_commands.add_parser("start", help="start it and keep it running")
    local_start.set_defaults(handler=cmd_local_start)
    local_stop = local_commands.add_parser("stop", help="stop it")
    local_stop.add_argument("--force", action="store_true", help="stop it even while other tgsis commands use it")
    local_stop.set_defaults(handler=cmd_local_stop)
    local_status = local_commands.add_parser("status", help="where it is and whether it runs (exit 3: stopped)")
    local_status.set_defaults(handler=cmd_local_status)
    local_dsn = local_commands.add_parser("dsn", help="print its connection string")
    local_dsn.set_defaults(handler=cmd_local_dsn)
    return parser


def _configure_logging(verbose: int, quiet: bool) -> None:
    level = logging.ERROR if quiet else (logging.WARNING, logging.INFO, logging.DEBUG)[min(verbose, 2)]
    if env := os.environ.get("TGSIS_LOG_LEVEL"):
        level = logging.getLevelName(env.upper()) if isinstance(logging.getLevelName(env.upper()), int) else level
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)


def _exit_on_sigterm(signum: int, frame: object) -> NoReturn:
    # SystemExit runs atexit handlers, which stop a local server we started.
    sys.exit(128 + signum)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``tgsis`` command; return its exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    _configure_logging(args.verbose, args.quiet)
    signal.signal(signal.SIGTERM, _exit_on_sigterm)
    handler: Handler = args.handler
    try:
        with warnings.catch_warnings():
            # objects a reader skipped (any command that reads files): one line each, not a Python warning dump
            shown = warnings.showwarning

            def one_line(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                         file: Any = None, line: str | None = None) -> None:
                if issubclass(category, SkippedObjectWarning):
                    print(f"tgsis: warning: {message}", file=sys.stderr)
                else:
                    shown(message, category, filename, lineno, file, line)

            warnings.showwarning = one_line
            return handler(args)
    except Error as exc:
        if isinstance(exc, NotVersionedError):  # the hint in this interface's words
            exc.hint = ("tgsis versioning enable features, to write features in versions; or work in DEFAULT "
                        "(--in DEFAULT, or tgsis version goto DEFAULT)")
        print(f"tgsis: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("tgsis: interrupted", file=sys.stderr)
        return 130
    finally:
        release_local_server()


if __name__ == "__main__":
    sys.exit(main())
