"""Reads from a snapshot older than add_property or a storage switch: the rows, or 40001, never an empty set.

Session B begins REPEATABLE READ and takes its snapshot by reading an unrelated table; session A adds a
property to a class whose properties are in chunks, or switches a table's storage (into chunks, back into
rows), and commits; B then reads the class's properties or the model table (SQL face, Python
``fetch_feature`` / ``fetch_features``, i.e. the download). PostgreSQL table rewrites and tables made after a
snapshot look EMPTY to that snapshot: before plan H, after the add and every switch, B's SQL read gave 0 rows
without an error (the Python readers failed with TG102 / TG103, rows missing). Now the add rewrites nothing
(B reads every row) and a switch's new chunk table refuses B with 40001 (retry), whose retry reads the rows.
Left open, marked ``xfail(strict=True)``: the SQL read of the plain row table a switch back into rows makes.
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
from tgsis.mesh import GeometryCollection, Surface

Conn = psycopg.Connection[Any]


def _old_snapshot(db_dsn: str) -> Conn:
    """A REPEATABLE READ session whose snapshot is taken now, by reading a table the test does not touch."""
    reader = connect(db_dsn, "reader")
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    reader.execute("SELECT count(*) FROM pg_catalog.pg_namespace")
    return reader


def _state(reader: Conn, read: Callable[[], Any]) -> tuple[Any, str | None]:
    """What ``read`` gives and no state, or its error's message and SQLSTATE (the transaction rolled back)."""
    try:
        return read(), None
    except psycopg.Error as exc:
        reader.rollback()
        return str(exc), exc.sqlstate
    except tgsis.errors.Error as exc:
        reader.rollback()
        return str(exc), exc.sqlstate or type(exc).__name__


def _class_in_chunks(conn: Conn, versioned: bool, collection: bool = False) -> tuple[int, int, float]:
    """A surface class (or a collection of one surface: its properties may be NULL) with a double and an
    integer cell property, one feature stored: (geoid, n, sum of the doubles)."""
    surface = curved_surface()
    n = surface.n_vertices
    tgsis.create_feature_class(
        conn,
        "layer",
        "GEOMETRYCOLLECTION" if collection else "SURFACE",
        cell_properties=[("porosity", "double precision"), ("facies", "integer")],
    )
    if versioned:
        tgsis.enable_feature_versioning(conn)
    porosity = np.linspace(0.25, 1.5, n)
    props: dict[str, Any] = {"porosity": porosity, "facies": np.arange(n, dtype=np.int32) % 7}
    member = Surface(surface.vertices, surface.cells, vertex_properties=props)
    geoid = F.insert_feature(conn, "layer", GeometryCollection([member]) if collection else member)
    conn.commit()
    return geoid, n, float(np.sum(porosity))


def _class_reads(reader: Conn, geoid: int) -> dict[str, Callable[[], tuple[int, float]]]:
    """The class's properties read by the SQL face, ``fetch_feature`` and ``fetch_features``: (count, sum)."""

    def face() -> tuple[int, float]:
        row = reader.execute("SELECT count(*), sum(porosity) FROM public.layer_cellpros").fetchone()  # one feature
        assert row is not None
        return int(row[0]), float(row[1] or 0.0)

    def python(one: bool) -> tuple[int, float]:
        feature = F.fetch_feature(reader, "layer", geoid) if one else F.fetch_features(reader, "layer", [geoid])[0]
        mesh = feature.mesh
        if isinstance(mesh, GeometryCollection):
            mesh = mesh.members[0]
        assert isinstance(mesh, Surface)
        values = mesh.vertex_properties.get("porosity")
        return (0, 0.0) if values is None else (len(values), float(np.sum(values)))

    return {"face": face, "fetch_feature": lambda: python(True), "fetch_features": lambda: python(False)}


READS = ["face", "fetch_feature", "fetch_features"]
ADDS = {
    "no default": "SELECT tgsis.add_property('layer', 'cell', '[\"grade\", \"smallint\"]')",
    "default": "SELECT tgsis.add_property('layer', 'cell', '[\"grade\", \"smallint\"]', '9')",
}


@pytest.mark.parametrize("read", READS)
@pytest.mark.parametrize("add", sorted(ADDS))
@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_an_add_property_in_chunks_keeps_an_older_snapshot_reading_every_row(
    db_dsn: str, conn: Conn, versioned: bool, add: str, read: str
) -> None:
    """The add rewrites nothing: the older snapshot reads the rows it saw (not an empty set, not 40001).

    Without a default the class is a collection (a surface's vertex property may not be NULL)."""
    geoid, n, total = _class_in_chunks(conn, versioned, collection=add == "no default")
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    reader = _old_snapshot(db_dsn)
    conn.execute(ADDS[add])
    conn.commit()
    got, state = _state(reader, _class_reads(reader, geoid)[read])
    assert state is None, got
    assert got[0] == n and got[1] == pytest.approx(total)
    reader.close()
    # and the new property is there for a new snapshot: the default at every present slot, else NULL
    row = conn.execute("SELECT count(*), count(grade), min(grade), max(grade) FROM public.layer_cellpros").fetchone()
    assert row == ((n, n, 9, 9) if add == "default" else (n, 0, None, None))


