"""Model 5 in the database: G-maps whose extra axes are knowledge or time, stored, checked and queried by box (issue 17, part 3)."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
from tgsis import gmaps
from tgsis.db import features as F
from tgsis.db import gmaps as G
from tgsis.errors import reraise

from .gmaps_shapes import grid

Conn = psycopg.Connection[Any]


def _class(conn: Conn, level: int = 3) -> F.FeatureClass:
    return F.create_feature_class(
        conn, "knowledge", "GMAP", time_model="MULTIDIM", cell_level=level, cell_properties={"confidence": "float8"}
    )


def _interpretations() -> tuple[gmaps.GMap, list[np.ndarray], gmaps.GMap]:
    """A horizon on a 5 x 4 grid and three interpretations of its depth, extruded along a knowledge axis.

    Layer l of the extrusion holds interpretation l's points with knowledge l:
    the (2+1)-G-map is the horizon's history of knowledge, one prism volume
    per triangle and interval.
    """
    vertices, triangles = grid(5, 4)
    horizon = gmaps.GMap.from_triangles(vertices, triangles)
    depths = [
        vertices[:, 0] * 0.0 - 100.0,
        -100.0 - 5.0 * vertices[:, 0],
        -110.0 - 5.0 * vertices[:, 0] + vertices[:, 1],
    ]
    layers = [np.column_stack([vertices[:, :2], z]) for z in depths]
    extruded = gmaps.extrude(horizon, [0.0, 1.0, 2.0])
    points = np.vstack([np.column_stack([layer, np.full(len(layer), float(k))]) for k, layer in enumerate(layers)])
    volumes = extruded.n_cells(3)
    history = gmaps.GMap(
        extruded.alpha, extruded.vertex, points, cell_properties={3: {"confidence": np.linspace(0.2, 0.9, volumes)}}
    )
    return horizon, layers, history


def test_the_history_of_a_horizon_is_stored_fetched_and_sliced_back(conn: Conn) -> None:
    fc = _class(conn)
    horizon, layers, history = _interpretations()
    geoid = G.insert_gmap(conn, fc, history, name="H1 knowledge", axes=["x", "y", "z", "knowledge"])
    back, axes = G.fetch_md_gmap(conn, fc, geoid)
    assert axes == ("x", "y", "z", "knowledge") and back.same_as(history)
    assert G.gmap_check(conn, geoid) == []
    assert conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (geoid,)).fetchall() == []
    # the slice at a knowledge value gives that interpretation back, cell for cell
    for k, layer in enumerate(layers):
        section = gmaps.slice(back, 3, float(k))
        assert section.n_darts == horizon.n_darts and [section.n_cells(i) for i in range(3)] == [
            horizon.n_cells(i) for i in range(3)
        ]
        assert np.array_equal(np.sort(section.points[:, :3], axis=0), np.sort(layer, axis=0))
    for level in range(4):
        _, cells = G.gmap_cells(conn, geoid, level)
        assert np.array_equal(cells, history.cells(level)), level


def test_box_queries_over_any_axes_use_the_indexes(conn: Conn) -> None:
    fc = _class(conn)
    _, layers, history = _interpretations()
    geoid = G.insert_gmap(conn, fc, history, axes=["x", "y", "z", "knowledge"])
    far = G.insert_gmap(
        conn,
        fc,
        gmaps.GMap(
            history.alpha, history.vertex, history.points + [1000, 0, 0, 0], cell_properties=history.cell_properties
        ),
        axes=["x", "y", "z", "knowledge"],
    )
    conn.commit()
    assert G.md_in_box(conn, fc, ["x", "knowledge"], [0, 1.5], [2, 2]) == [geoid]
    assert G.md_in_box(
        conn,
        fc,
        ["x"],
        [
            999,
        ],
        [2000],
    ) == [far]
    assert G.md_in_box(conn, fc, ["knowledge"], [3], [4]) == []
    with pytest.raises(tgsis.InvalidInputError, match="no feature of class knowledge has an axis 'age'") as caught:
        G.md_in_box(conn, fc, ["age"], [0], [1])  # no feature has that axis
    assert caught.value.detail == "Their axes: knowledge, x, y, z."
    conn.rollback()
    # the points of the last interpretation deeper than -115 (x, y, knowledge and z at once)
    ids = G.md_vertices_in_box(conn, geoid, ["z", "knowledge"], [-1e9, 1.5], [-115, 2])
    expected = np.flatnonzero((history.points[:, 3] >= 1.5) & (history.points[:, 2] <= -115))
    assert np.array_equal(ids, expected) and len(ids) > 0
    with conn.transaction():
        conn.execute("SET LOCAL enable_seqscan = off; SET LOCAL jit = off")
        plan = "\n".join(
            r[0]
            for r in conn.execute(
                "EXPLAIN SELECT f._geoid FROM knowledge f JOIN tgsis.md_gmap m ON m.geoid = f._geoid "
                "WHERE m.axes = '{x,y,z,knowledge}' "
                "AND m.extent && tgsis.md_query_box('{x,y,z,knowledge}', '{x}', '{0}', '{1}')"
                " AND NOT tgsis.cube_has_nan(m.extent)"  # the partial index's predicate
            ).fetchall()
        )
        points = "\n".join(
            r[0]
            for r in conn.execute(
                "EXPLAIN SELECT * FROM tgsis.md_vertex v WHERE cube(v.coordinate) <@ "
                "tgsis.md_query_box('{x,y,z,knowledge}', '{knowledge}', '{1}', '{2}') AND v.geoid = 1"
                " AND NOT 'NaN'::double precision = ANY (v.coordinate)"  # the partial index's predicate
            ).fetchall()
        )
    # (the points in chunks under TGSIS_TEST_TIME_STORAGE=chunks have no per-point index: no chunk box yet)
    assert ("md_vertex_point_idx" in points) != _points_in_chunks(conn), points
    assert "md_gmap_extent_idx" in plan, plan


def _points_in_chunks(conn: Conn) -> bool:
    """Whether tgsis.md_vertex is stored in chunks: its face has no per-point GiST index (docs/storage.md, "The
    points in chunks"), every plan reads the object's chunks."""
    return conn.execute("SELECT tgsis.stored_in_chunks('md_vertex')").fetchone() == (True,)


def _ids_in_box(conn: Conn, geoid: int, axes: list[str], low: list[float], high: list[float], scan: str) -> list[int]:
    """tgsis.md_vertices_in_box's ids with the plan forced: by the points' GiST index or by a sequential scan."""
    with conn.transaction():
        conn.execute("DISCARD PLANS")  # the function's cached plan is made again under these settings
        index = "on" if scan == "index" else "off"
        conn.execute(
            f"SET LOCAL enable_seqscan = {'off' if scan == 'index' else 'on'}; SET LOCAL enable_indexscan = {index}; "
            f"SET LOCAL enable_bitmapscan = {index}"
        )
        ids = [
            r[0]
            for r in conn.execute(
                "SELECT vrtxid FROM tgsis.md_vertices_in_box(%s, %s, %s, %s)", (geoid, axes, low, high)
            )
        ]
        plan = "\n".join(
            r[0]
            for r in conn.execute(
                "EXPLAIN SELECT vrtxid FROM tgsis.md_vertex v WHERE cube(v.coordinate) <@ "
                "tgsis.md_query_box('{x,y,z,knowledge}', %s, %s, %s) AND v.geoid = %s"
                " AND NOT 'NaN'::double precision = ANY (v.coordinate)",
                (axes, low, high, geoid),
            )
        )
    assert ("md_vertex_point_idx" in plan) == (scan == "index" and not _points_in_chunks(conn)), plan
    return ids


@pytest.fixture
def odd_points(conn: Conn) -> tuple[int, np.ndarray]:
    """A stored model-5 map whose points include NaN (on one axis, on all), -0.0 and infinities; its points read back."""
    fc = _class(conn)
    _, _, history = _interpretations()
    geoid = G.insert_gmap(conn, fc, history, axes=["x", "y", "z", "knowledge"])
    odd: dict[int, list[object]] = {
        0: ["NaN", 0.25, -100, 0],  # NaN on a queried axis
        1: ["NaN", "NaN", "NaN", "NaN"],  # no coordinate at all: found by a scan and missed by the index before
        2: [0.5, 0.5, -100, "NaN"],  # NaN on an axis a box over x and y leaves unbounded
        3: ["-0", 0.5, -100, 1],  # -0.0 on the face x = 0
        4: [0.5, "Infinity", -100, 1],
        5: ["-Infinity", 0.5, -100, 2],
    }
    for vrtxid, point in odd.items():
        conn.execute(
            "UPDATE tgsis.md_vertex SET coordinate = %s::double precision[] WHERE geoid = %s AND vrtxid = %s",
            ([str(c) for c in point], geoid, vrtxid),
        )
    conn.commit()
    rows = conn.execute("SELECT coordinate FROM tgsis.md_vertex WHERE geoid = %s ORDER BY vrtxid", (geoid,)).fetchall()
    return geoid, np.array([r[0] for r in rows], dtype=np.float64)


def _expected(points: np.ndarray, axes: list[str], low: list[float], high: list[float]) -> list[int]:
    """The closed box's points, none with a NaN coordinate, by numpy."""
    inside = ~np.isnan(points).any(axis=1)
    for axis, lo, hi in zip(axes, low, high):
        k = ["x", "y", "z", "knowledge"].index(axis)
        inside &= (points[:, k] >= lo) & (points[:, k] <= hi)
    return [int(i) for i in np.flatnonzero(inside)]


def test_a_box_answers_the_same_points_by_index_and_by_scan_nan_in_none(
    conn: Conn, odd_points: tuple[int, np.ndarray]
) -> None:
    geoid, points = odd_points
    # the faces: x = 0 (where -0.0 lies) and x = 0.5, y = 0.5 (grid points), and the whole of x and y
    for axes, low, high in (
        (["x", "y"], [0.0, 0.0], [0.5, 0.5]),
        (["x", "y"], [-np.inf, -np.inf], [np.inf, np.inf]),
        (["y"], [0.25], [0.25]),
        (["knowledge"], [0.0], [0.0]),
    ):
        expected = _expected(points, axes, low, high)
        assert 1 not in expected and 0 not in expected and 2 not in expected
        assert _ids_in_box(conn, geoid, axes, low, high, "index") == expected, (axes, low, high)
        assert _ids_in_box(conn, geoid, axes, low, high, "scan") == expected, (axes, low, high)
    assert 3 in _expected(points, ["x"], [0.0], [0.0])  # -0.0 on the face x = 0 is inside


# coordinates the points have: boxes with faces through points
_EDGES = st.sampled_from([0.0, 0.2, 0.25, 0.4, 0.5, 0.6, 0.75, 1.0, -100.0, -101.0, -115.0, 2.0])


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    box=st.lists(
        st.tuples(
            st.sampled_from(["x", "y", "z", "knowledge"]), _EDGES | st.floats(-200, 5), _EDGES | st.floats(-200, 5)
        ),
        min_size=1,
        max_size=4,
        unique_by=lambda b: b[0],
    )
)
def test_random_boxes_answer_as_numpy_by_index_and_by_scan(
    conn: Conn, odd_points: tuple[int, np.ndarray], box: list[tuple[str, float, float]]
) -> None:
    geoid, points = odd_points
    axes = [b[0] for b in box]
    low = [min(b[1], b[2]) for b in box]
    high = [max(b[1], b[2]) for b in box]
    expected = _expected(points, axes, low, high)
    assert _ids_in_box(conn, geoid, axes, low, high, "index") == expected
    assert _ids_in_box(conn, geoid, axes, low, high, "scan") == expected


