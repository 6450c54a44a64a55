"""pytest fixtures: a real PostgreSQL for every test, never a mock.

Load with ``pytest_plugins = ["tgsis.testing"]`` in a ``conftest.py``.

Which server, first match wins:

1. ``$TGSIS_TEST_DSN``: an existing server, as a role that may create
   databases (and roles, unless the ``tgsis_*`` roles exist);
2. Docker, through testcontainers, with the image of ``docker/``, when an
   engine answers and ``$TGSIS_PG`` does not ask for local binaries;
3. a throwaway local cluster (:meth:`tgsis.db.local.LocalServer.throwaway`)
   with the binaries ``$TGSIS_PG`` selects (embedded PostgreSQL 18 or the
   system's).

If none starts, every test that needs a database fails with the reasons:
a run without the database tests is a failed run.

Isolation: the session installs tgsis once into a template database; the
``db_dsn`` and ``conn`` fixtures give each test a fresh database cloned from
it (``CREATE DATABASE ... TEMPLATE``) and drop it afterwards, so tests may
commit, open several connections or break things freely. ``tx`` is the cheap
alternative for tests that only need one transaction: a connection to a
shared database inside a transaction that is rolled back after the test.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import os
import time
import uuid
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, Literal

import psycopg
import pytest
from psycopg import sql
from psycopg.conninfo import conninfo_to_dict, make_conninfo

from tgsis.db.install import install
from tgsis.db.local import LocalServer, find_binaries
from tgsis.db.sqlsource import ExtensionSources, find_sql_dir

__all__ = [
    "STORAGES",
    "TIME_BY_FILE",
    "TestServer",
    "conn",
    "db_dsn",
    "db_storage",
    "db_time_storage",
    "default_storage",
    "make_database",
    "pg",
    "start_test_server",
    "storage_of",
    "storage_template_db",
    "storage_templates",
    "time_storage",
    "time_storage_of",
    "time_swapped_file",
    "tx",
]

log = logging.getLogger(__name__)

_counter = itertools.count()


@dataclass
class TestServer:
    """The PostgreSQL server of a test session.

    Attributes
    ----------
    admin_dsn : str
        DSN of its maintenance database, as a role that may create databases.
    provider : {"dsn", "docker", "local"}
        Where it came from.
    description : str
        One line for reports.
    server_version : str
        ``server_version`` of the server, e.g. ``"15.18"``.
    extension_files : str or None
        ``None`` when ``CREATE EXTENSION tgsis`` works on this server, else why not.
    local : LocalServer or None
        The throwaway cluster, for provider ``local``.
    """

    __test__ = False  # not a test class, despite its name

    admin_dsn: str
    provider: Literal["dsn", "docker", "local"]
    description: str
    server_version: str = ""
    extension_files: str | None = None
    local: LocalServer | None = None
    _teardown: list[Callable[[], None]] = field(default_factory=list, repr=False)
    _admin: psycopg.Connection[Any] | None = field(default=None, repr=False)

    @property
    def major(self) -> int:
        """Major version of the server."""
        return int(self.server_version.split(".")[0])

    def dsn(self, dbname: str) -> str:
        """DSN of another database of this server."""
        params = conninfo_to_dict(self.admin_dsn)
        params["dbname"] = dbname
        return make_conninfo(**{k: str(v) for k, v in params.items() if v is not None})

    def _admin_execute(self, query: sql.SQL | sql.Composed, params: tuple[Any, ...] = ()) -> psycopg.Cursor[Any]:
        """Run one statement on the kept autocommit connection to the maintenance database.

        One connection for the session rather than one per database made or
        dropped (twice per test); opened again, and the statement run again,
        when a test ended it (``pg_terminate_backend``, a restart).
        """
        for attempt in range(2):
            if self._admin is None or self._admin.closed:
                self._admin = psycopg.connect(self.admin_dsn, autocommit=True)
            try:
                return self._admin.execute(query, params)
            except psycopg.OperationalError:
                if attempt or not self._admin.broken:
                    raise
                self._admin.close()
        raise AssertionError("unreachable")

    def create_database(self, name: str, template: str = "template0") -> str:
        """Create a database and return its DSN.

        ``STRATEGY FILE_COPY`` (PostgreSQL 15+): the template's files copied
        at once rather than its pages written through the write-ahead log
        (the default since 15), which costs more for the small databases of
        the tests.
        """
        strategy = sql.SQL(" STRATEGY FILE_COPY") if self._admin_version() >= 150000 else sql.SQL("")
        self._admin_execute(
            sql.SQL("CREATE DATABASE {} TEMPLATE {}{}").format(sql.Identifier(name), sql.Identifier(template), strategy)
        )
        return self.dsn(name)

    def _admin_version(self) -> int:
        if self._admin is None or self._admin.closed:
            self._admin_execute(sql.SQL("SELECT 1"))
        assert self._admin is not None
        return self._admin.info.server_version

    def drop_database(self, name: str) -> None:
        """Drop a database, ending its sessions.

        The sessions a test closed are waited for first (a few milliseconds;
        half a second at most, then ``FORCE`` ends those a test left open):
        ``DROP DATABASE`` finding one of them still on its way out sleeps a
        tenth of a second before it looks again, which most tests paid.
        """
        deadline = time.monotonic() + 0.5
        while time.monotonic() < deadline and self._admin_execute(
            sql.SQL("SELECT EXISTS (SELECT FROM pg_stat_activity WHERE datname = %s)"), (name,)
        ).fetchone() == (True,):
            time.sleep(0.002)
        self._admin_execute(sql.SQL("DROP DATABASE IF EXISTS {} WITH (FORCE)").format(sql.Identifier(name)))

    @contextlib.contextmanager
    def database(self, prefix: str, template: str = "template0") -> Iterator[tuple[str, str]]:
        """A database with a unique name, dropped on exit; yields ``(name, dsn)``."""
        name = f"{prefix}_{os.getpid()}_{next(_counter)}_{uuid.uuid4().hex[:6]}"
        dsn = self.create_database(name, template)
        try:
            yield name, dsn
        finally:
            with contextlib.suppress(Exception):
                self.drop_database(name)

    def close(self) -> None:
        if self._admin is not None:
            with contextlib.suppress(Exception):
                self._admin.close()
            self._admin = None
        for step in reversed(self._teardown):
            with contextlib.suppress(Exception):
                step()
        self._teardown.clear()


def _check_extension_files(server: TestServer) -> None:
    """Set ``extension_files`` to why CREATE EXTENSION tgsis would not give this client's SQL."""
    sources = ExtensionSources.default()
    with psycopg.connect(server.admin_dsn) as conn:
        server.server_version = str(conn.execute("SHOW server_version").fetchone()[0]).split()[0]  # type: ignore[index]
        available = conn.execute(
            "SELECT 1 FROM pg_available_extension_versions WHERE name = 'tgsis' AND version = %s",
            (sources.version,),
        ).fetchone()
    if not available:
        server.extension_files = (
            f"the server has no extension files for tgsis {sources.version}: run `make -C sql install` "
            "for its PostgreSQL (PGXS), or use the embedded PostgreSQL 18"
        )
        return
    local = server.local
    if local is not None and not local.binaries.has_extension_control_path and local.binaries.sharedir:
        installed = local.binaries.sharedir / "extension" / f"tgsis--{sources.version}.sql"
        if installed.read_text(encoding="utf-8") != sources.script():
            server.extension_files = f"{installed} differs from this checkout's SQL: run `make -C sql install` again"


