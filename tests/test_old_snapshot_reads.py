"""Reads from a snapshot older than add_property or a storage switch: the rows, or 40001, never an empty set.

Session B begins REPEATABLE READ and takes its snapshot by reading an unrelated table; session A adds a
property to a class whose properties are in chunks, or switches a table's storage (into chunks, back into
rows), and commits; B then reads the class's properties or the model table (SQL face, Python
``fetch_feature`` / ``fetch_features``, i.e. the download). PostgreSQL table rewrites and tables made after a
snapshot look EMPTY to that snapshot: before plan H, after the add and every switch, B's SQL read gave 0 rows
without an error (the Python readers failed with TG102 / TG103, rows missing). Now the add rewrites nothing
(B reads every row) and a switch's new chunk table refuses B with 40001 (retry), whose retry reads the rows.
The way back into rows makes a plain row table, which cannot refuse an older snapshot: the switch itself is
refused (TG202 naming the sessions) while such a snapshot is held, and that snapshot goes on reading the chunks.
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
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import GeometryCollection, Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


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


def _refused_while_held(conn: Conn, call: str, reader: Conn) -> None:
    """The way back into rows refuses (TG202, DETAIL naming the reader's pid) while ``reader``'s snapshot is older:
    the plain row table it would make would read EMPTY to that snapshot (plan I, A). Nothing changed."""
    with pytest.raises(psycopg.Error) as refused:
        conn.execute(call)
    assert refused.value.sqlstate == "TG202", refused.value
    assert f"pid {reader.info.backend_pid} " in (refused.value.diag.message_detail or ""), refused.value.diag
    assert refused.value.diag.message_hint
    conn.rollback()


@pytest.mark.parametrize("read", READS)
@pytest.mark.parametrize("switch", sorted(SWITCHES))
@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_a_class_switched_after_the_snapshot_is_read_or_refused_never_empty(
    db_dsn: str, conn: Conn, versioned: bool, switch: str, read: str
) -> None:
    geoid, n, total = _class_in_chunks(conn, versioned)
    if switch == "back into rows":
        conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
        conn.commit()
    reader = _old_snapshot(db_dsn)
    reads = _class_reads(reader, geoid)
    if switch == "back into rows":
        # refused while the older snapshot is held; that snapshot goes on reading the chunks, every row
        _refused_while_held(conn, f"SELECT tgsis.{SWITCHES[switch]}('layer')", reader)
        got, state = _state(reader, reads[read])
        assert state is None and got[0] == n and got[1] == pytest.approx(total), (got, state)
        reader.commit()
        conn.execute(f"SELECT tgsis.{SWITCHES[switch]}('layer')")  # the retry, once that snapshot is gone
        conn.commit()
        assert conn.execute("SELECT tgsis.stored_in_chunks('public', 'layer_cellpros')").fetchone() == (False,)
        reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")  # a snapshot after the switch
        got = reads[read]()
        assert got[0] == n and got[1] == pytest.approx(total)
        reader.close()
        return
    conn.execute(f"SELECT tgsis.{SWITCHES[switch]}('layer')")
    conn.commit()
    got, state = _state(reader, reads[read])
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
    reads = _model_reads(reader, fault)
    if "store_in_rows" in call:
        # refused while the older snapshot is held, which goes on reading the chunks; done once it is gone
        _refused_while_held(conn, call, reader)
        assert reads[read]() == expected[0]
        reader.commit()
        conn.execute(call)
        conn.commit()
        reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
        assert reads[read]() == expected[0]
        reader.close()
        return
    conn.execute(call)
    conn.commit()
    got, state = _state(reader, reads[read])
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
@pytest.mark.parametrize("read", READS)
def test_a_model_table_switched_back_into_rows_after_the_snapshot_is_read_or_refused(
    db_dsn: str, conn: Conn, fault_clone: int, read: str
) -> None:
    _model_switch(db_dsn, conn, fault_clone, "SELECT tgsis.store_in_rows('vrtx')", read)


@pytest.mark.storage("chunks")
@pytest.mark.parametrize("when", ["before the call", "after the call"])
def test_a_snapshot_taken_inside_the_switch_back_refuses_it_at_the_latest_at_commit(
    db_dsn: str, conn: Conn, fault_clone: int, when: str
) -> None:
    """A snapshot taken while the switch's transaction is open (before the call, or after it while the caller keeps
    the transaction open) does not see the switch's commit either: TG202 from the call's last check or at COMMIT,
    the switch rolled back, the chunks (and that snapshot's reads) kept; done once that snapshot is gone."""
    expected = conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fault_clone,)).fetchone()
    conn.commit()
    conn.execute("SELECT pg_current_xact_id()")  # the switch's transaction has its xid
    reader: Conn | None = None
    if when == "before the call":
        reader = _old_snapshot(db_dsn)
    try:
        conn.execute("SELECT tgsis.store_in_rows('vrtx')")
        assert reader is None, "the switch ran under an older snapshot"
        reader = _old_snapshot(db_dsn)
        conn.commit()
    except psycopg.Error as exc:
        assert exc.sqlstate == "TG202", exc
        assert reader is not None and f"pid {reader.info.backend_pid} " in (exc.diag.message_detail or "")
        conn.rollback()
    else:
        raise AssertionError("the switch committed under an older snapshot")
    assert conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,)
    assert _model_reads(reader, fault_clone)["face"]() == expected[0]  # type: ignore[index]
    reader.commit()
    conn.execute("SELECT tgsis.store_in_rows('vrtx')")
    conn.commit()
    assert conn.execute("SELECT to_regclass('pg_temp.tgsis_older_snapshots')").fetchone() == (None,)
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    assert _model_reads(reader, fault_clone)["face"]() == expected[0]  # type: ignore[index]
    reader.close()


@pytest.mark.storage("chunks")
def test_a_writer_under_an_older_snapshot_loses_and_duplicates_nothing_across_the_way_back(
    db_dsn: str, conn: Conn, fault_clone: int
) -> None:
    """A REPEATABLE READ writer through the face (an UPDATE, an INSERT) whose snapshot is older than the switch:
    the switch is refused while it is open, its writes land in the chunks, and the way back after it carries them
    once each."""
    before = conn.execute("SELECT count(*), max(vrtxid) FROM tgsis.vrtx WHERE geoid = %s", (fault_clone,)).fetchone()
    assert before is not None
    conn.commit()
    writer = _old_snapshot(db_dsn)
    _refused_while_held(conn, "SELECT tgsis.store_in_rows('vrtx')", writer)
    writer.execute("UPDATE tgsis.vrtx SET z = 1234.5 WHERE geoid = %s AND vrtxid = 0", (fault_clone,))
    writer.execute(
        "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 1, 2, 3)", (fault_clone, before[1] + 1)
    )
    writer.commit()  # the writer stays connected, idle: its face work tables went with its transaction
    conn.execute("SELECT tgsis.store_in_rows('vrtx')")
    conn.commit()
    writer.close()
    assert conn.execute(
        "SELECT count(*), count(DISTINCT vrtxid), count(*) FILTER (WHERE z = 1234.5 AND vrtxid = 0)"
        " FROM tgsis.vrtx WHERE geoid = %s",
        (fault_clone,),
    ).fetchone() == (before[0] + 1, before[0] + 1, 1)
