"""Hostile input that gave raw or unclear errors gets our SQLSTATE and a message naming the bad thing (issue 36, point 13).

Each case failed before its fix: a text value of a feature property that is
no value of its type (raw 22P02 / 22007 naming no property), a NUL byte in a
mesh's name (psycopg's error, no SQLSTATE), partition_model_storage with
numbers beyond its SQL parameters (raw 22003), create_model with an id of
2**63 (42883) or 1.5 (taken as object 1, no error), fetch_features with an
id of 1.5 (taken as 1), and a model-5 axis no G-map has (an empty answer).
Messages are bounded in size whatever the input.
"""

from __future__ import annotations

import datetime
from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.test_gmap_multidim import _class, _interpretations
from tgsis.db import gmaps as G
from tgsis.db import modelsets as M

Conn = psycopg.Connection[Any]


def _surface(name: str | None = None) -> tgsis.Surface:
    return tgsis.Surface(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]), np.array([[0, 1, 2]]), name=name)


def _state(conn: Conn) -> list[Any]:
    return [
        conn.execute(q).fetchall()
        for q in (
            "SELECT geoid, geoname FROM tgsis.geometry ORDER BY 1",
            "SELECT * FROM faults ORDER BY 1",
            "SELECT count(*) FROM tgsis.vrtx",
            "SELECT * FROM tgsis.model ORDER BY 1",
        )
    ]


@pytest.fixture
def db(conn: Conn) -> tuple[Conn, int]:
    tgsis.create_feature_class(
        conn, "faults", "SURFACE", feature_properties={"n": "integer", "d": "date", "note": "text", "x": "float8"}
    )
    fid = tgsis.insert_feature(conn, "faults", _surface(), {"n": 1})
    conn.commit()
    return conn, fid


BIG = "9" * 1_000_000

CASES: list[tuple[str, Callable[[Conn, int], Any], type[tgsis.Error], str]] = [
    (
        "integer property",
        lambda c, f: tgsis.insert_feature(c, "faults", _surface(), {"note": "ok", "n": "abc"}),
        tgsis.InvalidPropertyError,
        "value 'abc' of feature property 'n' of class faults is not a valid integer",
    ),
    (
        "date property",
        lambda c, f: tgsis.insert_feature(c, "faults", _surface(), {"d": "31/02/2020"}),
        tgsis.InvalidPropertyError,
        "value '31/02/2020' of feature property 'd' of class faults is not a valid date",
    ),
    (
        "huge number property",
        lambda c, f: tgsis.insert_feature(c, "faults", _surface(), {"n": BIG}),
        tgsis.InvalidPropertyError,
        "of feature property 'n' of class faults is not a valid integer",
    ),
    (
        "NUL in a mesh's name",
        lambda c, f: tgsis.insert_feature(c, "faults", _surface("top\x00bottom")),
        tgsis.InvalidInputError,
        "geometry name contains a NUL byte (at character 3)",
    ),
    (
        "huge model number",
        lambda c, f: tgsis.partition_model_storage(c, 2**40, 4),
        tgsis.InvalidInputError,
        "model = 1099511627776 is out of range",
    ),
    (
        "huge partition count",
        lambda c, f: tgsis.partition_model_storage(c, 1, 2**40),
        tgsis.InvalidInputError,
        "partitions = 1099511627776 is out of range",
    ),
    (
        "model id 2**63",
        lambda c, f: M.create_model(c, "m", [f, 2**63]),
        tgsis.InvalidInputError,
        "objects[1] = 9223372036854775808 is out of range",
    ),
    (
        "model id 1.5",
        lambda c, f: M.create_model(c, "m", [f + 0.5]),  # type: ignore[list-item]
        tgsis.InvalidInputError,
        "objects[0] must be an integer id, not float",
    ),
    (
        "added id 1.5",
        lambda c, f: M.add_to_model(c, "m", [1.5]),  # type: ignore[list-item]
        tgsis.InvalidInputError,
        "objects[0] must be an integer id, not float 1.5",
    ),
    (
        "fetched id 1.5",
        lambda c, f: tgsis.fetch_features(c, "faults", [f, f + 0.5]),  # type: ignore[list-item]
        tgsis.InvalidInputError,
        "ids[1] must be an integer id, not float",
    ),
]


