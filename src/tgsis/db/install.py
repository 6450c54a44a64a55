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
from dataclasses import dataclass, field
from typing import Any, Literal

import psycopg
from psycopg import sql

from tgsis.arguments import checked
from tgsis.db.sqlsource import EXTENSION, ExtensionSources, parse_version
from tgsis.errors import InstallationError, InUseError, InvalidInputError, reraise

__all__ = [
    "InstallResult",
    "InstalledVersion",
    "InstallationStatus",
    "install",
    "installation_status",
    "installed_version",
    "partition_model_storage",
    "uninstall",
]

log = logging.getLogger(__name__)

Storage = Literal["chunks", "rows"]
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
    fingerprint : str or None
        The fingerprint of the install script the objects were built from
        (``tgsis.installation.fingerprint``; :attr:`ExtensionSources.fingerprint`
        of the client that installed or upgraded them); ``""`` when none is
        recorded (versions before 0.3.0), ``None`` when the role may not read
        ``tgsis.installation`` (unknown). Not compared by ``==``.
    """

    version: str
    method: Literal["extension", "sql"]
    fingerprint: str | None = field(default=None, compare=False)


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
    steps : tuple of str
        What the call did, one sentence each, in order (``tgsis db install``
        prints them): roles and extensions created, the extension or script
        installed, the upgrade run, storage created, a grant made; empty when
        it did nothing. Not compared by ``==``.
    still_needed : tuple of str
        Statements a DBA must still run for the installing role (``GRANT
        tgsis_admin TO owner;`` when the installer may not grant it itself).
        Not compared by ``==``.
    """

    action: Literal["installed", "upgraded", "unchanged"]
    method: Literal["extension", "sql"]
    version: str
    previous_version: str | None = None
    steps: tuple[str, ...] = field(default=(), compare=False)
    still_needed: tuple[str, ...] = field(default=(), compare=False)


@dataclass(frozen=True)
class InstallationStatus:
    """The tgsis installation of a database compared with this client (:func:`installation_status`).

    Attributes
    ----------
    installed : InstalledVersion or None
        What the database holds (``None``: tgsis is not installed).
    client_version, client_fingerprint : str
        This client's version and the fingerprint of its install script.
    missing_storage : tuple of str
        Storage tables (``tgsis.model_tables``) that do not exist: a bare
        ``CREATE EXTENSION tgsis`` leaves all of them missing.
    state : {"not installed", "up to date", "upgrade", "client older", "other build", "storage missing"}
        ``up to date`` when this client can work with the database.
    problem : str or None
        What is wrong, in a sentence naming both sides; ``None`` when up to date.
    fix : str or None
        The command that fixes it.
    """

    installed: InstalledVersion | None
    client_version: str
    client_fingerprint: str
    missing_storage: tuple[str, ...]
    state: Literal["not installed", "up to date", "upgrade", "client older", "other build", "storage missing"]
    problem: str | None
    fix: str | None

    @property
    def ok(self) -> bool:
        """Whether this client can work with the database as it is."""
        return self.state == "up to date"


@checked
def installed_version(conn: psycopg.Connection[Any]) -> InstalledVersion | None:
    """Return the tgsis version installed in the connected database, or ``None``.

    Raises
    ------
    InstallationError
        If a schema ``tgsis`` exists that is not a tgsis installation.
    """
    with reraise():
        row = conn.execute("SELECT extversion FROM pg_catalog.pg_extension WHERE extname = %s", (EXTENSION,)).fetchone()
        if row is not None:
            return InstalledVersion(str(row[0]), "extension", _fingerprint(conn, str(row[0])))
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
    version = max(versions, key=parse_version)
    return InstalledVersion(version, "sql", _fingerprint(conn, version))