def _from_dsn(dsn: str) -> TestServer:
    return TestServer(dsn, "dsn", f"existing server from TGSIS_TEST_DSN ({conninfo_to_dict(dsn).get('host')})")


def _from_docker() -> TestServer:
    import docker  # installed with testcontainers

    client = docker.from_env(timeout=5)  # type: ignore[attr-defined]
    client.ping()
    from testcontainers.core.image import DockerImage
    from testcontainers.postgres import PostgresContainer

    repo = find_sql_dir().parent
    if not (repo / "docker" / "Dockerfile").is_file():
        raise RuntimeError(f"no docker/Dockerfile beside {find_sql_dir()}")
    image = DockerImage(path=str(repo), dockerfile_path="docker/Dockerfile", tag="tgsis-test:dev")
    image.build()
    container = PostgresContainer(str(image), username="postgres", password="postgres", dbname="postgres")
    container.start()
    url = container.get_connection_url(driver=None)
    server = TestServer(url, "docker", f"Docker container of {image}")
    server._teardown.append(container.stop)
    return server


def _from_local() -> TestServer:
    local = LocalServer.throwaway(find_binaries(), in_memory=True)
    server = TestServer(
        local.dsn(), "local", f"{local.binaries.describe()}, throwaway cluster {local.root}", local=local
    )
    server._teardown.append(local.destroy)
    return server


