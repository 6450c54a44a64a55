"""The linter holds the house rules: imports sorted, pycodestyle warnings, no database import in a numpy module (issue 38, part 4).

Each rule is shown a small file that breaks it, under the path of the module
it protects, through ``ruff check --stdin-filename`` with the repository's
configuration (pyproject.toml): before the rules were on, these passed.
"""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _ruff(path: str, text: str) -> str:
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "ruff",
            "check",
            "--no-cache",
            "--output-format",
            "concise",
            "--stdin-filename",
            path,
            "-",
        ],
        input=text,
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    return done.stdout + done.stderr


PURE_MODULES = [
    "src/tgsis/mesh.py",
    "src/tgsis/compare.py",
    "src/tgsis/temporal.py",
    "src/tgsis/edits.py",
    "src/tgsis/interpolation/deposition.py",
    "src/tgsis/gmaps/_core.py",
    "src/tgsis/formats/vtk.py",
    "src/tgsis/convert.py",
    "src/tgsis/pictures.py",
    "src/tgsis/postgis.py",
    "src/tgsis/errors.py",
]


@pytest.mark.parametrize("path", PURE_MODULES)
@pytest.mark.parametrize(
    "line",
    [
        "import psycopg",
        "from psycopg import sql",
        "from tgsis.db import connect",
        "from tgsis.db.features import insert_feature",
        "import tgsis.db.versions",
    ],
)
def test_a_numpy_module_may_not_import_the_database_layer(path: str, line: str) -> None:
    text = f'"""A module."""\n\n\ndef f() -> object:\n    {line}\n\n    return locals()\n'
    assert "TID251" in _ruff(path, text)


@pytest.mark.parametrize(
    "path", ["src/tgsis/db/features.py", "src/tgsis/view/app.py", "tests/test_x.py", "bench/bench_x.py"]
)
def test_the_database_side_may(path: str) -> None:
    assert "TID251" not in _ruff(
        path, '"""A module."""\n\nimport psycopg\n\nfrom tgsis.db import connect\n\nprint(psycopg, connect)\n'
    )


def test_imports_are_sorted() -> None:
    text = (
        '"""A module."""\n\nimport sys\nimport os\n\nimport numpy as np\n\nfrom tgsis.mesh import Surface\n\n'
        "print(sys, os, np, Surface)\n"
    )
    assert "I001" in _ruff("src/tgsis/edits.py", text)


def test_pycodestyle_warnings() -> None:
    assert "W291" in _ruff("src/tgsis/edits.py", '"""A module."""\n\nx = 1  \n')
    assert "W292" in _ruff("src/tgsis/edits.py", '"""A module."""\n\nx = 1')


def _hook_entries() -> dict[str, str]:
    """id -> entry of the hooks of .pre-commit-config.yaml (a flat list of local hooks)."""
    entries: dict[str, str] = {}
    hook = ""
    for line in (ROOT / ".pre-commit-config.yaml").read_text(encoding="utf-8").splitlines():
        key, _, value = line.strip().removeprefix("- ").partition(": ")
        if key == "id":
            hook = value
        elif key == "entry":
            entries[hook] = value
    return entries


def test_pre_commit_runs_the_checks_of_make_check() -> None:
    entries = _hook_entries()
    assert entries == {
        "ruff": ".venv/bin/ruff check --force-exclude",
        "ruff-format": "make --no-print-directory format",
        "mypy": ".venv/bin/python -m mypy",
    }
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    assert "\t$(BIN)/ruff format $(RUFF_FORMATTED)\n" in makefile  # the files `make check` keeps formatted
    assert "\t$(BIN)/python -m mypy\n" in makefile  # the same files ([tool.mypy] files)
    done = subprocess.run(["make", "-n", "format"], capture_output=True, text=True, cwd=ROOT, check=False)
    assert done.returncode == 0 and "ruff format src tests bench" in done.stdout, done.stderr


def test_mypy_checks_the_tests_too() -> None:
    pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert 'files = ["src/tgsis", "tests"]' in pyproject


def test_mypy_is_as_strict_over_the_tests_as_over_the_source() -> None:
    # issue 38 point 4: an override for tests.* switched 13 error codes off (Optional results used unchecked,
    # untyped calls, ...); the only override left is the third-party one (modules without type information)
    mypy = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["mypy"]
    assert mypy["strict"] is True and mypy["files"] == ["src/tgsis", "tests"]
    assert "disable_error_code" not in mypy and "warn_unused_ignores" not in mypy
    for override in mypy.get("overrides", []):
        assert set(override) == {"module", "ignore_missing_imports"}, override
        assert not [m for m in override["module"] if m.split(".")[0] in ("tests", "tgsis", "bench")], override