def _fingerprint(conn: psycopg.Connection[Any], version: str) -> str | None:
    """``tgsis.installation.fingerprint`` of ``version``: ``""`` when none is recorded (before 0.3.0, or a build of
    0.3.0 older than the column), ``None`` when the role may not read it (unknown: no mismatch)."""
    row = conn.execute(
        "SELECT to_regclass('tgsis.installation') IS NOT NULL AND has_table_privilege('tgsis.installation', 'SELECT')"
    ).fetchone()
    if row is None or not row[0]:
        return None
    # to_jsonb: the column is missing in databases of 0.1.0 and 0.2.0
    row = conn.execute(
        "SELECT to_jsonb(i) ->> 'fingerprint' FROM tgsis.installation i WHERE i.version = %s", (version,)
    ).fetchone()
    return "" if row is None or row[0] is None else str(row[0])


def _missing_storage(conn: psycopg.Connection[Any]) -> tuple[str, ...]:
    """The storage tables of the registry that do not exist (all of them after a bare CREATE EXTENSION)."""
    row = conn.execute(
        "SELECT to_regclass('tgsis.model_tables') IS NULL, to_regclass('tgsis.geometry') IS NULL"
    ).fetchone()
    assert row is not None
    if row[0]:  # 0.1.0 had no registry of data models: its storage is there when tgsis.geometry is
        return ("tgsis.geometry",) if row[1] else ()
    rows = conn.execute(
        "SELECT 'tgsis.' || quote_ident(t.tablename) FROM tgsis.model_tables t "
        "WHERE to_regclass(format('tgsis.%I', t.tablename)) IS NULL ORDER BY t.model, t.iudorder, t.tablename"
    ).fetchall()
    return tuple(str(r[0]) for r in rows)


def _fingerprint_mismatch(installed: InstalledVersion, sources: ExtensionSources, dbname: str) -> tuple[str, str]:
    """The problem and the fix of a database of this version built from other sources than the client's."""
    recorded = installed.fingerprint or "none recorded"
    problem = (
        f"database {dbname} has tgsis {installed.version} built from other SQL sources than this client's "
        f"{sources.version} (database: fingerprint {recorded}; client: fingerprint {sources.fingerprint})"
    )
    fix = (
        f"{installed.version} is a development version and there is no upgrade between two of its builds: use the "
        "client of the commit that installed the database, or install this client's tgsis into a new database "
        "(`tgsis db install`) and move the data there (`tgsis export` / `tgsis import`); released versions "
        "upgrade with `tgsis db install` (docs/install.md, 'Upgrading')"
    )
    return problem, fix


@checked
def installation_status(
    conn: psycopg.Connection[Any], *, sources: ExtensionSources | None = None
) -> InstallationStatus:
    """Compare the tgsis installed in the connected database with this client's SQL.

    The version and the fingerprint of the install script (what the objects
    were built from) are compared, and the storage tables checked: a
    database of an older release needs ``tgsis db install`` (an upgrade), a
    newer one a newer client, a database of the same development version
    built at another commit cannot be upgraded in place, and a bare ``CREATE
    EXTENSION tgsis`` lacks its storage tables.

    Parameters
    ----------
    conn : psycopg.Connection
        Connection to the database (any role that may read ``tgsis.installation``).
    sources : ExtensionSources, optional
        The client's SQL; by default the sources shipped with this client.

    Returns
    -------
    InstallationStatus
    """
    sources = sources or ExtensionSources.default()
    current = installed_version(conn)
    dbname = conn.info.dbname

    def status(
        state: Any, problem: str | None = None, fix: str | None = None, missing: tuple[str, ...] = ()
    ) -> InstallationStatus:
        return InstallationStatus(current, sources.version, sources.fingerprint, missing, state, problem, fix)

    if current is None:
        return status("not installed", f"tgsis is not installed in database {dbname}", "tgsis db install")
    with reraise():
        missing = _missing_storage(conn)
    if parse_version(current.version) > parse_version(sources.version):
        return status(
            "client older",
            f"database {dbname} has tgsis {current.version}, newer than this client's {sources.version}",
            "this client is older than the database: upgrade the client (pip install --upgrade tgsis)",
            missing,
        )
    if current.version != sources.version:
        statement = (
            f"ALTER EXTENSION tgsis UPDATE TO '{sources.version}'; SELECT tgsis.create_storage();"
            if current.method == "extension"
            else ""
        )
        return status(
            "upgrade",
            f"database {dbname} has tgsis {current.version}, this client {sources.version}",
            f"run `tgsis db install` ({current.version} -> {sources.version})"
            + (f", or in psql: {statement}" if statement else ""),
            missing,
        )
    # (a fingerprint this role may not read is unknown, not another build: db status shows it as such)
    if current.fingerprint is not None and current.fingerprint != sources.fingerprint:
        return status("other build", *_fingerprint_mismatch(current, sources, dbname), missing=missing)
    if missing:
        return status(
            "storage missing",
            f"database {dbname} has tgsis {current.version} without its storage tables "
            f"({len(missing)} missing: {', '.join(missing[:4])}{', ...' if len(missing) > 4 else ''}); "
            "CREATE EXTENSION alone does not create them",
            "run `tgsis db install`, or in psql: SELECT tgsis.create_storage();",
            missing,
        )
    return status("up to date")


