"""The package's public names have one source, and every public database function checks its arguments (issue 38, part 3).

Found: ``tgsis/__init__.py`` held three hand lists (``__all__``, the lazy
import table, the ``TYPE_CHECKING`` imports) that had drifted: seven PostGIS
names were missing from the type-checking block, so that a user's mypy saw
them as ``Any``; and ``append_period``, ``delete_period`` and
``class_property_periods`` skipped the argument checks every other database
function gets, because the checks were applied at the end of each module to
the names of its ``__all__``, which did not list them.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import subprocess
import sys
from pathlib import Path

import pytest

import tgsis

SOURCE = Path(tgsis.__file__).parent
INIT = SOURCE / "__init__.py"


def _type_checking_imports() -> dict[str, str]:
    """name -> module of the imports under ``if TYPE_CHECKING:`` in ``tgsis/__init__.py``."""
    tree = ast.parse(INIT.read_text(encoding="utf-8"))
    found: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            for statement in node.body:
                assert isinstance(statement, ast.ImportFrom) and statement.module, ast.dump(statement)
                for alias in statement.names:
                    assert alias.asname is None, f"{alias.name} is renamed under TYPE_CHECKING"
                    found[alias.name] = statement.module
    return found


def _lazy_names() -> list[str]:
    """The public names ``tgsis`` imports on first use, as a fresh interpreter sees them (here other tests may
    already have loaded them)."""
    program = "import tgsis; print(' '.join(n for n in tgsis.__all__ if n not in vars(tgsis)))"
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def test_the_type_checking_block_imports_every_lazy_name() -> None:
    lazy = _lazy_names()
    assert "connect" in lazy and "create_postgis_view" in lazy and "mesh_from_wkb" in lazy
    assert sorted(_type_checking_imports()) == sorted(lazy)


def test_the_type_checking_block_names_the_module_the_name_comes_from() -> None:
    wrong = [
        f"{name} from {module}"
        for name, module in _type_checking_imports().items()
        if getattr(importlib.import_module(module), name) is not getattr(tgsis, name)
        or name not in importlib.import_module(module).__all__
    ]
    assert wrong == []


def test_a_name_outside_all_is_no_lazy_attribute() -> None:
    with pytest.raises(AttributeError, match="has no attribute 'check_module'"):
        tgsis.check_module  # noqa: B018 - in tgsis.arguments.__all__, not in tgsis.__all__
    assert "__version__" in dir(tgsis) and isinstance(tgsis.__version__, str)


def _database_modules() -> list[str]:
    return sorted(f"tgsis.db.{p.stem}" if p.stem != "__init__" else "tgsis.db" for p in (SOURCE / "db").glob("*.py"))


def _exported_database_functions() -> list[tuple[str, str]]:
    """(module, name) of every function of a public ``tgsis.db`` module's ``__all__`` that takes a connection
    first, and every database function ``tgsis`` exports."""
    found: set[tuple[str, str]] = set()
    for module_name in _database_modules():
        if module_name.rsplit(".", 1)[-1].startswith("_"):
            continue
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", ()):
            value = getattr(module, name)
            if (
                inspect.isfunction(value)
                and inspect.unwrap(value).__module__ == module_name
                and list(inspect.signature(value).parameters)[:1] == ["conn"]
            ):
                found.add((module_name, name))
    for name in tgsis.__all__:
        value = getattr(tgsis, name)
        if inspect.isfunction(value) and inspect.unwrap(value).__module__.startswith("tgsis.db"):
            found.add((inspect.unwrap(value).__module__, name))
    return sorted(found)


def test_every_exported_database_function_checks_its_arguments() -> None:
    functions = _exported_database_functions()
    assert ("tgsis.db.evolving", "append_period") in functions and ("tgsis.db.features", "insert_feature") in functions
    unchecked = [
        f"{m}.{n}"
        for m, n in functions
        if not getattr(getattr(importlib.import_module(m), n), "__tgsis_checked__", False)
    ]
    assert unchecked == []


def _decorators(path: Path) -> dict[str, list[str]]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return {
        node.name: [ast.unparse(d) for d in node.decorator_list]
        for node in tree.body
        if isinstance(node, ast.FunctionDef)
    }


def test_the_checks_are_a_decorator_at_the_definition() -> None:
    # by construction: a new public function shows @checked where it is written, rather than
    # depending on a check_module(globals(), __all__) at the module's end that a name can miss
    missing = []
    for module_name, name in _exported_database_functions():
        path = SOURCE.joinpath(*module_name.split(".")[1:]).with_suffix(".py")
        if not path.exists():
            path = SOURCE.joinpath(*module_name.split(".")[1:], "__init__.py")
        if "checked" not in _decorators(path).get(name, []):
            missing.append(f"{module_name}.{name}")
    assert missing == []
    calls = [
        str(p.relative_to(SOURCE))
        for p in SOURCE.rglob("*.py")
        if "check_module(globals()" in p.read_text(encoding="utf-8")
    ]
    assert calls == []


def test_users_mypy_sees_the_signatures_of_lazy_and_checked_functions(tmp_path: Path) -> None:
    # a name missing from the TYPE_CHECKING block is Any for a user's mypy, and a decorator typed
    # Callable[..., Any] would make every checked function Any: both would let these calls through
    from mypy import api

    user = tmp_path / "user.py"
    user.write_text(
        "import tgsis\n"
        "def f(conn: tgsis.Box) -> None:\n"
        "    tgsis.create_postgis_view(1, 2, 3, 4, 5, 6)\n"
        "    tgsis.mesh_to_ewkb('not a mesh')\n"
        "    tgsis.delete_period(conn, 'x', 1.0)\n",
        encoding="utf-8",
    )
    out, err, _ = api.run(["--strict", "--no-incremental", "--cache-dir", str(tmp_path / "cache"), str(user)])
    lines = [line for line in out.splitlines() if "user.py" in line]
    assert any("user.py:3:" in line for line in lines), out + err
    assert any("user.py:4:" in line for line in lines), out + err
    assert any("user.py:5:" in line and "delete_period" in line for line in lines), out + err


# The names db/temporal.py and db/gmaps.py exported before they were split by model (issue 38, part 6), and the
# module of the model each now lives in; None: still defined in the old module (it serves every model of it).
SPLIT = {
    "tgsis.db.temporal": {
        "insert_series": "tgsis.db.instants",
        "add_instant": "tgsis.db.instants",
        "delete_instant": "tgsis.db.instants",
        "fetch_series": "tgsis.db.instants",
        "insert_evolving": "tgsis.db.evolving",
        "append_period": "tgsis.db.evolving",
        "delete_period": "tgsis.db.evolving",
        "fetch_evolving": "tgsis.db.evolving",
        "instants": None,
        "get_at": "tgsis.db._temporal_common",  # model 3's append_period takes the last shape with it
        "surfaces_at": None,
        "features_at": None,
        "lifespan": "tgsis.db._temporal_common",  # the view's time slider of models 2 and 3 reads it
        "frames_at": None,
        "export_series": None,
        "property_periods": None,
        "class_property_periods": None,
        "first_times": None,
    },
    "tgsis.db.gmaps": {
        "insert_gmap": None,
        "fetch_gmap": None,
        "gmap_at": None,
        "gmap_cells": None,
        "gmap_check": None,
        "GMapProblem": None,
        "fetch_md_gmap": "tgsis.db.multidim",
        "md_in_box": "tgsis.db.multidim",
        "md_vertices_in_box": "tgsis.db.multidim",
    },
}


@pytest.mark.parametrize("old", sorted(SPLIT))
def test_the_names_of_a_split_module_are_still_exported_from_it(old: str) -> None:
    module = importlib.import_module(old)
    assert sorted(module.__all__) == sorted(SPLIT[old])
    moved = {}
    for name, home in SPLIT[old].items():
        value = getattr(module, name)
        defined = inspect.unwrap(value).__module__
        assert defined == (home or old), f"{old}.{name} is defined in {defined}"
        if home is not None and not home.rsplit(".", 1)[-1].startswith("_"):
            assert name in importlib.import_module(home).__all__, f"{home} does not export {name}"
            moved[name] = home
        if name in tgsis.__all__:
            assert getattr(tgsis, name) is value, f"tgsis.{name} is another object than {old}.{name}"
    # the package imports a moved name from the module that defines it (the lazy table and the TYPE_CHECKING block)
    lazy = _type_checking_imports()
    assert {n: m for n, m in moved.items() if n in tgsis.__all__} == {n: lazy[n] for n in moved if n in tgsis.__all__}
