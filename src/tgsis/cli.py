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
import re
import shlex
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
from tgsis.db.install import install, installation_status, installed_version, uninstall
from tgsis.db.local import LocalServer, find_binaries
from tgsis import clihints, clistate, cliout
from tgsis.db import versions as V
from tgsis.db.classes import PropertyKind, add_property, drop_property, fill_property_rows, rename_property
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
from tgsis.db.sqlsource import ExtensionSources
from tgsis.errors import (Error, FileFormatError, InstallationError, InvalidGeometryError, InvalidInputError,
                          MissingPrivilegeError, NotFoundError, PolygonsSplitWarning, SkippedObjectWarning)
from tgsis.mesh import GeometryCollection, Geotype, Mesh, MeshReport, Surface
from tgsis.temporal import even_times

__all__ = ["main", "build_parser"]

Handler = Callable[[argparse.Namespace], int]


def _out(text: str) -> None:
    cliout.out(text)


def _json(args: argparse.Namespace) -> bool:
    """Whether the command prints one JSON document (``--json``) instead of lines for people."""
    return bool(getattr(args, "json", False))


def _table(args: argparse.Namespace, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> None:
    """Tab-separated rows under a header line (``--no-header`` leaves it out)."""
    cliout.table(header, rows, header_shown=not getattr(args, "no_header", False))


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
        _out(f"tgsis {result.version} is already installed ({result.method})"
             + (": nothing to do" if not result.steps else ""))
    elif result.action == "upgraded":
        _out(f"upgraded tgsis {result.previous_version} -> {result.version} ({result.method})")
    else:
        _out(f"installed tgsis {result.version} ({result.method})")
    for step in result.steps:
        _out(f"  {step}")
    for statement in result.still_needed:
        _out(f"still needed: a DBA runs `{statement}` (tgsis's owner registers classes and versions features "
             "as a member of tgsis_admin)")
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
        status = installation_status(conn)
        server = conn.execute("SELECT version()").fetchone()
        db = conn.info.dbname
    current = status.installed
    if _json(args):
        cliout.emit_json({"database": db, "source": target.source, "server": server[0] if server else None,
                          "tgsis": current.version if current else None,
                          "method": current.method if current else None,
                          "fingerprint": current.fingerprint if current else None,
                          "client": status.client_version, "client_fingerprint": status.client_fingerprint,
                          "missing_storage": list(status.missing_storage), "state": status.state,
                          "problem": status.problem, "fix": status.fix})
        return 0 if status.ok else 1
    _out(f"database: {db} (from {target.source})")
    _out(f"server:   {server[0] if server else '?'}")
    fingerprint = ("unknown: this role may not read tgsis.installation" if current and current.fingerprint is None
                   else (current.fingerprint if current else None) or "none recorded")
    installed = f"{current.version} ({current.method}, fingerprint {fingerprint})" if current else "not installed"
    _out(f"tgsis:    {installed}")
    _out(f"client:   {status.client_version} (fingerprint {status.client_fingerprint})")
    if status.missing_storage:
        _out(f"storage:  missing {len(status.missing_storage)} table(s): {', '.join(status.missing_storage)}")
    if status.ok:
        _out("state:    up to date")
    else:
        _out(f"state:    {status.state}: {status.problem}")
        _out(f"{'upgrade' if status.state == 'upgrade' else 'fix'}: {status.fix}")
    return 0 if status.ok else 1


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


def _require_this_build(conn: psycopg.Connection[Any]) -> None:
    """Refuse to work on a database whose tgsis is another version (or, when recorded, another build) than this
    client's, naming both and the command that fixes it, before the command meets a missing function or column."""
    current = installed_version(conn)
    if current is None:
        return  # the command says what it misses (tgsis db install)
    sources = ExtensionSources.default()
    if current.version == sources.version and current.fingerprint in (None, sources.fingerprint):
        return  # (no fingerprint: a role that may not read tgsis.installation; db status tells)
    status = installation_status(conn, sources=sources)
    if not status.ok and status.state != "storage missing":
        raise InstallationError(status.problem or status.state, hint=status.fix)


@contextlib.contextmanager
def _connect(args: argparse.Namespace) -> Iterator[psycopg.Connection[Any]]:
    """A connection working in the chosen version, or looking at VERSION@REVISION (DEFAULT when none is chosen)."""
    with connect(args.dsn) as conn:
        _require_this_build(conn)
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
    if _json(args):
        cliout.emit_json({"cluster": str(server.root), "binaries": server.binaries.describe(),
                          "status": "running" if running else "stopped" if server.is_initialized() else "not created",
                          "pid": server.pid() if running else None,
                          "started_by": (server.started_by() or "outside tgsis") if running else None,
                          "dsn": server.dsn("tgsis")})
        return 0 if running else 3
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


def _cell_properties(items: Sequence[str] | None, flag: str = "--property") -> list[Property]:
    """``--property NAME:TYPE[:SIZE][:VERTEX|CELL]`` items: a vector of SIZE components, an alignment of its own."""
    result = []
    for item in items or []:
        name, _, rest = item.partition(":")
        words = rest.split(":") if rest else []
        if not name or not words or not words[0] or len(words) > 3:
            raise InvalidInputError(f"{flag} {item!r} must be NAME:TYPE[:SIZE][:VERTEX|CELL], e.g. porosity:float8, "
                                    "slip:float8:3 or facies:int:CELL")
        size, alignment = 1, None
        for word in words[1:]:
            if word.upper() in ("VERTEX", "CELL") and alignment is None:
                alignment = word.upper()
            elif word.isdigit() and size == 1:
                size = int(word)
            else:
                raise InvalidInputError(f"{flag} {item!r}: {word!r} is neither a number of components nor "
                                        "VERTEX or CELL", hint=f"e.g. {flag} slip:float8:3:CELL")
        result.append(Property(name, words[0], size, alignment))  # type: ignore[arg-type]
    return result


def cmd_class_create(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        fc = create_feature_class(
            conn, args.name, args.geotype, feature_properties=_pairs(args.feature_property, "--feature-property"),
            cell_properties=_cell_properties(args.property), alignment=args.alignment.upper(), srs=args.srs,
            schema=args.schema, description=args.description, time_model=args.time_model, time_unit=args.time_unit,
            instant_properties=_pairs(args.instant_property, "--instant-property"), cell_level=args.cell_level,
            versioned=False if args.no_versioning else None)
    pros = f", {fc.protable}" if fc.protable else ""
    other = f", {fc.otherprotable}" if fc.otherprotable else ""
    _out(f"created feature class {fc.name} ({fc.geotype.value}{_time_label(fc)}) in schema {fc.schema}: "
         f"tables {fc.featuretable}, {fc.cellprotable}{other}{pros}, view {fc.viewname}"
         + ("" if fc.versioned else "; without versioning: one state in every version, written in DEFAULT"))
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
    if _json(args):
        cliout.emit_json({"classes": [{
            "name": fc.name, "geotype": fc.geotype.value, "srs": fc.srs, "schema": fc.schema,
            "alignment": fc.alignment, "time_model": fc.time_model, "time_unit": fc.time_unit,
            "description": fc.description, "versioned": fc.versioned,
            "feature_properties": [{"name": p.name, "type": p.type} for p in fc.feature_properties],
            "properties": [{"name": p.name, "type": p.type, "size": p.size, "alignment": p.alignment or fc.alignment}
                           for p in fc.cell_properties],
            "instant_properties": [{"name": p.name, "type": p.type} for p in fc.instant_properties]}
            for fc in classes]})
        return 0
    rows = []
    for fc in classes:
        fprops = ", ".join(f"{p.name} {p.type}" for p in fc.feature_properties) or "-"
        cprops = ", ".join(f"{p.name} {p.type}{f'[{p.size}]' if p.size > 1 else ''}"
                           f"{f' ({p.alignment.lower()})' if p.alignment else ''}" for p in fc.cell_properties) or "-"
        iprops = ", ".join(f"{p.name} {p.type}" for p in fc.instant_properties) or "-"
        rows.append((fc.name, fc.geotype.value, fc.srs, fc.schema, fc.time_model.lower()
                     + (f" in {fc.time_unit}" if fc.time_unit else ""), fprops, f"{fc.alignment.lower()}: {cprops}",
                     iprops if fc.time_model != "STATIC" else "-"))
    _table(args, ("class", "geotype", "srs", "schema", "time", "feature properties", "properties",
                  "per-instant properties"), rows)
    if not classes:
        print("no feature classes", file=sys.stderr)
    return 0


def cmd_class_drop(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        deleted = drop_feature_class(conn, args.name, force=args.force)
    _out(f"dropped feature class {args.name}" + (f" and its {deleted} feature(s)" if deleted else ""))
    return 0


def _with_default(item: str) -> tuple[str, str | None]:
    """``NAME:TYPE...=VALUE``: the property part and the default value (None without ``=``)."""
    spec, sep, value = item.partition("=")
    return spec, (value if sep else None)


def _property_ref(text: str) -> tuple[str, PropertyKind | None]:
    """``NAME`` or ``KIND:NAME`` (feature, cell, instant: which property when a class has two of that name)."""
    kind, sep, name = text.partition(":")
    if not sep:
        return text, None
    if kind not in ("feature", "cell", "instant") or not name:
        raise InvalidInputError(f"property {text!r} must be NAME or KIND:NAME with KIND feature, cell or instant")
    return name, kind  # type: ignore[return-value]


def _properties_json(fc: FeatureClass) -> dict[str, Any]:
    return {"feature_properties": [{"name": p.name, "type": p.type} for p in fc.feature_properties],
            "properties": [{"name": p.name, "type": p.type, "size": p.size, "alignment": p.alignment or fc.alignment}
                           for p in fc.cell_properties],
            "instant_properties": [{"name": p.name, "type": p.type} for p in fc.instant_properties]}


def _stored_count(conn: psycopg.Connection[Any], fc: FeatureClass, kind: str, prop: Property | tuple[str, str],
                  ) -> tuple[int, int, str]:
    """How many rows the working version reads with a new property: (rows, geometries, what a row is)."""
    if kind == "feature":
        table, what = fc.featuretable, "feature"
    elif kind == "instant":
        table, what = fc.protable or fc.featuretable, "instant row"
    else:
        alignment = prop.alignment if isinstance(prop, Property) and prop.alignment else fc.alignment
        table, what = fc.property_table(alignment) or fc.cellprotable, f"{alignment.lower()} row"
    row = conn.execute(psycopg_sql.SQL("SELECT count(*), count(DISTINCT _geoid) FROM {}").format(
        fc.qualified(table))).fetchone()
    assert row is not None
    return int(row[0]), int(row[1]), what


def _value_pairs(items: Sequence[str] | None, flag: str) -> dict[str, str]:
    """``NAME=VALUE`` items (repeatable flag)."""
    values: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InvalidInputError(f"{flag} {item[:200]!r} must be NAME=VALUE", hint=f"e.g. {flag} porosity=0.2")
        values[name] = value
    return values


def _shown_value(value: str, typename: str) -> str:
    """A default as output shows it: a number as it is, any other value quoted as an SQL literal."""
    numeric = re.match(r"(small|big)?int|integer|float|double|real|numeric|decimal", typename.strip().lower())
    return value if numeric else "'" + value.replace("'", "''") + "'"


def cmd_class_alter(args: argparse.Namespace) -> int:
    fills = _value_pairs(args.fill_property, "--fill-property")
    drops = [_property_ref(name) for name in args.drop_property or []]
    renames = [(*_property_ref(old), new) for old, new in args.rename_property or []]
    adds: list[tuple[PropertyKind, Property | tuple[str, str], str | None]] = []
    for item in args.add_feature_property or []:
        spec, default = _with_default(item)
        adds.extend(("feature", pair, default) for pair in _pairs([spec], "--add-feature-property"))
    for item in args.add_property or []:
        spec, default = _with_default(item)
        adds.extend(("cell", prop, default) for prop in _cell_properties([spec], "--add-property"))
    for item in args.add_instant_property or []:
        spec, default = _with_default(item)
        adds.extend(("instant", pair, default) for pair in _pairs([spec], "--add-instant-property"))
    if not (fills or drops or renames or adds):
        raise InvalidInputError("tgsis class alter needs a change",
                                hint="give --add-property, --add-feature-property, --add-instant-property, "
                                     "--rename-property, --drop-property or --fill-property")
    changes: list[dict[str, Any]] = []
    with _connect(args) as conn, conn.transaction():   # every change or none
        fc = get_feature_class(conn, args.name)
        if fills:
            for table, (geometries, rows) in fill_property_rows(conn, args.name, fills).items():
                changes.append({"op": "fill", "table": table, "geometries": geometries, "rows": rows, "values": fills})
        for name, kind in drops:
            fc = drop_property(conn, args.name, name, kind=kind, force=args.force)
            changes.append({"op": "drop", "property": name, "kind": kind})
        for old, kind, new in renames:
            fc = rename_property(conn, args.name, old, new, kind=kind)
            changes.append({"op": "rename", "property": old, "kind": kind, "to": new})
        for kind, prop, default in adds:
            fc = add_property(conn, args.name, prop, kind=kind, default=default)
            name, typename = (prop.name, prop.type) if isinstance(prop, Property) else prop
            rows, geometries, what = _stored_count(conn, fc, kind, prop)
            changes.append({"op": "add", "property": name, "kind": kind, "default": default, "type": typename,
                            "stored_rows": rows if default is not None else 0,
                            "stored_geometries": geometries if default is not None else 0, "row": what})
        # the rows were counted as the session's version reads them; add_property gave every version's rows the default
        version = V.working_version(conn)
        others = conn.execute("SELECT count(*) > 1 FROM tgsis.versions").fetchone()
        in_versions = (f" as version {V.show_name(version)} reads them; every version's rows got it"
                       if others and others[0] else "")
    if _json(args):
        cliout.emit_json({"class": fc.name, "changes": changes, **_properties_json(fc)})
        return 0
    members = fc.geotype is Geotype.GEOMETRYCOLLECTION
    for change in changes:
        what = f"{change['kind']} property " if change.get("kind") else "property "
        if change["op"] == "fill":
            _out(f"filled {change['table']}: {change['rows']} row(s) of {change['geometries']} "
                 f"{'member(s)' if members else 'feature(s)'} that had none, in every version")
        elif change["op"] == "drop":
            _out(f"dropped {what}{change['property']}")
        elif change["op"] == "rename":
            _out(f"renamed {what}{change['property']} to {change['to']}")
        elif change["default"] is None:
            _out(f"added {what}{change['property']}")
        else:
            default = _shown_value(change["default"], change["type"])
            if change["stored_rows"] == 0 and not in_versions:
                got = f"no stored rows, none got the default {default} (it is not kept: new rows give their own values)"
            elif change["kind"] == "feature":
                got = f"{change['stored_rows']} feature(s) got the default {default}{in_versions}"
            else:
                got = (f"{change['stored_rows']} {change['row']}(s) of {change['stored_geometries']} "
                       f"{'member(s)' if members else 'feature(s)'} got the default {default}{in_versions}")
            _out(f"added {what}{change['property']}: {got}")
    cprops = ", ".join(f"{p.name} {p.type}{f'[{p.size}]' if p.size > 1 else ''}"
                       f"{f' ({p.alignment.lower()})' if p.alignment else ''}" for p in fc.cell_properties) or "-"
    _out(f"feature class {fc.name}: feature properties "
         f"{', '.join(f'{p.name} {p.type}' for p in fc.feature_properties) or '-'}; "
         f"{fc.alignment.lower()} properties {cprops}"
         + (f"; per-instant properties {', '.join(f'{p.name} {p.type}' for p in fc.instant_properties) or '-'}"
            if fc.time_model != "STATIC" else ""))
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
        warnings.simplefilter("always", PolygonsSplitWarning)
        meshes = formats.read(args.file, format=args.format)
    for warning in caught:
        if issubclass(warning.category, PolygonsSplitWarning):
            print(f"tgsis: warning: {warning.message}", file=sys.stderr)
        elif not issubclass(warning.category, SkippedObjectWarning):
            warnings.warn_explicit(warning.message, warning.category, warning.filename, warning.lineno)
    skipped = [w.message for w in caught if isinstance(w.message, SkippedObjectWarning)]
    if skipped and args.strict:
        what = "; ".join(f"GOCAD {w.object_type} object{f' {w.name!r}' if w.name else ''} at line {w.line}"
                         + (f" (its {', '.join(w.skipped)})" if w.skipped else "") for w in skipped)
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


def _features_named(conn: Any, fc: FeatureClass, name: str) -> list[int]:
    """The features of class ``fc`` named ``name`` (as the session's version sees them), after taking the name's lock.

    The lock (a transaction-level advisory lock on class and name) makes two
    imports of one name take turns: the second sees the first's feature once
    it is committed, so that it warns, or replaces it with ``--replace``,
    instead of both adding a feature of that name.
    """
    conn.execute("SELECT pg_advisory_xact_lock(hashtextextended(%s, 0))",
                 (f"tgsis import: {fc.schema}.{fc.featuretable}: {name}",))
    return [int(r[0]) for r in conn.execute(
        psycopg_sql.SQL("SELECT g.geoid FROM {}.{} f JOIN tgsis.geometry g ON g.geoid = f._geoid "
                        "WHERE g.geoname = %s ORDER BY g.geoid").format(
            psycopg_sql.Identifier(fc.schema), psycopg_sql.Identifier(fc.featuretable)), (name,)).fetchall()]


def _replaced_one(fc: FeatureClass, name: str, same: Sequence[int]) -> int | None:
    """The feature ``--replace`` replaces: the one of that name, none, or an error when there are several."""
    if len(same) > 1:
        raise InvalidInputError(f"--replace: class {fc.name} has {len(same)} features named {name!r} "
                                f"({', '.join(map(str, same))}): which one to replace is not clear",
                                hint=f"tgsis ls --class {fc.name} lists them; import with --name to store it under "
                                     "another name")
    return same[0] if same else None


def _warn_same_name(fc: FeatureClass, name: str, same: Sequence[int]) -> None:
    ids = ", ".join(map(str, same))
    print(f"tgsis: warning: class {fc.name} already has a feature named {name!r} ({'id' if len(same) == 1 else 'ids'} "
          f"{ids}): this import adds another one; --replace replaces it", file=sys.stderr)


def _report_json(report: MeshReport) -> dict[str, Any]:
    return {"duplicate_vertices": len(report.duplicate_vertices), "degenerate_cells": len(report.degenerate_cells),
            "summary": report.summary()}


def _import_instant(args: argparse.Namespace, conn: psycopg.Connection[Any], fc: FeatureClass, meshes: list[Mesh],
                    values: dict[str, Any]) -> int:
    """``tgsis import FILE --class C --at T [--feature ID]``: a surface of a model-2 class at model time T."""
    from tgsis.db.temporal import add_instant, instants
    from tgsis.temporal import SurfaceSeries

    if fc.time_model != "INSTANTS":
        raise InvalidInputError(f"--at and --feature take a class of surfaces at instants (INSTANTS); {fc.name} is "
                                f"{fc.time_model}", hint="tgsis interpolate --class CLASS builds evolving surfaces")
    if args.at is None:
        raise InvalidInputError(f"feature class {fc.name} holds surfaces at instants: give --at T, the model time of "
                                "the file's surface")
    if not math.isfinite(args.at):
        raise InvalidInputError(f"--at must be a finite model time, got {args.at!r}")
    if args.replace:
        raise InvalidInputError("--replace does not go with --at: the instant is new (tgsis import --at T --feature ID "
                                "adds it)")
    if len(meshes) != 1 or not isinstance(meshes[0], Surface):
        raise InvalidInputError(f"{args.file} holds {len(meshes)} object(s) ({', '.join(type(m).__name__ for m in meshes)}): "
                                "an instant is one surface", hint="write the surface of that instant to a file of its own")
    surface = meshes[0]
    if args.feature is not None:
        if values:
            raise InvalidInputError("--set does not go with --feature: the feature's properties stay")
        if args.alive:
            raise InvalidInputError("--alive does not go with --feature: the feature keeps whether it is alive "
                                    "(set when it was stored)")
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
    if _json(args):
        cliout.emit_json({"file": args.file, "class": fc.name, "id": fid, "at": args.at, "instants": known,
                          "vertices": surface.n_vertices, "cells": surface.n_cells})
    else:
        _out(f"stored feature {fid} ({fc.name}) at t = {cliout.show_time(args.at)}{_unit(fc)}: {surface.n_vertices} "
             f"vertices, {surface.n_cells} triangles; its instants: {', '.join(cliout.show_time(t) for t in known)}")
    return 0


def cmd_import(args: argparse.Namespace) -> int:
    from tgsis.db.checkin import save_feature
    from tgsis.db.features import delete_feature

    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise InvalidInputError(f"--tolerance must be a finite number >= 0, got {args.tolerance}")
    meshes = _read_for_import(args)
    reports = [_import_report(mesh, args.tolerance) for mesh in meshes]
    if args.reject_flagged:
        _check_flagged(args.file, meshes, reports)
    values = _feature_values(args.set)
    stem = Path(args.file).stem
    header = ("id", "name", "geotype", "vertices", "cells", "replaced", "defects")
    with _connect(args) as conn:
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
                with cliout.busy(f"uploading {collection.n_vertices} vertices"):
                    if old is not None:
                        delete_feature(conn, fc, old)
                    fid = insert_feature(conn, fc, collection, values, drop_extra_properties=args.drop_extra_properties)
            if same and not args.replace:
                _warn_same_name(fc, collection.name or "", same)
            members: list[dict[str, Any]] = [
                {"index": i, "name": mesh.name, "geotype": mesh.geotype.value, "vertices": mesh.n_vertices,
                 "cells": mesh.n_cells, "cell_name": type(mesh).cell_name, "defects": _report_json(report)}
                for i, (mesh, report) in enumerate(zip(meshes, reports))]
            if _json(args):
                cliout.emit_json({"file": args.file, "class": fc.name, "features": [{
                    "id": fid, "name": collection.name, "geotype": collection.geotype.value,
                    "vertices": collection.n_vertices, "cells": collection.n_cells, "replaced": old,
                    "same_name": [] if args.replace else same, "members": members}]})
                return 0
            _table(args, header, [(fid, collection.name, collection.geotype.value, collection.n_vertices,
                                   collection.n_cells, old if old is not None else "", f"{len(collection)} members")])
            for m in members:  # under the collection's line, one per member
                _out(f"\tmember {m['index']}\t{m['name'] or ''}\t{m['geotype']}\t{m['vertices']}\t{m['cells']}\t"
                     f"\t{m['defects']['summary']}")
            return 0
        if args.name and len(meshes) > 1:
            raise InvalidInputError(f"{args.file} holds {len(meshes)} objects: --name names only one",
                                    hint="import into a GEOMETRYCOLLECTION class to store them as one feature")
        names = [args.name or mesh.name or stem for mesh in meshes]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice and args.replace:
            raise InvalidInputError(f"--replace: {args.file} holds several objects named {twice[0]!r}, so which one "
                                    "replaces the stored feature is not clear", hint="import without --replace")
        ids: list[int] = []
        replaced: list[int | None] = []
        warned: list[tuple[str, list[int]]] = []
        with conn.transaction(), cliout.progress("uploading objects", len(meshes), "object") as moved:
            for i, (mesh, name) in enumerate(zip(meshes, names)):  # all objects of the file, or none
                same = _features_named(conn, fc, name)
                old = _replaced_one(fc, name, same) if args.replace else None
                if old is not None:
                    save_feature(conn, fc, old, mesh, values or None, name=name,
                                 drop_extra_properties=args.drop_extra_properties)
                    ids.append(old)
                else:
                    ids.append(insert_feature(conn, fc, mesh, values, name=name,
                                              drop_extra_properties=args.drop_extra_properties))
                    if same:
                        warned.append((name, same))
                replaced.append(old)
                moved(i + 1, len(meshes))
    for name, same in warned:
        _warn_same_name(fc, name, same)
    if _json(args):
        cliout.emit_json({"file": args.file, "class": fc.name, "features": [{
            "id": fid, "name": name, "geotype": mesh.geotype.value, "vertices": mesh.n_vertices, "cells": mesh.n_cells,
            "cell_name": type(mesh).cell_name, "defects": _report_json(report), "replaced": old,
            "same_name": next((same for n, same in warned if n == name), [])}
            for fid, name, mesh, report, old in zip(ids, names, meshes, reports, replaced)]})
        return 0
    _table(args, header, [(fid, name, mesh.geotype.value, mesh.n_vertices, mesh.n_cells,
                           old if old is not None else "", report.summary())
                          for fid, name, mesh, report, old in zip(ids, names, meshes, reports, replaced)])
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
        with cliout.busy(f"downloading feature {args.id}"):
            feature = fetch_feature(conn, fc, args.id)
        assert feature.mesh is not None
        if args.png and not isinstance(feature.mesh, Surface):     # refused before any file is written
            raise InvalidInputError(f"feature {args.id} is no surface: --png draws surfaces")
        with cliout.busy(f"writing {args.file}"):
            formats.write(feature.mesh, args.file, format=args.format)
        members = f" in {len(feature.mesh)} members" if isinstance(feature.mesh, GeometryCollection) else ""
        _out(f"wrote feature {feature.id} ({fc.name}, {feature.mesh.n_vertices} vertices{members}) to {args.file}")
        if args.png:
            _picture_of(conn, [args.id], None, args.png, title=f"feature {args.id} ({fc.name}) {feature.mesh.name or ''}")
    return 0


def _sizes_in_time(conn: psycopg.Connection[Any], time_model: str, geoid: int) -> str | None:
    """How many vertices and cells one shape of a surface in time has (model 2: per instant, model 3: per topology
    period), where tgsis.geometry adds up the rows of every instant or period; None for other models."""
    if time_model == "INSTANTS":
        counts = conn.execute(
            "SELECT (SELECT array_agg(n ORDER BY t) FROM (SELECT times, count(*) FROM tgsis.times_vrtx WHERE geoid = %s"
            "        GROUP BY times) AS v(t, n)),"
            "       (SELECT array_agg(n ORDER BY t) FROM (SELECT times, count(*) FROM tgsis.times_trgl WHERE geoid = %s"
            "        GROUP BY times) AS c(t, n)), (SELECT count(*) FROM tgsis.times WHERE geoid = %s)",
            (geoid, geoid, geoid)).fetchone()
        each, unit = "per instant", "instants"
    elif time_model == "EVOLVING":
        counts = conn.execute(
            "SELECT (SELECT array_agg(n ORDER BY t) FROM (SELECT timem, count(*) FROM tgsis.node WHERE geoid = %s"
            "        GROUP BY timem) AS v(t, n)),"
            "       (SELECT array_agg(n ORDER BY t) FROM (SELECT timem, count(*) FROM tgsis.d4dtrgl WHERE geoid = %s"
            "        GROUP BY timem) AS c(t, n)), (SELECT count(DISTINCT timem) FROM tgsis.node WHERE geoid = %s)",
            (geoid, geoid, geoid)).fetchone()
        each, unit = "per topology period", "periods"
    else:
        return None
    if counts is None or not counts[0]:
        return None
    vertices, cells, k = list(counts[0]), list(counts[1] or [0]), int(counts[2])
    if min(vertices) == max(vertices) and min(cells) == max(cells):
        return f"{vertices[0]} vertices, {cells[0]} cells " + (
            f"at each of its {k} {unit}" if unit == "instants" else f"in each of its {k} {unit}")
    return f"{min(vertices)} to {max(vertices)} vertices, {min(cells)} to {max(cells)} cells {each} ({k} {unit})"


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
        sizes = _sizes_in_time(conn, fc.time_model, args.id)
        here = working_version(conn)
        versioned = fc.versioned and conn.execute(
            "SELECT EXISTS (SELECT FROM tgsis.versioned_tables WHERE objectclass = 'feature')").fetchone() == (True,)
        differs = []
        differing: list[dict[str, Any]] = []
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
                        differs.append(f"{V.show_name(version.name)} ({what})")
                        differing.append({"version": version.name,
                                          "what": what if what in ("only there", "not there") else "differs",
                                          "rows": sum(d.added + d.removed + d.changed for d in changed)})
        conn.rollback()
    name, geotype, nvrtx, ncell, members, timemodel, alive = row[:7]
    found = feature.mesh if feature is not None else None
    mesh = found if isinstance(found, Mesh) else None
    plain = mesh is not None
    if _json(args):
        cliout.emit_json({
            "id": args.id, "name": name, "class": fc.name, "geotype": geotype, "time_model": fc.time_model,
            "time_unit": fc.time_unit, "version": here, "vertices": nvrtx, "cells": ncell, "members": members,
            "box": None if row[7] is None else {axis: [row[7 + 2 * i], row[8 + 2 * i]] for i, axis in enumerate("xyz")},
            "lifespan": None if span is None else {"first": span[0], "last": span[1], "alive": span[2]},
            "instants": [{"t": t, "topology": starts} for t, starts in steps],
            "properties": properties, "instant_properties": [p.name for p in fc.instant_properties],
            "vertex_properties": list(mesh.vertex_properties) if plain and mesh is not None else [],
            "cell_properties": list(mesh.cell_properties) if plain and mesh is not None else [],
            "versioned": versioned, "differs_in": differing if versioned else None})
        return 0
    _out(f"feature {args.id}: {name or '(no name)'}, class {fc.name} ({geotype}{_time_label(fc)}), "
         f"in version {V.show_name(here)}")
    _out(f"  {sizes or f'{nvrtx} vertices, {ncell} cells'}" + (f", {members} members" if members is not None else ""))
    if row[7] is not None:
        _out("  box: " + ", ".join(f"{axis} [{row[7 + 2 * i]!r}, {row[8 + 2 * i]!r}]" for i, axis in enumerate("xyz")))
    if span is None:
        _out("  static: the same at every time")
    else:
        topology = [t for t, starts in steps if starts]
        _out(f"  exists from t = {cliout.show_time(span[0])} to {cliout.show_time(span[1])}{_unit(fc)}"
             + (" and after (alive)" if span[2] else "")
             + f"; {len(steps)} instants, topology (re)defined at {', '.join(cliout.show_time(t) for t in topology)}")
    if properties:
        _out("  properties: " + ", ".join(f"{k} = {v!r}" for k, v in properties.items()))
    if fc.instant_properties:
        _out("  per-instant properties: " + ", ".join(p.name for p in fc.instant_properties))
    if plain and mesh is not None:
        if mesh.vertex_properties:
            _out("  vertex properties: " + ", ".join(mesh.vertex_properties))
        if mesh.cell_properties:
            _out("  cell properties: " + ", ".join(mesh.cell_properties))
    if versioned:
        _out("  versions where it differs from " + V.show_name(here) + ": " + (", ".join(differs) if differs else "none"))
    elif not fc.versioned:
        _out(f"  class {fc.name} is not versioned: every version sees this state")
    return 0


def cmd_query(args: argparse.Namespace) -> int:
    from tgsis.db.temporal import class_property_periods

    if math.isnan(args.value):
        raise InvalidInputError("VALUE must be a number, got nan", hint="-inf and inf are allowed")
    with _connect(args) as conn:
        found = class_property_periods(conn, args.feature_class, args.property, args.op, args.value,
                                       convention=args.convention)
    if _json(args):
        cliout.emit_json({"class": args.feature_class, "property": args.property, "op": args.op, "value": args.value,
                          "convention": args.convention, "features": [
                              {"id": fid, "first": {"t": periods[0].start, "right_after": not periods[0].start_closed},
                               "periods": [{"start": p.start, "end": p.end, "start_closed": p.start_closed,
                                            "end_closed": p.end_closed} for p in periods]}
                              for fid, periods in found.items()]})
        return 0
    if args.first:
        _table(args, ("id", "first", "when"), [
            (fid, cliout.show_time(periods[0].start), "" if periods[0].start_closed else "(right after it)")
            for fid, periods in found.items()])
    else:
        _table(args, ("id", "periods"), [(fid, " ".join(str(p) for p in periods)) for fid, periods in found.items()])
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
    # a G-map's geometry row counts its darts where other geometries count cells (tgsis gmap cells counts its cells)
    def darts(geotype: str, ncell: int) -> tuple[int | None, int | None]:
        return (None, ncell) if geotype == "GMAP" else (ncell, None)

    if _json(args):
        cliout.emit_json({"features": [{"id": geoid, "class": cls, "name": name, "geotype": geotype, "vertices": nvrtx,
                                        "cells": darts(geotype, ncell)[0], "members": nmembers,
                                        "darts": darts(geotype, ncell)[1]}
                                       for cls, geoid, name, geotype, nvrtx, ncell, nmembers in rows]})
        return 0
    _table(args, ("id", "class", "name", "geotype", "vertices", "cells", "members", "darts"),
           [(geoid, cls, name or "", geotype, nvrtx, *("" if n is None else n for n in darts(geotype, ncell)[:1]),
             "" if nmembers is None else nmembers, *("" if n is None else n for n in darts(geotype, ncell)[1:]))
            for cls, geoid, name, geotype, nvrtx, ncell, nmembers in rows])
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

    with _connect(args) as conn, cliout.busy(f"downloading feature {args.id}"):
        co = checkout(conn, args.id, args.feature_class)
    formats.write(co.mesh, args.file, format=args.format)
    written = formats.read_one(args.file, format=args.format)
    if not np.array_equal(written.vertices, co.mesh.vertices):  # the format must keep every bit of the base
        raise InvalidInputError(f"{args.file}: the format does not keep the coordinates exactly, so a check-in "
                                "would see every vertex as moved", hint="use .ts (GOCAD) or .vtu (VTK)")
    side = co.save(_checkout_file(args.file))
    _out(f"checked out feature {co.token.feature_id} ({co.token.feature_class}, {co.mesh.n_vertices} vertices, "
         f"{co.mesh.n_cells} {type(co.mesh).cell_name}s) of version {V.show_name(co.token.version)} at revision "
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
    with connect(args.dsn) as conn, cliout.busy("checking in"):  # the check-out's version, whatever version commands work in now
        _require_this_build(conn)
        result = checkin(conn, co, edited, _feature_values(args.set) or None, name=args.name,
                         tolerance=args.tolerance, on_conflict=args.on_conflict, child_version=args.child_version,
                         keep=not args.no_keep, drop_extra_properties=args.drop_extra_properties)
    save = result.save
    if result.checkout is not None and not result.conflict:  # before anything is printed (a reader may go away)
        result.checkout.save(side)
    counts = save.diff.counts()
    moved = save.vertices_moved
    child = shlex.quote(save.version)  # the commands are pasted into a shell: a free-text name stays one argument
    commands = ([f"tgsis version conflicts {child} --rows",
                 f"tgsis version resolve {child} feature {save.feature_id} parent|child|manual",
                 f"tgsis version merge {child} --remove"] if result.conflict else [])
    if args.png and isinstance(edited, Surface):
        from scipy.spatial import cKDTree

        from tgsis import pictures

        # how far each vertex lies from the checked-out shape: 0 for the ones kept
        distance = cKDTree(co.mesh.vertices).query(edited.vertices)[0]
        distance[save.diff.vertex_map >= 0] = 0.0
        pictures.scene([edited], args.png, colour=[distance], colour_label="moved from the check-out (m)",
                       title=f"feature {save.feature_id} checked in to {save.version}")
    if _json(args):
        cliout.emit_json({
            "feature_id": save.feature_id, "version": save.version, "conflict": result.conflict,
            "vertices": {"kept": counts["vertices_kept"], "moved": moved,
                         "removed": counts["vertices_removed"] - moved, "added": counts["vertices_added"] - moved},
            "cells": {"kept": counts["cells_kept"] + save.cells_on_moved, "removed": save.cells_removed,
                      "added": save.cells_added, "on_moved_vertices": save.cells_on_moved},
            "rows": {"written": save.rows_written, "deleted": save.rows_deleted, "inserted": save.rows_inserted,
                     "updated": save.rows_updated},
            "record": str(side) if result.checkout is not None and not result.conflict else None,
            "png": args.png, "commands": commands})
        return 0
    _out(f"checked in feature {save.feature_id} into version {V.show_name(save.version)}"
         + (" (a new child version: the feature had changed since check-out)" if result.conflict else ""))
    _out(f"  vertices: {counts['vertices_kept']} kept, {moved} moved, "
         f"{counts['vertices_removed'] - moved} removed, {counts['vertices_added'] - moved} "
         f"added; {type(edited).cell_name}s: {counts['cells_kept'] + save.cells_on_moved} kept"
         + (f" ({save.cells_on_moved} of them on moved vertices)" if save.cells_on_moved else "")
         + f", {save.cells_removed} removed, {save.cells_added} added")  # by content, as they are stored
    _out(f"  rows written: {save.rows_written} ({save.rows_deleted} deleted, {save.rows_inserted} inserted, "
         f"{save.rows_updated} updated)")
    if args.png:
        _out(f"  drew the edit to {args.png}")
    if commands:
        _out(f"  both edits meet as a conflict of {V.show_name(save.version)}: " + "; ".join(commands))
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
    with cliout.progress(f"interpolating {name}", None, "step") as moved:
        result = interpolate(source, target, setup, args.t0, args.t1, name=name, alive=args.alive, progress=moved,
                             split=args.split)
    _out(f"interpolated {name}: {result.source.n_vertices} vertices, {result.source.n_cells} triangles "
         f"({result.source.n_vertices - source.n_vertices} added by cutting and refinement), m = {setup.steps}, "
         f"error to the target {result.error:.3g}")
    _out("  " + ", ".join(f"{stage} {seconds:.2f} s" for stage, seconds in result.timings.items()))
    if args.preview:
        times = np.linspace(args.t0, args.t1, args.frames).tolist()
        paths = write_previews(result.evolving, times, args.preview, stem=Path(args.source).stem)
        _out(f"  {len(paths)} previews in {args.preview}")
    if args.feature_class:
        with _connect(args) as conn, cliout.busy(f"uploading {name}"):
            fid = insert_feature(conn, args.feature_class, result.evolving)
            unit = _unit(get_feature_class(conn, args.feature_class))
        # as the user gave the times (the source may be the later shape), then the span in time order
        _out(f"stored as feature {fid} of class {args.feature_class}: the source ({name}) at t = {args.t0:g}{unit}, "
             f"the target at t = {args.t1:g}{unit}; it exists from t = {min(args.t0, args.t1):g} to "
             f"{max(args.t0, args.t1):g}{unit}" + (" and after (alive)" if args.alive else ""))
    return 0


def cmd_corners(args: argparse.Namespace) -> int:
    from tgsis.interpolation import propose_corners

    if args.count is not None and args.count < 1:
        raise InvalidInputError(f"--count must be >= 1, got {args.count}", hint="leave --count out for every corner")
    if not 0 <= args.min_angle <= 180:  # NaN too
        raise InvalidInputError(f"--min-angle must be from 0 to 180 degrees, got {args.min_angle}")
    surface = _read_surface(args.file, "surface")
    corners = propose_corners(surface, min_angle=args.min_angle, count=args.count)
    if _json(args):
        cliout.emit_json({"file": args.file, "corners": [{"vertex": v, "xyz": surface.vertices[v].tolist()}
                                                         for v in corners.tolist()]})
        return 0
    _out(json.dumps(corners.tolist()))
    for vertex in corners.tolist():
        x, y, z = surface.vertices[vertex].tolist()  # every digit: repr of the float (6 digits are ~10 m in UTM)
        print(f"vertex {vertex}: {x!r} {y!r} {z!r}", file=sys.stderr)
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
    # the file says when the snapshot is: {t} in its name, or a folder's file feature_ID_tT.FORMAT
    file = args.file.replace("{t}", repr(args.time))
    if Path(file).is_dir():
        if not args.format:
            raise InvalidInputError(f"{args.file} is a folder: give --format (e.g. --format vtu) for the file "
                                    f"feature_{args.id}_t{args.time!r}.FORMAT written in it")
        file = str(Path(file) / f"feature_{args.id}_t{args.time!r}.{args.format.lower().lstrip('.')}")
    target = formats.format_for(file, args.format)  # an unknown format fails before connecting
    with _connect(args) as conn:
        fc = class_of_feature(conn, args.id)
        surface = get_at(conn, args.id, args.time, convention=args.convention, properties=True)
        if surface is None:
            raise NotFoundError(f"feature {args.id} ({fc.name}) does not exist at t = {args.time!r}{_unit(fc)}",
                                hint=_life(lifespan(conn, args.id), fc))
        _with_z_convention(conn, args.id, surface)
        # and its name, which GOCAD writes in its header and VTK in its field data (and a legacy file's title)
        surface.name = f"{surface.name or f'feature {args.id}'} at t = {args.time!r}{_unit(fc)}"
        target.write(surface, file)
        _out(f"wrote feature {args.id} ({fc.name}) at t = {args.time!r}{_unit(fc)}: {surface.n_vertices} vertices, "
             f"{surface.n_cells} triangles, to {file}")
        if args.png:
            _picture_of(conn, [args.id, *args.with_ids], args.time, args.png,
                        title=f"feature {args.id} ({fc.name}) at t = {args.time!r}{_unit(fc)} (SQL snapshot)")
    return 0


def _with_z_convention(conn: Any, feature_id: int, surface: Surface) -> None:
    """The snapshot (stored z: elevation) in the z convention its feature was stored with, as an export gives it.

    GOCAD then writes ``ZPOSITIVE`` as the imported file had it; the formats
    without a z convention write elevation whatever it is (tgsis._zpositive).
    """
    from tgsis.db.meaning import restore_meaning

    row = conn.execute("SELECT zpositive FROM tgsis.geometry WHERE geoid = %s", (feature_id,)).fetchone()
    if row is not None and row[0] is not None:
        restore_meaning(surface, row[0], None, None, None)


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
        with cliout.progress("writing frames", args.steps, "frame") as moved:
            written = export_series(conn, args.id, folder / f"{stem}.pvd", start=args.start, end=args.end,
                                    steps=args.steps, convention=args.convention, progress=moved)
    if args.gif:
        from tgsis import pictures

        shown = [(t, [surface]) for t, surface in written.frames if surface is not None]
        first = shown[0][1][0] if shown else None
        same = first is not None and all(s[0].vertices.shape == first.vertices.shape for _, s in shown)
        pictures.animation(shown, args.gif, title=f"feature {args.id} ({fc.name})", time_unit=fc.time_unit or "",
                           reference=[first] if same and first is not None else None,
                           colour_label=f"moved since t = {shown[0][0]!r} (m)" if shown else "")
    times = [t for t, _ in written.frames]
    if _json(args):
        cliout.emit_json({"pvd": str(written.pvd), "feature_id": args.id, "class": fc.name, "time_unit": fc.time_unit,
                          "frames": [{"t": t, "file": str(file), "vertices": surface.n_vertices if surface else None,
                                      "triangles": surface.n_cells if surface else None}
                                     for (t, surface), file in zip(written.frames, written.files)],
                          "missing": len(written.missing), "gif": args.gif})
        return 0
    _table(args, ("t", "file", "vertices", "triangles"), [
        (cliout.show_time(t), file, *((surface.n_vertices, surface.n_cells) if surface
                                      else ("no object (empty grid)", "")))
        for (t, surface), file in zip(written.frames, written.files)])
    missing = f", {len(written.missing)} without the object" if written.missing else ""
    _out(f"wrote {written.pvd}: feature {args.id} ({fc.name}) at {len(times)} times from "
         f"{cliout.show_time(times[0])} to {cliout.show_time(times[-1])}{_unit(fc)}{missing}")
    if args.gif:
        _out(f"drew {len(times)} frames to {args.gif}")
    return 0


# --------------------------------------------------------------------------- versions


def cmd_version_create(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        revision = V.create_version(conn, args.name, args.parent, description=args.description)
    _out(f"created version {V.show_name(args.name)} (parent {V.show_name(args.parent)}), working revision {revision}")
    return 0


def cmd_version_list(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        versions = V.list_versions(conn)
        current = V.working_version(conn)
    if _json(args):
        cliout.emit_json({"current": current, "versions": [_version_json(v, current) for v in versions]})
        return 0
    _table(args, ("current", "version", "parent", "initrevision", "working", "owner", "created", "description"), [
        ("*" if v.name == current else "", v.name, v.parent or "-",
         v.initrevision if v.initrevision is not None else "-", v.workingrevision, v.owner,
         cliout.show_moment(v.created_at), v.description or "") for v in versions])
    return 0


def _version_json(v: V.Version, current: str | None) -> dict[str, Any]:
    return {"name": v.name, "parent": v.parent, "depth": v.depth, "initrevision": v.initrevision,
            "working_revision": v.workingrevision, "revisions": list(v.revisions),
            "saved": [{"name": n, "revision": r} for n, r in sorted(v.saved.items(), key=lambda item: item[1])],
            "owner": v.owner, "created_at": v.created_at, "description": v.description, "current": v.name == current}


def cmd_version_tree(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        versions = V.list_versions(conn)
        current = V.working_version(conn)
    if _json(args):  # depth-first order: each version after its parent
        cliout.emit_json({"current": current, "versions": [_version_json(v, current) for v in versions]})
        return 0
    _out(V.format_tree(versions))
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
        _out(f"commands on this database now work in version {V.show_name(name)} (working revision {working})")
    else:
        _out(f"commands on this database now look at revision {revision} of version {V.show_name(name)} (read-only)")
    return 0


def cmd_version_current(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        name, working, viewing = V.working_version(conn), V.working_revision(conn), V.viewing_revision(conn)
    source = ("--in" if args.in_version else "$TGSIS_VERSION" if os.environ.get("TGSIS_VERSION")
              else "tgsis version goto" if clistate.remembered_version(_target_key(args)) else "default")
    if _json(args):
        cliout.emit_json({"version": name, "working_revision": working, "viewing_revision": viewing,
                          "read_only": viewing is not None, "source": source})
        return 0
    looking = f"\tviewing revision {viewing} (read-only)" if viewing is not None else ""
    _out(f"{name}\tworking revision {working}{looking}\t(from {source})")
    return 0


def cmd_version_save(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        saved = V.save_revision(conn, args.name)
        version, working = V.working_version(conn), V.working_revision(conn)
    _out(f"saved revision {saved} of {V.show_name(version)} as {V.show_name(args.name)}; new working revision {working}")
    return 0


def cmd_version_delete(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        removed = V.delete_version(conn, args.name)
    if clistate.remembered_version(_target_key(args)) == args.name:
        clistate.remember_version(_target_key(args), None)
    _out(f"deleted version {V.show_name(args.name)} and {removed} row version(s)")
    return 0


def _discards_json(discards: Sequence[V.Discard]) -> list[dict[str, Any]]:
    return [{"table": d.shortname, "what": d.description, "rows_added": d.rows_added, "rows_removed": d.rows_removed,
             "rows_changed": d.rows_changed, "values_changed": d.values_changed} for d in discards]


def cmd_version_conflicts(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        conflicts = V.find_conflicts(conn, args.name)
        details = {(c.objectclass, c.objectkey): V.conflict_rows(conn, args.name, c.objectclass, c.objectkey)
                   for c in conflicts} if args.rows else {}
        # what each solution would throw away of the other side's edits (until merges are three-way), read with
        # this role's rights: one that may not read some of the objects' rows still gets the list, without it
        lost: dict[tuple[str, str, str], list[V.Discard]] | None = None
        try:
            with conn.transaction():
                discards = V.conflict_discards(conn, args.name) if conflicts else []
            lost = {}
            for d in discards:
                lost.setdefault((d.objectclass, d.objectkey, d.solution), []).append(d)
        except MissingPrivilegeError as exc:
            print(f"tgsis: warning: what each solution discards is not shown: {exc.message}", file=sys.stderr)
            lost = None
    if _json(args):
        cliout.emit_json({"version": args.name, "conflicts": [{
            "objectclass": c.objectclass, "objectkey": c.objectkey, "solution": c.solution,
            "both_changed": list(c.conflicttype), "child_tables": list(c.childtables),
            "parent_tables": list(c.parenttables),
            "discards": None if lost is None else {
                solution: {"edits_of": other, "tables": _discards_json(lost.get(key + (solution,), []))}
                for key in [(c.objectclass, c.objectkey)] for solution, other in (("child", "parent"), ("parent", "child"))},
            **({"rows": [{"table": table, "side": side, "key": key, "row": row}
                         for table, side, key, row in details.get((c.objectclass, c.objectkey), [])]}
               if args.rows else {})} for c in conflicts]})
        return 0
    if conflicts and not getattr(args, "no_header", False):
        _out("class\tkey\tsolution\tboth changed\tchanged in " + args.name + "\tchanged in parent"
             + "\tchild discards (the parent's edits)\tparent discards (the version's edits)"
             + ("\n\ttable\tside\trow key (JSON)\trow (JSON)" if args.rows else ""))
    for c in conflicts:
        both = ", ".join(c.conflicttype) or "different tables"
        said = ["?" if lost is None else
                "; ".join(d.summary() for d in lost.get((c.objectclass, c.objectkey, solution), [])) or "nothing"
                for solution in ("child", "parent")]
        _out(f"{c.objectclass}\t{c.objectkey}\t{c.solution}\t{both}\t"
             f"{', '.join(c.childtables)}\t{', '.join(c.parenttables)}\t{said[0]}\t{said[1]}")
        for table, side, key, row in details.get((c.objectclass, c.objectkey), []):
            _out(f"\t{table}\t{side}\t{json.dumps(key)}\t{json.dumps(row)}")
    if not conflicts:
        print(f"version {V.show_name(args.name)} has no conflicts with its parent", file=sys.stderr)
    return 0


def cmd_version_resolve(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        c = V.resolve_conflict(conn, args.name, args.objectclass, args.objectkey, args.solution,
                               discard_other=args.discard_other)
    _out(f"{c.objectclass} {c.objectkey} in {V.show_name(args.name)}: {c.solution}")
    if c.discarded is None:
        _out("  what it discarded of the other side's edits is not shown: this role may not read the object's rows")
    elif c.discarded:
        _out(f"  discarded {V.describe_discards(c.discarded)}")
    return 0


def _recorded_discards(conn: Any, version: str) -> dict[tuple[str, str], tuple[str, list[V.Discard]]] | None:
    """What the recorded solutions discard, or None when this role may not read some of the objects' rows."""
    try:
        with conn.transaction():
            return V.recorded_discards(conn, version)
    except MissingPrivilegeError:
        return None


def _say_discarded(lost: dict[tuple[str, str], tuple[str, list[V.Discard]]] | None) -> None:
    if lost is None:
        _out("  what the solutions discarded of the other side's edits is not shown: this role may not read "
             "some of the objects' rows")
        return
    for (objectclass, objectkey), (solution, discards) in lost.items():
        _out(f"  {objectclass} {objectkey} ({solution}): discarded {V.describe_discards(discards)}")


def cmd_version_merge(args: argparse.Namespace) -> int:
    with _connect(args) as conn, cliout.busy(f"merging {V.show_name(args.name)}"), conn.transaction():
        # what the recorded solutions throw away, read in the merge's transaction (a change since unsolves them)
        lost = _recorded_discards(conn, args.name)
        written = V.merge_version(conn, args.name, remove=args.remove)
    _out(f"merged {V.show_name(args.name)} into its parent: {written} row(s) written" + ("; version removed" if args.remove else ""))
    _say_discarded(lost)
    if args.remove and clistate.remembered_version(_target_key(args)) == args.name:
        clistate.remember_version(_target_key(args), None)
    return 0


def cmd_version_refresh(args: argparse.Namespace) -> int:
    with _connect(args) as conn, conn.transaction():
        lost = _recorded_discards(conn, args.name)
        written = V.refresh_version(conn, args.name)
    _out(f"refreshed {V.show_name(args.name)} from its parent: {written} row(s) written")
    _say_discarded(lost)
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
    if _json(args):
        cliout.emit_json({"a": args.a, "b": args.b, "differences": [
            {"objectclass": d.objectclass, "objectkey": d.objectkey, "table": d.table, "added": d.added,
             "removed": d.removed, "changed": d.changed} for d in differences]})
        return 0
    _table(args, ("class", "key", "table", "added", "removed", "changed"),
           [(d.objectclass, d.objectkey, d.table, f"+{d.added}", f"-{d.removed}", f"~{d.changed}")
            for d in differences])
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
    _out(f"version {V.show_name(args.name)} believed from {args.valid_from}"
         + (f" to {args.valid_to}" if args.valid_to else " on"))
    return 0


def cmd_version_chain(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        if args.at:
            believed = V.version_believed_at(conn, _moment(args.at), args.root)
            if _json(args):
                cliout.emit_json({"at": _moment(args.at), "root": args.root, "version": believed})
            else:
                _out(believed if believed is not None else "-")
            return 0 if believed is not None else 3
        chain = V.version_chain(conn, args.root)
    if _json(args):
        cliout.emit_json({"root": args.root, "chain": [{"version": name, "valid_from": start, "valid_to": end}
                                                       for name, start, end in chain]})
        return 0
    _table(args, ("version", "believed from", "believed to"),
           [(name, cliout.show_moment(start), cliout.show_moment(end) if end else "still believed")
            for name, start, end in chain])
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
    if _json(args):
        cliout.emit_json({"locks": [{"objectclass": lk.objectclass, "objectkey": lk.objectkey, "version": lk.version,
                                     "role": lk.locked_by, "exclusive": lk.exclusive, "since": lk.locked_at}
                                    for lk in locks]})
        return 0
    _table(args, ("class", "key", "version", "role", "kind", "since"),
           [(lk.objectclass, lk.objectkey, lk.version, lk.locked_by, "exclusive" if lk.exclusive else "version",
             cliout.show_moment(lk.locked_at)) for lk in locks])
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
    _out(f"version {V.show_name(args.name)} is owned by {args.role}")
    return 0


def cmd_version_privileges(args: argparse.Namespace) -> int:
    with _connect(args) as conn:
        owners = {v.name: v.owner for v in V.list_versions(conn) if args.name in (None, v.name)}
        grants = V.version_privileges(conn, args.name)
    if args.name is not None and not owners:
        raise NotFoundError(f"version {args.name!r} does not exist")
    if _json(args):
        cliout.emit_json({"versions": [{"name": name, "owner": owner, "grants": [
            {"role": g.grantee, "privilege": g.privilege, "granted_by": g.granted_by, "granted_at": g.granted_at}
            for g in grants if g.version == name]} for name, owner in owners.items()]})
        return 0
    rows: list[tuple[str, ...]] = []
    for name, owner in owners.items():
        rows.append((name, owner, "owner (every right)"))
        rows += [(name, g.grantee, g.privilege, g.granted_by) for g in grants if g.version == name]
    _table(args, ("version", "role", "right", "granted by"), rows)
    return 0


def cmd_version_compress(args: argparse.Namespace) -> int:
    remembered = clistate.remembered_version(_target_key(args))
    looked_at = _split_version(remembered)[1] if remembered else None
    with connect(args.dsn) as conn:
        report = V.compress_versions(conn, dry_run=args.dry_run)
        gone = looked_at is not None and not args.dry_run and conn.execute(
            "SELECT NOT EXISTS (SELECT FROM tgsis.revisions WHERE revision = %s)", (looked_at,)).fetchone() == (True,)
    totals = {what: sum(i.removed for i in report if i.what == what)
              for what in ("rows", "lastrevs", "revisions", "set entries")}
    if _json(args):
        if gone:
            clistate.remember_version(_target_key(args), None)
        cliout.emit_json({"dry_run": args.dry_run, "removed": [{"what": i.what, "name": i.name, "removed": i.removed}
                                                               for i in report],
                          "totals": totals, "forgotten": remembered if gone else None})
        return 0
    if report:
        _table(args, ("what", "name", "removed"), [(item.what, item.name, item.removed) for item in report])
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
    if _json(args):
        cliout.emit_json({"tables": [{"schema": t.schema, "table": t.table, "objectclass": t.objectclass,
                                      "key": t.objectkeyfield, "order": t.iudorder, "shortname": t.shortname,
                                      "row_key": list(t.keycolumns)} for t in tables]})
        return 0
    _table(args, ("table", "class", "key", "order", "shortname", "row key"),
           [(f"{t.schema}.{t.table}", t.objectclass, t.objectkeyfield, t.iudorder, t.shortname,
             ", ".join(t.keycolumns)) for t in tables])
    if not tables:
        print("no versioned tables", file=sys.stderr)
    return 0


# --------------------------------------------------------------------------- demo


# --------------------------------------------------------------------------- G-maps (models 4 and 5)


def _gmap_of_file(path: str, fmt: str | None) -> tuple[Any, str | None]:
    """The G-map of the first mesh of a file (its cell properties on the top cells) and the mesh's name."""
    from tgsis import formats, gmaps

    meshes = formats.read(path, fmt)
    if not meshes:
        raise InvalidGeometryError(f"{path} holds no mesh")
    if len(meshes) > 1:
        print(f"tgsis: warning: {path} holds {len(meshes)} objects; the first ({meshes[0].name or 'unnamed'}) is "
              "taken", file=sys.stderr)
    return gmaps.from_mesh(meshes[0]), meshes[0].name


def _gmap_summary(g: Any) -> str:
    counts = ", ".join(f"{g.n_cells(i)} {i}-cells" for i in range(g.dimension + 1))
    return f"a {g.dimension}-G-map in R^{g.embedding_dimension} with {g.n_darts} darts ({counts})"


def cmd_gmap_import(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import insert_gmap

    g, name = _gmap_of_file(args.file, args.format)
    with _connect(args) as conn:
        fc = get_feature_class(conn, args.feature_class)
        geoid = insert_gmap(conn, fc, g, name=args.name or name, drop_extra_properties=args.drop_extra_properties,
                            axes=args.axes.split(",") if args.axes else None)
    if _json(args):
        cliout.emit_json({"id": geoid, "class": fc.name, "dimension": g.dimension, "darts": g.n_darts,
                          "cells": [g.n_cells(i) for i in range(g.dimension + 1)]})
    else:
        _out(f"stored feature {geoid} of class {fc.name}: {_gmap_summary(g)}")
    return 0


def cmd_gmap_check(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import gmap_check

    with _connect(args) as conn:
        problems = gmap_check(conn, args.id)
    if _json(args):
        cliout.emit_json({"id": args.id, "valid": not problems,
                          "problems": [{"problem": p.problem, "count": p.count, "darts": list(p.darts)}
                                       for p in problems]})
        return 0 if not problems else 1
    _table(args, ("problem", "count", "darts"), [(p.problem, p.count, ",".join(map(str, p.darts))) for p in problems])
    print(f"feature {args.id}: " + ("a valid G-map" if not problems else f"{len(problems)} kind(s) of violation"),
          file=sys.stderr)
    return 0 if not problems else 1


def cmd_gmap_cells(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import gmap_cells

    with _connect(args) as conn:
        dartids, cells = gmap_cells(conn, args.id, args.level, args.at)
    sizes = np.bincount(cells) if len(cells) else np.zeros(0, dtype=np.int64)
    when = "" if args.at is None else f" at t = {cliout.show_time(args.at)}"
    if _json(args):
        cliout.emit_json({"id": args.id, "level": args.level, "t": args.at, "cells": len(sizes), "darts": len(dartids),
                          "darts_per_cell": {"min": int(sizes.min()) if len(sizes) else None,
                                             "max": int(sizes.max()) if len(sizes) else None}})
    elif not len(cells):
        print(f"feature {args.id} does not exist{when}", file=sys.stderr)
    else:
        _out(f"feature {args.id}{when}: {len(sizes)} {args.level}-cells of {len(dartids)} darts "
             f"({int(sizes.min())}..{int(sizes.max())} darts each)")
    return 0


def cmd_gmap_at(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import gmap_at
    from tgsis.formats.vtk import write_gmap_vtu

    with _connect(args) as conn:
        g = gmap_at(conn, args.id, args.time)
    if g is None:
        raise NotFoundError(f"feature {args.id} does not exist at t = {args.time!r}")
    write_gmap_vtu(g, args.file)
    _out(f"wrote feature {args.id} at t = {cliout.show_time(args.time)}: {_gmap_summary(g)}, to {args.file}")
    return 0


def _values(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InvalidInputError(f"--values {text!r} must be numbers separated by commas, e.g. 0,1,2") from None
    return values


def cmd_extrude(args: argparse.Namespace) -> int:
    from tgsis import gmaps
    from tgsis.db.gmaps import fetch_md_gmap, insert_gmap
    from tgsis.formats.vtk import write_gmap_vtu

    if not args.feature_class and not args.output:
        raise InvalidInputError("say where the extrusion goes: --class (a class of multiply indexed G-maps), "
                                "--output (a .vtu for ParaView), or both")
    values = _values(args.values)
    axes: list[str] | None = None
    with contextlib.ExitStack() as stack:
        conn = stack.enter_context(_connect(args)) if args.feature_class or args.source.isdigit() else None
        if args.source.isdigit() and not Path(args.source).exists():
            assert conn is not None
            fc = class_of_feature(conn, int(args.source))
            if fc.time_model == "MULTIDIM":
                g, named = fetch_md_gmap(conn, fc, int(args.source))
                axes, name = list(named), None
            else:
                mesh = fetch_feature(conn, fc, int(args.source)).mesh
                if not isinstance(mesh, Mesh):
                    raise InvalidGeometryError(f"feature {args.source} is a collection: extrude one of its members")
                g, name = gmaps.from_mesh(mesh), mesh.name
        else:
            g, name = _gmap_of_file(args.source, args.format)
        axes = (axes or [("x", "y", "z")[i] if i < 3 else f"axis{i + 1}" for i in range(g.embedding_dimension)])
        if args.axis in axes:
            raise InvalidInputError(f"--axis {args.axis!r} is an axis of the source already: {', '.join(axes)}")
        axes = [*axes, args.axis]
        extruded = gmaps.extrude(g, values)
        if args.output:
            write_gmap_vtu(extruded, args.output, name=name, axes=axes)
        geoid = None
        if args.feature_class:
            assert conn is not None
            geoid = insert_gmap(conn, args.feature_class, extruded, name=args.name or name, axes=axes,
                                drop_extra_properties=True)
    summary = _gmap_summary(extruded)
    if _json(args):
        cliout.emit_json({"id": geoid, "output": args.output, "axes": axes, "dimension": extruded.dimension,
                          "darts": extruded.n_darts, "cells": [extruded.n_cells(i) for i in range(extruded.dimension + 1)]})
    else:
        where = [f"feature {geoid} of class {args.feature_class}" if geoid is not None else "",
                 args.output or ""]
        _out(f"extruded along {args.axis} over {len(values) - 1} interval(s): {summary}; "
             f"stored as {' and '.join(w for w in where if w)}")
    return 0


def cmd_slice(args: argparse.Namespace) -> int:
    from tgsis import gmaps
    from tgsis.db.gmaps import fetch_md_gmap
    from tgsis.formats.vtk import write_gmap_vtu

    with _connect(args) as conn:
        g, axes = fetch_md_gmap(conn, class_of_feature(conn, args.id), args.id)
    if args.axis not in axes:
        raise InvalidInputError(f"feature {args.id} has no axis {args.axis!r}; its axes: {', '.join(axes)}")
    at = axes.index(args.axis)
    section = gmaps.slice(g, at, args.value)
    rest = [a for a in axes if a != args.axis]
    if args.output:
        write_gmap_vtu(section, args.output, axes=rest)
    if _json(args):
        cliout.emit_json({"id": args.id, "axis": args.axis, "value": args.value, "output": args.output, "axes": rest,
                          "dimension": section.dimension, "darts": section.n_darts,
                          "cells": [section.n_cells(i) for i in range(section.dimension + 1)]})
    else:
        _out(f"feature {args.id} at {args.axis} = {args.value!r}: {_gmap_summary(section)}"
             + (f", to {args.output}" if args.output else ""))
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    from tgsis.scenarios import SCENARIOS, run_scenario

    if args.list:
        if _json(args):
            cliout.emit_json({"scenarios": [{"name": s.name, "summary": s.summary} for s in SCENARIOS.values()]})
        else:
            _table(args, ("scenario", "shows"), [(s.name, s.summary) for s in SCENARIOS.values()])
        return 0
    if _json(args) or args.no_header:
        raise InvalidInputError("--json and --no-header go with --list", hint="tgsis demo --list --json")
    run_scenario(args.name, args.dsn, out=_out, folder=args.dir, size=args.size)
    return 0


def cmd_view(args: argparse.Namespace) -> int:
    from psycopg.conninfo import conninfo_to_dict, make_conninfo

    from tgsis.db.connect import local_dsn

    try:
        from tgsis.view import serve
        # the extra's libraries, checked before anything starts
        import jinja2  # noqa: F401
        import starlette  # noqa: F401
        import uvicorn  # noqa: F401
    except ImportError as exc:
        raise Error(f"tgsis view needs the optional extra 'view' ({exc.name} is not installed)",
                    hint="pip install 'tgsis[view]'") from exc
    target = resolve_target(args.dsn)
    if target.dsn is None:
        conninfo = local_dsn(args.db or "tgsis")
    else:
        conninfo = make_conninfo(target.dsn, dbname=args.db) if args.db else target.dsn
    with connect(conninfo) as conn:
        if installed_version(conn) is None:
            raise NotFoundError(f"tgsis is not installed in database {conn.info.dbname}",
                                hint="tgsis db install, or --db NAME for another database of the server "
                                     "(the demo's: --db tgsis_demo)")
        if args.in_version:
            name, revision = _split_version(args.in_version)
            if revision is None:
                V.goto_version(conn, name, local=True)
            else:
                V.goto_revision(conn, name, revision, local=True)
        database = conn.info.dbname
    shown = conninfo_to_dict(conninfo).get("dbname") or database
    serve(conninfo, host=args.host, port=args.port, writable=args.writable, database=str(shown),
          open_browser=args.open, default_version=args.in_version,
          on_listening=lambda url: _out(f"tgsis view of database {shown} "
                                        f"({'writable' if args.writable else 'read-only'}) at {url} (Ctrl-C stops it)"))
    return 0


# --------------------------------------------------------------------------- parser




def _output_options(json_only: bool = False) -> argparse.ArgumentParser:
    """``--json`` (and, for tables, ``--no-header``): the options of every command that lists or reports."""
    parent = argparse.ArgumentParser(add_help=False)
    parent.add_argument("--json", action="store_true",
                        help="print one JSON document (its keys: docs/cli.md) instead of lines for people")
    if not json_only:
        parent.add_argument("--no-header", action="store_true", help="leave out the header line of the table")
    return parent


def _command(commands: Any, name: str, help: str, examples: Sequence[str], handler: Handler | None = None,
             tabular: bool | None = None) -> argparse.ArgumentParser:
    """A sub-command with its help, its examples (shown by ``--help``), and ``--json`` when it lists or reports.

    ``tabular``: None, no output options; False, ``--json``; True, ``--json`` and ``--no-header``.
    """
    parents = [] if tabular is None else [_output_options(json_only=not tabular)]
    parser: argparse.ArgumentParser = commands.add_parser(
        name, help=help, description=help, parents=parents, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=("example:\n" if len(examples) == 1 else "examples:\n") + "\n".join(f"  {e}" for e in examples))
    if handler is not None:
        parser.set_defaults(handler=handler)
    return parser


_GEOTYPES = ("MULTIPOINT", "MULTILINESTRING", "SURFACE", "MULTITETRA", "GEOMETRYCOLLECTION", "GMAP")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``tgsis`` command.

    Every argument has a help text and every command examples (``--help``
    shows them; tests/test_cli_help.py walks the tree and fails on one without).
    """
    parser = argparse.ArgumentParser(
        prog="tgsis",
        description="tgsis: spatio-temporal geoscience information system on PostgreSQL",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n  tgsis demo\n  tgsis --dsn 'host=db.example.org dbname=geo' ls --class faults\n"
               "  tgsis --in cfm6 version current --json\nsee docs/cli.md",
    )
    parser.add_argument("--version", action="version", version=f"tgsis {tgsis.__version__}",
                        help="print the client's version and exit")
    parser.add_argument("--dsn", help="libpq connection string (default: $TGSIS_DSN, PG* variables, "
                                      "else the local server tgsis runs itself)")
    parser.add_argument("--in", dest="in_version", metavar="VERSION[@REVISION]",
                        help="work in this version, or look at one of its revisions (default: $TGSIS_VERSION, "
                             "else what `tgsis version goto` chose, else DEFAULT)")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output (-vv: debug)")
    parser.add_argument("-q", "--quiet", action="store_true", help="errors only")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    demo = _command(commands, "demo", "run a sample application end to end (default: cfm, the release story)",
                    ["tgsis demo saltdome --dir out   # then look at out/*.png, out/saltdome.gif",
                     "tgsis demo --list", "tgsis demo --list --json"], cmd_demo, tabular=True)
    demo.add_argument("name", nargs="?", default="cfm", metavar="NAME",
                      help="the scenario (tgsis demo --list names them; default: cfm)")
    demo.add_argument("--list", action="store_true", help="list the scenarios and what each shows")
    demo.add_argument("--dir", metavar="DIR", help="folder for the files it writes (default: a new temporary folder)")
    demo.add_argument("--size", choices=("small", "large"), default="small",
                      help="how much data the scenario makes (default: small, under a minute)")

    view = _command(commands, "view", "look at the database in a browser: classes, features, versions, "
                                      "surfaces in 3D through time, versions compared (the extra tgsis[view])",
                    ["tgsis view --open", "tgsis view --db tgsis_demo   # after tgsis demo",
                     "tgsis --dsn 'host=db.example.org dbname=geo' view --port 8080"], cmd_view)
    view.add_argument("--port", type=_integer(0, 65535), default=8765,
                      help="TCP port to listen on (default: 8765; 0: any free port)")
    view.add_argument("--host", default="127.0.0.1",
                      help="address to listen on (default: 127.0.0.1, this machine only)")
    view.add_argument("--db", metavar="NAME",
                      help="another database of the same server (e.g. tgsis_demo, the demo's)")
    view.add_argument("--open", action="store_true", help="open the system's web browser on the first page")
    view.add_argument("--writable", action="store_true",
                      help="leave transactions writable (default: every transaction is read-only)")

    db = _command(commands, "db", "install, upgrade or inspect tgsis in a database",
                  ["tgsis --dsn 'host=db.example.org dbname=geo' db install"])
    db_commands = db.add_subparsers(dest="db_command", metavar="ACTION", required=True)
    db_install = _command(db_commands, "install", "install or upgrade tgsis (a no-op when up to date)",
                          ["tgsis db install", "tgsis db install --method sql   # managed PostgreSQL"], cmd_db_install)
    db_install.add_argument("--method", choices=("auto", "extension", "sql"), default="auto",
                            help="extension: CREATE EXTENSION (needs the files on the server); "
                                 "sql: run the script from the client; auto: extension when available")
    db_uninstall = _command(db_commands, "uninstall", "remove tgsis and all its data from the database",
                            ["tgsis db uninstall --yes"], cmd_db_uninstall)
    db_uninstall.add_argument("--yes", action="store_true", help="really do it")
    db_uninstall.add_argument("--cascade", action="store_true", help="also drop objects that depend on tgsis")
    _command(db_commands, "status", "the database's tgsis against this client's (exit 1 unless up to date)",
             ["tgsis db status", "tgsis db status --json"], cmd_db_status, tabular=False)

    cls = _command(commands, "class", "feature classes: create, list, alter, drop", ["tgsis class list"])
    cls_commands = cls.add_subparsers(dest="class_command", metavar="ACTION", required=True)
    cls_create = _command(cls_commands, "create", "register a feature class",
                          ["tgsis class create faults --geotype SURFACE --srs 32611 --feature-property release:text",
                           "tgsis class create moving --geotype SURFACE --time-model EVOLVING --time-unit Ma "
                           "--instant-property throw:float8",
                           "tgsis class create history --geotype GMAP --time-model MULTIDIM --cell-level 3 "
                           "--property change_m:float8"], cmd_class_create)
    cls_create.add_argument("name", help="the class's name (letters, digits, underscores)")
    cls_create.add_argument("--geotype", required=True, type=str.upper, choices=_GEOTYPES,
                            help="what its features are: " + ", ".join(_GEOTYPES))
    cls_create.add_argument("--feature-property", action="append", metavar="NAME:TYPE",
                            help="a property of the whole feature (repeatable), e.g. creator:text")
    cls_create.add_argument("--property", action="append", metavar="NAME:TYPE[:SIZE][:VERTEX|CELL]",
                            help="a per-vertex (or per-cell) property (repeatable), e.g. porosity:float8; SIZE: a "
                                 "vector of SIZE components (slip:float8:3); VERTEX or CELL: an alignment other "
                                 "than --alignment (facies:int:CELL)")
    cls_create.add_argument("--alignment", default="VERTEX", type=str.upper, choices=("VERTEX", "CELL"),
                            help="where --property values are unless they say otherwise (default: VERTEX)")
    cls_create.add_argument("--srs", type=_INT4, default=0, help="spatial reference id (EPSG), 0 = undefined")
    cls_create.add_argument("--schema", default="public", help="schema of the class's tables (default: public)")
    cls_create.add_argument("--description", help="what the class holds, for people")
    cls_create.add_argument("--time-model", default="STATIC", type=str.upper,
                            choices=("STATIC", "INSTANTS", "EVOLVING", "GMAP", "MULTIDIM"),
                            help="STATIC (model 1), INSTANTS: surfaces at instants (model 2), "
                                 "EVOLVING: continuously evolving surfaces (model 3), GMAP: G-maps in time (model 4), "
                                 "MULTIDIM: G-maps with time or knowledge as axes (model 5)")
    cls_create.add_argument("--cell-level", type=int, metavar="LEVEL",
                            help="classes of G-maps (GMAP, MULTIDIM): the dimension of the cells --property values "
                                 "belong to (0 vertices, 1 edges, 2 faces, 3 volumes)")
    cls_create.add_argument("--time-unit", help="unit of model time of a temporal class, e.g. Ma")
    cls_create.add_argument("--instant-property", action="append", metavar="NAME:TYPE",
                            help="per-instant feature property of a temporal class (repeatable)")
    cls_create.add_argument("--no-versioning", action="store_true",
                            help="a class without versioning: its features hold one state that every version sees, "
                                 "written in DEFAULT only (docs/versioning.md, \"Versioning per class\")")
    _command(cls_commands, "list", "list the feature classes", ["tgsis class list", "tgsis class list --json"],
             cmd_class_list, tabular=True)
    cls_alter = _command(cls_commands, "alter", "add, rename or drop properties of a feature class, in every version",
                         ["tgsis class alter horizons --add-property permeability:float8=0 --add-feature-property "
                          "author:text",
                          "tgsis class alter horizons --rename-property porosity phi --drop-property author",
                          "tgsis class alter horizons --drop-property phi --force   # deletes its values",
                          "tgsis class alter horizons --fill-property porosity=0.2   # features without rows get them"],
                         cmd_class_alter, tabular=False)
    cls_alter.add_argument("name", help="the class to change")
    cls_alter.add_argument("--add-property", action="append", metavar="NAME:TYPE[:SIZE][:VERTEX|CELL][=VALUE]",
                           help="a new per-vertex (or per-cell) property (repeatable), as for tgsis class create "
                                "--property; VALUE: what the stored vertices (cells) get, needed when the class "
                                "has features")
    cls_alter.add_argument("--add-feature-property", action="append", metavar="NAME:TYPE[=VALUE]",
                           help="a new property of the whole feature (repeatable); stored features get VALUE, "
                                "else none (NULL)")
    cls_alter.add_argument("--add-instant-property", action="append", metavar="NAME:TYPE[=VALUE]",
                           help="a new per-instant property of a temporal class (repeatable); stored instants get "
                                "VALUE, else none (NULL)")
    cls_alter.add_argument("--rename-property", action="append", nargs=2, metavar=("OLD", "NEW"),
                           help="rename a property, keeping its values (repeatable); write KIND:OLD (feature, cell, "
                                "instant) when the class has two properties called OLD")
    cls_alter.add_argument("--drop-property", action="append", metavar="NAME",
                           help="drop a property (repeatable; KIND:NAME as for --rename-property); refused while "
                                "stored values would be lost, unless --force")
    cls_alter.add_argument("--force", action="store_true",
                           help="drop properties even if that deletes their stored values")
    cls_alter.add_argument("--fill-property", action="append", metavar="NAME=VALUE",
                           help="repair: give the stored features that have no rows for the vertex or cell "
                                "properties (a property added by tgsis 0.2.0 or earlier to a class without one) a row "
                                "per vertex or cell holding VALUE, in every version (repeatable: one per property "
                                "of that table); runs before the other changes")
    cls_drop = _command(cls_commands, "drop", "drop a feature class (refused while it has features)",
                        ["tgsis class drop faults", "tgsis class drop faults --force   # with its features"],
                        cmd_class_drop)
    cls_drop.add_argument("name", help="the class to drop")
    cls_drop.add_argument("--force", action="store_true", help="also delete its features and their geometries")

    imp = _command(commands, "import", "store the objects of a geometry file as features of a class "
                                       "(as one feature in a GEOMETRYCOLLECTION class)",
                   ["tgsis import Garlock.ts --class faults --set release=6.1 --drop-extra-properties",
                    "tgsis import Garlock.ts --class faults --replace   # a new version of the same fault",
                    "tgsis import model.vtu --class models --json",
                    "tgsis import top_2024.ts --class horizons --at 2024 --feature 7   # a model-2 instant"],
                   cmd_import, tabular=True)
    imp.add_argument("file", help="the geometry file (.ts, .pl, .vs, .so, .lso, .gp, .ml, .vtu, .obj, .ply, .off, "
                                       ".stl)")
    imp.add_argument("--class", dest="feature_class", required=True, help="the feature class to store them in")
    imp.add_argument("--name", help="feature name (default: the name in the file, else the file name; "
                                    "for a GEOMETRYCOLLECTION class the file name)")
    imp.add_argument("--format", help="file format (default: from the extension)")
    imp.add_argument("--set", action="append", metavar="NAME=VALUE", help="a feature property value (repeatable)")
    imp.add_argument("--drop-extra-properties", action="store_true",
                     help="ignore properties of the file that the class does not store")
    imp.add_argument("--replace", action="store_true",
                     help="replace the feature of the same name in the class (written by difference, keeping its "
                          "id; in a version, a change of that version) instead of adding a second one")
    imp.add_argument("--reject-flagged", action="store_true",
                     help="refuse the whole file if any object has duplicate vertices (other than GOCAD ATOMs) "
                          "or degenerate cells")
    imp.add_argument("--strict", action="store_true",
                     help="refuse the whole file if it holds objects tgsis cannot read (a GOCAD SGrid beside "
                          "surfaces), instead of skipping them with a warning")
    imp.add_argument("--tolerance", type=float, default=0.0, metavar="T",
                     help="cells of length/area/volume at most T count as degenerate (default 0: exactly zero)")
    imp.add_argument("--at", type=float, metavar="T",
                     help="a class of surfaces at instants (INSTANTS): the surface is the shape at model time T, of a "
                          "new feature (known from T on) or, with --feature, of an existing one")
    imp.add_argument("--feature", type=_ID, metavar="ID",
                     help="with --at: add the instant T to this feature instead of storing a new one")
    imp.add_argument("--alive", action="store_true",
                     help="with --at, for a new feature: it still exists after its last instant (keeps its last shape; "
                          "default: it exists only from its first to its last instant, as from Python)")

    exp = _command(commands, "export", "write a feature to a geometry file",
                   ["tgsis export 3 garlock.ts", "tgsis export 3 garlock.vtu --png garlock.png"], cmd_export)
    exp.add_argument("id", type=_ID, help="the feature's id (tgsis ls lists them)")
    exp.add_argument("file", help="the file to write; its extension gives the format")
    exp.add_argument("--class", dest="feature_class", help="its feature class (default: looked up)")
    exp.add_argument("--format", help="file format (default: from the extension)")
    exp.add_argument("--png", metavar="PNG", help="also draw the feature (a surface) to this PNG file")

    at = _command(commands, "at", "write the surface of a feature at model time T to a file",
                  ["tgsis at 12 -7.5 fault_7.5Ma.ts", "tgsis at 13 1.5 horizon.vtu --convention right"], cmd_at)
    at.add_argument("id", type=_ID, help="the feature's id")
    at.add_argument("time", type=float, metavar="T", help="model time (in the class's unit)")
    at.add_argument("file", help="the file to write; its extension gives the format; {t} in it is replaced by T; "
                    "a folder gets feature_ID_tT.FORMAT (with --format)")
    at.add_argument("--format", help="file format (default: from the extension)")
    at.add_argument("--convention", type=str.lower, choices=("left", "right"), default="left",
                    help="step convention of a surface known at instants (default: left)")
    at.add_argument("--png", metavar="PNG", help="also draw the surface at T to this PNG file, coloured by how far "
                                                  "it moved since its first instant")
    at.add_argument("--with", dest="with_ids", type=_ID, nargs="+", default=[], metavar="ID",
                    help="with --png: other features drawn at T in the same scene (the structure at T)")

    series = _command(commands, "series", "write a feature over model time as a ParaView .pvd time series",
                      ["tgsis series 12 out --from -10 --to 0 --steps 101", "tgsis series 12 out --name fault_history",
                       "tgsis series 12 out --json"], cmd_series, tabular=True)
    series.add_argument("id", type=_ID, help="the feature's id")
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

    co = _command(commands, "checkout", "write a feature to a file for editing, recording what it was",
                  ["tgsis checkout 42 fault.ts   # edit fault.ts in any tool, then: tgsis checkin fault.ts"],
                  cmd_checkout)
    co.add_argument("id", type=_ID, help="the feature's id")
    co.add_argument("file", help="the file to edit (.ts, .vtk, .vtu, ...); the record goes to FILE.tgsis-checkout.npz")
    co.add_argument("--class", dest="feature_class", help="its feature class (default: looked up)")
    co.add_argument("--format", help="file format (default: from the extension)")

    ci = _command(commands, "checkin", "write an edited file back by difference, unless the feature changed "
                                       "since check-out",
                  ["tgsis checkin fault.ts", "tgsis checkin fault.ts --tolerance 0.01 --on-conflict child --json"],
                  cmd_checkin, tabular=False)
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

    interp = _command(commands, "interpolate", "the surface evolving from SOURCE (at T0) to TARGET (at T1): "
                                               "morphological interpolation, stored as a model-3 feature",
                      ["tgsis interpolate flat.ts dome.ts --setup dome.json --t0 0 --t1 1 --class salt --preview out"],
                      cmd_interpolate)
    interp.add_argument("source", help="surface file at T0")
    interp.add_argument("target", help="surface file at T1")
    interp.add_argument("--setup", required=True, help="JSON set-up: control vertices, fences, cuts, attachments, "
                                                       "steps, tolerance (see docs/interpolation.md)")
    interp.add_argument("--t0", type=float, required=True, help="time of the source")
    interp.add_argument("--t1", type=float, required=True, help="time of the target")
    interp.add_argument("--class", dest="feature_class", help="EVOLVING feature class to store it in "
                                                               "(without: computed and previewed only)")
    interp.add_argument("--name", help="feature name (default: the source's)")
    interp.add_argument("--split", choices=("auto", "centroid"), default="auto",
                        help="how the compatible meshes are refined: centroid is the design's rule (split the "
                             "triangle at its centroid), auto (default) bisects its longest interior edge instead, "
                             "which converges where centroid splits stall")
    interp.add_argument("--alive", action="store_true",
                        help="the surface goes on existing after its last instant, in its last shape")
    interp.add_argument("--preview", metavar="DIR", help="write PNG views of a few instants to DIR")
    interp.add_argument("--frames", type=_INT4, default=5, help="number of preview instants (default 5)")

    corners = _command(commands, "corners", "propose control vertices: the sharp corners of a surface's border",
                       ["tgsis corners horizon.ts --count 4", "tgsis corners horizon.ts --json"], cmd_corners,
                       tabular=False)
    corners.add_argument("file", help="a file holding one surface")
    corners.add_argument("--count", type=_INT4, help="exactly this many corners")
    corners.add_argument("--min-angle", type=float, default=35.0, help="smallest turn of a corner, degrees (35)")

    info = _command(commands, "info", "what a feature is: class, counts, box, lifespan and instants, properties, "
                                      "the versions where it differs", ["tgsis info 3", "tgsis info 3 --json"],
                    cmd_info, tabular=False)
    info.add_argument("id", type=_ID, help="the feature's id")

    query = _command(
        commands, "query", "the features of a temporal class whose per-instant property satisfies PROPERTY OP VALUE, "
                           "and when",
        ["tgsis query faults throw '>=' 100 --first   # when each fault's throw first reaches 100",
         "tgsis query faults throw '<' 5 --json"], cmd_query, tabular=True)
    query.add_argument("feature_class", metavar="CLASS", help="an INSTANTS or EVOLVING feature class")
    query.add_argument("property", metavar="PROPERTY", help="a numeric per-instant property of the class")
    query.add_argument("op", metavar="OP", choices=("<", "<=", "=", "<>", ">=", ">"), help="one of < <= = <> >= >")
    query.add_argument("value", metavar="VALUE", type=float, help="the number compared with (-inf, inf allowed)")
    query.add_argument("--first", action="store_true", help="only when the condition first holds, per feature")
    query.add_argument("--convention", type=str.lower, choices=("left", "right"), default="left",
                       help="step convention of features known at instants (default: left)")

    cut = _command(commands, "cut", "cut a surface along vertex paths (its edges become borders on both sides)",
                   ["tgsis cut horizon.ts horizon_cut.ts --path 12,13,14,15"], cmd_cut)
    cut.add_argument("file", metavar="FILE", help="a file holding one surface")
    cut.add_argument("output", metavar="OUTPUT", help="the cut surface is written here")
    cut.add_argument("--path", type=_vertex_path, action="append", required=True, metavar="V1,V2,...",
                     help="a cutting path: vertex indices of FILE along interior edges, only its ends on the border "
                          "(repeat for several paths)")
    cut.add_argument("--format", help="format of OUTPUT (default: from its extension)")

    ls = _command(commands, "ls", "list features", ["tgsis ls", "tgsis ls --class faults --json",
                                                    "tgsis --in cfm6 ls --no-header | cut -f1"], cmd_ls, tabular=True)
    ls.add_argument("--class", dest="feature_class", help="only this feature class")

    ver = _command(commands, "version", "versions (long transactions): create, goto, save, merge, lock, grant, ...",
                   ["tgsis version create cfm6 && tgsis version goto cfm6"])
    ver_commands = ver.add_subparsers(dest="version_command", metavar="ACTION", required=True)
    ver_create = _command(ver_commands, "create", "create a child version",
                          ["tgsis version create cfm6 --description 'release 6.1'"], cmd_version_create)
    ver_create.add_argument("name", help="the new version's name")
    ver_create.add_argument("--parent", default="DEFAULT", help="parent version (default: DEFAULT)")
    ver_create.add_argument("--description", help="what the version is for, for people")
    _command(ver_commands, "list", "list the versions (* marks the one commands work in)",
             ["tgsis version list", "tgsis version list --json"], cmd_version_list, tabular=True)
    _command(ver_commands, "tree", "print the version tree with revisions",
             ["tgsis version tree", "tgsis version tree --json"], cmd_version_tree, tabular=False)
    ver_goto = _command(ver_commands, "goto", "work in a version from now on (remembered per database)",
                        ["tgsis version goto cfm6", "tgsis version goto cfm6@2   # look at revision 2, read-only",
                         "tgsis version goto DEFAULT"], cmd_version_goto)
    ver_goto.add_argument("name", metavar="VERSION[@REVISION]",
                          help="a version, or a revision of its history to look at read-only")
    _command(ver_commands, "current", "the version commands work in, and its working revision",
             ["tgsis version current", "tgsis version current --json"], cmd_version_current, tabular=False)
    ver_save = _command(ver_commands, "save", "freeze the working revision under a name, start a new one",
                        ["tgsis version save imported"], cmd_version_save)
    ver_save.add_argument("name", help="the name of the saved revision")
    ver_delete = _command(ver_commands, "delete", "delete a version without children, with its changes",
                          ["tgsis version delete cfm6"], cmd_version_delete)
    ver_delete.add_argument("name", help="the version to delete")

    ver_conflicts = _command(ver_commands, "conflicts", "objects changed both in a version and in its parent",
                             ["tgsis version conflicts cfm6", "tgsis version conflicts cfm6 --rows --json"],
                             cmd_version_conflicts, tabular=True)
    ver_conflicts.add_argument("name", help="the child version (its parent is the other side)")
    ver_conflicts.add_argument("--rows", action="store_true", help="also print the rows that differ, per side")
    ver_resolve = _command(ver_commands, "resolve", "record how a conflicting object is merged",
                           ["tgsis version resolve cfm6 feature 42 child",
                            "tgsis version resolve cfm6 feature 42 child --discard-other"], cmd_version_resolve)
    ver_resolve.add_argument("name", help="the child version")
    ver_resolve.add_argument("objectclass", metavar="CLASS", help="object class ('feature' for features)")
    ver_resolve.add_argument("objectkey", metavar="KEY", help="object key (for features: the id)")
    ver_resolve.add_argument("solution", type=str.lower, choices=("parent", "child", "manual", "unsolved"),
                             help="which side the merge keeps: parent, child, manual (the rows as the child has them "
                                  "after your edit), or unsolved (undecided again)")
    ver_resolve.add_argument("--discard-other", action="store_true",
                             help="record child or parent even though it throws away the other side's edits of the "
                                  "object since the version was based (without it such a solution is refused, "
                                  "with the counts; tgsis version conflicts shows them)")

    ver_merge = _command(ver_commands, "merge", "apply a version's changes to its parent (one transaction)",
                         ["tgsis version merge cfm6 --remove"], cmd_version_merge)
    ver_merge.add_argument("name", help="the version to merge into its parent")
    ver_merge.add_argument("--remove", action="store_true", help="delete the version after merging it")
    ver_refresh = _command(ver_commands, "refresh", "bring the parent's changes into a version",
                           ["tgsis version refresh cfm6"], cmd_version_refresh)
    ver_refresh.add_argument("name", help="the version to refresh")

    ver_diff = _command(ver_commands, "diff", "objects whose rows differ between two versions or revisions",
                        ["tgsis version diff DEFAULT cfm6", "tgsis version diff cfm6@2 cfm6 --json",
                         "tgsis version diff DEFAULT cfm6 --png out"], cmd_version_diff, tabular=True)
    ver_diff.add_argument("a", metavar="A[@REVISION]", help="the version (or revision) compared from")
    ver_diff.add_argument("b", metavar="B[@REVISION]", help="the version (or revision) compared to")
    ver_diff.add_argument("--png", metavar="DIR", help="also draw each changed surface feature to DIR/diff_ID.png, "
                                                       "coloured by how far its vertices moved from A")

    ver_valid = _command(ver_commands, "valid", "set the period in which a version was believed true",
                         ["tgsis version valid cfm5 2020-01-01 2023-06-30", "tgsis version valid cfm6 2023-06-30"],
                         cmd_version_valid)
    ver_valid.add_argument("name", help="the version")
    ver_valid.add_argument("valid_from", metavar="FROM", help="ISO date or time")
    ver_valid.add_argument("valid_to", metavar="TO", nargs="?", help="ISO date or time (omitted: still believed)")
    ver_chain = _command(ver_commands, "chain", "the chain of believed versions, or the one believed --at a time",
                         ["tgsis version chain", "tgsis version chain --at 2024-01-01 --json"], cmd_version_chain,
                         tabular=True)
    ver_chain.add_argument("--root", default="DEFAULT", help="the version the chain starts from (default: DEFAULT)")
    ver_chain.add_argument("--at", help="ISO date or time: print the version believed then (exit 3: none)")

    ver_compress = _command(
        ver_commands, "compress", "remove revisions and row versions no version, named revision or child can reach",
        ["tgsis version compress --dry-run", "tgsis version compress --json"], cmd_version_compress, tabular=True)
    ver_compress.add_argument("--dry-run", action="store_true", help="only report what would be removed")

    ver_lock = _command(ver_commands, "lock", "lock objects for a version: no other version may change them",
                        ["tgsis version lock cfm6 feature 3 4 --exclusive"], cmd_version_lock)
    ver_lock.add_argument("name", help="the version that holds the locks")
    ver_lock.add_argument("objectclass", metavar="CLASS", help="object class ('feature' for features)")
    ver_lock.add_argument("keys", nargs="+", metavar="KEY", help="object keys (feature ids)")
    ver_lock.add_argument("--exclusive", action="store_true", help="also keep other roles from changing them in the version")
    ver_unlock = _command(ver_commands, "unlock", "release a version's object locks (all, of a class, or some keys)",
                          ["tgsis version unlock cfm6", "tgsis version unlock cfm6 feature 3"], cmd_version_unlock)
    ver_unlock.add_argument("name", help="the version that holds the locks")
    ver_unlock.add_argument("objectclass", metavar="CLASS", nargs="?", help="only the locks of this object class")
    ver_unlock.add_argument("keys", nargs="*", metavar="KEY", help="only the locks of these keys")
    ver_locks = _command(ver_commands, "locks", "list object locks (of one version, or all)",
                         ["tgsis version locks", "tgsis version locks cfm6 --json"], cmd_version_locks, tabular=True)
    ver_locks.add_argument("name", nargs="?", help="only the locks of this version")

    privileges = ("write", "create", "merge", "delete", "all")
    for verb in ("grant", "revoke"):
        ver_grant = _command(ver_commands, verb, f"{verb} a right on a version (owner or tgsis_admin only)",
                             [f"tgsis version {verb} cfm6 write {'ana' if verb == 'grant' else 'public'}"],
                             cmd_version_grant)
        ver_grant.add_argument("name", help="the version")
        ver_grant.add_argument("privilege", metavar="RIGHT", type=str.lower, choices=privileges,
                               help="one of " + ", ".join(privileges))
        ver_grant.add_argument("role", help="a role, or public")
        ver_grant.set_defaults(revoke=verb == "revoke")
    ver_owner = _command(ver_commands, "owner", "hand a version to another role", ["tgsis version owner cfm6 ana"],
                         cmd_version_owner)
    ver_owner.add_argument("name", help="the version")
    ver_owner.add_argument("role", help="its new owner")
    ver_privileges = _command(ver_commands, "privileges", "owners and granted rights (of one version, or all)",
                              ["tgsis version privileges", "tgsis version privileges cfm6 --json"],
                              cmd_version_privileges, tabular=True)
    ver_privileges.add_argument("name", nargs="?", help="only this version")

    vt = _command(commands, "versioning", "turn versioning of tables on or off", ["tgsis versioning enable features"])
    vt_commands = vt.add_subparsers(dest="versioning_command", metavar="ACTION", required=True)
    vt_enable = _command(vt_commands, "enable", "version a table (or 'features': model 1 and all feature classes)",
                         ["tgsis versioning enable features", "tgsis versioning enable wells --key id --class well"],
                         cmd_versioning_enable)
    vt_enable.add_argument("table", help="name or schema.name, or 'features'")
    vt_enable.add_argument("--key", help="column holding the object key")
    vt_enable.add_argument("--class", dest="object_class", help="object class")
    vt_enable.add_argument("--order", type=_INT4, default=0, help="iudorder within the object class (default 0)")
    vt_enable.add_argument("--shortname", help="name in conflict reports (default: the table name)")
    vt_disable = _command(vt_commands, "disable", "make a versioned table plain again with DEFAULT's rows",
                          ["tgsis versioning disable wells", "tgsis versioning disable features --force"],
                          cmd_versioning_disable)
    vt_disable.add_argument("table", help="name or schema.name, or 'features'")
    vt_disable.add_argument("--force", action="store_true", help="even if versions other than DEFAULT changed it")
    _command(vt_commands, "list", "list the versioned tables", ["tgsis versioning list", "tgsis versioning list --json"],
             cmd_versioning_list, tabular=True)

    local = _command(commands, "local", "the local PostgreSQL server tgsis runs by itself",
                     ["tgsis local start && psql \"$(tgsis local dsn)\""])
    local_commands = local.add_subparsers(dest="local_command", metavar="ACTION", required=True)
    _command(local_commands, "start", "start it and keep it running", ["tgsis local start"], cmd_local_start)
    local_stop = _command(local_commands, "stop", "stop it", ["tgsis local stop"], cmd_local_stop)
    local_stop.add_argument("--force", action="store_true", help="stop it even while other tgsis commands use it")
    _command(local_commands, "status", "where it is and whether it runs (exit 3: stopped)",
             ["tgsis local status", "tgsis local status --json"], cmd_local_status, tabular=False)
    _command(local_commands, "dsn", "print its connection string", ["psql \"$(tgsis local dsn)\""], cmd_local_dsn)
    gmap = _command(commands, "gmap", "G-maps (models 4 and 5): import from a mesh file, check, cells, snapshot",
                    ["tgsis gmap import blocks.ts --class blocks && tgsis gmap check 1"])
    gmap_commands = gmap.add_subparsers(dest="gmap_command", required=True, metavar="COMMAND")
    gmap_import = _command(gmap_commands, "import", "store the first mesh of a file as a G-map feature (its cells' "
                           "properties on the top cells)",
                           ["tgsis gmap import blocks.ts --class blocks", "tgsis gmap import cube.vtu --class history "
                            "--axes x,y,z --json"], cmd_gmap_import, tabular=False)
    gmap_import.add_argument("file", help="a mesh file (GOCAD, VTK, OBJ, PLY, OFF, STL)")
    gmap_import.add_argument("--class", dest="feature_class", required=True,
                             help="a class of G-maps (time model GMAP or MULTIDIM, with a cell level)")
    gmap_import.add_argument("--name", help="the feature's name (default: the mesh's)")
    gmap_import.add_argument("--format", help="file format (default: from the extension)")
    gmap_import.add_argument("--axes", help="a MULTIDIM class: the names of the axes, comma-separated (default x,y,z)")
    gmap_import.add_argument("--drop-extra-properties", action="store_true",
                             help="ignore cell properties the class does not store instead of failing")
    gmap_check = _command(gmap_commands, "check", "check a stored G-map: involutions, fixed points, compositions, "
                          "periods, points (exit 1 when it breaks one)",
                          ["tgsis gmap check 12", "tgsis gmap check 12 --json"], cmd_gmap_check, tabular=True)
    gmap_check.add_argument("id", type=_ID, help="the feature's id")
    gmap_cells = _command(gmap_commands, "cells", "count the i-cells of a stored G-map (at model time T for model 4)",
                          ["tgsis gmap cells 12 2 --at 1.5", "tgsis gmap cells 14 3 --json"], cmd_gmap_cells,
                          tabular=False)
    gmap_cells.add_argument("id", type=_ID, help="the feature's id")
    gmap_cells.add_argument("level", type=int, help="the cell dimension i (0 vertices, 1 edges, 2 faces, 3 volumes)")
    gmap_cells.add_argument("--at", type=float, metavar="T", help="model time (G-maps in time, model 4)")
    gmap_at = _command(gmap_commands, "at", "write a stored G-map at model time T to a .vtu for ParaView (polygons "
                       "or polyhedra, properties on cells)", ["tgsis gmap at 12 1.5 blocks_1.5.vtu"], cmd_gmap_at)
    gmap_at.add_argument("id", type=_ID, help="the feature's id")
    gmap_at.add_argument("time", type=float, metavar="T", help="model time (in the class's unit)")
    gmap_at.add_argument("file", help="the .vtu file to write")

    extrude = _command(commands, "extrude", "extrude a mesh or feature along a new axis (model 5): an (n+1)-G-map, "
                       "stored in a class and/or written for ParaView",
                       ["tgsis extrude horizon.ts --axis knowledge --values 2019,2021,2023 --class history",
                        "tgsis extrude 12 --axis t --values 0,1 --output prism.vtu"], cmd_extrude, tabular=False)
    extrude.add_argument("source", help="a mesh file, or the id of a stored feature (model 1 or 5)")
    extrude.add_argument("--axis", required=True, help="the name of the new axis (e.g. knowledge, t)")
    extrude.add_argument("--values", required=True, help="increasing values of the new axis, comma-separated: "
                                                         "the layers (at least two)")
    extrude.add_argument("--class", dest="feature_class", help="store it in this class of multiply indexed G-maps")
    extrude.add_argument("--output", help="write it to this .vtu (polyhedra; extra axes as point data)")
    extrude.add_argument("--name", help="the stored feature's name (default: the source's)")
    extrude.add_argument("--format", help="the source file's format (default: from the extension)")

    slice_ = _command(commands, "slice", "the object of a stored multiply indexed G-map at a value of one of its axes",
                      ["tgsis slice 14 --axis knowledge --value 2021 --output top_2021.vtu", "tgsis slice 14 --axis t "
                       "--value 0.5 --json"], cmd_slice, tabular=False)
    slice_.add_argument("id", type=_ID, help="the feature's id (a class of time model MULTIDIM)")
    slice_.add_argument("--axis", required=True, help="the axis to cut (one of the feature's axes)")
    slice_.add_argument("--value", required=True, type=float, help="where along it")
    slice_.add_argument("--output", help="write the slice to this .vtu")

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
        exc.hint = clihints.to_cli(exc.hint)  # the hint in this interface's words (its flags and commands)
        print(f"tgsis: error: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # the reader went away while something other than _out wrote to stdout
        cliout.drop_stdout()  # stdout to /dev/null, so that the flush at exit does not fail too
        return 0
    except KeyboardInterrupt:
        print("tgsis: interrupted", file=sys.stderr)
        return 130
    finally:
        release_local_server()


if __name__ == "__main__":
    sys.exit(main())
