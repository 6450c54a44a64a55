"""add/rename/drop property keeps a solved conflict solved, on a class stored in rows as in chunks (plan G, X1).

A conflict's marks fingerprint its objects' stored row versions (``tgsis.changed_objects``: ``record_out``
of each ``<table>_ver`` row, or of each chunk version). Adding or dropping a column changes every row's
text without changing what the version's side of the conflict chose: the marks are read before the alter
and renewed after it (``tgsis.conflict_marks`` / ``tgsis.renew_conflict_marks``) in both storages, so the
next merge finds the solution it was given. Before, the rows storage set the conflict back to unsolved.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


def _solved_conflict(conn: Conn, storage: str) -> int:
    """A versioned class (properties in ``storage``) whose vertex 3 changed in e1 and in the parent, solved by the child."""
    surface = curved_surface()
    n = surface.n_vertices
    tgsis.create_feature_class(
        conn,
        "layer",
        "SURFACE",
        cell_properties=[("porosity", "double precision"), ("facies", "integer")],
        feature_properties=[("label", "text"), ("age", "integer")],
    )
    tgsis.enable_feature_versioning(conn)
    props: dict[str, Any] = {"porosity": np.linspace(0, 1, n), "facies": np.arange(n, dtype=np.int32) % 7}
    geoid = F.insert_feature(
        conn,
        "layer",
        Surface(surface.vertices, surface.cells, vertex_properties=props),
        properties={"label": "a", "age": 1},
    )
    tgsis.create_version(conn, "e1")
    conn.commit()
    if storage == "chunks":
        conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
        conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET porosity = 1.0 WHERE _geoid = %s AND _idx = 3", (geoid,))
        conn.execute("UPDATE public.layer SET label = 'child' WHERE _geoid = %s", (geoid,))
    conn.execute("UPDATE public.layer_cellpros SET porosity = 2.0 WHERE _geoid = %s AND _idx = 3", (geoid,))
    conn.execute("UPDATE public.layer SET label = 'parent' WHERE _geoid = %s", (geoid,))
    conn.commit()
    with pytest.raises(tgsis.UnsolvedConflictsError):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    tgsis.resolve_conflict(conn, "e1", "feature", geoid, "child")
    conn.commit()
    return geoid


def _solved(conn: Conn) -> list[tuple[Any, ...]]:
    return conn.execute(
        "SELECT objectclass, objectkey, solution <> 'unsolved' FROM tgsis.conflicts ORDER BY 1, 2"
    ).fetchall()


ALTERS = {
    "add cell": lambda conn: tgsis.add_property(conn, "layer", ("grade", "smallint"), default="9"),
    "add feature": lambda conn: tgsis.add_property(conn, "layer", ("note", "text"), kind="feature"),
    "rename cell": lambda conn: tgsis.rename_property(conn, "layer", "facies", "rock"),
    "drop cell": lambda conn: tgsis.drop_property(conn, "layer", "facies", force=True),
    "drop feature": lambda conn: tgsis.drop_property(conn, "layer", "age", force=True),
}


@pytest.mark.parametrize("storage", ["rows", "chunks"])
@pytest.mark.parametrize("alter", sorted(ALTERS))
def test_a_solved_conflict_stays_solved_across_an_alter(conn: Conn, storage: str, alter: str) -> None:
    geoid = _solved_conflict(conn, storage)
    before = _solved(conn)
    assert before and all(r[2] for r in before)
    ALTERS[alter](conn)
    conn.commit()
    tgsis.merge_version(conn, "e1")  # still solved: the alter changed no value either side chose
    conn.commit()
    assert conn.execute(
        "SELECT porosity FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 3", (geoid,)
    ).fetchone() == (1.0,)
    assert conn.execute("SELECT label FROM public.layer WHERE _geoid = %s", (geoid,)).fetchone() == ("child",)


@pytest.mark.parametrize("storage", ["rows", "chunks"])
def test_a_conflict_changed_after_the_alter_is_unsolved_again(conn: Conn, storage: str) -> None:
    """The renewal carries the marks of the alter only: a later edit of either side unsolves the conflict."""
    geoid = _solved_conflict(conn, storage)
    tgsis.add_property(conn, "layer", ("grade", "smallint"), default="9")
    conn.commit()
    conn.execute("UPDATE public.layer_cellpros SET porosity = 3.0 WHERE _geoid = %s AND _idx = 3", (geoid,))
    conn.commit()
    with pytest.raises(tgsis.UnsolvedConflictsError):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