def _extension_available(conn: psycopg.Connection[Any], version: str) -> bool:
    row = conn.execute(
        "SELECT 1 FROM pg_catalog.pg_available_extension_versions WHERE name = %s AND version = %s",
        (EXTENSION, version),
    ).fetchone()
    return row is not None


def _create_extension(conn: psycopg.Connection[Any], version: str) -> None:
    conn.execute(
        sql.SQL("CREATE EXTENSION {} VERSION {} CASCADE").format(sql.Identifier(EXTENSION), sql.Literal(version))
    )


def _create_storage(conn: psycopg.Connection[Any]) -> bool:
    """Create the tables of stored objects after ``CREATE EXTENSION``, unless they exist; whether it created any.

    They are left out of the extension script so that they are no extension
    members: pg_dump dumps them whole (``sql/storage/create_storage.sql`` says
    why). Also completes a database where someone ran ``CREATE EXTENSION
    tgsis`` by hand.
    """
    if not _missing_storage(conn):
        return False
    row = conn.execute("SELECT tgsis.create_storage()").fetchone()
    return bool(row and row[0])


def _install_fresh(
    conn: psycopg.Connection[Any], sources: ExtensionSources, method: Method, steps: list[str]
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
                steps.append(
                    f"created the extension tgsis {sources.version} "
                    f"(CREATE EXTENSION tgsis VERSION '{sources.version}' CASCADE)"
                )
                if _create_storage(conn):
                    steps.append("created the storage tables (SELECT tgsis.create_storage())")
            return "extension"
        except psycopg.errors.InsufficientPrivilege as exc:
            if method == "extension":
                raise
            log.warning("CREATE EXTENSION tgsis refused (%s); installing with plain SQL", exc.diag.message_primary)
            steps.append(f"CREATE EXTENSION tgsis was refused ({exc.diag.message_primary}): installed with plain SQL")
    _prepare_plain_sql(conn, sources)
    conn.execute(sources.script(psql_guard=False).encode("utf-8"))
    steps.append(f"ran the install script of tgsis {sources.version} (plain SQL: schema tgsis with its storage tables)")
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
    conn: psycopg.Connection[Any], current: InstalledVersion, sources: ExtensionSources, steps: list[str]
) -> None:
    if current.method == "extension":
        if not _extension_available(conn, sources.version):
            raise InstallationError(
                f"cannot upgrade the tgsis extension from {current.version} to {sources.version}: "
                "the server has no extension files for the new version",
                hint="run `make -C sql install` for the new version on the server",
            )
        conn.execute(
            sql.SQL("ALTER EXTENSION {} UPDATE TO {}").format(sql.Identifier(EXTENSION), sql.Literal(sources.version))
        )
        steps.append(
            f"upgraded tgsis {current.version} -> {sources.version} "
            f"(ALTER EXTENSION tgsis UPDATE TO '{sources.version}')"
        )
        if _create_storage(conn):
            steps.append("created the storage tables (SELECT tgsis.create_storage())")
        return
    _prepare_plain_sql(conn, sources)
    chain = sources.upgrade_path(current.version, sources.version)
    for path in chain:
        log.info("applying %s", path.name)
        conn.execute(sources.upgrade_sql(path).encode("utf-8"))
    steps.append(
        f"upgraded tgsis {current.version} -> {sources.version} (plain SQL: "
        + ", ".join(path.name for path in chain)
        + ")"
    )


