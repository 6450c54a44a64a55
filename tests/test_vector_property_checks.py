"""A wrong vector property value answers the same on a class in chunks as on its twin in rows (plan L, V2).

A class's vector property (``t[]`` of size k) is NULL or exactly k values from index 1, none NULL: the row
table's column CHECK (``<table>_<column>_check``) refuses anything else with 23514. A class in chunks has no
row table, only its shape (``<table>_shape``, the CHECKs kept); its writers (the face's trigger and
``tgsis.write_property_rows``, both through ``tgsis.write_chunk_rows``) answer as the row table: 23514, the
same constraint name (``diag.constraint_name``), table and schema, the same message, nothing written; and
``tgsis.errors.translate`` gives users the same exception class for both. Then two sessions writing vector
properties of one class in chunks through the face at once, as the scalar two-writer tests of
tests/test_chunk_face.py: different rows both kept, the same row waits and is refused 40001, bits kept.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tests.storage_data import answer, classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


PROPS = [("normal", "double precision", 3), ("t", "real", 1), ("pair", "integer", 2)]
#: the compared columns: keys, then each property by its bits (array_send keeps shape and element bits)
COLUMNS = "_geoid, _idx, array_send(normal), float4send(t), array_send(pair)"

#: too short, too long, a NULL inside, a 2-D array, a wrong lower bound; by UPDATE and by INSERT
BAD = [
    "UPDATE {t} SET normal = ARRAY[1, 2] WHERE _geoid = 1 AND _idx = 3",
    "UPDATE {t} SET normal = ARRAY[1, 2, 3, 4] WHERE _geoid = 1 AND _idx < 3",
    "UPDATE {t} SET normal = ARRAY[1, NULL, 3] WHERE _geoid = 1 AND _idx = 3",
    "UPDATE {t} SET pair = '{{{{1,2}}}}' WHERE _geoid = 1 AND _idx = 3",
    "UPDATE {t} SET pair = '[0:1]={{1,2}}' WHERE _geoid = 1 AND _idx = 3",
    "INSERT INTO {t} (_geoid, _idx, normal, pair) VALUES (1, 9000, ARRAY[1, 2, 3], ARRAY[1])",
    "INSERT INTO {t} (_geoid, _idx, pair) VALUES (1, 9001, ARRAY[1, 2]), (1, 9002, ARRAY[1, 2, NULL])",
]


def _rows(conn: Conn, relation: str) -> list[tuple[Any, ...]]:
    query = f"SELECT {COLUMNS} FROM {relation} ORDER BY 1, 2"
    return [tuple(bytes(v) if isinstance(v, memoryview) else v for v in r) for r in conn.execute(query).fetchall()]


def _twins(conn: Conn) -> None:
    """Classes ``onrows`` (kept in rows) and ``inchunks`` (stored in chunks) with the same vector rows."""
    for name in ("onrows", "inchunks"):
        tgsis.create_feature_class(conn, name, "GEOMETRYCOLLECTION", cell_properties=list(PROPS))
        conn.execute(
            f"INSERT INTO public.{name}_cellpros (_geoid, _idx, normal, t, pair) "
            "SELECT g, i, ARRAY[sin(i), '-0'::float8, 'NaN'::float8], (i / 3.0)::real, "
            "CASE WHEN i % 5 = 0 THEN NULL ELSE ARRAY[i, -i] END "
            "FROM generate_series(1, 2) g, generate_series(0, 299) i"
        )
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()


def test_a_wrong_vector_answers_as_the_row_table_s_check(conn: Conn) -> None:
    _twins(conn)
    before = _rows(conn, "public.inchunks_cellpros")
    assert before == _rows(conn, "public.onrows_cellpros")
    chunks = "SELECT array_send(normal), array_send(pair) FROM public.inchunks_cellpros_chunk ORDER BY chunk"
    chunk_bits = conn.execute(chunks).fetchall()
    for statement in BAD:
        rows = answer(conn, statement.format(t="public.onrows_cellpros"), "onrows")
        in_chunks = answer(conn, statement.format(t="public.inchunks_cellpros"), "inchunks")
        assert rows[0] == "23514" and rows[2] in ("X_cellpros_normal_check", "X_cellpros_pair_check"), rows
        assert in_chunks == rows, statement
    # the detail of the chunks' answer names the property and its size
    with pytest.raises(psycopg.errors.CheckViolation) as caught:
        conn.execute(BAD[0].format(t="public.inchunks_cellpros"))
    conn.rollback()
    assert caught.value.diag.message_detail and "normal" in caught.value.diag.message_detail
    assert "exactly 3 values" in caught.value.diag.message_detail
    # tgsis.write_property_rows, the edit path of the Python API: the same answer
    call = (
        "SELECT tgsis.write_property_rows('public.inchunks_cellpros', 1, '{3}'::bigint[], "
        "ARRAY[ROW(1, 3, ARRAY[1, 2]::float8[], 1, ARRAY[1, 2])::public.inchunks_cellpros])"
    )
    assert answer(conn, call, "inchunks") == answer(conn, BAD[0].format(t="public.onrows_cellpros"), "onrows")
    # nothing written anywhere
    assert _rows(conn, "public.inchunks_cellpros") == before == _rows(conn, "public.onrows_cellpros")
    assert conn.execute(chunks).fetchall() == chunk_bits


def _waits_for_a_lock(conn: Conn, pid: int) -> bool:
    row = conn.execute("SELECT wait_event_type FROM pg_stat_activity WHERE pid = %s", (pid,)).fetchone()
    conn.rollback()
    return row is not None and row[0] == "Lock"


def test_two_sessions_writing_vectors_through_the_face(db_dsn: str, conn: Conn) -> None:
    _twins(conn)
    face = "public.inchunks_cellpros"
    outcomes: dict[str, list[Any]] = {}
    for case, second_id in (("different", 2), ("same", 1)):
        first = psycopg.connect(db_dsn, options="-c lock_timeout=20s")
        second = psycopg.connect(db_dsn, options="-c lock_timeout=20s")
        try:
            update = f"UPDATE {face} SET normal = ARRAY[normal[1] + 1, normal[2], normal[3]], pair = ARRAY[7, -7] WHERE _geoid = 1 AND _idx = %s"
            assert first.execute(update, (1,)).rowcount == 1  # open: holds the chunk
            result: list[Any] = []

            def run(session: Conn = second) -> None:
                try:
                    session.execute(update.replace("pair = ARRAY[7, -7]", "pair = ARRAY[8, -8]"), (second_id,))
                    session.commit()
                    result.append("ok")
                except psycopg.Error as exc:
                    session.rollback()
                    result.append(exc.sqlstate)

            worker = threading.Thread(target=run)
            worker.start()
            deadline = time.monotonic() + 60
            while not _waits_for_a_lock(conn, second.info.backend_pid):  # one chunk: the second waits in both cases
                assert worker.is_alive() and time.monotonic() < deadline, result
                time.sleep(0.05)
            first.commit()
            worker.join(60)
            assert not worker.is_alive()
            outcomes[case] = result
        finally:
            first.close()
            second.close()
    # as the scalar face (test_chunk_face): the different row written after the wait, the same row 40001
    assert outcomes == {"different": ["ok"], "same": ["40001"]}
    # the twin in rows given the same writes: every row and bit alike (-0, NaN kept; vertex 1 changed once per case)
    rows = "public.onrows_cellpros"
    conn.execute(
        f"UPDATE {rows} SET normal = ARRAY[normal[1] + 2, normal[2], normal[3]], pair = ARRAY[7, -7] WHERE _geoid = 1 AND _idx = 1"
    )
    conn.execute(
        f"UPDATE {rows} SET normal = ARRAY[normal[1] + 1, normal[2], normal[3]], pair = ARRAY[8, -8] WHERE _geoid = 1 AND _idx = 2"
    )
    conn.commit()
    assert _rows(conn, face) == _rows(conn, rows)
    assert conn.execute(f"SELECT count(*) FROM {face}").fetchone() == (600,)


def test_the_python_api_refuses_a_wrong_vector_shape_alike_on_both_storages(conn: Conn) -> None:
    surface = curved_surface()
    n = surface.n_vertices
    caught = []
    for name in ("onrows", "inchunks"):
        tgsis.create_feature_class(conn, name, "SURFACE", cell_properties=[("normal", "double precision", 3)])
        conn.commit()
        if name == "inchunks":
            conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
            conn.commit()
        for bad in (np.zeros((n, 2)), np.zeros((n, 4)), np.zeros(n), np.zeros((n, 3, 1))):
            with pytest.raises(tgsis.errors.Error) as error:
                F.insert_feature(
                    conn, name, Surface(surface.vertices, surface.cells, vertex_properties={"normal": bad})
                )
            conn.rollback()
            caught.append((type(error.value).__name__, error.value.sqlstate))
        assert conn.execute(f"SELECT count(*) FROM public.{name}_cellpros").fetchone() == (0,)
    assert caught[:4] == caught[4:], caught
