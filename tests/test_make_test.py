"""The README's test command does its own set-up, and CI runs nothing else (issue 36, point 11).

On a fresh Debian machine ``make test`` failed 63 tests: PostGIS for
PostgreSQL 15 and Chromium were missing, because ``.ci/run`` installed them
and the README's command did not. Now ``.ci/run`` is the README's command
only (parsed here from both files), and ``make test`` starts with
``tools/setup-machine``, which installs the missing distribution packages,
saying so first, and does nothing when they are there. The set-up runs here
against fake ``dpkg-query``, ``apt-get``, ``apt-cache``, ``sudo`` and ``id``
on a PATH without the real ones (nothing is installed by these tests), and
``tools/test-suites`` with fake interpreters: both suites side by side, the
embedded one in a copy of the repository with nothing beside it.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import stat
import subprocess
from collections.abc import Sequence
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SETUP = ROOT / "tools" / "setup-machine"
SUITES = ROOT / "tools" / "test-suites"
PACKAGES = [
    "postgresql-15",
    "postgresql-server-dev-15",
    "postgresql-15-postgis-3",
    "chromium",
    "python3-venv",
    "make",
    "gcc",
]


def _readme_commands() -> list[str]:
    """The commands of the README's quickstart block, comments dropped."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    quickstart = text.split("## Quickstart", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```sh\n(.*?)```", quickstart, re.S)
    assert len(blocks) == 1, "the quickstart shows one shell block"
    return [line.split("#", 1)[0].strip() for line in blocks[0].splitlines() if line.split("#", 1)[0].strip()]


def _ci_commands() -> list[str]:
    """What .ci/run runs, besides its shell options and going to the repository's root."""
    commands = []
    for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines():
        line = line.split("#", 1)[0].strip() if not line.lstrip().startswith("#!") else ""
        if not line or line == "set -euo pipefail" or line == 'cd "$(dirname "${BASH_SOURCE[0]}")/.."':
            continue
        commands.append(line)
    return commands


def test_the_readme_shows_two_commands_and_ci_runs_only_them() -> None:
    assert _readme_commands() == ["make demo", "make test"]
    ci = _ci_commands()
    assert ci == ["make test"], f".ci/run runs more than the README's commands: {ci}"


def test_make_test_sets_the_machine_up_before_anything_else() -> None:
    out = subprocess.run(
        ["make", "-n", "--no-print-directory", "test"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "MAKEFLAGS": ""},
    ).stdout.splitlines()
    assert out[0] == "tools/setup-machine", out
    assert out[-1].startswith("VENV=.venv tools/test-suites"), out
    assert any("mypy" in line for line in out) and any("ruff check" in line for line in out)
    # nothing is installed into the system's PostgreSQL: no PGXS install in the recipe
    assert not any(re.search(r"\binstall\b", line) and "sql" in line for line in out), out


# --------------------------------------------------------------------------- tools/setup-machine, faked


def _script(path: Path, text: str) -> None:
    path.write_text("#!/bin/bash\n" + text)
    path.chmod(path.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)


