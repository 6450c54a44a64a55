"""Answers that could be silently wrong (plan O, G): each test here failed on main before its fix.

1. A stored box that differs from the measured one only by a NaN was left stale: the comparisons read the box
   through ``cube_ll_coord`` / ``cube_ur_coord``, which take the least and the greatest of a corner pair by ``<``
   and ``>`` and so hide a NaN (``(NaN, 0, 0),(1, 1, 1)`` reads as ``(1, 0, 0),(1, 1, 1)``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.roles import login_roles
from tests.storage_data import in_chunks, storage_of, switch_tables, tables_as_rows
from tgsis import gmaps
from tgsis.db import features as F
from tgsis.db import gmaps as G
from tgsis.errors import InvalidInputError

Conn = psycopg.Connection[Any]

#: how a box is read here: its 2m coordinates as stored (low corner, then high), NaN kept where it is
STORED = (
    "SELECT array_agg(cube_coord(bbox, d) ORDER BY d) FROM tgsis.geometry, generate_series(1, 6) AS d WHERE geoid = %s"
)


def _one(conn: Conn, query: str, params: tuple[Any, ...] = ()) -> Any:
    row = conn.execute(query, params).fetchone()
    assert row is not None, query
    return row[0]


def _plane(name: str) -> tgsis.Surface:
    """Two triangles in the plane x = 1: the measured box is (1, 0, 0),(1, 1, 1), its x corners equal."""
    vertices = np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0]])
    return tgsis.Surface(vertices, np.array([[0, 1, 2], [1, 3, 2]]), name=name)


def _stale_nan_box(conn: Conn, geoid: int) -> None:
    """The stored box made stale by a NaN at its low x alone (cube_ll_coord and cube_ur_coord both read 1 there)."""
    conn.execute(
        "UPDATE tgsis.geometry SET bbox = cube(ARRAY['NaN', 0, 0]::float8[], ARRAY[1, 1, 1]::float8[]) WHERE geoid = %s",
        (geoid,),
    )
    assert np.isnan(_one(conn, STORED, (geoid,))[0])
    assert _one(conn, "SELECT cube_ll_coord(bbox, 1) = cube_ur_coord(bbox, 1) FROM tgsis.geometry WHERE geoid = %s",
                (geoid,))  # fmt: skip


def test_the_sql_merge_brings_a_box_stale_only_by_a_nan_up_to_date(conn: Conn) -> None:
    """tgsis.merge_geometry_row (the SQL merge's last step) compared the box through cube_ll_coord / cube_ur_coord:
    a box (NaN, 0, 0),(1, 1, 1) read as the measured (1, 0, 0),(1, 1, 1), so it said 0 rows changed and kept the
    NaN."""
    tgsis.enable_feature_versioning(conn)  # the merge's step reads row versions
    surfaces = F.create_feature_class(conn, "planes", "SURFACE")
    F.insert_feature(conn, surfaces, _plane("p"))
    geoid = _one(conn, "SELECT _geoid FROM planes")
    conn.commit()
    _stale_nan_box(conn, geoid)
    working = _one(conn, "SELECT workingset FROM tgsis.versions WHERE name = 'DEFAULT'")
    assert _one(conn, "SELECT tgsis.merge_geometry_row(%s, 'trgl', %s)", (geoid, working)) == 1
    assert _one(conn, STORED, (geoid,)) == [1.0, 0.0, 0.0, 1.0, 1.0, 1.0]
    assert _one(conn, "SELECT tgsis.merge_geometry_row(%s, 'trgl', %s)", (geoid, working)) == 0  # now equal


def test_the_python_write_brings_a_box_stale_only_by_a_nan_up_to_date(conn: Conn) -> None:
    """tgsis.db._state_write.update_geometry_row, the Python writers' twin of the above, compared alike."""
    from tgsis.db._state_write import update_geometry_row

    surfaces = F.create_feature_class(conn, "planes", "SURFACE")
    F.insert_feature(conn, surfaces, _plane("p"))
    geoid = _one(conn, "SELECT _geoid FROM planes")
    conn.commit()
    _stale_nan_box(conn, geoid)
    bounds = np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    assert update_geometry_row(conn, geoid, bounds, 4, 2) == 1
    assert _one(conn, STORED, (geoid,)) == [1.0, 0.0, 0.0, 1.0, 1.0, 1.0]
    assert update_geometry_row(conn, geoid, bounds, 4, 2) == 0


def test_a_collections_box_keeps_its_members_finite_corners_beside_a_nan(conn: Conn) -> None:
    """tgsis.refresh_geometry of a collection took each member's corners through cube_ll_coord / cube_ur_coord: a
    member (0, 0, 0),(NaN, 1, 1) (a vertex of NaN x: its measured box) read as (NaN, 0, 0),(NaN, 1, 1), so the
    union of it with (2, 0, 0),(3, 1, 1) was (2, 0, 0),(NaN, 1, 1), its low x 2 where the members' vertices reach
    0; and tgsis.check_geometry, comparing by cube's = (the same reading), called it up to date."""
    a = _one(conn, "SELECT tgsis.new_geometry('SURFACE', 'a', ARRAY[0, 0, 0, 1, 1, 1]::float8[], 3, 1)")
    conn.execute(  # new_geometry takes finite bounds only; the measured box of a NaN vertex, as refresh writes it
        "UPDATE tgsis.geometry SET bbox = cube(ARRAY[0, 0, 0]::float8[], ARRAY['NaN', 1, 1]::float8[]) WHERE geoid = %s",
        (a,),
    )
    b = _one(conn, "SELECT tgsis.new_geometry('SURFACE', 'b', ARRAY[2, 0, 0, 3, 1, 1]::float8[], 3, 1)")
    assert _one(conn, STORED, (a,))[:3] == [0.0, 0.0, 0.0]
    c = _one(conn, "SELECT tgsis.new_geometry('GEOMETRYCOLLECTION', 'c', NULL, 0, 0, %s)", ([a, b],))
    conn.execute("SELECT tgsis.refresh_geometry(%s)", (c,))
    got = _one(conn, STORED, (c,))
    assert got[:3] == [0.0, 0.0, 0.0] and np.isnan(got[3]) and got[4:] == [1.0, 1.0], got
    assert conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (c,)).fetchall() == []
    conn.execute(
        "UPDATE tgsis.geometry SET bbox = cube(ARRAY[2, 0, 0]::float8[], ARRAY['NaN', 1, 1]::float8[]) WHERE geoid = %s",
        (c,),
    )
    assert [p for p, *_ in conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (c,)).fetchall()] == [
        "bounding box or counts out of date (run tgsis.refresh_geometry)"
    ]


