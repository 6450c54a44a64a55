"""The numpy modules load without the database layer (issue 17, part 0).

Found: ``import tgsis.mesh`` loaded psycopg and the whole ``tgsis.db`` layer,
because the package's ``__init__`` imported it and ``tgsis.errors`` imported
psycopg. Each pure module is imported here in a fresh interpreter, which must
then hold neither psycopg nor any module of ``tgsis.db``; and the database
names of the package still resolve, on first use.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

PURE = ["tgsis", "tgsis.mesh", "tgsis.compare", "tgsis.edits", "tgsis.temporal", "tgsis.interpolation", "tgsis.gmaps",
        "tgsis.formats", "tgsis.errors", "tgsis.pictures", "tgsis.postgis"]


@pytest.mark.parametrize("module", PURE)
def test_a_pure_module_imports_neither_psycopg_nor_the_database_layer(module: str) -> None:
    program = (f"import sys, {module}; "
               "print(' '.join(sorted(m for m in sys.modules if m == 'psycopg' or m.startswith(('psycopg.', 'tgsis.db')))))")
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "", f"import {module} loaded {done.stdout.strip()}"


def test_the_database_names_load_on_first_use() -> None:
    program = ("import sys, tgsis; assert 'tgsis.db' not in sys.modules; "
               "f = tgsis.insert_feature; assert 'tgsis.db.features' in sys.modules; "
               "from tgsis import connect, merge_version; assert f is tgsis.insert_feature; "
               "assert set(tgsis.__all__) <= set(dir(tgsis)); "
               "import tgsis as t\ntry:\n    t.no_such_name\nexcept AttributeError as e:\n    print(e)")
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "module 'tgsis' has no attribute 'no_such_name'"
