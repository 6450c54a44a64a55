"""``--server-tests-only`` (tests/conftest.py) deselects exactly the tests that reach no server;
``--no-pure-tests`` and ``--pure-tests-only`` split the first suite into its server tests and a pass
of the pure tests alone.

``make test`` runs the whole suite on PostgreSQL 15 and again on 18; the
pure tests (no fixture depending, at any depth, on the server fixture ``pg``,
no mark ``own_server``) give the same result on both, so the second suite
deselects them (tools/test-suites), and the tests marked ``one_server`` too. Checked here on a tiny tests folder that
uses the suite's own hooks, with pytest run in a subprocess: which tests are
kept, that the others are *deselected* (said in the summary line, never
skipped), and the exit status when a selection holds pure tests alone.
"""

from __future__ import annotations

import pytest

pytest_plugins = ["pytester"]

CONFTEST = """
import pytest

from tests.conftest import (  # the suite's own hooks
    pytest_addoption,
    pytest_collection_modifyitems,
    pytest_configure,
    pytest_report_collectionfinish,
    pytest_sessionfinish,
)


@pytest.fixture(scope="session")
def pg():  # stands for tgsis.testing's server fixture (nothing is started here)
    return "server"


@pytest.fixture
def db(pg):
    return pg


@pytest.fixture
def deeper(db):
    return db


@pytest.fixture
def plain(tmp_path):
    return tmp_path
"""

TESTS = """
import pytest


def test_pure():
    pass


def test_pure_with_a_fixture(plain):
    pass


@pytest.mark.parametrize("n", [1, 2])
def test_pure_cases(n):
    pass


def test_server(pg):
    pass


def test_server_two_fixtures_deep(deeper):
    pass


@pytest.mark.usefixtures("db")
def test_server_by_usefixtures():
    pass


@pytest.mark.own_server
def test_own_server():
    pass


@pytest.mark.parametrize("n", [1, 2])
def test_server_cases(db, n):
    pass


@pytest.mark.own_server
@pytest.mark.one_server
def test_one_server_of_its_own():
    pass


@pytest.mark.one_server
def test_one_server_by_the_fixture(db):
    pass


class TestGroup:
    def test_pure_method(self):
        pass

    def test_server_method(self, plain, deeper):
        pass
"""

MARKED_MODULE = """
import pytest

pytestmark = pytest.mark.own_server


def test_marked_by_its_module():
    pass
"""

SERVER_TESTS = {
    "test_cases.py::test_server",
    "test_cases.py::test_server_two_fixtures_deep",
    "test_cases.py::test_server_by_usefixtures",
    "test_cases.py::test_own_server",
    "test_cases.py::test_server_cases[1]",
    "test_cases.py::test_server_cases[2]",
    "test_cases.py::TestGroup::test_server_method",
    "test_marked.py::test_marked_by_its_module",
}
ONE_SERVER_TESTS = {
    "test_cases.py::test_one_server_of_its_own",
    "test_cases.py::test_one_server_by_the_fixture",
}
PURE_TESTS = {
    "test_cases.py::test_pure",
    "test_cases.py::test_pure_with_a_fixture",
    "test_cases.py::test_pure_cases[1]",
    "test_cases.py::test_pure_cases[2]",
    "test_cases.py::TestGroup::test_pure_method",
}


def _pytest(pytester: pytest.Pytester, *args: str) -> pytest.RunResult:
    return pytester.runpytest_inprocess("-p", "no:cacheprovider", "-q", "--strict-markers", *args)


def _folder(pytester: pytest.Pytester) -> pytest.Pytester:
    pytester.makeconftest(CONFTEST)
    pytester.makepyfile(test_cases=TESTS, test_marked=MARKED_MODULE)
    return pytester


def _collected(out: list[str]) -> set[str]:
    return {line for line in out if "::" in line}


def test_the_option_keeps_the_tests_that_reach_a_server_and_deselects_the_others(pytester: pytest.Pytester) -> None:
    folder = _folder(pytester)
    everything = _pytest(folder, "--collect-only")
    assert everything.ret == 0, everything.stdout.str()
    assert _collected(everything.outlines) == SERVER_TESTS | ONE_SERVER_TESTS | PURE_TESTS
    assert "deselected" not in everything.stdout.str()
    kept = _pytest(folder, "--collect-only", "--server-tests-only")
    assert kept.ret == 0, kept.stdout.str()
    assert _collected(kept.outlines) == SERVER_TESTS
    total, deselected = len(SERVER_TESTS | ONE_SERVER_TESTS | PURE_TESTS), len(ONE_SERVER_TESTS | PURE_TESTS)
    assert f"{len(SERVER_TESTS)}/{total} tests collected ({deselected} deselected)" in kept.stdout.str()