def _lifting(first_end: float, second_start: float) -> gmaps.EvolvingGMap:
    """A square lifted from t = -1 to 1 in two topology periods meeting at 0, given as ``first_end`` (the first's
    last instant) and ``second_start`` (the second's topology instant): -0.0 or 0.0, equal as floats."""
    square = gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    up = [0.0, 0.0, 1.0]
    first = gmaps.GMapPeriod([-1.0, first_end], square, np.stack([square.points, square.points + up]), level=2)
    second = gmaps.GMapPeriod(
        [second_start, 1.0], square, np.stack([square.points + up, square.points + np.multiply(up, 3)]), level=2
    )
    return gmaps.EvolvingGMap([first, second], name="lifted")


@pytest.mark.parametrize("ends", [(-0.0, 0.0), (0.0, -0.0), (-0.0, -0.0)], ids=["m0-0", "0-m0", "m0-m0"])
def test_a_g_map_instant_of_minus_zero_is_the_instant_zero_in_sql_and_in_python(
    conn: Conn, ends: tuple[float, float]
) -> None:
    fc = F.create_feature_class(conn, "lifted", "GMAP", time_model="GMAP", cell_level=2)
    evolving = _lifting(*ends)
    geoid = F.insert_feature(conn, fc, evolving)
    conn.commit()
    # stored with the bits given (the server's path on chunks: the client codec declines a key of -0.0)
    stored = conn.execute(
        "SELECT float8send(timet) FROM tgsis.gmap_timet WHERE geoid = %s ORDER BY timem, timet", (geoid,)
    ).fetchall()
    assert [bytes(b) for (b,) in stored][1:3] == [
        np.float64(ends[0]).tobytes()[::-1],
        np.float64(ends[1]).tobytes()[::-1],
    ]
    with pytest.raises(psycopg.errors.UniqueViolation):  # one instant: 0.0 and -0.0 are one key
        conn.execute("INSERT INTO tgsis.gmap_timem (geoid, timem) VALUES (%s, %s)", (geoid, -ends[1]))
    conn.rollback()
    fetched = G.fetch_gmap(conn, fc, geoid)
    sql_points = "SELECT array_agg(array_send(coordinate) ORDER BY nodeid) FROM tgsis.gmap_points_at(%s, %s)"
    answers = []
    for t in (-0.0, 0.0):
        python, stored_at, read = evolving.at(t), fetched.at(t), G.gmap_at(conn, geoid, t)
        assert python is not None and stored_at is not None and read is not None
        assert python.same_as(stored_at) and python.same_as(read), t
        assert np.array_equal(read.points[:, 2], np.ones(4)), t  # lifted by 1 at 0
        answers.append(
            (
                _one(conn, sql_points, (geoid, t)),
                conn.execute("SELECT * FROM tgsis.gmap_frame(%s, %s)", (geoid, t)).fetchall(),
            )
        )
    assert answers[0] == answers[1]
    assert conn.execute("SELECT * FROM tgsis.gmap_check(%s)", (geoid,)).fetchall() == []


