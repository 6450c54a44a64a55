"""Every test that takes `pg`, `db_dsn`, `conn` or `make_database` gets a real
PostgreSQL from the tgsis.testing plugin (see docs/testing.md).

Set-ups built once: a test that asks for one of the fixtures of
``_BUILT_ONCE`` gets, as its fresh database (``db_dsn``, ``conn``), a clone
(``CREATE DATABASE ... TEMPLATE``) of a database where that set-up was
built once per session, instead of building it again: the test still has a
database of its own, which it may change and commit as it likes.
A test module lists set-ups of its own the same way, in a module-level
``BUILT_ONCE`` (fixture name -> set-up). The test's own code then no longer
makes those calls: the clone is the database they made, in the same order.
A module's fixture over such a set-up returns ``cloned_or_built(...)``, so that
a module importing the fixture (and ordering its own set-up before it) still
gets it built on the test's connection.

``--server-tests-only`` deselects the pure tests: those that never reach a
PostgreSQL server, so give the same result on every version. A test reaches
one when a fixture it uses depends, at any depth, on the server fixture
``pg`` (``item.fixturenames`` is that closure), or when it starts or reaches
a server by itself (a local server of its own, a child process that does):
those carry the mark ``own_server``. ``tools/test-suites`` passes the option
to the second suite (PostgreSQL 18), so that the pure tests run once.
It deselects as well the tests marked ``one_server``: they reach a server,
but what they check is the harness's handling of processes (signals, the
lease watcher, where a throwaway cluster's folder goes), the same code on
every version; the version-specific part (initdb/pg_ctl flags, installing
the extension) is checked by other tests that run in both suites.

``--no-pure-tests`` deselects the pure tests alone (the first suite's
server tests, ``one_server`` ones included), ``--pure-tests-only`` keeps
them alone: ``tools/test-suites`` runs the pure tests in a pass of their
own, on the second suite's side, so that the two sides take about as long
(docs/testing.md, "Balance").
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any, Protocol

import psycopg
import pytest

if TYPE_CHECKING:  # (imported at run time as the plugin below, not before it: pytest rewrites its asserts)
    from tgsis.testing import TestServer

pytest_plugins = ["tgsis.testing"]

Conn = psycopg.Connection[Any]

SERVER_FIXTURE = "pg"  # tgsis.testing's session server: every database fixture depends on it
OWN_SERVER = "own_server"  # the mark of a test that starts or reaches a server without that fixture
ONE_SERVER = "one_server"  # the mark of a test of process handling alone: --server-tests-only deselects it


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--server-tests-only",
        action="store_true",
        help="deselect the tests that reach no PostgreSQL server (neither the fixture pg, at any depth, "
        f"nor the mark {OWN_SERVER}) and those marked {ONE_SERVER}: what they prove does not depend on the "
        "server's version",
    )
    parser.addoption(
        "--slowest-files",
        type=int,
        default=0,
        metavar="N",
        help="at the end, the N test files whose tests took longest (set-up, call and teardown summed): the "
        "profile of a whole run, per file (tools/test-suites asks for it; docs/testing.md)",
    )
    parser.addoption(
        "--no-pure-tests",
        action="store_true",
        help=f"deselect the tests that reach no PostgreSQL server (neither pg nor {OWN_SERVER}); keep the others, "
        f"{ONE_SERVER} included: they run in a pass of their own (--pure-tests-only)",
    )
    parser.addoption(
        "--pure-tests-only",
        action="store_true",
        help=f"deselect the tests that reach a PostgreSQL server (pg at any depth, or the mark {OWN_SERVER}): "
        "the pure tests' pass of their own",
    )


def pytest_configure(config: pytest.Config) -> None:
    if config.getoption("--slowest-files") > 0:
        config.pluginmanager.register(SlowestFiles(config.getoption("--slowest-files")), "tgsis-slowest-files")
    config.addinivalue_line(
        "markers",
        f"{OWN_SERVER}: the test starts or reaches a PostgreSQL server without the fixture pg "
        "(its own local server, a child process that starts one): kept by --server-tests-only",
    )
    config.addinivalue_line(
        "markers",
        f"{ONE_SERVER}: the test checks the harness's handling of processes (signals, the lease watcher, "
        "where a cluster's folder goes), not what differs between PostgreSQL versions: deselected by "
        "--server-tests-only, so it runs in one suite",
    )


def runs_on_every_server(item: pytest.Item) -> bool:
    """Whether --server-tests-only keeps ``item``: it reaches a server and is not marked ``one_server``."""
    return reaches_server(item) and item.get_closest_marker(ONE_SERVER) is None


def reaches_server(item: pytest.Item) -> bool:
    """Whether ``item`` reaches a PostgreSQL server: uses ``pg`` (at any depth) or has the mark ``own_server``.

    An item that is not a test function (no ``fixturenames``) counts as reaching one.
    """
    fixturenames = getattr(item, "fixturenames", None)
    if fixturenames is None:
        return True
    return SERVER_FIXTURE in fixturenames or item.get_closest_marker(OWN_SERVER) is not None


_SELECTIONS = ("--server-tests-only", "--no-pure-tests", "--pure-tests-only")


def _kept(config: pytest.Config) -> Callable[[pytest.Item], bool] | None:
    """Which tests the options keep (``None``: all of them); two of them at once stop the run."""
    given = [option for option in _SELECTIONS if config.getoption(option)]
    if len(given) > 1:
        raise pytest.UsageError(f"{' and '.join(given)} select different tests: give one of them")
    if config.getoption("--server-tests-only"):
        return runs_on_every_server
    if config.getoption("--no-pure-tests"):
        return reaches_server
    if config.getoption("--pure-tests-only"):
        return lambda item: not reaches_server(item)
    return None


@pytest.hookimpl(trylast=True)  # after -k and -m: a selection of pure tests alone is told from one of nothing
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    kept = _kept(config)
    if kept is None:
        return
    others = [item for item in items if not kept(item)]
    if others:
        config.hook.pytest_deselected(items=others)
        items[:] = [item for item in items if kept(item)]
        config.stash[_EMPTIED_BY_OPTION] = not items


_EMPTIED_BY_OPTION = pytest.StashKey[bool]()


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """A selection the options emptied (``make test PYTEST_ARGS=tests/test_cli_help.py``: pure tests alone,
    in a server suite) passes here: it ran in another pass. A selection that collects nothing at all still
    fails (exit 5)."""
    if session.config.stash.get(_EMPTIED_BY_OPTION, False) and exitstatus == pytest.ExitCode.NO_TESTS_COLLECTED:
        session.exitstatus = pytest.ExitCode.OK


def pytest_report_collectionfinish(config: pytest.Config, items: list[pytest.Item]) -> str | None:
    if config.getoption("--server-tests-only"):
        return (
            "--server-tests-only: the tests that reach no PostgreSQL server, and those marked "
            f"{ONE_SERVER}, are deselected (they run on the other suite)"
        )
    if config.getoption("--no-pure-tests"):
        return "--no-pure-tests: the tests that reach no PostgreSQL server are deselected (they run in a pass of their own)"
    if config.getoption("--pure-tests-only"):
        return "--pure-tests-only: the tests that reach a PostgreSQL server are deselected (they run in the suites)"
    return None


class SlowestFiles:
    """``--slowest-files N``: each file's test phases summed, the N longest said at the end (a profile per file)."""

    def __init__(self, count: int) -> None:
        self.count = count
        self.seconds: dict[str, list[float]] = {}  # file -> [seconds of its tests' phases, tests]

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        entry = self.seconds.setdefault(report.nodeid.split("::")[0], [0.0, 0])
        entry[0] += report.duration
        entry[1] += report.when == "call"

    def pytest_terminal_summary(self, terminalreporter: Any) -> None:
        if not self.seconds:
            return
        total = sum(spent for spent, _ in self.seconds.values())
        terminalreporter.write_sep("=", f"slowest {self.count} files (set-up + call + teardown of their tests)")
        for name, (spent, tests) in sorted(self.seconds.items(), key=lambda item: -item[1][0])[: self.count]:
            terminalreporter.write_line(f"{spent:8.1f}s {100 * spent / total:5.1f}% {int(tests):5d} tests  {name}")
        tests = int(sum(t for _, t in self.seconds.values()))
        terminalreporter.write_line(f"{total:8.1f}s in all: {tests} tests in {len(self.seconds)} files")


