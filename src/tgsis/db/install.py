"""Installing, upgrading and removing the tgsis objects in a database.

Two routes run the same SQL (see :mod:`tgsis.db.sqlsource`):

* ``extension``: ``CREATE EXTENSION tgsis`` / ``ALTER EXTENSION tgsis UPDATE``,
  when the server has the extension files (``make -C sql install``, or
  PostgreSQL 18's ``extension_control_path``);
* ``sql``: the script run by the client, for databases where extension files
  cannot be installed (managed cloud PostgreSQL). The installed version is
  read from ``tgsis.installation``; upgrades apply ``updates/`` scripts.

Whatever the route, everything happens in one transaction under an advisory
lock: two clients installing at once give one install and one no-op, and a
failure leaves the database as it was.
"""

from __future__ import annotations

import logging
import numbers
from dataclasses import dataclass
from typing import Any, Literal

import psycopg
from psycopg import sql

from tgsis.db.sqlsource import EXTENSION, ExtensionSources, parse_version
from tgsis.errors import InstallationError, InUseError, InvalidInputError, reraise

__all__ = ["InstallResult", "InstalledVersion", "install", "installed_version", "partition_model_storage", "uninstall"]

log = logging.getLogger(__name__)

Method = Literal["auto", "extension", "sql"]

# Serialises install/upgrade/uninstall of tgsis within one database.
_LOCK_SQL = "SELECT pg_advisory_xact_lock(hashtextextended('tgsis.install', 0))"


@dataclass(frozen=True)
class InstalledVersion:
    """What is installed in a database.

    Attributes
    ----------
    version : str
        The tgsis version of the installed objects.
    method : {"extension", "sql"}
        How it was installed.
    """

    version: str
    method: Literal["extension", "sql"]


@dataclass(frozen=True)
class InstallResult:
    """Outcome of :func:`install`.

    Attributes
    ----------
    action : {"installed", "upgraded", "unchanged"}
        What the call did.
    method : {"extension", "sql"}
        Route of the installed objects.
    version : str
        Version installed now.
    previous_version : str or None
        Version before an upgrade (or the same version when unchanged).
    """

    action: Literal["installed", "upgraded", "unchanged"]
    method: Literal["extension", "sql"]
    version: str
    previous_version: str | None = None


def installed_version(conn: psycopg.Connection[Any]) -> InstalledVersion | None:
    """Return the tgsis version installed in the connected database, or ``None``.

    Raises
    ------
    InstallationError
        If a schema ``tgsis`` exists that is not a tgsis installation.
    """
    with reraise():
        row = conn.execute(
            "SELECT extversion FROM pg_catalog.pg_extension WHERE extname = %s", (EXTENSION,)
        ).fetchone()
        if row is not None:
            return InstalledVersion(str(row[0]), "extension")
        row = conn.execute(
            "SELECT to_regnamespace('tgsis') IS NOT NULL, to_regclass('tgsis.installation') IS NOT NULL"
        ).fetchone()
        assert row is not None
        schema_exists, table_exists = bool(row[0]), bool(row[1])
        if not schema_exists:
            return None
        if not table_exists:
            raise InstallationError(
                "schema tgsis exists but holds no tgsis installation (no table tgsis.installation)",
                hint="rename or drop that schema, then install tgsis",
            )
        versions = [str(r[0]) for r in conn.execute("SELECT version FROM tgsis.installation").fetchall()]
    if not versions:
        raise InstallationError("tgsis.installation is empty: the tgsis schema was tampered with")
    return InstalledVersion(max(versions, key=parse_version), "sql")


def _extension_available(conn: psycopg.Connection[Any], version: str) -> bool:
    row = conn.execute(
        "SELECT 1 FROM pg_catalog.pg_available_extension_versions WHERE name = %s AND version = %s",
        (EXTENSION, version),
    ).fetchone()
    return row is not None


def _create_extension(conn: psycopg.Connection[Any], version: str) -> None:
    conn.execute(
        sql.SQL("CREATE EXTENSION {} VERSION {} CASCADE").format(
            sql.Identifier(EXTENSION), sql.Literal(version)
        )
    )
    _create_storage(conn)