def _fake_machine(tmp_path: Path, *, debian: bool = True, sudo: bool = True) -> Path:
    """A bin folder with the few real programs the script needs and fakes of the package tools."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in ("bash", "sed", "cat", "env", "basename"):
        real = shutil.which(tool)
        assert real is not None
        (bin_dir / tool).symlink_to(real)
    log = 'echo "$(basename "$0") $*" >> "$FAKE_LOG"\n'
    _script(bin_dir / "id", 'echo "$FAKE_UID"\n')
    if debian:
        _script(
            bin_dir / "dpkg-query",
            log + 'for p in $FAKE_INSTALLED; do [ "$p" = "${!#}" ] && '
            'printf installed && exit 0; done; echo "dpkg-query: no packages found matching ${!#}" >&2; exit 1\n',
        )
        _script(bin_dir / "apt-get", log)
        _script(
            bin_dir / "apt-cache",
            'for p in $FAKE_UNAVAILABLE; do [ "$p" = "$2" ] && '
            'printf "%s:\\n  Installed: (none)\\n  Candidate: (none)\\n" "$2" && exit 0; done; '
            'printf "%s:\\n  Installed: (none)\\n  Candidate: 1.0\\n" "$2"\n',
        )
    if sudo:
        _script(bin_dir / "sudo", log + 'exec "$@"\n')
    return bin_dir


def _setup(
    tmp_path: Path,
    *args: str,
    installed: Sequence[str],
    uid: int = 0,
    unavailable: Sequence[str] = (),
    debian: bool = True,
    sudo: bool = True,
    **env: str,
) -> tuple[int, str, list[str]]:
    """Run tools/setup-machine on the fake machine: exit status, its output (stdout then stderr), the calls made."""
    bin_dir = _fake_machine(tmp_path, debian=debian, sudo=sudo)
    log = tmp_path / "calls.log"
    log.touch()
    done = subprocess.run(
        [str(bin_dir / "bash"), str(SETUP), *args],
        capture_output=True,
        text=True,
        check=False,
        env={
            "PATH": str(bin_dir),
            "FAKE_LOG": str(log),
            "FAKE_UID": str(uid),
            "FAKE_INSTALLED": " ".join(installed),
            "FAKE_UNAVAILABLE": " ".join(unavailable),
            **env,
        },
    )
    calls = [c for c in log.read_text().splitlines() if not c.startswith("dpkg-query")]
    return done.returncode, done.stdout + done.stderr, calls


def test_setup_does_nothing_and_says_so_when_everything_is_installed(tmp_path: Path) -> None:
    status, out, calls = _setup(tmp_path, installed=PACKAGES)
    assert status == 0 and calls == []
    assert out == f"make: the system packages tgsis needs are installed ({' '.join(PACKAGES)})\n"


def test_setup_installs_what_is_missing_saying_so_first(tmp_path: Path) -> None:
    bin_dir = _fake_machine(tmp_path)
    # the fakes write into the script's own output: the order of the lines is the order of events
    out_file = tmp_path / "out.txt"
    with out_file.open("a") as out:  # appended to by the script and the fakes alike
        done = subprocess.run(
            [str(bin_dir / "bash"), str(SETUP)],
            stdout=out,
            stderr=subprocess.STDOUT,
            check=False,
            env={
                "PATH": str(bin_dir),
                "FAKE_LOG": str(out_file),
                "FAKE_UID": "0",
                "FAKE_INSTALLED": "python3-venv make gcc",
                "FAKE_UNAVAILABLE": "",
            },
        )
    assert done.returncode == 0
    lines = [line for line in out_file.read_text().splitlines() if not line.startswith("dpkg-query")]
    missing = "postgresql-15 postgresql-server-dev-15 postgresql-15-postgis-3 chromium"
    assert lines[0] == f"make: installing the system packages tgsis needs that are missing here: {missing}"
    assert lines.index("apt-get update -qq") > 0
    assert f"apt-get install -y -qq --no-install-recommends {missing}" in lines
    assert lines[-1] == f"make: installed: {missing}"


def test_setup_as_a_user_goes_through_sudo(tmp_path: Path) -> None:
    status, out, calls = _setup(tmp_path, installed=[p for p in PACKAGES if p != "chromium"], uid=1000)
    assert status == 0, out
    assert calls == [
        "sudo apt-get update -qq",
        "apt-get update -qq",
        "sudo apt-get install -y -qq --no-install-recommends chromium",
        "apt-get install -y -qq --no-install-recommends chromium",
    ]
    assert "sudo apt-get install -y --no-install-recommends chromium" in out


def test_setup_dry_run_installs_nothing(tmp_path: Path) -> None:
    status, out, calls = _setup(tmp_path, "--dry-run", installed=[])
    assert status == 0 and calls == []
    assert f"missing here: {' '.join(PACKAGES)}" in out and "(--dry-run: nothing installed)" in out


def test_setup_without_root_nor_sudo_says_what_to_install(tmp_path: Path) -> None:
    status, out, calls = _setup(tmp_path, installed=[p for p in PACKAGES if p != "chromium"], uid=1000, sudo=False)
    assert status == 1 and calls == []
    assert "missing system packages: chromium" in out and "needs root" in out


def test_setup_refuses_packages_the_sources_do_not_have(tmp_path: Path) -> None:
    status, out, calls = _setup(
        tmp_path,
        installed=["chromium", "python3-venv", "make", "gcc"],
        unavailable=["postgresql-15", "postgresql-15-postgis-3"],
    )
    assert status == 1
    assert calls == ["apt-get update -qq"], "nothing installed when a package cannot be"
    assert "not in this machine's package sources: postgresql-15 postgresql-15-postgis-3" in out
    assert "https://wiki.postgresql.org/wiki/Apt" in out


def test_setup_on_another_system_says_what_to_install_by_hand(tmp_path: Path) -> None:
    status, out, calls = _setup(tmp_path, installed=[], debian=False)
    assert status == 1 and calls == []
    assert "not a Debian or Ubuntu machine" in out and "TGSIS_SETUP=skip make test" in out
    (tmp_path / "skip").mkdir()
    status, out, calls = _setup(tmp_path / "skip", installed=[], debian=False, TGSIS_SETUP="skip")
    assert status == 0 and calls == [] and "TGSIS_SETUP=skip" in out


def test_setup_refuses_an_unknown_argument(tmp_path: Path) -> None:
    status, out, calls = _setup(tmp_path, "--yes", installed=[])
    assert status == 2 and "usage" in out and calls == []
    (tmp_path / "more").mkdir()
    status, out, calls = _setup(tmp_path / "more", "postgresql-16", installed=[])
    assert status == 2 and "postgresql-15" in out and calls == []


def test_the_venv_asks_for_python3_venv_alone(tmp_path: Path) -> None:
    # `make demo` on a fresh Debian: python3 -m venv needs ensurepip, which Debian ships in python3-venv
    status, out, calls = _setup(tmp_path, "python3-venv", installed=[], uid=0)
    assert status == 0, out
    assert calls == ["apt-get update -qq", "apt-get install -y -qq --no-install-recommends python3-venv"]
    assert "missing here: python3-venv\n" in out
    (tmp_path / "again").mkdir()
    status, out, calls = _setup(tmp_path / "again", "python3-venv", installed=["python3-venv"])
    assert status == 0 and calls == [] and out == "make: the system packages tgsis needs are installed (python3-venv)\n"
    recipe = subprocess.run(
        ["make", "-n", "-B", "--no-print-directory", ".venv/.installed"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "MAKEFLAGS": ""},
    ).stdout
    first, second = recipe.splitlines()[:2]
    assert "import ensurepip" in first and "tools/setup-machine python3-venv" in first
    assert second.endswith("-m venv .venv")


def test_the_demo_as_root_asks_for_the_os_user_of_the_local_server(tmp_path: Path) -> None:
    # `make demo` as root on a fresh Debian: the local server runs as the OS user postgres (never as
    # root), which the small package postgresql-common makes
    status, out, calls = _setup(tmp_path, "postgresql-common", installed=[], uid=0)
    assert status == 0, out
    assert calls == ["apt-get update -qq", "apt-get install -y -qq --no-install-recommends postgresql-common"]
    recipe = subprocess.run(
        ["make", "-n", "--no-print-directory", "demo"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "MAKEFLAGS": ""},
    ).stdout
    step = recipe[: recipe.index("postgresql-common")].rsplit("if ", 1)[1]
    assert 'id -u)" -eq 0' in step and "TGSIS_PG_OS_USER" in step and "id postgres" in step
    # the step comes before the demo itself
    assert recipe.index("postgresql-common") < recipe.index("tgsis demo")


# --------------------------------------------------------------------------- tools/test-suites, faked


def _fake_venv(folder: Path, record: Path, fail_when: str = "") -> None:
    """A venv whose python records its server choice, folder and arguments (and fails for ``fail_when``)."""
    (folder / "bin").mkdir(parents=True)
    _script(
        folder / "bin" / "python",
        f'echo "$TGSIS_PG|$PWD|$*|$(ls -A .. | tr "\\n" " ")|$TGSIS_TEST_STORAGE$TGSIS_TEST_STORAGE_BY_FILE$TGSIS_TEST_TIME_STORAGE" '
        f">> {shlex.quote(str(record))}\n"
        f'[ "$TGSIS_PG" = {shlex.quote(fail_when) or "__never__"} ] && exit 3\nexit 0\n',
    )


def _run_suites(
    tmp_path: Path, fail_when: str = "", make_first: str = "", **env: str
) -> tuple[int, str, list[list[str]]]:
    record = tmp_path / "runs.txt"
    record.touch()
    _fake_venv(tmp_path / "venv", record, fail_when)
    fake_bin = tmp_path / "bin"
    fake_bin.mkdir()
    # `make -C COPY .venv/.installed` in the copy: a fake venv there too (after `make_first`, shell)
    _script(
        fake_bin / "make",
        make_first + f'[ "$1" = -C ] && mkdir -p "$2/.venv/bin" && '
        f'ln -s {shlex.quote(str(tmp_path / "venv" / "bin" / "python"))} "$2/.venv/bin/python"\n',
    )
    done = subprocess.run(
        [str(SUITES), "-k", "x y"],
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
        env={
            **{k: v for k, v in os.environ.items() if not k.startswith("TGSIS_")},
            "PATH": f"{fake_bin}:{os.environ['PATH']}",
            "VENV": str(tmp_path / "venv"),
            **env,
        },
    )
    return done.returncode, done.stdout + done.stderr, [line.split("|") for line in record.read_text().splitlines()]


def test_the_suites_run_on_both_servers_the_embedded_one_in_a_copy_alone(tmp_path: Path) -> None:
    status, out, runs = _run_suites(tmp_path)
    assert status == 0, out
    by_pass = {args.split()[-4]: (server, folder, storage) for server, folder, args, _, storage in runs}
    beside = {args.split()[-4]: set(listing.split()) for _, _, args, listing, _ in runs}
    order = [args.split()[-4] for _, _, args, _, _ in runs]  # the option choosing each pass's tests
    assert [args for _, _, args, _, _ in runs] == [
        f"-m pytest -p no:cacheprovider --durations=15 --slowest-files=25 {option} -k x y" for option in order
    ], runs
    # both storages of model 1 stay tested: PostgreSQL 15 on chunks (the default), 18 on rows, every other
    # file the other way round (1: TGSIS_TEST_STORAGE_BY_FILE, tests/test_harness.py), and model 2's time tables
    # in the other storage than model 1's in every other file (by-file: TGSIS_TEST_TIME_STORAGE); the pure tests run
    # once, in a pass of their own (tests/test_server_tests_only.py checks the options)
    assert by_pass == {
        "--no-pure-tests": ("system", str(ROOT), "chunks1by-file"),
        "--pure-tests-only": ("system", str(ROOT), "chunks"),
        "--server-tests-only": ("embedded", by_pass["--server-tests-only"][1], "rows1by-file"),
    }
    copy = Path(by_pass["--server-tests-only"][1])
    assert copy.name == "tgsis" and copy != ROOT
    # the pure pass ends before the embedded suite starts (they share one side of the two cores)
    assert order[-1] == "--server-tests-only", order
    # nothing beside the copy but the logs of this run (no ../shared, no other checkout)
    assert beside["--server-tests-only"] <= {"tgsis", "venv.log", "system.log", "pure.log", "embedded.log"}, beside
    assert not copy.exists(), "the copy is removed afterwards"
    assert "done: the suite passed on both PostgreSQL versions" in out


@pytest.mark.parametrize("failing", ["system", "embedded"])
def test_a_failing_suite_fails_the_command(tmp_path: Path, failing: str) -> None:
    status, out, runs = _run_suites(tmp_path, fail_when=failing)
    assert status == 3, out
    assert {r[0] for r in runs} == {"system", "embedded"}, "the other suite still ran"
    assert "a test suite failed (exit 3)" in out


def test_the_copys_venv_is_made_while_the_system_suite_runs(tmp_path: Path) -> None:
    # the fake make of the copy's venv waits for the system's suite to have started (10 s at most)
    record = shlex.quote(str(tmp_path / "runs.txt"))
    status, out, runs = _run_suites(
        tmp_path,
        make_first=f"for i in $(seq 100); do grep -q '^system|.*--no-pure-tests' {record} && break; sleep 0.1; done\n"
        f"grep -q '^system|.*--no-pure-tests' {record} || exit 7\n",
    )
    assert status == 0, out
    assert {r[0] for r in runs} == {"system", "embedded"}


def test_a_copy_without_its_venv_fails_the_command_saying_so(tmp_path: Path) -> None:
    status, out, runs = _run_suites(tmp_path, make_first="echo pip: no such package >&2; exit 2\n")
    assert status == 1, out
    assert "pip: no such package" in out and "the copy's venv could not be made" in out
    assert "embedded" not in {r[0] for r in runs}


def test_one_server_chosen_runs_one_suite_here(tmp_path: Path) -> None:
    status, out, runs = _run_suites(tmp_path, TGSIS_PG="embedded")
    assert status == 0, out
    assert [run[:3] for run in runs] == [["embedded", str(ROOT), "-m pytest -k x y"]]
