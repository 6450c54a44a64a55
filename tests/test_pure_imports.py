"""The numpy modules load without the database layer, and modules share code through private modules (issue 17, part 0).

Found: ``import tgsis.mesh`` loaded psycopg and the whole ``tgsis.db`` layer,
because the package's ``__init__`` imported it and ``tgsis.errors`` imported
psycopg. Each pure module is imported here in a fresh interpreter, which must
then hold neither psycopg nor any module of ``tgsis.db``; and the database
names of the package still resolve, on first use.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest

import tgsis

PURE = [
    "tgsis",
    "tgsis.mesh",
    "tgsis.convert",
    "tgsis.compare",
    "tgsis.edits",
    "tgsis.merge3",
    "tgsis.temporal",
    "tgsis.interpolation",
    "tgsis.gmaps",
    "tgsis.formats",
    "tgsis.errors",
    "tgsis.pictures",
    "tgsis.drawing",
    "tgsis.view.meshes",
    "tgsis.view.regions",
    "tgsis.postgis",
    "tgsis.datamodels",
]


@pytest.mark.parametrize("module", PURE)
def test_a_pure_module_imports_neither_psycopg_nor_the_database_layer(module: str) -> None:
    program = (
        f"import sys, {module}; "
        "print(' '.join(sorted(m for m in sys.modules if m == 'psycopg' or m.startswith(('psycopg.', 'tgsis.db')))))"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "", f"import {module} loaded {done.stdout.strip()}"


# A source tree that is not installed: the package metadata is not found (as with PYTHONPATH=src).
NOT_INSTALLED = (
    "import importlib.metadata as m; real = m.version; "
    "m.version = lambda n: (_ for _ in ()).throw(m.PackageNotFoundError(n)) if n == 'tgsis' else real(n); "
)


@pytest.mark.parametrize("module", PURE)
def test_a_pure_module_of_a_source_tree_imports_neither_psycopg_nor_the_database_layer(module: str) -> None:
    # issue 38: the version fallback of tgsis/__init__.py read sql/tgsis.control through tgsis.db (and psycopg)
    program = (
        NOT_INSTALLED + f"import sys, {module}; "
        "print(' '.join(sorted(m for m in sys.modules if m == 'psycopg' or m.startswith(('psycopg.', 'tgsis.db')))))"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "", f"import {module} loaded {done.stdout.strip()}"


def test_the_version_of_a_source_tree_is_the_extensions() -> None:
    program = NOT_INSTALLED + "import tgsis; print(tgsis.__version__); print('__version__' in dir(tgsis))"
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == [tgsis.__version__, "True"]


def test_the_database_names_load_on_first_use() -> None:
    program = (
        "import sys, tgsis; assert 'tgsis.db' not in sys.modules; "
        "f = tgsis.insert_feature; assert 'tgsis.db.features' in sys.modules; "
        "from tgsis import connect, merge_version; assert f is tgsis.insert_feature; "
        "assert set(tgsis.__all__) <= set(dir(tgsis)); "
        "import tgsis as t\ntry:\n    t.no_such_name\nexcept AttributeError as e:\n    print(e)"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "module 'tgsis' has no attribute 'no_such_name'"


def _imports(path: Path) -> list[tuple[str, list[str], bool]]:
    """(module, names, at top level) of every ``from tgsis... import`` of a file."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    top = {id(node) for node in tree.body}
    return [
        (node.module or "", [a.name for a in node.names], id(node) in top)
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("tgsis")
    ]