def start_test_server() -> TestServer:
    """Start (or reach) the session's server, in the order of the module documentation.

    Raises
    ------
    RuntimeError
        No server could be had; the message lists why for each way tried.
    """
    tried: list[str] = []
    providers: list[tuple[str, Callable[[], TestServer]]] = []
    if dsn := os.environ.get("TGSIS_TEST_DSN"):
        providers.append(("TGSIS_TEST_DSN", lambda: _from_dsn(dsn)))
    else:
        if not os.environ.get("TGSIS_PG") and os.environ.get("TGSIS_TEST_DOCKER", "1") != "0":
            providers.append(("Docker", _from_docker))
        providers.append(("local cluster", _from_local))
    for name, provider in providers:
        server: TestServer | None = None
        try:
            server = provider()
            _check_extension_files(server)
        except Exception as exc:  # noqa: BLE001 - every reason is reported
            if server is not None:
                server.close()
            tried.append(f"{name}: {type(exc).__name__}: {exc}".strip())
            log.info("test server via %s unavailable: %s", name, exc)
            continue
        if tried:
            server.description += f"; tried before: {'; '.join(tried)}"
        return server
    raise RuntimeError("no PostgreSQL server for the tests:\n  " + "\n  ".join(tried))


# --------------------------------------------------------------------------- fixtures

_SESSION: dict[str, Any] = {}


@pytest.fixture(scope="session")
def pg() -> Iterator[TestServer]:
    """The session's PostgreSQL server (fails every test that needs it if none can start)."""
    try:
        server = start_test_server()
    except RuntimeError as exc:
        pytest.fail(str(exc), pytrace=False)
    _SESSION["server"] = server
    try:
        yield server
    finally:
        server.close()


STORAGES = ("rows", "chunks")
"""The storages of model 1 a test database can have (docs/storage.md): ``rows`` or ``chunks``."""

STORAGE_MARK = "storage"
"""``@pytest.mark.storage("rows")``: the test's databases (``db_dsn``, ``conn``, ``tx``) have that storage."""


def default_storage(node: pytest.Item | pytest.Collector | None = None) -> Literal["rows", "chunks"]:
    """The storage of the tests without the mark ``storage``: ``$TGSIS_TEST_STORAGE``, else ``chunks``.

    With ``$TGSIS_TEST_STORAGE_BY_FILE=1``, the tests of every other file
    (``node``'s file: its name's CRC-32 odd, :func:`swapped_file`) take the
    other storage: two suites with opposite storages then run each file
    once on each storage, and each storage on both servers
    (docs/testing.md). Without ``node``: ``$TGSIS_TEST_STORAGE``'s.

    Raises
    ------
    pytest.UsageError
        ``$TGSIS_TEST_STORAGE`` names no storage of :data:`STORAGES`, or
        ``$TGSIS_TEST_STORAGE_BY_FILE`` is neither empty, ``0`` nor ``1``.
    """
    value = os.environ.get("TGSIS_TEST_STORAGE") or "chunks"
    if value not in STORAGES:
        raise pytest.UsageError(f"TGSIS_TEST_STORAGE={value!r} names no storage: use one of {', '.join(STORAGES)}")
    storage: Literal["rows", "chunks"] = "rows" if value == "rows" else "chunks"
    by_file = os.environ.get("TGSIS_TEST_STORAGE_BY_FILE") or "0"
    if by_file not in ("0", "1"):
        raise pytest.UsageError(f"TGSIS_TEST_STORAGE_BY_FILE={by_file!r}: use 1 (storage by file) or 0")
    if by_file == "1" and node is not None and swapped_file(node.path.name):
        return "chunks" if storage == "rows" else "rows"
    return storage