def _create_storage(conn: psycopg.Connection[Any]) -> None:
    """Create the tables of stored objects after ``CREATE EXTENSION``, unless they exist.

    They are left out of the extension script so that they are no extension
    members: pg_dump dumps them whole (``sql/core/create_storage.sql`` says
    why). Also completes a database where someone ran ``CREATE EXTENSION
    tgsis`` by hand.
    """
    row = conn.execute("SELECT to_regclass('tgsis.geometry') IS NULL").fetchone()
    if row is not None and row[0]:
        conn.execute("SELECT tgsis.create_storage()")


def _install_fresh(
    conn: psycopg.Connection[Any], sources: ExtensionSources, method: Method
) -> Literal["extension", "sql"]:
    available = _extension_available(conn, sources.version)
    if method == "extension" and not available:
        raise InstallationError(
            f"the server has no extension files for tgsis {sources.version}",
            hint="run `make -C sql install` on the server (PGXS), or install with method='sql'",
        )
    if method in ("auto", "extension") and available:
        try:
            with conn.transaction():
                _create_extension(conn, sources.version)
            return "extension"
        except psycopg.errors.InsufficientPrivilege as exc:
            if method == "extension":
                raise
            log.warning("CREATE EXTENSION tgsis refused (%s); installing with plain SQL", exc.diag.message_primary)
    _prepare_plain_sql(conn, sources)
    conn.execute(sources.script(psql_guard=False).encode("utf-8"))
    return "sql"


def _prepare_plain_sql(conn: psycopg.Connection[Any], sources: ExtensionSources) -> None:
    """Do for the plain-SQL route what CREATE EXTENSION does before running a script.

    Creates the required extensions (``requires`` of the control file) and sets
    the search path to tgsis, their schemas and pg_temp, for this transaction.
    """
    for name in sources.requires:
        conn.execute(sql.SQL("CREATE EXTENSION IF NOT EXISTS {}").format(sql.Identifier(name)))
    rows = conn.execute(
        "SELECT e.extnamespace::regnamespace::text FROM pg_catalog.pg_extension e "
        "JOIN unnest(%s::text[]) WITH ORDINALITY AS r(name, ord) ON r.name = e.extname ORDER BY r.ord",
        (sources.requires,),
    ).fetchall()
    # the same value CREATE EXTENSION sets, so that SET search_path FROM CURRENT
    # gives both routes identical functions
    schemas = list(dict.fromkeys(["tgsis", *(str(r[0]) for r in rows), "pg_temp"]))
    conn.execute("SELECT set_config('search_path', %s, true)", (", ".join(schemas),))


def _upgrade(
    conn: psycopg.Connection[Any], current: InstalledVersion, sources: ExtensionSources
) -> None:
    if current.method == "extension":
        if not _extension_available(conn, sources.version):
            raise InstallationError(
                f"cannot upgrade the tgsis extension from {current.version} to {sources.version}: "
                "the server has no extension files for the new version",
                hint="run `make -C sql install` for the new version on the server",
            )
        conn.execute(
            sql.SQL("ALTER EXTENSION {} UPDATE TO {}").format(
                sql.Identifier(EXTENSION), sql.Literal(sources.version)
            )
        )
        _create_storage(conn)
        return
    _prepare_plain_sql(conn, sources)
    for path in sources.upgrade_path(current.version, sources.version):
        log.info("applying %s", path.name)
        conn.execute(sources.upgrade_sql(path).encode("utf-8"))