def test_the_pure_tests_are_deselected_not_skipped(pytester: pytest.Pytester) -> None:
    run = _pytest(_folder(pytester), "--server-tests-only", "-rA")
    assert run.ret == 0, run.stdout.str()
    summary = run.outlines[-1]
    assert f"{len(SERVER_TESTS)} passed, {len(ONE_SERVER_TESTS | PURE_TESTS)} deselected" in summary, summary
    assert "skipped" not in run.stdout.str()
    assert "the tests that reach no PostgreSQL server, and those marked one_server, are deselected" in run.stdout.str()
    passed = {line.removeprefix("PASSED ") for line in run.outlines if line.startswith("PASSED ")}
    assert passed == SERVER_TESTS


def test_a_selection_of_pure_tests_alone_passes_and_a_selection_of_nothing_still_fails(
    pytester: pytest.Pytester,
) -> None:
    folder = _folder(pytester)
    pure_only = _pytest(folder, "--server-tests-only", "-k", "pure")
    assert pure_only.ret == 0, pure_only.stdout.str()
    assert (
        f"{len(SERVER_TESTS | ONE_SERVER_TESTS | PURE_TESTS)} deselected" in pure_only.stdout.str()
    )  # -k the server ones, the option the rest
    nothing = _pytest(folder, "--server-tests-only", "-k", "no_such_test")
    assert nothing.ret == 5, nothing.stdout.str()
    folder.makepyfile(test_failing="def test_pure_but_failing():\n    assert False\n")
    assert _pytest(folder, "--server-tests-only", "-k", "failing").ret == 0  # deselected: it runs on the other suite


def test_the_first_suite_and_the_pure_pass_split_the_tests_between_them(pytester: pytest.Pytester) -> None:
    # tools/test-suites: the first suite (--no-pure-tests) keeps the one_server tests, the pure pass the rest
    folder = _folder(pytester)
    server = _pytest(folder, "--collect-only", "--no-pure-tests")
    assert server.ret == 0, server.stdout.str()
    assert _collected(server.outlines) == SERVER_TESTS | ONE_SERVER_TESTS
    assert "the tests that reach no PostgreSQL server are deselected" in server.stdout.str()
    pure = _pytest(folder, "--pure-tests-only", "-rA")
    assert pure.ret == 0, pure.stdout.str()
    assert f"{len(PURE_TESTS)} passed, {len(SERVER_TESTS | ONE_SERVER_TESTS)} deselected" in pure.outlines[-1]
    assert {line.removeprefix("PASSED ") for line in pure.outlines if line.startswith("PASSED ")} == PURE_TESTS
    assert "skipped" not in pure.stdout.str()


def test_a_selection_the_pass_options_empty_passes_and_two_options_stop_the_run(pytester: pytest.Pytester) -> None:
    folder = _folder(pytester)
    assert _pytest(folder, "--no-pure-tests", "-k", "pure").ret == 0  # they run in the pure pass
    assert _pytest(folder, "--pure-tests-only", "-k", "server").ret == 0  # they run in the suites
    assert _pytest(folder, "--pure-tests-only", "-k", "no_such_test").ret == 5
    both = _pytest(folder, "--no-pure-tests", "--pure-tests-only")
    assert both.ret == pytest.ExitCode.USAGE_ERROR, both.stdout.str()
    assert "--no-pure-tests and --pure-tests-only select different tests: give one of them" in both.stderr.str()


def test_slowest_files_sums_each_files_tests_and_says_the_longest(pytester: pytest.Pytester) -> None:
    folder = _folder(pytester)
    folder.makepyfile(
        test_slow="import time\n\n\ndef test_a():\n    time.sleep(0.3)\n\n\ndef test_b():\n    time.sleep(0.3)\n"
    )
    run = _pytest(folder, "--slowest-files=2")
    assert run.ret == 0, run.stdout.str()
    out = run.stdout.str()
    lines = out[out.index("slowest 2 files") :].splitlines()[1:4]
    assert lines[0].endswith("    2 tests  test_slow.py") and float(lines[0].split("s")[0]) >= 0.6, lines
    assert "test_cases.py" in lines[1] or "test_marked.py" in lines[1], lines
    assert lines[2].endswith(f"in all: {2 + len(SERVER_TESTS | ONE_SERVER_TESTS | PURE_TESTS)} tests in 3 files"), lines
    assert "slowest" not in _pytest(folder).stdout.str()  # only when asked