def swapped_file(name: str) -> bool:
    """Whether the test file ``name`` (its base name) takes the other storage under ``$TGSIS_TEST_STORAGE_BY_FILE``."""
    return zlib.crc32(name.encode()) % 2 == 1


def storage_of(node: pytest.Item | pytest.Collector | None) -> str:
    """The storage a test asks for with ``@pytest.mark.storage(...)`` (closest mark), else :func:`default_storage`.

    Raises
    ------
    pytest.UsageError
        The mark names no storage of :data:`STORAGES`, or has not one argument.
    """
    mark = node.get_closest_marker(STORAGE_MARK) if node is not None else None
    if mark is None:
        return default_storage(node)
    if len(mark.args) != 1 or mark.kwargs or mark.args[0] not in STORAGES:
        raise pytest.UsageError(
            f"{node.nodeid if node is not None else ''}: @pytest.mark.storage takes one storage of "
            f"{', '.join(STORAGES)}, not {mark.args!r} {mark.kwargs or ''}".rstrip()
        )
    return str(mark.args[0])


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        f"{STORAGE_MARK}(name): the test's databases (db_dsn, conn, tx, storage_template_db) store model 1 in "
        f"{' or '.join(STORAGES)} whatever TGSIS_TEST_STORAGE says (a template of that storage, built at first use)",
    )


TIME_BY_FILE = "by-file"
"""``$TGSIS_TEST_TIME_STORAGE=by-file``: model 2's time tables take the other storage than model 1's in every other
file (:func:`time_swapped_file`), so that the storage of an upgraded database (model 1 in chunks, model 2 in rows)
and its mirror are tested as well as the storages that go together (:func:`time_storage_of`)."""


def time_storage() -> Literal["rows", "chunks"] | None:
    """The storage forced on the time models' tables in the templates: ``$TGSIS_TEST_TIME_STORAGE``, else ``None``.

    The tables of models 2 to 5 registered for chunks (``tgsis.model_tables.chunkcolumn``): model 2's
    times_vrtx and times_trgl, model 3's d4dtrgl and d4dvrtx, the G-maps' gmap_dart, gmap_alpha, md_dart,
    md_alpha and their points gmap_vertex and md_vertex.

    ``None`` (unset, or :data:`TIME_BY_FILE`): the templates as the install leaves them. Model 2's time tables
    are stored in chunks by default (``chunkdefault``) as model 1's are, so they follow the template's storage
    (:func:`default_storage`: under ``$TGSIS_TEST_STORAGE_BY_FILE`` every other file takes the other one, the
    same registry, :func:`swapped_file`), unless :func:`time_storage_of` says otherwise for a file; models 3 to
    5 stay rows. ``rows`` or ``chunks``: every one of those tables is switched to that storage after the
    install (``tgsis.store_in_rows`` / ``tgsis.store_in_chunks``), whatever the template's model 1.

    Raises
    ------
    pytest.UsageError
        ``$TGSIS_TEST_TIME_STORAGE`` names no storage of :data:`STORAGES` and is not :data:`TIME_BY_FILE`.
    """
    value = os.environ.get("TGSIS_TEST_TIME_STORAGE") or None
    if value is None or value == TIME_BY_FILE:
        return None
    if value not in STORAGES:
        raise pytest.UsageError(
            f"TGSIS_TEST_TIME_STORAGE={value!r} names no storage: use one of {', '.join(STORAGES)} or {TIME_BY_FILE}"
        )
    return "chunks" if value == "chunks" else "rows"


def time_swapped_file(name: str) -> bool:
    """Whether model 2's time tables take the other storage than model 1's in the test file ``name`` (its base
    name) under ``$TGSIS_TEST_TIME_STORAGE=by-file``: the second bit of the name's CRC-32, independent of the
    first one (:func:`swapped_file`), so that each file runs the two storages of model 2 in the two suites."""
    return (zlib.crc32(name.encode()) >> 1) % 2 == 1


