"""The linter holds the house rules: imports sorted, pycodestyle warnings, no database import in a numpy module (issue 38, part 4).

Each rule is shown a small file that breaks it, under the path of the module
it protects, through ``ruff check --stdin-filename`` with the repository's
configuration (pyproject.toml): before the rules were on, these passed.
"""

from __future__ import annotations

import re
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


def _hooks() -> dict[str, dict[str, str]]:
    """id -> {key: value} of the hooks of .pre-commit-config.yaml (a flat list of local hooks)."""
    hooks: dict[str, dict[str, str]] = {}
    hook: dict[str, str] = {}
    for line in (ROOT / ".pre-commit-config.yaml").read_text(encoding="utf-8").splitlines():
        key, _, value = line.strip().removeprefix("- ").partition(": ")
        if key == "id":
            hook = hooks.setdefault(value, {})
        elif not line.lstrip().startswith("#"):
            hook[key] = value
    return hooks


def _make_commands(*targets: str) -> list[str]:
    """The tool commands (mypy, ruff) that ``make targets`` runs, in order (an install of the venv left out)."""
    done = subprocess.run(
        ["make", "-n", "--no-print-directory", *targets], capture_output=True, text=True, cwd=ROOT, check=False
    )
    assert done.returncode == 0, done.stderr
    return [
        line
        for line in done.stdout.splitlines()
        if line.startswith(".venv/bin/") and (" -m mypy" in line or "ruff " in line)
    ]


def test_pre_commit_runs_the_checks_of_make_check() -> None:
    # issue 38 point 4: the hooks passed their files to ruff check (files make check does not lint) and ran
    # neither when pyproject.toml (the tools' configuration) changed; each hook is now a target of make check
    hooks = _hooks()
    assert {name: hook["entry"] for name, hook in hooks.items()} == {
        "ruff": "make --no-print-directory lint",
        "ruff-format": "make --no-print-directory format",
        "mypy": "make --no-print-directory typecheck",
    }
    check = _make_commands("check")
    assert check == [
        ".venv/bin/python -m mypy",
        ".venv/bin/ruff check src tests bench",
        ".venv/bin/ruff format --check src tests bench",
    ]
    assert _make_commands("typecheck") == check[:1] and _make_commands("lint") == check[1:2]
    assert _make_commands("format") == [check[2].replace(" --check", "")]  # writes what check checks
    for name, hook in hooks.items():
        assert hook["language"] == "system" and hook["pass_filenames"] == "false", name
        files = re.compile(hook["files"])
        changed = [
            "src/tgsis/mesh.py",
            "src/tgsis/x.pyi",
            "tests/test_x.py",
            "bench/bench_x.py",
            "pyproject.toml",
        ]
        assert all(files.search(path) for path in changed), name
        assert not any(files.search(path) for path in ["sql/core/schema.sql", "docs/view_pictures.py"]), name


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
