"""The SQL sources: one build for both install routes, one version everywhere."""

from __future__ import annotations

import shutil
import subprocess
from importlib.metadata import version as package_version
from pathlib import Path

import pytest

import tgsis
from tgsis.db.sqlsource import PSQL_GUARD, ExtensionSources, parse_version
from tgsis.errors import InstallationError

SQL_DIR = Path(__file__).resolve().parents[1] / "sql"


@pytest.fixture
def sources() -> ExtensionSources:
    return ExtensionSources(SQL_DIR)


def test_pgxs_build_equals_python_build(sources: ExtensionSources, tmp_path: Path) -> None:
    work = tmp_path / "sql"
    shutil.copytree(SQL_DIR, work, ignore=shutil.ignore_patterns("build"))
    # PGXS needs pg_config only for `install`; building the script is plain make.
    result = subprocess.run(
        ["make", "-C", str(work), f"build/tgsis--{sources.version}.sql"], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stderr
    built = (work / "build" / f"tgsis--{sources.version}.sql").read_text(encoding="utf-8")
    assert built == sources.script()
    assert "@TGSIS_VERSION@" not in built


def test_driver_script_drops_only_the_psql_guard(sources: ExtensionSources) -> None:
    with_guard = sources.script().splitlines()
    without = sources.script(psql_guard=False).splitlines()
    assert PSQL_GUARD in with_guard
    assert [line for line in with_guard if line != PSQL_GUARD] == without


def test_one_version_for_client_extension_and_package(sources: ExtensionSources) -> None:
    assert tgsis.__version__ == sources.version == package_version("tgsis")
    assert f"SELECT '{sources.version}'::text" in sources.script()


def test_sources_list_every_sql_file_once(sources: ExtensionSources) -> None:
    listed = sources.files
    assert len(listed) == len(set(listed))
    assert all((SQL_DIR / name).is_file() for name in listed)
    on_disk = {
        str(p.relative_to(SQL_DIR))
        for p in SQL_DIR.rglob("*.sql")
        if p.parts[len(SQL_DIR.parts)] not in ("build", "updates", "upgrade", "test")
    }
    assert on_disk == set(listed), "every SQL source must be listed in sources.txt (and only those)"


def test_every_function_and_table_is_commented(sources: ExtensionSources) -> None:
    script = sources.script()
    import re

    for kind, pattern in (
        ("FUNCTION", r"CREATE (?:OR REPLACE )?FUNCTION (tgsis\.\w+)"),
        ("TABLE", r"CREATE TABLE (tgsis\.\w+)"),
    ):
        for name in re.findall(pattern, script):
            assert re.search(rf"COMMENT ON {kind} {re.escape(name)}\b", script), f"{name} has no COMMENT"


def test_parse_version_rejects_non_numeric() -> None:
    assert parse_version("0.10.2") > parse_version("0.9.9")
    with pytest.raises(InstallationError, match="not of the form"):
        parse_version("1.0-beta")


def _sources_with_updates(tmp_path: Path, *updates: str) -> ExtensionSources:
    root = tmp_path / "sql"
    shutil.copytree(SQL_DIR, root, ignore=shutil.ignore_patterns("build"))
    (root / "updates").mkdir(exist_ok=True)
    for name in updates:
        (root / "updates" / name).write_text("-- test\n", encoding="utf-8")
    return ExtensionSources(root)


def test_upgrade_path_takes_the_shortest_chain(tmp_path: Path) -> None:
    src = _sources_with_updates(
        tmp_path,
        "tgsis--0.0.1--0.0.2.sql",
        "tgsis--0.0.2--0.1.0.sql",
        "tgsis--0.0.1--0.0.5.sql",
        "tgsis--0.0.5--0.1.0.sql",
        "tgsis--0.0.2--0.0.3.sql",
    )
    names = [p.name for p in src.upgrade_path("0.0.2", "0.1.0")]
    assert names == ["tgsis--0.0.2--0.1.0.sql"]
    assert len(src.upgrade_path("0.0.1", "0.1.0")) == 2
    assert src.upgrade_path("0.1.0", "0.1.0") == []


def test_missing_upgrade_path_is_an_installation_error(tmp_path: Path) -> None:
    src = _sources_with_updates(tmp_path, "tgsis--0.0.1--0.0.2.sql")
    with pytest.raises(InstallationError, match="no upgrade path from tgsis 0.0.2 to 0.1.0") as info:
        src.upgrade_path("0.0.2", "0.1.0")
    assert "tgsis--0.0.1--0.0.2.sql" in (info.value.detail or "")


def test_extension_dir_layout_for_extension_control_path(sources: ExtensionSources, tmp_path: Path) -> None:
    target = sources.write_extension_dir(tmp_path)
    assert target == tmp_path / "extension"
    assert (target / "tgsis.control").read_text() == (SQL_DIR / "tgsis.control").read_text()
    assert (target / f"tgsis--{sources.version}.sql").read_text() == sources.script()


def test_a_function_that_disables_a_plan_node_turns_jit_off(sources: ExtensionSources) -> None:
    # before PostgreSQL 18 a disabled node (enable_sort, enable_nestloop ... off) adds 1e10 to the plan's cost,
    # far above jit_above_cost: on a server with JIT (Debian's packages) every call compiled its queries, 0.6 s
    # for what runs in milliseconds (an evolving surface's insert took 3 s on 15.20, 0.07 s on 18)
    import re

    headers = re.findall(r"CREATE (?:OR REPLACE )?FUNCTION (tgsis\.\w+)\((.*?)\bAS \$", sources.script(), re.S)
    disabling = {name: header for name, header in headers if re.search(r"^SET enable_\w+ = off", header, re.M)}
    assert len(disabling) >= 5  # the check sees the functions (surface_side_gap, gmap_side_gap, three G-map checks)
    assert [n for n, h in disabling.items() if not re.search(r"^SET jit = off\b", h, re.M)] == []