def _moved(history: gmaps.GMap, points: np.ndarray) -> gmaps.GMap:
    return gmaps.GMap(history.alpha, history.vertex, points, cell_properties=history.cell_properties)


def _nan_maps() -> dict[str, np.ndarray]:
    """The points of three model-5 maps: some points with a NaN, every point with one, a NaN point far off in y."""
    points = _interpretations()[2].points
    some = points.copy()
    some[0, 0] = np.nan  # NaN on one axis
    some[1] = np.nan  # on all
    some[2] = [np.nan, 5000.0, -5000.0, 7.0]  # a NaN point whose other coordinates lie far outside
    some[3, 0] = -0.0
    every = points.copy()
    every[:, 3] = np.nan  # no point has a position
    far = points + [1000, 0, 0, 0]
    far[5] = [np.nan, 5000.0, 0.0, 0.0]
    return {"some": some, "every": every, "far": far}


def _store(conn: Conn, fc: F.FeatureClass, points: np.ndarray) -> int:
    """A model-5 map of these points: inserted finite (the client refuses NaN), its NaN points set by plain SQL, refreshed."""
    history = _interpretations()[2]
    geoid = G.insert_gmap(conn, fc, _moved(history, history.points), axes=["x", "y", "z", "knowledge"])
    for vrtxid in np.flatnonzero(np.isnan(points).any(axis=1) | (points != history.points).any(axis=1)):
        conn.execute(
            "UPDATE tgsis.md_vertex SET coordinate = %s::double precision[] WHERE geoid = %s AND vrtxid = %s",
            ([repr(float(c)) for c in points[vrtxid]], geoid, int(vrtxid)),
        )
    conn.execute("SELECT tgsis.refresh_geometry(%s)", (geoid,))
    return geoid