def time_storage_of(node: pytest.Item | pytest.Collector | None) -> Literal["rows", "chunks"]:
    """The storage of model 2's time tables in the databases of the test (or module) ``node``.

    :func:`time_storage` when it forces one; else model 1's storage (:func:`storage_of`), as the install leaves
    it, except under ``$TGSIS_TEST_TIME_STORAGE=by-file`` for the unmarked tests of a file
    :func:`time_swapped_file` names: the other storage. A test marked ``storage`` asks for model 1's storage and
    keeps model 2 with it.
    """
    forced = time_storage()
    if forced is not None:
        return forced
    model1: Literal["rows", "chunks"] = "rows" if storage_of(node) == "rows" else "chunks"
    if (
        node is not None
        and os.environ.get("TGSIS_TEST_TIME_STORAGE") == TIME_BY_FILE
        and node.get_closest_marker(STORAGE_MARK) is None
        and time_swapped_file(node.path.name)
    ):
        return "chunks" if model1 == "rows" else "rows"
    return model1


def _install_template(
    conn: psycopg.Connection[Any], method: Literal["extension", "sql"], storage: str, time: str
) -> str:
    """Install tgsis into a template database with model 1 stored in ``storage``; the route taken.

    Model 2's time tables (registered for chunks by default) take ``storage`` too; the time models' tables are
    then switched as :func:`time_storage` says, when it says, else model 2's into ``time`` when it differs.
    """
    route = install(conn, method=method, storage="rows" if storage == "rows" else "chunks").method
    forced = time_storage()
    target = forced or time
    if forced is not None or time != storage:
        conn.execute(
            sql.SQL(
                "SELECT tgsis.{}(tablename) FROM tgsis.model_tables"
                " WHERE model >= 2 AND chunkcolumn IS NOT NULL AND tgsis.stored_in_chunks(tablename) = {}"
                " AND (chunkdefault OR {}) ORDER BY model, iudorder, tablename"
            ).format(
                sql.Identifier("store_in_chunks" if target == "chunks" else "store_in_rows"),
                sql.Literal(target == "rows"),
                sql.Literal(forced is not None),
            )
        )
        conn.commit()
    return route


@pytest.fixture(scope="session")
def storage_templates(pg: TestServer) -> Iterator[Callable[..., str]]:
    """Factory ``storage_templates(storage, time=None) -> name`` of a template database with tgsis installed.

    Model 1 is stored in ``storage`` (``"rows"`` or ``"chunks"``), model 2's time tables in ``time`` (``None``:
    :func:`time_storage`'s when it forces one, else ``storage``, as the install leaves them); each is built at
    its first use, once per session. Installed with ``CREATE EXTENSION`` when the server has the files, else
    with the plain SQL.
    """
    built: dict[tuple[str, str], str] = {}
    with contextlib.ExitStack() as stack:

        def get(storage: str, time: str | None = None) -> str:
            if storage not in STORAGES or (time is not None and time not in STORAGES):
                raise ValueError(f"no storage {storage!r}/{time!r}: use one of {', '.join(STORAGES)}")
            time = time_storage() or time or storage
            if (storage, time) not in built:
                label = storage if time == storage else f"{storage}_time_{time}"
                name, dsn = stack.enter_context(pg.database(f"tgsis_tpl_{label}"))
                with psycopg.connect(dsn) as conn:
                    method = _install_template(
                        conn, "extension" if pg.extension_files is None else "sql", storage, time
                    )
                _SESSION.setdefault("template_method", method)
                _SESSION.setdefault("storages", []).append(
                    storage if time == storage else f"{storage} (model 2 {time})"
                )
                built[storage, time] = name
            return built[storage, time]

        yield get


@pytest.fixture(scope="module")
def template_db(request: pytest.FixtureRequest, storage_templates: Callable[..., str]) -> str:
    """Name of a database with tgsis installed, model 1 in :func:`default_storage` (cloned by :func:`db_dsn`).

    Model 2's time tables as :func:`time_storage_of` says for the module. A test marked ``storage`` takes
    :func:`storage_template_db` instead (``db_dsn`` does): this one is the default storage's (its module's,
    under ``$TGSIS_TEST_STORAGE_BY_FILE``) whatever the mark says.
    """
    storage = default_storage(request.node)
    time = time_storage_of(request.node) if request.node.get_closest_marker(STORAGE_MARK) is None else storage
    return storage_templates(storage, time)


@pytest.fixture
def db_storage(request: pytest.FixtureRequest) -> str:
    """The storage of model 1 in the test's databases: its mark ``storage``, else :func:`default_storage`."""
    return storage_of(request.node)