def test_a_g_map_instant_of_nan_is_refused_by_sql_and_by_python_alike(conn: Conn) -> None:
    fc = F.create_feature_class(conn, "lifted", "GMAP", time_model="GMAP", cell_level=2)
    geoid = F.insert_feature(conn, fc, _lifting(0.0, 0.0))
    conn.commit()
    nan = float("nan")
    with pytest.raises(InvalidInputError, match="model time NaN is not a time") as python:
        G.gmap_at(conn, geoid, nan)
    assert python.value.code == "TG100"
    for query in ("SELECT * FROM tgsis.gmap_at(%s, %s)", "SELECT * FROM tgsis.gmap_points_at(%s, %s)"):
        with pytest.raises(psycopg.DatabaseError, match="model time NaN is not a time") as sql_error:
            conn.execute(query, (geoid, nan)).fetchall()
        assert sql_error.value.sqlstate == "TG100" and sql_error.value.diag.message_hint, query
        conn.rollback()
    with pytest.raises(InvalidInputError):  # a G-map of a NaN instant is not made, so not stored
        _lifting(nan, 0.0)
    for stored in ("INSERT INTO tgsis.gmap_timem (geoid, timem) VALUES (%s, 'NaN')",
                   "INSERT INTO tgsis.gmap_timet (geoid, timem, timet) VALUES (%s, 0, 'NaN')"):  # fmt: skip
        with pytest.raises(psycopg.errors.CheckViolation):  # psql: the tables' CHECK (finite instants)
            conn.execute(stored, (geoid,))
        conn.rollback()


def _indexes(conn: Conn, relation: str) -> list[str]:
    return [r[0] for r in conn.execute("SELECT indexrelid::regclass::text FROM pg_index WHERE indrelid = %s::regclass"
                                       " ORDER BY 1", (relation,)).fetchall()]  # fmt: skip


@pytest.mark.parametrize(
    "definition",
    ["(geoid, revision DESC)", "(geoid) WHERE NOT revclosed", "USING gin (lastrevs)"],
    ids=["revision", "revclosed", "lastrevs"],
)
def test_a_dbas_index_on_the_revision_columns_refuses_the_switch_into_chunks(conn: Conn, definition: str) -> None:
    tables_as_rows(conn, ("vrtx",))
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    assert storage_of(conn, "vrtx") == "tgsis.vrtx_ver"
    conn.execute(f"CREATE INDEX dba_idx ON tgsis.vrtx_ver {definition}")
    conn.commit()
    before = _indexes(conn, "tgsis.vrtx_ver")
    with pytest.raises(psycopg.DatabaseError, match="dba_idx") as refused:
        conn.execute("SELECT tgsis.store_in_chunks('vrtx')")
    assert refused.value.sqlstate == "TG202" and refused.value.diag.message_hint, refused.value
    conn.rollback()
    assert not in_chunks(conn) and _indexes(conn, "tgsis.vrtx_ver") == before
    conn.execute("DROP INDEX tgsis.dba_idx")  # as the hint says: then the switch goes
    switch_tables(conn, ("vrtx",), "chunks")
    assert in_chunks(conn)