@pytest.mark.parametrize("case", CASES, ids=[case[0] for case in CASES])
def test_python_calls(
    db: tuple[Conn, int], case: tuple[str, Callable[[Conn, int], Any], type[tgsis.Error], str]
) -> None:
    conn, fid = db
    _, call, error, message = case
    before = _state(conn)
    with pytest.raises(error) as caught:
        call(conn, fid)
    assert message in str(caught.value), str(caught.value)[:300]
    assert caught.value.sqlstate == error.code and not isinstance(caught.value, tgsis.DatabaseError)
    assert len(str(caught.value)) + len(caught.value.detail or "") + len(caught.value.hint or "") < 2000
    conn.rollback()
    assert _state(conn) == before


def test_good_values_still_go_in(db: tuple[Conn, int]) -> None:
    conn, _ = db
    fid = tgsis.insert_feature(conn, "faults", _surface("top"), {"n": "42", "d": "2020-02-28", "note": "x", "x": 1.5})
    assert tgsis.fetch_feature(conn, "faults", fid).properties == {
        "n": 42,
        "d": datetime.date(2020, 2, 28),
        "note": "x",
        "x": 1.5,
    }
    model = M.create_model(conn, "m", [fid])
    assert model > 0 and [o.id for o in M.model_objects(conn, "m")] == [fid]


def test_a_model5_axis_no_gmap_has(conn: Conn) -> None:
    fc = _class(conn)
    _, _, history = _interpretations()
    geoid = G.insert_gmap(conn, fc, history, axes=["x", "y", "z", "knowledge"])
    conn.commit()
    with pytest.raises(tgsis.InvalidInputError, match=r"no feature of class knowledge has an axis 'age'") as caught:
        G.md_in_box(conn, fc, ["x", "age"], [0, 0], [1, 1])
    assert caught.value.sqlstate == "TG100" and caught.value.detail == "Their axes: knowledge, x, y, z."
    conn.rollback()
    with pytest.raises(tgsis.InvalidInputError, match=f"multiply indexed G-map {geoid} has no axis 'time'") as caught:
        G.md_vertices_in_box(conn, geoid, ["time"], [0], [1])
    assert caught.value.detail == "Its axes: x, y, z, knowledge."
    conn.rollback()
    long_axis = "a" * 100_000
    with pytest.raises(tgsis.InvalidInputError) as caught:
        G.md_vertices_in_box(conn, geoid, [long_axis], [0], [1])
    assert len(str(caught.value)) < 300
    conn.rollback()
    # an axis some features lack is no error: they are not in the box
    assert G.md_in_box(conn, fc, ["knowledge"], [1.5], [2]) == [geoid]


@pytest.mark.parametrize(
    ("query", "sqlstate", "message"),
    [
        (
            "SELECT tgsis.partition_model_storage(1::smallint, 99999999999)",
            "TG100",
            "number of partitions 99999999999 is out of range",
        ),
        ("SELECT tgsis.partition_model_storage(99999999999, 4)", "TG200", "data model 99999999999 does not exist"),
        ("SELECT tgsis.partition_model_storage(40000, 4)", "TG200", "data model 40000 does not exist"),
    ],
)
def test_partition_numbers_in_sql(conn: Conn, query: str, sqlstate: str, message: str) -> None:
    with pytest.raises(psycopg.Error) as caught:
        conn.execute(query)
    assert caught.value.sqlstate == sqlstate and message in str(caught.value.diag.message_primary)
    conn.rollback()
    # written without casts, a good call works
    assert "vrtx" in conn.execute("SELECT tgsis.partition_model_storage(1, 2)").fetchone()[0]  # type: ignore[index]