def _fault(conn: Conn) -> int:
    from tests.merge_data import make_fault

    return make_fault(conn)


def _three_regions(conn: Conn) -> int:
    from tests.test_conflict_regions import three_regions

    return three_regions(conn)


def _two_conflicts(conn: Conn) -> int:
    from tests.test_resolve_all_regions import two_conflicts

    return two_conflicts(conn)


def _series(conn: Conn) -> int:
    from tests.test_merge_instants import make_series

    return make_series(conn)


def _evolving(conn: Conn) -> int:
    from tests.test_merge_instants import make_evolving

    return make_evolving(conn)


def _periods(conn: Conn) -> int:
    from tests.test_sql_merge_periods import make_periods

    return make_periods(conn)


class BuiltOnce(Protocol):
    """The ``built_once`` fixture: ``get(name, build=None) -> (database, value)``."""

    def __call__(self, name: str, build: Callable[[Conn], int] | None = None, /) -> tuple[str, int]: ...


class BuiltOnceByStorage(Protocol):
    """The ``built_once_by_storage`` fixture: ``get(storage, name, build=None, time=None) -> (database, value)``."""

    def __call__(
        self, storage: str, name: str, build: Callable[[Conn], int] | None = None, /, time: str | None = None
    ) -> tuple[str, int]: ...