def _box_of(points: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The extent tgsis.md_extent gives: the box of the points without a NaN coordinate; None without one."""
    positioned = points[~np.isnan(points).any(axis=1)]
    return (positioned.min(axis=0), positioned.max(axis=0)) if len(positioned) else None


def _stored_boxes(conn: Conn, geoid: int) -> tuple[list[float] | None, list[float] | None]:
    """The stored extent (low then high, every axis) and 3D bbox of a model-5 map."""
    row = conn.execute(
        "SELECT (SELECT array_agg(cube_ll_coord(m.extent, i) ORDER BY i) || array_agg(cube_ur_coord(m.extent, i) ORDER BY i)"
        "          FROM generate_series(1, cube_dim(m.extent)) i),"
        "       (SELECT array_agg(cube_ll_coord(g.bbox, i) ORDER BY i) || array_agg(cube_ur_coord(g.bbox, i) ORDER BY i)"
        "          FROM generate_series(1, cube_dim(g.bbox)) i)"
        "  FROM tgsis.md_gmap m JOIN tgsis.geometry g USING (geoid) WHERE geoid = %s",
        (geoid,),
    ).fetchone()
    assert row is not None
    return row[0], row[1]


def _problems(conn: Conn, geoid: int) -> set[str]:
    return {r[0] for r in conn.execute("SELECT problem FROM tgsis.check_geometry(%s)", (geoid,))}


_STALE = "extent, bounding box or counts out of date (run tgsis.refresh_geometry)"


def test_nan_points_take_no_part_in_the_extent_alike_at_insert_and_by_refresh(conn: Conn) -> None:
    fc = _class(conn)
    history = _interpretations()[2]
    finite = G.insert_gmap(conn, fc, _moved(history, history.points), axes=["x", "y", "z", "knowledge"])
    at_insert = _stored_boxes(conn, finite)  # by the client
    conn.execute("SELECT tgsis.refresh_geometry(%s)", (finite,))
    assert _stored_boxes(conn, finite) == at_insert and _problems(conn, finite) == set()  # by tgsis.md_extent
    for points in _nan_maps().values():
        geoid = _store(conn, fc, points)
        box = _box_of(points)
        expected: tuple[list[float] | None, list[float] | None] = (None, None)
        if box is not None:
            low, high = box
            expected = ([*low, *high], [*low[:3], *high[:3]])
        assert _stored_boxes(conn, geoid) == expected
        # the NaN points are reported as such, the boxes are not stale
        assert _problems(conn, geoid) == {"point without 4 finite coordinates"}
        conn.execute("SELECT tgsis.refresh_geometry(%s)", (geoid,))
        assert _stored_boxes(conn, geoid) == expected
    conn.commit()


def test_an_extent_stored_with_a_nan_is_stale_and_refreshed(conn: Conn) -> None:
    """An extent computed the old way (a NaN counted as the largest value) is reported, and refresh_geometry mends it."""
    fc = _class(conn)
    points = _nan_maps()["some"]
    geoid = _store(conn, fc, points)
    expected = _stored_boxes(conn, geoid)
    low, high = np.nanmin(points, axis=0), points.max(axis=0)  # 0.2.0's md_extent: max is NaN where a NaN is
    assert np.isnan(high[0])
    conn.execute(
        "UPDATE tgsis.md_gmap SET extent = cube(%s::double precision[], %s::double precision[]) WHERE geoid = %s",
        ([str(v) for v in low], [str(v) for v in high], geoid),
    )
    assert _STALE in _problems(conn, geoid)
    conn.execute("SELECT tgsis.refresh_geometry(%s)", (geoid,))
    assert _stored_boxes(conn, geoid) == expected
    assert _STALE not in _problems(conn, geoid)
    conn.commit()


def _md_in_box(
    conn: Conn, fc: F.FeatureClass, axes: list[str], low: list[float], high: list[float], scan: str
) -> list[int]:
    """tgsis.md_in_box's ids with the plan forced: by the extents' GiST index or by sequential scans."""
    with conn.transaction():
        index = "on" if scan == "index" else "off"
        conn.execute(
            f"SET LOCAL enable_seqscan = {'off' if scan == 'index' else 'on'}; SET LOCAL enable_indexscan = {index}; "
            f"SET LOCAL enable_bitmapscan = {index}"
        )
        ids = G.md_in_box(conn, fc, axes, low, high)
        plan = "\n".join(
            r[0]
            for r in conn.execute(
                "EXPLAIN SELECT f._geoid FROM knowledge f JOIN tgsis.md_gmap m ON m.geoid = f._geoid "
                "WHERE m.axes = '{x,y,z,knowledge}' AND m.extent && tgsis.md_query_box('{x,y,z,knowledge}', %s, %s, %s)"
                " AND NOT tgsis.cube_has_nan(m.extent)",  # the partial index's predicate (md_in_box's)
                (axes, low, high),
            )
        )
    assert ("md_gmap_extent_idx" in plan) == (scan == "index"), plan
    return ids


@pytest.fixture
def nan_maps(conn: Conn) -> tuple[F.FeatureClass, dict[int, tuple[np.ndarray, np.ndarray] | None]]:
    """A class holding the maps of _nan_maps and one without NaN; each map's id and expected extent."""
    fc = _class(conn)
    boxes: dict[int, tuple[np.ndarray, np.ndarray] | None] = {}
    for points in [*_nan_maps().values(), _interpretations()[2].points]:
        boxes[_store(conn, fc, points)] = _box_of(points)
    conn.commit()
    return fc, boxes


def _meeting(
    boxes: dict[int, tuple[np.ndarray, np.ndarray] | None], axes: list[str], low: list[float], high: list[float]
) -> list[int]:
    """The maps whose extent meets the closed box, by numpy: a map without an extent meets none."""
    found = []
    for geoid, box in boxes.items():
        if box is None:
            continue
        ks = [["x", "y", "z", "knowledge"].index(a) for a in axes]
        if all(box[0][k] <= hi and lo <= box[1][k] for k, lo, hi in zip(ks, low, high)):
            found.append(geoid)
    return sorted(found)


def test_md_in_box_answers_alike_by_index_and_by_scan_nan_in_no_extent(
    conn: Conn, nan_maps: tuple[F.FeatureClass, dict[int, tuple[np.ndarray, np.ndarray] | None]]
) -> None:
    fc, boxes = nan_maps
    for axes, low, high in (
        (["y"], [4000.0], [6000.0]),  # only NaN points reach there
        (["knowledge"], [-np.inf], [np.inf]),  # every map with a position, not the one without
        (["x", "y", "z", "knowledge"], [-np.inf] * 4, [np.inf] * 4),
        (["x"], [1.0], [1.0]),  # the face x = 1 of three extents
        (["x"], [1001.0], [1001.0]),
    ):
        expected = _meeting(boxes, axes, low, high)
        assert _md_in_box(conn, fc, axes, low, high, "index") == expected, (axes, low, high)
        assert _md_in_box(conn, fc, axes, low, high, "scan") == expected, (axes, low, high)
    every = [geoid for geoid, box in boxes.items() if box is None]
    assert len(every) == 1 and every[0] not in _meeting(boxes, ["x"], [-np.inf], [np.inf])


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    box=st.lists(
        st.tuples(
            st.sampled_from(["x", "y", "z", "knowledge"]),
            _EDGES | st.floats(-200, 1100) | st.sampled_from([1000.0, 1001.0, 5000.0, 7.0]),
            _EDGES | st.floats(-200, 1100) | st.sampled_from([1000.0, 1001.0, 5000.0, -5000.0]),
        ),
        min_size=1,
        max_size=4,
        unique_by=lambda b: b[0],
    )
)
def test_random_boxes_find_maps_as_numpy_by_index_and_by_scan(
    conn: Conn,
    nan_maps: tuple[F.FeatureClass, dict[int, tuple[np.ndarray, np.ndarray] | None]],
    box: list[tuple[str, float, float]],
) -> None:
    fc, boxes = nan_maps
    axes = [b[0] for b in box]
    low = [min(b[1], b[2]) for b in box]
    high = [max(b[1], b[2]) for b in box]
    expected = _meeting(boxes, axes, low, high)
    assert _md_in_box(conn, fc, axes, low, high, "index") == expected
    assert _md_in_box(conn, fc, axes, low, high, "scan") == expected


