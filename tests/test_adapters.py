"""tgsis.register_types: cubes as numpy (2, d) arrays, model-time intervals as ranges of floats."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg.types.multirange import Multirange
from psycopg.types.range import Range

import tgsis
from tgsis.db.adapters import parse_cube, unpack_cube


def _surface(x0: float) -> tgsis.Surface:
    return tgsis.Surface(
        np.array([[x0, 3.7e6, -5000.0], [x0 + 10.5, 3.7e6 + 1, -4000.25], [x0, 3.7e6 + 2, -4500]]),
        np.array([[0, 1, 2]]),
    )


def test_without_registration_a_box_is_text(conn: psycopg.Connection[Any]) -> None:
    tgsis.create_feature_class(conn, "rocks", "SURFACE")
    geoid = tgsis.insert_feature(conn, "rocks", _surface(326126.29688))
    (text,) = conn.execute("SELECT bbox FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone()  # type: ignore[misc]
    assert isinstance(text, str) and text.startswith("(326126.29688")


def test_boxes_come_back_as_2_by_3_arrays(conn: psycopg.Connection[Any]) -> None:
    tgsis.create_feature_class(conn, "rocks", "SURFACE")
    surfaces = [_surface(326126.29688), _surface(-1.5e-7)]
    ids = [tgsis.insert_feature(conn, "rocks", s) for s in surfaces]
    tgsis.register_types(conn)
    for geoid, surface in zip(ids, surfaces):
        (box,) = conn.execute("SELECT bbox FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone()  # type: ignore[misc]
        assert isinstance(box, np.ndarray) and box.dtype == np.float64 and box.shape == (2, 3)
        want = np.stack([surface.vertices.min(axis=0), surface.vertices.max(axis=0)])
        np.testing.assert_array_equal(box, want)  # every digit: cube prints float8 exactly
    (boxes,) = conn.execute("SELECT array_agg(bbox ORDER BY geoid) FROM tgsis.geometry").fetchone()  # type: ignore[misc]
    assert len(boxes) == 2 and all(b.shape == (2, 3) for b in boxes)
    (point,) = conn.execute("SELECT cube(ARRAY[1, 2, 3]::float8[])").fetchone()  # type: ignore[misc]
    np.testing.assert_array_equal(point, [[1, 2, 3], [1, 2, 3]])
    (null,) = conn.execute("SELECT NULL::cube").fetchone()  # type: ignore[misc]
    assert null is None


def test_a_box_read_in_binary_is_bit_exact_whatever_extra_float_digits(conn: psycopg.Connection[Any]) -> None:
    # 0.1 + 0.2 and 1/3 need 17 significant digits: the text form rounds them to 15 under extra_float_digits <= 0
    tgsis.create_feature_class(conn, "rocks", "SURFACE")
    vertices = np.array([[0.1 + 0.2, 1 / 3, -5000.000000000001], [7e-310, 3.7e6 + 1 / 3, -4000.25], [1e300, 2, 0]])
    geoid = tgsis.insert_feature(conn, "rocks", tgsis.Surface(vertices, np.array([[0, 1, 2]])))
    want = np.stack([vertices.min(axis=0), vertices.max(axis=0)])
    tgsis.register_types(conn)
    conn.execute("SET extra_float_digits = 0")
    query = "SELECT bbox, ARRAY[bbox, bbox], cube(ARRAY[0.1::float8 + 0.2::float8, '-0'::float8]) FROM tgsis.geometry WHERE geoid = %s"
    box, boxes, point = conn.execute(query, (geoid,), binary=True).fetchone()  # type: ignore[misc]
    assert box.dtype == np.float64 and box.tobytes() == want.tobytes()  # bit for bit, -0.0 and subnormals too
    assert len(boxes) == 2 and all(b.tobytes() == want.tobytes() for b in boxes)
    assert point.tobytes() == np.array([[0.1 + 0.2, -0.0], [0.1 + 0.2, -0.0]]).tobytes()
    (text_box,) = conn.execute("SELECT bbox FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone()  # type: ignore[misc]
    assert not np.array_equal(text_box, want)  # what binary reads are for: the text form rounded
    conn.execute("RESET extra_float_digits")


@pytest.mark.parametrize("data", [b"", b"\x00\x00\x00", b"\x00\x00\x00\x00", b"\x00\x00\x00\x02" + bytes(24)])
def test_a_bad_binary_cube_is_refused(data: bytes) -> None:
    with pytest.raises(ValueError, match="not a binary cube"):
        unpack_cube(data)


def test_a_box_goes_in_as_a_cube(conn: psycopg.Connection[Any]) -> None:
    tgsis.register_types(conn)
    box = tgsis.Box.of([[0.0, 0, 0], [1, 2, 3.25]])
    row = conn.execute(
        "SELECT %s::cube @> cube(ARRAY[0.5, 1, 3]::float8[]), cube_dim(%s), %s", (box, box, box)
    ).fetchone()
    assert row is not None and row[0] is True and row[1] == 3
    np.testing.assert_array_equal(row[2], box)
    with pytest.raises(ValueError, match=r"a box is \(2, d\)"):
        tgsis.Box.of(np.zeros((3, 3)))


def test_time_intervals_come_back_as_ranges_of_floats(conn: psycopg.Connection[Any]) -> None:
    tgsis.register_types(conn)
    rng = conn.execute("SELECT tgsis.timerange(1.5, 2, '[)')").fetchone()[0]  # type: ignore[index]
    assert isinstance(rng, Range) and (rng.lower, rng.upper, rng.bounds) == (1.5, 2.0, "[)")
    assert isinstance(rng.lower, float)
    forever = conn.execute("SELECT tgsis.timerange(3, NULL, '[)')").fetchone()[0]  # type: ignore[index]
    assert forever.lower == 3.0 and forever.upper is None and forever.upper_inf
    merged = conn.execute(
        "SELECT range_agg(r) FROM (VALUES (tgsis.timerange(1, 2, '[)')), "
        "(tgsis.timerange(2, 3, '[]')), (tgsis.timerange(5, 6, '()'))) v(r)"
    ).fetchone()[0]  # type: ignore[index]
    assert isinstance(merged, Multirange)
    assert [(r.lower, r.upper, r.bounds) for r in merged] == [(1.0, 3.0, "[]"), (5.0, 6.0, "()")]
    # and back in as a parameter; PostgreSQL's range operators and functions on them as on any range
    assert conn.execute("SELECT %s::tgsis.timerange @> 1.75::float8", (rng,)).fetchone() == (True,)
    assert conn.execute(
        "SELECT 1.75::float8 <@ %s::tgsis.timerange, lower(%s::tgsis.timerange), "
        "isempty(tgsis.timerange(1, 1)), upper_inf(tgsis.timerange(1, NULL))",
        (rng, rng),
    ).fetchone() == (True, 1.5, True, True)
    meet = conn.execute("SELECT tgsis.timerange(1, 2) * tgsis.timerange(1.5, 4)").fetchone()[0]  # type: ignore[index]
    assert (meet.lower, meet.upper) == (1.5, 2.0)
    # a range with a NaN bound sent as a parameter is refused by name
    with pytest.raises(psycopg.Error, match="NaN is no bound") as caught:
        conn.execute("SELECT %s::tgsis.timerange", (Range(1.0, float("nan")),))
    assert caught.value.sqlstate == "TG100"
    conn.rollback()


def test_registration_is_per_connection(conn: psycopg.Connection[Any], db_dsn: str) -> None:
    tgsis.register_types(conn)
    with psycopg.connect(db_dsn) as other:
        assert isinstance(other.execute("SELECT cube(1)").fetchone()[0], str)  # type: ignore[index]
    cursor = conn.cursor()
    assert isinstance(cursor.execute("SELECT cube(1)").fetchone()[0], np.ndarray)  # type: ignore[index]


def test_register_types_refuses_a_database_without_tgsis(make_database: Any) -> None:
    with psycopg.connect(make_database()) as bare:
        with pytest.raises(tgsis.InstallationError, match="tgsis is not installed in this database") as info:
            tgsis.register_types(bare)
        assert "tgsis db install" in (info.value.hint or "")


@pytest.mark.parametrize("text", ["", "()", "(1, 2),(3)", "(1,2),(3,4),(5,6)", "box"])
def test_a_bad_cube_text_is_refused(text: str) -> None:
    with pytest.raises(ValueError, match="not a cube"):
        parse_cube(text)