def _storage_steps(conn: psycopg.Connection[Any], storage: Storage) -> list[str]:
    """What an install or upgrade made of the tables registered for chunks: lines, none before chunks (0.2.0)."""
    if conn.execute("SELECT to_regprocedure('tgsis.stored_in_chunks(text)') IS NULL").fetchone() == (True,):
        return []
    row = conn.execute(
        "SELECT array_agg(t.tablename::text ORDER BY t.model, t.iudorder, t.tablename)"
        "         FILTER (WHERE tgsis.stored_in_chunks(t.tablename)),"
        "       array_agg(t.tablename::text ORDER BY t.model, t.iudorder, t.tablename)"
        "         FILTER (WHERE NOT tgsis.stored_in_chunks(t.tablename) AND t.model = 1),"
        "       array_agg(t.tablename::text ORDER BY t.model, t.iudorder, t.tablename)"
        "         FILTER (WHERE NOT tgsis.stored_in_chunks(t.tablename) AND t.model <> 1)"
        # the tables stored in chunks by default (model 1's, model 2's time tables), and any other switched by hand
        "  FROM tgsis.model_tables t"
        " WHERE t.chunkdefault OR (t.chunkcolumn IS NOT NULL AND tgsis.stored_in_chunks(t.tablename))"
    ).fetchone()
    if row is None:
        return []
    chunked, rows, kept = list(row[0] or []), list(row[1] or []), list(row[2] or [])
    steps = []
    if chunked:
        steps.append(f"stored in chunks: {', '.join(chunked)} (docs/storage.md)")
    if storage == "rows":
        rows += kept
        kept = []
    if rows:
        why = "storage='rows'" if storage == "rows" else "the upgrade's warnings say why"
        steps.append(f"stored as rows: {', '.join(rows)} ({why})")
    if kept:
        # an upgraded database keeps its time tables where they were (docs/storage.md, "The storage switch")
        steps.append(
            f"kept as rows: {', '.join(kept)} (an upgrade moves model 1 only;"
            " SELECT tgsis.store_in_chunks(table) moves the others, docs/storage.md)"
        )
    return steps


_TGSIS_ROLES = ("tgsis_reader", "tgsis_editor", "tgsis_admin", "tgsis_nobody")


def _existing(conn: psycopg.Connection[Any]) -> tuple[set[str], set[str]]:
    """The tgsis roles and the extensions that exist (to say what an install created)."""
    roles = {
        str(r[0])
        for r in conn.execute(
            "SELECT rolname FROM pg_catalog.pg_roles WHERE rolname = ANY(%s)", (list(_TGSIS_ROLES),)
        ).fetchall()
    }
    extensions = {str(r[0]) for r in conn.execute("SELECT extname FROM pg_catalog.pg_extension").fetchall()}
    return roles, extensions


