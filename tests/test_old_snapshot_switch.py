"""A storage switch into chunks and an older REPEATABLE READ snapshot (plan G, A).

``tgsis.store_in_chunks`` / ``tgsis.store_class_in_chunks`` move the rows into a chunk table the switch's
transaction makes: a transaction whose snapshot predates the switch would read that table, and so the face
with today's name, EMPTY, silently. The faces, the chunk views and the Python chunk readers check once per
statement (``tgsis.chunk_snapshot_guard``): such a read gets 40001 (retry), and its retry reads the rows.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tests.sessions import connect
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]

pytestmark = pytest.mark.storage("rows")


def _old_snapshot(db_dsn: str) -> Conn:
    """A REPEATABLE READ session whose snapshot is taken now (no lock on the tables the test switches)."""
    reader = connect(db_dsn, "reader")
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    reader.execute("SELECT 1")
    return reader


def _state(reader: Conn, read: Callable[[], Any]) -> tuple[Any, str | None]:
    try:
        return read(), None
    except psycopg.Error as exc:
        reader.rollback()
        return str(exc), exc.sqlstate
    except tgsis.errors.Error as exc:
        reader.rollback()
        return str(exc), exc.sqlstate or type(exc).__name__


@pytest.mark.parametrize("read", ["face", "chunk view", "python"])
def test_a_model_table_switched_after_the_snapshot_is_refused_not_read_empty(
    db_dsn: str, conn: Conn, fault_clone: int, read: str
) -> None:
    expected = conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fault_clone,)).fetchone()
    assert expected is not None and expected[0] > 0
    reader = _old_snapshot(db_dsn)
    conn.execute("SELECT tgsis.store_in_chunks('vrtx')")
    conn.commit()
    reads: dict[str, Callable[[], Any]] = {
        "face": lambda: reader.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fault_clone,)).fetchone(),
        "chunk view": lambda: reader.execute(
            "SELECT count(*) FROM tgsis.vrtx_chunk_rows WHERE geoid = %s", (fault_clone,)
        ).fetchone(),
        "python": lambda: (len(F.fetch_feature(reader, "faults", fault_clone).mesh.vertices),),  # type: ignore[union-attr]
    }
    got, state = _state(reader, reads[read])
    assert state == "40001", (got, state)
    assert reads[read]() == expected  # the retry (READ COMMITTED: after the switch)
    reader.close()


@pytest.mark.parametrize("read", ["face", "python"])
@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_a_class_switched_into_chunks_after_the_snapshot_is_refused_not_read_empty(
    db_dsn: str, conn: Conn, versioned: bool, read: str
) -> None:
    surface = curved_surface()
    n = surface.n_vertices
    tgsis.create_feature_class(conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision")])
    if versioned:
        tgsis.enable_feature_versioning(conn)
    porosity = np.linspace(0, 1, n)
    geoid = F.insert_feature(
        conn, "layer", Surface(surface.vertices, surface.cells, vertex_properties={"porosity": porosity})
    )
    conn.commit()

    def reading(reader: Conn) -> tuple[int, float]:
        if read == "face":
            row = reader.execute(
                "SELECT count(*), sum(porosity) FROM public.layer_cellpros WHERE _geoid = %s", (geoid,)
            ).fetchone()
            assert row is not None
            return int(row[0]), float(row[1] or 0.0)
        mesh = F.fetch_feature(reader, "layer", geoid).mesh
        assert isinstance(mesh, Surface)
        return len(mesh.vertex_properties["porosity"]), float(np.sum(mesh.vertex_properties["porosity"]))

    reader = _old_snapshot(db_dsn)
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    got, state = _state(reader, lambda: reading(reader))
    assert state == "40001", (got, state)
    got = reading(reader)  # the retry (READ COMMITTED: after the switch)
    assert got[0] == n and got[1] == pytest.approx(float(np.sum(porosity)))
    reader.close()