def install(
    conn: psycopg.Connection[Any],
    *,
    method: Method = "auto",
    sources: ExtensionSources | None = None,
) -> InstallResult:
    """Install or upgrade tgsis in the connected database.

    A second call with the same version is a no-op; a call with a newer client
    upgrades; a database newer than the client is refused. Everything runs in
    one transaction (a savepoint if the connection is already in one: the
    caller then commits).

    Parameters
    ----------
    conn : psycopg.Connection
        Connection to the target database, as a role that may create schemas
        (and roles, unless the ``tgsis_*`` roles exist).
    method : {"auto", "extension", "sql"}
        ``auto`` uses ``CREATE EXTENSION`` when the server has the extension
        files for this version and the role may use them, else the plain SQL.
    sources : ExtensionSources, optional
        The SQL to install; by default the sources shipped with this client.

    Returns
    -------
    InstallResult

    Raises
    ------
    InstallationError
        Unknown method, newer version in the database, no upgrade path, a
        foreign ``tgsis`` schema, or missing extension files for
        ``method="extension"``.
    MissingPrivilegeError
        The ``tgsis_*`` roles are missing and the role may not create them.
    """
    if method not in ("auto", "extension", "sql"):
        raise InstallationError(f"unknown install method {method!r}: use 'auto', 'extension' or 'sql'")
    sources = sources or ExtensionSources.default()
    target = sources.version
    with reraise(), conn.transaction():
        conn.execute(_LOCK_SQL)
        current = installed_version(conn)
        if current is None:
            done = _install_fresh(conn, sources, method)
            log.info("installed tgsis %s (%s)", target, done)
            return InstallResult("installed", done, target)
        if parse_version(current.version) > parse_version(target):
            raise InstallationError(
                f"the database has tgsis {current.version}, newer than this client's {target}",
                hint="upgrade the tgsis Python package",
            )
        if current.version == target:
            if current.method == "extension":
                _create_storage(conn)
            return InstallResult("unchanged", current.method, target, current.version)
        _upgrade(conn, current, sources)
        # the PostGIS wrappers are made at run time (sql/postgis/enable_postgis.sql): again for the new version
        if conn.execute("SELECT to_regprocedure('tgsis.postgis_geometry(text, bigint)') IS NOT NULL "
                        "AND to_regprocedure('tgsis.enable_postgis()') IS NOT NULL").fetchone() == (True,):
            conn.execute("SELECT tgsis.enable_postgis()")
        log.info("upgraded tgsis %s -> %s (%s)", current.version, target, current.method)
        return InstallResult("upgraded", current.method, target, current.version)


# Objects outside schema tgsis that a cascading drop of tgsis could take with
# it: relations, their columns (a column of a tgsis type), functions, types,
# constraints (foreign keys to tgsis tables), triggers, policies. Parts that go
# with their relation (row types, rules of views, internal triggers) are left out.
_OUTSIDE_OBJECTS_SQL = """
SELECT 'pg_class'::regclass::oid, c.oid, 0 FROM pg_catalog.pg_class c WHERE c.relnamespace NOT IN (%(ns)s, 'pg_toast'::regnamespace)
UNION ALL
SELECT 'pg_class'::regclass::oid, a.attrelid, a.attnum
  FROM pg_catalog.pg_attribute a JOIN pg_catalog.pg_class c ON c.oid = a.attrelid
 WHERE c.relnamespace NOT IN (%(ns)s, 'pg_toast'::regnamespace) AND a.attnum > 0 AND NOT a.attisdropped
UNION ALL
SELECT 'pg_proc'::regclass::oid, p.oid, 0 FROM pg_catalog.pg_proc p WHERE p.pronamespace <> %(ns)s
UNION ALL
SELECT 'pg_type'::regclass::oid, y.oid, 0 FROM pg_catalog.pg_type y
 WHERE y.typnamespace <> %(ns)s AND y.typrelid = 0 AND y.typcategory <> 'A'
UNION ALL
SELECT 'pg_constraint'::regclass::oid, k.oid, 0 FROM pg_catalog.pg_constraint k WHERE k.connamespace <> %(ns)s
UNION ALL
SELECT 'pg_trigger'::regclass::oid, g.oid, 0
  FROM pg_catalog.pg_trigger g JOIN pg_catalog.pg_class c ON c.oid = g.tgrelid
 WHERE c.relnamespace <> %(ns)s AND NOT g.tgisinternal
UNION ALL
SELECT 'pg_policy'::regclass::oid, o.oid, 0
  FROM pg_catalog.pg_policy o JOIN pg_catalog.pg_class c ON c.oid = o.polrelid WHERE c.relnamespace <> %(ns)s
"""


_PG_CLASS = 1259  # pg_class's own oid, fixed in every PostgreSQL


def _outside_objects(conn: psycopg.Connection[Any], namespace: int) -> set[tuple[int, int, int]]:
    rows = conn.execute(_OUTSIDE_OBJECTS_SQL, {"ns": namespace}).fetchall()
    return {(int(r[0]), int(r[1]), int(r[2])) for r in rows}


def _describe(conn: psycopg.Connection[Any], objects: set[tuple[int, int, int]]) -> list[str]:
    relations = {o[1] for o in objects if o[0] == _PG_CLASS and o[2] == 0}
    objects = {o for o in objects if not (o[0] == _PG_CLASS and o[2] != 0 and o[1] in relations)}
    rows = conn.execute(
        "SELECT pg_describe_object(c, o, s) FROM unnest(%s::oid[], %s::oid[], %s::int[]) AS u(c, o, s)",
        ([o[0] for o in objects], [o[1] for o in objects], [o[2] for o in objects]),
    ).fetchall()
    return sorted(str(r[0]) for r in rows)