def test_a_malformed_box_is_refused(conn: Conn) -> None:
    fc = _class(conn)
    with pytest.raises(tgsis.InvalidInputError, match="low <= high"):
        G.md_in_box(conn, fc, ["x"], [2], [1])
    conn.rollback()
    with pytest.raises(tgsis.InvalidInputError, match="one low and one high value per axis"):
        G.md_in_box(conn, fc, ["x", "y"], [0], [1])
    conn.rollback()
    with pytest.raises(tgsis.InvalidInputError, match="name each of the 4 axes once"):
        G.insert_gmap(conn, fc, _interpretations()[2], axes=["x", "x", "z", "k"])


def test_a_broken_stored_map_is_reported_naming_its_darts(conn: Conn) -> None:
    fc = _class(conn)
    geoid = F.insert_feature(conn, fc, _interpretations()[2])
    conn.execute("UPDATE tgsis.md_alpha SET dartid2 = dartid WHERE geoid = %s AND level = 0 AND dartid = 4", (geoid,))
    problems = {p.problem: p.darts for p in G.gmap_check(conn, geoid)}
    assert 4 in problems["dart free in alpha_0 (only alpha_3 may have fixed points)"]
    assert "alpha_0 is not an involution" in problems


def test_model_5_is_versioned_with_the_features(conn: Conn) -> None:
    fc = _class(conn)
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "reinterpreted")
    with tgsis.in_version(conn, "reinterpreted"):
        geoid = G.insert_gmap(conn, fc, _interpretations()[2], axes=["x", "y", "z", "knowledge"])
        conn.commit()
        assert G.fetch_md_gmap(conn, fc, geoid)[0].same_as(_interpretations()[2])
        assert G.md_in_box(conn, fc, ["knowledge"], [0], [2]) == [geoid]
        conn.commit()
    assert G.md_in_box(conn, fc, ["knowledge"], [0], [2]) == []  # DEFAULT has none yet
    conn.commit()
    tgsis.merge_version(conn, "reinterpreted")
    conn.commit()
    assert G.md_in_box(conn, fc, ["knowledge"], [0], [2]) == [geoid]
    with pytest.raises(tgsis.InvalidInputError, match="time is one of its axes"), reraise():
        G.gmap_cells(conn, geoid, 1, 0.5)


def test_a_g_map_in_time_is_refused_by_a_class_of_model_5_by_every_route(conn: Conn) -> None:
    # the refusal moved with model 5 to db/multidim.py (issue 38, part 6): insert_gmap hands the class on, and
    # insert_feature reaches the same code through model 4's entry (model 5 stores no EvolvingGMap)
    fc = _class(conn)
    conn.commit()
    evolving = gmaps.EvolvingGMap([gmaps.GMapPeriod([0.0, 1.0], _interpretations()[0])])
    for insert in (G.insert_gmap, tgsis.insert_feature):
        with pytest.raises(tgsis.InvalidInputError, match="give a tgsis.gmaps.GMap .time is one of its axes"):
            insert(conn, fc, evolving)
        conn.rollback()
    assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == (0,)
    # a plain G-map through insert_feature is stored by model 5 with the default axis names
    history = _interpretations()[2]
    geoid = tgsis.insert_feature(conn, fc, history)
    assert G.fetch_md_gmap(conn, fc, geoid)[1] == ("x", "y", "z", "axis4")
    assert tgsis.fetch_object(conn, fc, geoid).same_as(history)