@pytest.fixture
def db_time_storage(request: pytest.FixtureRequest) -> str:
    """The storage of model 2's time tables in the test's databases (:func:`time_storage_of`)."""
    return time_storage_of(request.node)


@pytest.fixture
def storage_template_db(db_storage: str, db_time_storage: str, storage_templates: Callable[..., str]) -> str:
    """Name of the template database of the test's storages (:func:`db_storage`, :func:`db_time_storage`)."""
    return storage_templates(db_storage, db_time_storage)


@pytest.fixture
def make_database(pg: TestServer) -> Iterator[Callable[..., str]]:
    """Factory ``make_database(template="template0") -> dsn`` of databases dropped after the test."""
    with contextlib.ExitStack() as stack:

        def make(template: str = "template0") -> str:
            return stack.enter_context(pg.database("tgsis_t", template))[1]

        yield make


@pytest.fixture
def db_dsn(make_database: Callable[..., str], storage_template_db: str) -> str:
    """DSN of a fresh database with tgsis installed (the test's storage), dropped after the test."""
    return make_database(storage_template_db)


@pytest.fixture
def conn(db_dsn: str) -> Iterator[psycopg.Connection[Any]]:
    """Connection (not autocommit) to a fresh database with tgsis installed."""
    with psycopg.connect(db_dsn) as connection:
        yield connection


@pytest.fixture(scope="session")
def shared_databases(pg: TestServer, storage_templates: Callable[..., str]) -> Iterator[Callable[..., str]]:
    """Factory ``shared_databases(storage, time=None) -> dsn``: one database per storage pair (model 1, model 2's
    time tables: :func:`storage_templates`) shared by the tests of :func:`tx`."""
    made: dict[str, str] = {}  # template -> dsn
    with contextlib.ExitStack() as stack:

        def get(storage: str, time: str | None = None) -> str:
            template = storage_templates(storage, time)
            if template not in made:
                made[template] = stack.enter_context(pg.database("tgsis_shared", template))[1]
            return made[template]

        yield get


@pytest.fixture(scope="session")
def shared_db_dsn(shared_databases: Callable[..., str]) -> str:
    """DSN of one database with tgsis installed (the default storage), shared by the tests that use :func:`tx`."""
    return shared_databases(default_storage())


@pytest.fixture
def tx(
    db_storage: str, db_time_storage: str, shared_databases: Callable[..., str]
) -> Iterator[psycopg.Connection[Any]]:
    """Connection inside a transaction that is rolled back after the test (cheaper than :func:`conn`).

    The shared database of the test's storages (:func:`db_storage`, :func:`db_time_storage`). The test
    must not commit (psycopg refuses ``commit()`` inside the transaction
    block); tests that commit, or that need several connections to see each
    other's data, use :func:`conn` / :func:`db_dsn`.
    """
    with psycopg.connect(shared_databases(db_storage, db_time_storage)) as connection:
        with connection.transaction(force_rollback=True):
            yield connection


def pytest_terminal_summary(terminalreporter: Any) -> None:
    """Say which server the database tests ran against (CI logs show it per run)."""
    server: TestServer | None = _SESSION.get("server")
    if server is None:
        return
    terminalreporter.write_sep("-", "tgsis test database")
    terminalreporter.write_line(f"server: PostgreSQL {server.server_version}: {server.description}")
    terminalreporter.write_line(
        f"template installed with: {_SESSION.get('template_method', 'not used')}"
        f" (model 1 in: {', '.join(_SESSION.get('storages', [])) or 'no template made'}; default storage: "
        f"{default_storage()}"
        + (", the other one for every other file" if os.environ.get("TGSIS_TEST_STORAGE_BY_FILE") == "1" else "")
        + (
            f"; models 2 to 5's tables registered for chunks in {time_storage()} (TGSIS_TEST_TIME_STORAGE)"
            if time_storage() is not None
            else "; model 2's time tables in the other storage for every other file"
            if os.environ.get("TGSIS_TEST_TIME_STORAGE") == TIME_BY_FILE
            else "; model 2's time tables with model 1"
        )
        + "); CREATE EXTENSION tgsis: "
        + ("available" if server.extension_files is None else f"NOT available ({server.extension_files})")
    )