def _drop_tgsis(conn: psycopg.Connection[Any], method: str) -> None:
    if method == "extension":
        conn.execute(sql.SQL("DROP EXTENSION {} CASCADE").format(sql.Identifier(EXTENSION)))
    conn.execute(sql.SQL("DROP SCHEMA {} CASCADE").format(sql.Identifier("tgsis")))


def uninstall(conn: psycopg.Connection[Any], *, cascade: bool = False) -> InstalledVersion | None:
    """Remove tgsis and its data from the connected database (the cluster-wide roles stay).

    Parameters
    ----------
    conn : psycopg.Connection
        Connection to the database.
    cascade : bool
        Also drop objects outside schema ``tgsis`` that depend on it (views on
        tgsis tables, foreign keys to them, columns of tgsis types). Without
        it such objects make the call fail, naming them, and nothing is removed.

    Returns
    -------
    InstalledVersion or None
        What was removed; ``None`` if tgsis was not installed.

    Raises
    ------
    InUseError
        Objects outside schema ``tgsis`` depend on it and ``cascade`` is false.
    """
    with reraise(), conn.transaction():
        conn.execute(_LOCK_SQL)
        current = installed_version(conn)
        if current is None:
            return None
        row = conn.execute("SELECT 'tgsis'::regnamespace::oid").fetchone()
        assert row is not None
        namespace = int(row[0])
        before = _outside_objects(conn, namespace)
        lost: set[tuple[int, int, int]] = set()
        # Drop everything, see what else went, and undo when that is not allowed:
        # pg_depend alone cannot tell columns and rules apart as simply.
        with conn.transaction(force_rollback=not cascade):
            _drop_tgsis(conn, current.method)
            lost = before - _outside_objects(conn, namespace)
        if not cascade:
            if lost:
                names = _describe(conn, lost)
                raise InUseError(
                    f"uninstalling tgsis would also drop {len(names)} object(s) outside schema tgsis",
                    detail="; ".join(names[:20]) + (" ..." if len(names) > 20 else ""),
                    hint="drop or change them first, or uninstall with cascade (tgsis db uninstall --cascade)",
                )
            _drop_tgsis(conn, current.method)  # nothing else depends on tgsis: for real
    return current


def partition_model_storage(conn: psycopg.Connection[Any], model: int, partitions: int) -> list[str]:
    """Hash-partition the storage tables of a data model by geoid (``tgsis.partition_model_storage``).

    For a database that will outgrow plain tables (docs/scaling.md): run it
    once after :func:`install`, before storing data of that model and before
    :func:`tgsis.enable_feature_versioning`. The tables keep their
    definitions, index names, comments, owner and the group roles' rights.

    Parameters
    ----------
    conn : psycopg.Connection
        Connection of the tables' owner (the role that installed tgsis) or a superuser.
    model : int
        The data model, 1 to 5 (``tgsis.data_models``); the core tables stay plain.
    partitions : int
        2 to 1024, and no more than the server's lock table holds
        (``max_locks_per_transaction`` x (``max_connections`` +
        ``max_prepared_transactions``) locks, about 4 per partition of each
        table; docs/scaling.md): on a default server 221 for model 1.

    Returns
    -------
    list of str
        The tables partitioned (names in schema ``tgsis``).

    Raises
    ------
    InvalidInputError
        ``partitions`` out of range (also: more than the lock table holds; the hint gives the most), or model 0.
    NotFoundError
        No such data model.
    InUseError
        A table holds rows, is versioned or is partitioned already (nothing is changed).
    MissingPrivilegeError
        The role may not run it or does not own the tables.
    """
    # the SQL parameters are smallint and integer: a larger number would come back as a raw 22003
    for name, value, high, hint in (("model", model, 2**15 - 1, "SELECT model FROM tgsis.data_models lists them"),
                                    ("partitions", partitions, 2**31 - 1, "give 2 to 1024 partitions")):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise InvalidInputError(f"{name} must be an integer, not {type(value).__name__} {repr(value)[:100]}",
                                    hint=hint)
        if not -high - 1 <= int(value) <= high:
            raise InvalidInputError(f"{name} = {str(int(value))[:100]} is out of range", hint=hint)
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.partition_model_storage(%s::smallint, %s::integer)",
                           (model, partitions)).fetchone()
    assert row is not None
    return list(row[0])