@pytest.mark.parametrize("relation", ["layer_cellpros", "layer_cellpros_chunk_rows"], ids=["face", "chunk view"])
@pytest.mark.parametrize("add", sorted(ADDS))
def test_an_older_snapshot_reading_the_added_property_gets_40001_not_null(
    db_dsn: str, conn: Conn, add: str, relation: str
) -> None:
    """The chunk versions that snapshot sees have no array for the new property (NULL): naming it is refused,
    where it would read NULL instead of the default every newer snapshot reads; the other columns read."""
    _, n, total = _class_in_chunks(conn, False, collection=add == "no default")
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    reader = _old_snapshot(db_dsn)
    conn.execute(ADDS[add])
    conn.commit()
    got, state = _state(reader, lambda: reader.execute(f"SELECT count(grade) FROM public.{relation}").fetchone())
    assert state == "40001", (got, state)
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")  # the retry, after the add
    assert reader.execute(f"SELECT count(*), count(grade), sum(porosity) FROM public.{relation}").fetchone() == (
        n,
        n if add == "default" else 0,
        pytest.approx(total),
    )
    reader.close()


SWITCHES = {"into chunks": "store_class_in_chunks", "back into rows": "store_class_in_rows"}

#: Left open (docs/storage.md): the way back into rows makes a plain table, which cannot refuse a snapshot older
#: than it; such a snapshot reads it empty through SQL (PostgreSQL's caveat for a table made after a snapshot).
ROWS_FACE_OPEN = pytest.mark.xfail(
    strict=True, reason="a plain row table made after the snapshot reads empty through SQL: not guarded (open)"
)


def _read_params(switch_back: bool) -> list[Any]:
    return [pytest.param(r, marks=ROWS_FACE_OPEN) if switch_back and r == "face" else r for r in READS]


@pytest.mark.parametrize(
    ("switch", "read"),
    [
        pytest.param(s, r, marks=ROWS_FACE_OPEN) if s == "back into rows" and r == "face" else (s, r)
        for s in sorted(SWITCHES)
        for r in READS
    ],
)
@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_a_class_switched_after_the_snapshot_is_read_or_refused_never_empty(
    db_dsn: str, conn: Conn, versioned: bool, switch: str, read: str
) -> None:
    geoid, n, total = _class_in_chunks(conn, versioned)
    if switch == "back into rows":
        conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
        conn.commit()
    reader = _old_snapshot(db_dsn)
    conn.execute(f"SELECT tgsis.{SWITCHES[switch]}('layer')")
    conn.commit()
    reads = _class_reads(reader, geoid)
    got, state = _state(reader, reads[read])
    if switch == "back into rows" and read != "face":
        # a row table made after the snapshot: the Python readers find its rows missing and say so (TG103)
        assert state is not None or got == (n, pytest.approx(total)), (got, state)
        reader.close()
        return
    assert state in (None, "40001"), (got, state)
    if state is None:
        assert got[0] == n and got[1] == pytest.approx(total), "an older snapshot read the class's rows empty"
    else:
        got = reads[read]()  # the retry (READ COMMITTED: after the switch)
        assert got[0] == n and got[1] == pytest.approx(total)
    reader.close()


def _model_reads(reader: Conn, fault: int) -> dict[str, Callable[[], int]]:
    def face() -> int:
        row = reader.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fault,)).fetchone()
        assert row is not None
        return int(row[0])

    def python(one: bool) -> int:
        feature = F.fetch_feature(reader, "faults", fault) if one else F.fetch_features(reader, "faults", [fault])[0]
        mesh = feature.mesh
        return 0 if mesh is None else mesh.n_vertices

    return {"face": face, "fetch_feature": lambda: python(True), "fetch_features": lambda: python(False)}


def _model_switch(db_dsn: str, conn: Conn, fault: int, call: str, read: str) -> None:
    expected = conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fault,)).fetchone()
    assert expected is not None and expected[0] > 0
    conn.commit()
    reader = _old_snapshot(db_dsn)
    conn.execute(call)
    conn.commit()
    reads = _model_reads(reader, fault)
    got, state = _state(reader, reads[read])
    if "store_in_rows" in call and read != "face":
        # a row table made after the snapshot: the Python readers find the rows missing and say so (TG102)
        assert state is not None or got == expected[0], (got, state)
        reader.close()
        return
    assert state in (None, "40001"), (got, state)
    if state is None:
        assert got == expected[0], "an older snapshot read the model table's rows empty"
    else:
        assert reads[read]() == expected[0]  # the retry
    reader.close()


@pytest.mark.storage("rows")
@pytest.mark.parametrize("read", READS)
def test_a_model_table_switched_into_chunks_after_the_snapshot_is_read_or_refused(
    db_dsn: str, conn: Conn, fault_clone: int, read: str
) -> None:
    _model_switch(db_dsn, conn, fault_clone, "SELECT tgsis.store_in_chunks('vrtx')", read)


@pytest.mark.storage("chunks")
@pytest.mark.parametrize("read", _read_params(True))
def test_a_model_table_switched_back_into_rows_after_the_snapshot_is_read_or_refused(
    db_dsn: str, conn: Conn, fault_clone: int, read: str
) -> None:
    _model_switch(db_dsn, conn, fault_clone, "SELECT tgsis.store_in_rows('vrtx')", read)