@pytest.mark.parametrize("definition", ["(revision, geoid)", "(geoid, chunk)"], ids=["revision", "key"])
def test_a_dbas_index_on_a_chunk_table_refuses_the_way_back(conn: Conn, definition: str) -> None:
    tables_as_rows(conn, ("vrtx",))
    tgsis.enable_feature_versioning(conn)
    switch_tables(conn, ("vrtx",), "chunks")
    conn.execute(f"CREATE INDEX dba_idx ON tgsis.vrtx_chunk {definition}")
    conn.commit()
    before = _indexes(conn, "tgsis.vrtx_chunk")
    with pytest.raises(psycopg.DatabaseError, match="dba_idx") as refused:
        conn.execute("SELECT tgsis.store_in_rows('vrtx')")
    assert refused.value.sqlstate == "TG202" and refused.value.diag.message_hint, refused.value
    conn.rollback()
    assert in_chunks(conn) and _indexes(conn, "tgsis.vrtx_chunk") == before
    conn.execute("DROP INDEX tgsis.dba_idx")
    switch_tables(conn, ("vrtx",), "rows")
    assert not in_chunks(conn)


FILL = "SELECT * FROM tgsis.fill_property_rows(%s, '{\"facies\": 4}')"


def _fill_outcome(conn: Conn, name: str) -> tuple[str | None, list[Any]]:
    try:
        made = conn.execute(FILL, (name,)).fetchall()
    except psycopg.DatabaseError as error:
        conn.rollback()
        return error.sqlstate, [conn.execute(f"SELECT count(*) FROM public.{name}_simplexpros").fetchone()]
    conn.commit()
    return None, made


def test_fill_property_rows_answers_another_roles_object_lock_as_on_rows(conn: Conn, db_dsn: str) -> None:
    tgsis.enable_feature_versioning(conn)
    for name in ("onrows", "inchunks"):
        tgsis.create_feature_class(
            conn, name, "SURFACE", cell_properties=[tgsis.Property("facies", "int", alignment="CELL")], versioned=False
        )
    conn.commit()
    for name, storage in (("onrows", "rows"), ("inchunks", "chunks")):
        if _one(conn, "SELECT tgsis.stored_in_chunks('public', %s)", (f"{name}_simplexpros",)) != (storage == "chunks"):
            conn.execute(f"SELECT tgsis.store_class_in_{storage}(%s)", (name,))
    plane = _plane("p")
    plane = tgsis.Surface(plane.vertices, plane.cells, cell_properties={"facies": np.array([7, 8], dtype=np.int32)})
    geoids = {name: F.insert_feature(conn, name, plane) for name in ("onrows", "inchunks")}
    for name, geoid in geoids.items():  # the rows an older tgsis did not make, as fill_property_rows repairs
        conn.execute(f"DELETE FROM public.{name}_simplexpros WHERE _geoid = %s", (geoid,))
    conn.commit()
    assert _one(conn, "SELECT tgsis.stored_in_chunks('public', 'inchunks_simplexpros')")
    assert not _one(conn, "SELECT tgsis.stored_in_chunks('public', 'onrows_simplexpros')")
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        ed = made.connect("ed")
        for geoid in geoids.values():
            ed.execute("SELECT tgsis.lock_objects('DEFAULT', 'feature', %s, true)", ([str(geoid)],))
        ed.commit()
        refused = {name: _fill_outcome(conn, name) for name in geoids}
        assert refused["onrows"] == refused["inchunks"] == ("TG303", [(0,)]), refused
        for geoid in geoids.values():
            ed.execute("SELECT tgsis.unlock_objects('DEFAULT', 'feature', %s)", ([str(geoid)],))
        ed.commit()
        ed.close()
    done = {name: _fill_outcome(conn, name) for name in geoids}
    for name in geoids:
        assert done[name] == (None, [(f"{name}_cellpros", 0, 0), (f"{name}_simplexpros", 1, 2)]), done