# fixture name -> the set-up it gives, built on a connection (committed) and returning a value (a geoid)
_BUILT_ONCE: dict[str, Callable[[Conn], int]] = {
    "fault_clone": _fault,  # tests.merge_data.make_fault: the curved fault in DEFAULT, version e1
    "three_regions_clone": _three_regions,  # tests.test_conflict_regions.three_regions
    "two_conflicts_clone": _two_conflicts,  # tests.test_resolve_all_regions.two_conflicts
    "series_clone": _series,  # tests.test_merge_instants.make_series: a model-2 surface in DEFAULT, version e1
    "evolving_clone": _evolving,  # tests.test_merge_instants.make_evolving: a model-3 surface in DEFAULT, version e1
    "periods_clone": _periods,  # tests.test_sql_merge_periods.make_periods: a model-3 surface in DEFAULT, version e1
}


@pytest.fixture(scope="session")
def built_once_by_storage(pg: TestServer, storage_templates: Callable[..., str]) -> Iterator[BuiltOnceByStorage]:
    """``get(storage, name, build=None, time=None) -> (database, value)``: :func:`built_once`'s set-ups, per
    template (model 1's storage, model 2's time tables': ``tgsis.testing.storage_templates``)."""
    built: dict[tuple[str, str], tuple[str, int]] = {}
    with contextlib.ExitStack() as stack:

        def get(
            storage: str, name: str, build: Callable[[Conn], int] | None = None, /, time: str | None = None
        ) -> tuple[str, int]:
            template = storage_templates(storage, time)
            if (template, name) not in built:
                database, dsn = stack.enter_context(pg.database("tgsis_once", template))
                with psycopg.connect(dsn) as conn:
                    value = (build or _BUILT_ONCE[name])(conn)
                    conn.commit()
                built[template, name] = (database, value)
            return built[template, name]

        yield get


