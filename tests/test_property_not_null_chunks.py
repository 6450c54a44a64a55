"""A NULL in a NOT NULL property answers the same on a class in chunks as on its twin in rows (plan M, X item 2).

A vertex or cell property of a class that is not a collection is NOT NULL: the row table refuses a NULL with
23502 (``null value in column "<column>" of relation "<table>" violates not-null constraint``, the column,
table and schema in diag). A class in chunks has no row table; its writers (the face's trigger and
``tgsis.write_property_rows``, both through ``tgsis.write_chunk_rows``) answered TG100 ("a row to write has a
NULL value"). They now answer as the row table: 23502, the same message and diag fields, the first NULL
column in column order, the same exception class of ``tgsis.errors.translate``, and nothing written. A
collection's properties may be NULL on both storages (its members lack some), its keys not.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tests.storage_data import answer, classes_as_rows

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


PROPS: list[tuple[str, str] | tuple[str, str, int]] = [
    ("normal", "double precision", 3),
    ("porosity", "double precision"),
    ("facies", "integer"),
]
#: the compared columns: keys, then each property by its bits
COLUMNS = "_geoid, _idx, array_send(normal), float8send(porosity), facies"

#: a NULL vector, a NULL scalar, a property left out (NULL), two left out (the first named), by UPDATE and INSERT
BAD = [
    "UPDATE {t} SET normal = NULL WHERE _geoid = 1 AND _idx = 3",
    "UPDATE {t} SET porosity = NULL WHERE _geoid = 1 AND _idx < 3",
    "UPDATE {t} SET normal = NULL, facies = NULL WHERE _geoid = 2 AND _idx = 7",
    "INSERT INTO {t} (_geoid, _idx, porosity, facies) VALUES (1, 9000, 1, 1)",
    "INSERT INTO {t} (_geoid, _idx, normal) VALUES (1, 9001, ARRAY[1, 2, 3])",
    "INSERT INTO {t} (_geoid, _idx, normal, porosity, facies) VALUES (1, 9002, ARRAY[1, 2, 3], 1, 1), (1, 9003, NULL, 1, 1)",
]
#: a NULL key, in a collection too: the row table names the key column
NULL_KEYS = [
    "INSERT INTO {t} (_geoid, _idx, normal, porosity, facies) VALUES (NULL, 9004, ARRAY[1, 2, 3], 1, 1)",
    "INSERT INTO {t} (_geoid, _idx, normal, porosity, facies) VALUES (1, NULL, NULL, 1, 1)",
    "UPDATE {t} SET _idx = NULL WHERE _geoid = 1 AND _idx = 3",
]


def _rows(conn: Conn, relation: str) -> list[tuple[Any, ...]]:
    query = f"SELECT {COLUMNS} FROM {relation} ORDER BY 1, 2"
    return [tuple(bytes(v) if isinstance(v, memoryview) else v for v in r) for r in conn.execute(query).fetchall()]


def _twins(conn: Conn, geometry: str = "SURFACE", versioned: bool = False) -> None:
    """Classes ``onrows`` (kept in rows) and ``inchunks`` (stored in chunks) with the same property rows, versioned
    (feature versioning) or not."""
    for name in ("onrows", "inchunks"):
        tgsis.create_feature_class(conn, name, geometry, cell_properties=list(PROPS))
        conn.execute(
            f"INSERT INTO public.{name}_cellpros (_geoid, _idx, normal, porosity, facies) "
            "SELECT g, i, ARRAY[sin(i), '-0'::float8, 'NaN'::float8], i / 3.0, i % 7 "
            "FROM generate_series(1, 2) g, generate_series(0, 299) i"
        )
    conn.commit()
    if versioned:
        tgsis.enable_feature_versioning(conn)
        conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()


@pytest.mark.parametrize("versioned", [False, True], ids=["unversioned", "versioned"])
def test_a_null_in_a_not_null_property_answers_as_the_row_table(conn: Conn, versioned: bool) -> None:
    _twins(conn, versioned=versioned)
    before = _rows(conn, "public.inchunks_cellpros")
    assert before == _rows(conn, "public.onrows_cellpros")
    chunks = "SELECT c::text FROM public.inchunks_cellpros_chunk c ORDER BY _geoid, chunk, revision"
    chunk_rows = conn.execute(chunks).fetchall()
    named = set()
    for statement in BAD + NULL_KEYS:
        rows = answer(conn, statement.format(t="public.onrows_cellpros"), "onrows")
        in_chunks = answer(conn, statement.format(t="public.inchunks_cellpros"), "inchunks")
        assert rows[0] == "23502", rows
        assert in_chunks == rows, statement
        named.add(rows[3])
    assert named == {"normal", "porosity", "_geoid", "_idx"}
    # a wrong vector (V2's 23514) names the same relation too, versioned or not
    check = "UPDATE {t} SET normal = ARRAY[1, 2] WHERE _geoid = 1 AND _idx = 3"
    rows = answer(conn, check.format(t="public.onrows_cellpros"), "onrows")
    assert rows[0] == "23514" and answer(conn, check.format(t="public.inchunks_cellpros"), "inchunks") == rows
    # tgsis.write_property_rows, the edit path of the Python API: the same answer
    call = (
        "SELECT tgsis.write_property_rows('public.inchunks_cellpros', 1, '{3}'::bigint[], "
        "ARRAY[ROW(1, 3, NULL, 1, 1)::public.inchunks_cellpros])"
    )
    assert answer(conn, call, "inchunks") == answer(conn, BAD[0].format(t="public.onrows_cellpros"), "onrows")
    # nothing written anywhere
    assert _rows(conn, "public.inchunks_cellpros") == before == _rows(conn, "public.onrows_cellpros")
    assert conn.execute(chunks).fetchall() == chunk_rows


def test_a_collection_s_properties_take_a_null_on_both_storages(conn: Conn) -> None:
    _twins(conn, "GEOMETRYCOLLECTION")
    for statement in BAD:
        for name in ("onrows", "inchunks"):
            assert answer(conn, statement.format(t=f"public.{name}_cellpros"), name) == ("written",), statement
    for statement in NULL_KEYS:
        rows = answer(conn, statement.format(t="public.onrows_cellpros"), "onrows")
        assert rows[0] == "23502" and answer(conn, statement.format(t="public.inchunks_cellpros"), "inchunks") == rows
    assert _rows(conn, "public.inchunks_cellpros") == _rows(conn, "public.onrows_cellpros")