def _make_owner_admin(conn: psycopg.Connection[Any], steps: list[str]) -> tuple[str, ...]:
    """Make tgsis's owner (the installing role) a member of tgsis_admin, or say which GRANT a DBA must run.

    The owner registers feature classes and versions features, which tgsis allows members of
    tgsis_admin (superusers are). A role that created the tgsis roles, or that holds ADMIN OPTION
    on tgsis_admin, may grant it to itself; otherwise the statement is returned.
    """
    row = conn.execute(
        "SELECT current_user, pg_has_role(current_user, 'tgsis_admin', 'MEMBER'), "
        "(SELECT n.nspowner = r.oid FROM pg_catalog.pg_namespace n, pg_catalog.pg_roles r "
        "  WHERE n.nspname = 'tgsis' AND r.rolname = current_user), "
        "format('GRANT tgsis_admin TO %I', current_user)"
    ).fetchone()
    assert row is not None
    user, member, owner, grant = str(row[0]), bool(row[1]), bool(row[2]), str(row[3])
    if member or not owner:
        return ()
    try:
        with conn.transaction():
            conn.execute(grant.encode("utf-8"))  # the role's name quoted by format('%I')
    except psycopg.errors.InsufficientPrivilege:
        return (grant + ";",)
    steps.append(f"granted tgsis_admin to {user}, tgsis's owner (it registers classes and versions features)")
    return ()


@checked
def install(
    conn: psycopg.Connection[Any],
    *,
    method: Method = "auto",
    sources: ExtensionSources | None = None,
    storage: Storage = "chunks",
) -> InstallResult:
    """Install or upgrade tgsis in the connected database.

    A second call with the same build is a no-op (it creates the storage
    tables a bare ``CREATE EXTENSION tgsis`` left out); a call with a newer
    client upgrades; a database newer than the client, or of the same
    development version built from other sources (another fingerprint), is
    refused. Everything runs in one transaction (a savepoint if the
    connection is already in one: the caller then commits). The installing
    role becomes tgsis's owner and a member of ``tgsis_admin`` when it may
    grant that to itself (:attr:`InstallResult.still_needed` says the
    ``GRANT`` otherwise).

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
    storage : {"chunks", "rows"}
        How the model tables registered for chunks (model 1's vertices and
        simplices, docs/storage.md) are stored when this call creates them,
        and whether an upgrade switches those of an older version to chunks
        (``"rows"`` keeps rows). Set for the call's transaction as the
        setting ``tgsis.storage``, which both routes read
        (``tgsis.chosen_storage``). An installed database is left as it is:
        ``SELECT tgsis.store_in_chunks('vrtx')`` switches a table later.

    Returns
    -------
    InstallResult

    Raises
    ------
    InstallationError
        Unknown method or storage, newer version in the database, another build of the
        same version, no upgrade path, a foreign ``tgsis`` schema, or missing
        extension files for ``method="extension"``.
    MissingPrivilegeError
        The ``tgsis_*`` roles are missing and the role may not create them.
    """
    if method not in ("auto", "extension", "sql"):
        raise InstallationError(f"unknown install method {method!r}: use 'auto', 'extension' or 'sql'")
    if storage not in ("chunks", "rows"):
        raise InstallationError(f"unknown storage {storage!r}: use 'chunks' or 'rows'")
    sources = sources or ExtensionSources.default()
    target = sources.version
    steps: list[str] = []
    result: tuple[str, Literal["extension", "sql"], str | None]
    with reraise(), conn.transaction():
        conn.execute(_LOCK_SQL)
        # read by tgsis.chosen_storage (create_storage, the upgrade script) on both routes; the caller's value
        # comes back at the end (the setting is the transaction's: a caller's transaction would keep ours)
        row = conn.execute(
            "SELECT current_setting('tgsis.storage', true), set_config('tgsis.storage', %s, true)", (storage,)
        ).fetchone()
        caller_storage = "" if row is None or row[0] is None else str(row[0])
        current = installed_version(conn)
        roles_before, extensions_before = _existing(conn)
        if current is None:
            done = _install_fresh(conn, sources, method, steps)
            log.info("installed tgsis %s (%s)", target, done)
            result = ("installed", done, None)
        else:
            if parse_version(current.version) > parse_version(target):
                raise InstallationError(
                    f"the database has tgsis {current.version}, newer than this client's {target}",
                    hint="this client is older than the database: upgrade the client (pip install --upgrade tgsis)",
                )
            if current.version == target:
                if current.fingerprint is not None and current.fingerprint != sources.fingerprint:
                    problem, fix = _fingerprint_mismatch(current, sources, conn.info.dbname)
                    raise InstallationError(problem, hint=fix)
                if _create_storage(conn):
                    steps.append(
                        "created the storage tables the extension was created without (SELECT tgsis.create_storage())"
                    )
                result = ("unchanged", current.method, current.version)
            else:
                _upgrade(conn, current, sources, steps)
                # the PostGIS wrappers are made at run time (sql/postgis/enable_postgis.sql): again for the new version
                if conn.execute(
                    "SELECT to_regprocedure('tgsis.postgis_geometry(text, bigint)') IS NOT NULL "
                    "AND to_regprocedure('tgsis.enable_postgis()') IS NOT NULL"
                ).fetchone() == (True,):
                    conn.execute("SELECT tgsis.enable_postgis()")
                    steps.append("made the PostGIS functions again (SELECT tgsis.enable_postgis())")
                log.info("upgraded tgsis %s -> %s (%s)", current.version, target, current.method)
                result = ("upgraded", current.method, current.version)
        roles_after, extensions_after = _existing(conn)
        if created := sorted(roles_after - roles_before, key=_TGSIS_ROLES.index):
            steps.insert(0, "created the roles " + ", ".join(created))
        if required := sorted((extensions_after - extensions_before) - {EXTENSION}):
            steps.insert(0, "created the extension(s) tgsis needs: " + ", ".join(required))
        if result[0] != "unchanged":
            steps.extend(_storage_steps(conn, storage))
        still_needed = _make_owner_admin(conn, steps)
        conn.execute("SELECT set_config('tgsis.storage', %s, true)", (caller_storage,))
    action, route, previous = result
    return InstallResult(action, route, target, previous, tuple(steps), still_needed)  # type: ignore[arg-type]


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