@pytest.fixture
def built_once(db_storage: str, db_time_storage: str, built_once_by_storage: BuiltOnceByStorage) -> BuiltOnce:
    """``get(name, build=None) -> (database, value)``: a set-up built at its first use, once per session.

    ``name`` is a fixture of ``_BUILT_ONCE``, or the name of ``build``, a set-up
    of a test module: listed in its ``BUILT_ONCE`` (``db_dsn`` below), or
    cloned by a ``db_dsn`` of the module's own (``test_sql_merge_feature_row.py``,
    one set-up per parameter). A name stands for one set-up, always built by
    the same code. Built on the template of the test's storage (its mark
    ``storage``, else the default: ``db_storage``; model 2's: ``db_time_storage``), once per template.
    """

    def get(name: str, build: Callable[[Conn], int] | None = None) -> tuple[str, int]:
        return built_once_by_storage(db_storage, name, build, time=db_time_storage)

    return get


@pytest.fixture
def db_dsn(
    request: pytest.FixtureRequest,
    make_database: Callable[..., str],
    storage_template_db: str,
    built_once: BuiltOnce,
) -> str:
    """The plugin's fresh database, or a clone of the set-up built once that the test asks for.

    The set-ups: ``_BUILT_ONCE``'s, and those a test module lists in its own
    ``BUILT_ONCE`` (fixture name -> set-up), named ``module.fixture`` in
    ``built_once``; the module's fixture of that name returns
    ``built_once(f"{__name__}.fixture", set_up)[1]``. Of the test's storage
    (the mark ``storage``) in both cases.
    """
    asked: list[tuple[str, Callable[[Conn], int] | None]] = [
        (name, None) for name in _BUILT_ONCE if name in request.fixturenames
    ]
    local: dict[str, Callable[[Conn], int]] = getattr(request.module, "BUILT_ONCE", {})
    asked += [
        (f"{request.module.__name__}.{name}", build) for name, build in local.items() if name in request.fixturenames
    ]
    assert len(asked) <= 1, f"a test's database is the clone of one set-up, not of {[a[0] for a in asked]}"
    return make_database(built_once(*asked[0])[0] if asked else storage_template_db)


def cloned_or_built(
    request: pytest.FixtureRequest, conn: Conn, built_once: BuiltOnce, name: str, set_up: Callable[[Conn], int]
) -> int:
    """The value of a module's set-up ``set_up`` listed as ``name`` in its ``BUILT_ONCE``: the test's database is
    its clone (``db_dsn``) when the test's module lists it so; else (a module that imports the fixture, and
    orders its own fixtures around it) it is built on the test's connection ``conn``, as before, and committed."""
    if getattr(request.module, "BUILT_ONCE", {}).get(name) is set_up:
        return built_once(f"{request.module.__name__}.{name}", set_up)[1]
    value = set_up(conn)
    conn.commit()
    return value


@pytest.fixture
def fault_clone(db_dsn: str, built_once: BuiltOnce) -> int:
    """Geoid of ``make_fault``'s fault, already in the test's database (cloned, not built again)."""
    return built_once("fault_clone")[1]


@pytest.fixture
def three_regions_clone(db_dsn: str, built_once: BuiltOnce) -> int:
    """Geoid of ``three_regions``'s fault, already in the test's database (cloned, not built again)."""
    return built_once("three_regions_clone")[1]


@pytest.fixture
def series_clone(db_dsn: str, built_once: BuiltOnce) -> int:
    """Geoid of ``make_series``'s surface at instants, already in the test's database (cloned, not built again)."""
    return built_once("series_clone")[1]


@pytest.fixture
def two_conflicts_clone(db_dsn: str, built_once: BuiltOnce) -> int:
    """Geoid of ``two_conflicts``'s fault, already in the test's database (cloned, not built again)."""
    return built_once("two_conflicts_clone")[1]


@pytest.fixture
def periods_clone(db_dsn: str, built_once: BuiltOnce) -> int:
    """Geoid of ``make_periods``'s surface of two topology periods, already in the test's database (cloned)."""
    return built_once("periods_clone")[1]


@pytest.fixture
def evolving_clone(db_dsn: str, built_once: BuiltOnce) -> int:
    """Geoid of ``make_evolving``'s surface of one topology period, already in the test's database (cloned)."""
    return built_once("evolving_clone")[1]