def _module_name(path: Path) -> str:
    parts = path.relative_to(SOURCE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


SOURCE = Path(tgsis.__file__).parent


def test_no_module_takes_a_private_name_of_another_public_module() -> None:
    # what several modules share lives in a private module (_name.py) under a public name
    found = [
        f"{_module_name(path)} imports {names} from {module}"
        for path in sorted(SOURCE.rglob("*.py"))
        for module, imported, _ in _imports(path)
        if not module.rsplit(".", 1)[-1].startswith("_")
        for names in [[n for n in imported if n.startswith("_") and not n.startswith("__")]]
        if names
    ]
    assert found == []


def _all_imports(path: Path) -> list[str]:
    """Every module of tgsis a file imports: at top level, inside functions or for type checkers alone."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found: list[str] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").startswith("tgsis"):
            module = node.module or ""
            # `from tgsis.db import features` names a module; `from tgsis.db import connect`, a name of one
            found += [f"{module}.{a.name}" if f"{module}.{a.name}" in MODULES else module for a in node.names]
        elif isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name.startswith("tgsis")]
    return found


MODULES = {_module_name(path): path for path in sorted(SOURCE.rglob("*.py"))}


def _import_graph() -> nx.DiGraph:
    graph = nx.DiGraph()
    for name, path in MODULES.items():
        graph.add_node(name)
        graph.add_edges_from((name, target) for target in _all_imports(path) if target != name and target in MODULES)
    return graph


# Cycles not broken yet, each named by its modules: a new cycle, a longer one, or one that is gone while
# still listed here fails. (Issue 38, part 4 broke the last one, tgsis.mesh -> tgsis.convert -> tgsis.mesh: the
# mesh classes' to_*/from_* methods reach tgsis.convert through tgsis._conversions, which convert fills.)
KNOWN_CYCLES: set[frozenset[str]] = set()


def test_the_modules_of_tgsis_import_each_other_without_a_cycle() -> None:
    # lazy imports inside functions and imports for type checkers count too: they hide a cycle, they do
    # not remove it (issue 38 found mesh <-> convert, formats.vtk -> gmaps -> temporal -> formats.pvd -> ...,
    # gmaps._core <-> gmaps._build)
    graph = _import_graph()
    assert len(graph) > 60 and graph.has_edge("tgsis.convert", "tgsis.mesh")
    cycles = {frozenset(c) for c in nx.strongly_connected_components(graph) if len(c) > 1}
    assert sorted(sorted(c) for c in cycles - KNOWN_CYCLES) == []
    assert sorted(sorted(c) for c in KNOWN_CYCLES - cycles) == []  # broken: remove it from KNOWN_CYCLES
    # the mesh classes' to_*/from_* methods reach tgsis.convert through tgsis._conversions, not by importing it
    assert not nx.has_path(graph, "tgsis.mesh", "tgsis.convert") and graph.has_edge("tgsis.mesh", "tgsis._conversions")


def test_the_database_modules_import_each_other_without_a_cycle() -> None:
    graph = _import_graph().subgraph([name for name in MODULES if name.startswith("tgsis.db")])
    assert list(nx.simple_cycles(graph)) == []
    assert graph.has_edge("tgsis.db.features", "tgsis.db.classes")  # the graph sees the imports
    # model 1 hands other models' objects on through the registry (tgsis.datamodels), not by importing their modules
    assert not graph.has_edge("tgsis.db.features", "tgsis.db.temporal")
    assert not nx.has_path(graph, "tgsis.db.temporal", "tgsis.db.features")


# The database module of each data model (the registry's DataModel.module) and the modules that re-export
# several models' names (db/temporal.py: models 2 and 3, db/gmaps.py: models 4 and 5).
MODEL_MODULES = ["tgsis.db.features", "tgsis.db.instants", "tgsis.db.evolving", "tgsis.db.gmaps", "tgsis.db.multidim"]


def test_a_models_database_module_imports_no_other_models_module() -> None:
    # issue 38, part 6: models 2 and 3 shared db/temporal.py, models 4 and 5 db/gmaps.py; split by model, what two
    # models share is in a private module (db/_temporal_common.py, db/_gmap_common.py). Only model 4's insert_gmap
    # hands a class of model 5 on to it (tgsis.insert_gmap stores both, as before the split).
    graph = _import_graph()
    assert set(MODEL_MODULES) <= set(graph), sorted(set(MODEL_MODULES) - set(graph))
    reached = {
        (a, b)
        for a in MODEL_MODULES
        for b in [*MODEL_MODULES, "tgsis.db.temporal"]
        if a != b and nx.has_path(graph, a, b)
    }
    assert reached == {("tgsis.db.gmaps", "tgsis.db.multidim")}


# What the mesh classes' conversion methods do in a fresh interpreter that imported tgsis.mesh alone (or the
# package's names): they reach tgsis.convert and tgsis._zpositive, which tgsis.mesh does not import (issue 38, part 4).
CONVERSIONS = """
import numpy as np
{imports}
s = Surface(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), [[0, 1, 2]], cell_properties={{"k": [7.0]}},
            name="s", metadata={{"zpositive": "Depth"}})
back = Surface.from_pyvista(s.to_pyvista())
assert back.same_as(s) and back.metadata["zpositive"] == "Depth", back
assert Surface.from_meshio(s.to_meshio()).same_as(s)
assert s.to_trimesh().vertices[1].tolist() == [1.0, 0.0, -0.0]  # trimesh: elevation
c = GeometryCollection([s, PointSet(np.zeros((2, 3)), cell_properties={{"k": [1.0, 2.0]}})], name="c")
assert c.to_pyvista().n_cells == 3 and len(c.to_meshio().cells) == 2
try:
    PointSet.from_pyvista(s.to_pyvista())
except InvalidGeometryError as exc:
    print(exc.message)
"""


@pytest.mark.parametrize(
    "imports",
    [
        "from tgsis.mesh import GeometryCollection, PointSet, Surface\nfrom tgsis.errors import InvalidGeometryError",
        "from tgsis import GeometryCollection, InvalidGeometryError, PointSet, Surface",
    ],
)
def test_the_mesh_classes_convert_after_importing_tgsis_mesh_alone(imports: str) -> None:
    done = subprocess.run(
        [sys.executable, "-c", CONVERSIONS.format(imports=imports)], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "the pyvista dataset is a Surface, not a PointSet"


def test_a_mesh_method_without_the_conversions_says_what_to_import(monkeypatch: pytest.MonkeyPatch) -> None:
    # only possible when tgsis.mesh is loaded without its package (whose __init__ imports tgsis.convert)
    import numpy as np

    import tgsis._conversions

    monkeypatch.setattr(tgsis._conversions, "_installed", None)
    with pytest.raises(RuntimeError, match=r"tgsis\.convert has not been imported \(import tgsis does it\)"):
        tgsis.Surface(np.eye(3), [[0, 1, 2]]).to_pyvista()