@checked
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


@checked
def partition_model_storage(conn: psycopg.Connection[Any], model: int, partitions: int) -> list[str]:
    """Hash-partition the storage tables of a data model by geoid (``tgsis.partition_model_storage``).

    For a database that will outgrow plain tables (docs/scaling.md): run it
    once, best after :func:`install` before storing data of that model (the
    rows are then moved once). The tables keep their definitions, index
    names, comments, owner and the group roles' rights. Their storage is
    partitioned with its data, versioned or not, verified bit for bit: the
    table, or ``<table>_ver`` (its versioned view stays the same view), or a
    table stored in chunks its chunk table (its face stays the same view).

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
        table; docs/scaling.md): on a default server 218 for model 1 (row storage).

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
        A table is partitioned already, or other objects use its storage (views, foreign keys, a user's
        trigger: named; nothing is changed).
    MissingPrivilegeError
        The role may not run it or does not own the tables.
    """
    # the SQL parameters are smallint and integer: a larger number would come back as a raw 22003
    for name, value, high, hint in (
        ("model", model, 2**15 - 1, "SELECT model FROM tgsis.data_models lists them"),
        ("partitions", partitions, 2**31 - 1, "give 2 to 1024 partitions"),
    ):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise InvalidInputError(
                f"{name} must be an integer, not {type(value).__name__} {repr(value)[:100]}", hint=hint
            )
        if not -high - 1 <= int(value) <= high:
            raise InvalidInputError(f"{name} = {str(int(value))[:100]} is out of range", hint=hint)
    with reraise(), conn.transaction():
        row = conn.execute(
            "SELECT tgsis.partition_model_storage(%s::smallint, %s::integer)", (model, partitions)
        ).fetchone()
    assert row is not None
    return list(row[0])
