"""Model 4 in the database: G-maps in time stored and fetched, checked, cut into cells and snapshotted in SQL (issue 17, part 2)."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis import gmaps
from tgsis.db import features as F
from tgsis.db import gmaps as G
from tgsis.db.classes import class_of_feature
from tgsis.db.inspect import may_read_features
from tgsis.errors import reraise

from .gmaps_shapes import block_tetrahedra, grid, icosahedron
from .roles import login_roles

Conn = psycopg.Connection[Any]
rng = np.random.default_rng(17)


def _class(conn: Conn, name: str = "blocks", level: int = 2) -> F.FeatureClass:
    return F.create_feature_class(
        conn,
        name,
        "GMAP",
        time_model="GMAP",
        cell_level=level,
        cell_properties={"porosity": "float8"},
        feature_properties={"note": "text"},
    )


def _faces(g: gmaps.GMap) -> gmaps.GMap:
    """The G-map with a porosity per face."""
    return gmaps.GMap(g.alpha, g.vertex, g.points, cell_properties={2: {"porosity": rng.random(g.n_cells(2))}})


def _evolving() -> gmaps.EvolvingGMap:
    """A square of 2 triangles rising from t = 0 to 1, then (a topology change) a 3 x 3 grid of 8 triangles to t = 3."""
    square = gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    first = gmaps.GMapPeriod(
        [0.0, 1.0],
        square,
        np.stack([square.points, square.points + [0, 0, 1]]),
        level=2,
        cell_values={"porosity": [[0.1, 0.2], [0.3, 0.4]]},
    )
    vertices, triangles = grid(2, 2)  # its points on the square's edges: the shape does not jump at t = 1
    fine = gmaps.GMap.from_triangles(vertices + [0, 0, 1], triangles)
    lifted = fine.points + [0, 0, 2]
    second = gmaps.GMapPeriod(
        [1.0, 2.0, 3.0],
        fine,
        np.stack([fine.points, (fine.points + lifted) / 2, lifted]),
        level=2,
        cell_values={"porosity": rng.random((3, fine.n_cells(2)))},
    )
    return gmaps.EvolvingGMap([first, second], alive=True, name="rising")


def _same(a: gmaps.GMap | None, b: gmaps.GMap | None) -> bool:
    return (a is None and b is None) or (a is not None and b is not None and a.same_as(b))


def test_a_closed_surface_round_trips_with_its_face_properties(conn: Conn) -> None:
    fc = _class(conn)
    sphere = _faces(gmaps.GMap.from_triangles(*icosahedron()))
    geoid = F.insert_feature(conn, fc, sphere, {"note": "sphere"}, name="ico")
    back = G.fetch_gmap(conn, fc, geoid)
    assert back.alive and back.name == "ico" and len(back.periods) == 1
    assert back.at(0.0) is not None and back.at(0.0).same_as(sphere)  # type: ignore[union-attr]
    assert back.at(1e9).same_as(sphere)  # type: ignore[union-attr]  # alive
    assert back.at(-1.0) is None
    assert conn.execute("SELECT note FROM blocks WHERE _geoid = %s", (geoid,)).fetchone() == ("sphere",)
    # the spec's relations, as psql users read them
    assert conn.execute("SELECT dimension, embedding FROM tgsis.gmap WHERE geoid = %s", (geoid,)).fetchone() == (2, 3)
    assert conn.execute("SELECT count(*) FROM tgsis.gmap_dart WHERE geoid = %s", (geoid,)).fetchone() == (120,)
    assert conn.execute("SELECT count(*) FROM tgsis.gmap_alpha WHERE geoid = %s", (geoid,)).fetchone() == (360,)
    assert conn.execute(
        "SELECT count(*) FROM tgsis.gmap_cell WHERE geoid = %s AND celllevel = 2", (geoid,)
    ).fetchone() == (20,)
    assert conn.execute(
        "SELECT count(*), bool_and(positive IS NOT NULL) FROM tgsis.gmap_dart WHERE geoid = %s", (geoid,)
    ).fetchone() == (120, True)  # a sphere is orientable
    assert G.gmap_check(conn, geoid) == []
    assert conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (geoid,)).fetchall() == []
    assert conn.execute("SELECT nvrtx, ncell FROM tgsis.refresh_geometry(%s)", (geoid,)).fetchone() == (12, 120)


def test_a_solid_of_tetrahedra_round_trips(conn: Conn) -> None:
    fc = _class(conn, "solids", level=3)
    vertices, tetrahedra = block_tetrahedra(2)
    solid = gmaps.GMap.from_tetrahedra(vertices, tetrahedra, cell_properties={"porosity": rng.random(len(tetrahedra))})
    geoid = F.insert_feature(conn, fc, solid)
    back = G.fetch_gmap(conn, fc, geoid).at(0.0)
    assert back is not None and back.same_as(solid)
    assert [back.n_cells(i) for i in range(4)] == [solid.n_cells(i) for i in range(4)]
    assert back.euler_characteristic() == 1


def test_the_snapshot_in_sql_equals_python_at_random_times(conn: Conn) -> None:
    fc = _class(conn)
    evolving = _evolving()
    geoid = F.insert_feature(conn, fc, evolving)
    fetched = G.fetch_gmap(conn, fc, geoid)
    for t in [-0.5, 0.0, 0.25, 1.0, 1.0 - 1e-12, 1.5, 3.0, 7.0, *rng.uniform(-1, 4, 12)]:
        python, stored, sql = evolving.at(t), fetched.at(t), G.gmap_at(conn, geoid, t)
        assert _same(python, stored) and _same(python, sql), t
    # the SQL functions psql users call give the same snapshot
    for t in (0.25, 1.0, 2.5, 9.0):
        expected = evolving.at(t)
        assert expected is not None
        rows = conn.execute("SELECT dartid, nodeid, alpha FROM tgsis.gmap_at(%s, %s)", (geoid, t)).fetchall()
        first = rows[0][0]
        assert np.array_equal(np.array([r[2] for r in rows]).T - first, expected.alpha), t
        points = conn.execute("SELECT nodeid, coordinate FROM tgsis.gmap_points_at(%s, %s)", (geoid, t)).fetchall()
        first_node = points[0][0]
        assert np.array_equal(np.array([r[1] for r in rows]) - first_node, expected.vertex)
        assert np.array_equal(np.array([p[1] for p in points]), expected.points), t
    assert conn.execute("SELECT count(*) FROM tgsis.gmap_at(%s, -1)", (geoid,)).fetchone() == (0,)
    # at the topology instant the new topology applies
    at_change = G.gmap_at(conn, geoid, 1.0)
    assert at_change is not None and at_change.n_darts == evolving.periods[1].gmap.n_darts


def test_sql_cells_are_the_python_cells(conn: Conn) -> None:
    fc = _class(conn)
    evolving = _evolving()
    geoid = F.insert_feature(conn, fc, evolving)
    for t in (0.5, 2.0):
        snapshot = evolving.at(t)
        assert snapshot is not None
        for level in range(3):
            dartids, cells = G.gmap_cells(conn, geoid, level, t)
            assert len(dartids) == snapshot.n_darts
            assert np.array_equal(cells, snapshot.cells(level)), (t, level)
    assert len(G.gmap_cells(conn, geoid, 1, -5.0)[0]) == 0  # it does not exist then
    with pytest.raises(tgsis.InvalidInputError, match="cell level 3 is not a cell dimension"):
        G.gmap_cells(conn, geoid, 3, 0.5)


def test_property_values_at_t_are_interpolated(conn: Conn) -> None:
    fc = _class(conn)
    geoid = F.insert_feature(conn, fc, _evolving())
    values = conn.execute(
        "SELECT acellid, value FROM tgsis.gmap_property_at('blocks', %s, 'porosity', 0.5)", (geoid,)
    ).fetchall()
    assert [round(v, 12) for _, v in values] == [0.2, 0.3]
    with pytest.raises(tgsis.InvalidPropertyError, match="no numeric scalar cell property 'nope'"), reraise():
        conn.execute("SELECT * FROM tgsis.gmap_property_at('blocks', %s, 'nope', 0.5)", (geoid,))


def _stored_map(conn: Conn) -> tuple[F.FeatureClass, int]:
    fc = _class(conn)
    geoid = F.insert_feature(conn, fc, _evolving())
    conn.commit()
    return fc, geoid


def _problems(conn: Conn, geoid: int) -> dict[str, tuple[int, ...]]:
    return {p.problem: p.darts for p in G.gmap_check(conn, geoid)}


def test_a_fetch_reads_rows_of_any_shape_and_names_the_check_when_they_are_no_g_map(conn: Conn) -> None:
    fc, geoid = _stored_map(conn)
    stored = G.fetch_gmap(conn, fc, geoid)
    # a row above the dimension: not one row per dart and level any more, the periods are still read right
    conn.execute("INSERT INTO tgsis.gmap_alpha (geoid, level, dartid, dartid2) VALUES (%s, 3, 0, 0)", (geoid,))
    assert all(_same(G.fetch_gmap(conn, fc, geoid).at(t), stored.at(t)) for t in (0.5, 2.5))
    conn.execute("DELETE FROM tgsis.gmap_alpha WHERE geoid = %s AND level = 1 AND dartid = 0", (geoid,))
    with pytest.raises(tgsis.InvalidGMapError, match=r"period 0\.0 has 11 alpha_1 rows for 12 darts") as caught:
        G.fetch_gmap(conn, fc, geoid)
    assert f"tgsis.gmap_check({geoid})" in str(caught.value.hint)


def test_the_sql_check_names_a_non_involution(conn: Conn) -> None:
    _, geoid = _stored_map(conn)
    conn.execute("UPDATE tgsis.gmap_alpha SET dartid2 = 5 WHERE geoid = %s AND level = 0 AND dartid = 0", (geoid,))
    problems = _problems(conn, geoid)
    assert 0 in problems["alpha_0 is not an involution"]


def test_the_sql_check_names_a_fixed_point_below_n(conn: Conn) -> None:
    _, geoid = _stored_map(conn)
    conn.execute(
        "UPDATE tgsis.gmap_alpha SET dartid2 = dartid WHERE geoid = %s AND level = 1 AND dartid IN (6, 7)", (geoid,)
    )
    problems = _problems(conn, geoid)
    assert problems["dart free in alpha_1 (only alpha_2 may have fixed points)"] == (6, 7)


def test_the_sql_check_names_a_broken_composition(conn: Conn) -> None:
    fc, geoid = _stored_map(conn)
    # two darts of different triangles sewn by alpha_2 as an involution, but across edges that do not match
    a, b = conn.execute(
        "SELECT min(dartid), max(dartid) FROM tgsis.gmap_alpha WHERE geoid = %s AND level = 2 "
        "AND dartid2 = dartid AND dartid < 12",
        (geoid,),
    ).fetchone()  # type: ignore[misc]
    conn.execute(
        "UPDATE tgsis.gmap_alpha SET dartid2 = CASE dartid WHEN %s THEN %s ELSE %s END "
        "WHERE geoid = %s AND level = 2 AND dartid IN (%s, %s)",
        (a, b, a, geoid, a, b),
    )
    problems = _problems(conn, geoid)
    assert "alpha_2 is not an involution" not in problems
    assert "alpha_0 o alpha_2 is not an involution" in problems
    assert set(problems["alpha_0 o alpha_2 is not an involution"]) & {a, b}


def test_the_sql_check_names_a_dart_crossing_periods(conn: Conn) -> None:
    _, geoid = _stored_map(conn)
    conn.execute("UPDATE tgsis.gmap_dart SET timem = 1 WHERE geoid = %s AND dartid = 3", (geoid,))
    problems = _problems(conn, geoid)
    crossing = [darts for problem, darts in problems.items() if "into another topology period" in problem]
    assert any(3 in darts for darts in crossing)
    assert "dart of a node missing from its topology period" in problems
    assert [
        p
        for p in conn.execute("SELECT problem FROM tgsis.check_geometry(%s)", (geoid,)).fetchall()
        if "another topology period" in p[0]
    ]


def test_a_broken_map_is_refused_naming_its_darts_and_nothing_is_written(conn: Conn) -> None:
    fc = _class(conn)
    conn.commit()
    square = gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 1, 2]])
    alpha = square.alpha.copy()
    alpha[0, 0], alpha[0, 1] = 0, 0  # a fixed point and a non-involution of alpha_0
    broken = gmaps.GMap(alpha, square.vertex, square.points)
    before = conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone()
    with pytest.raises(tgsis.InvalidGMapError, match="dart"):
        F.insert_feature(conn, fc, broken)
    assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == before
    assert conn.execute("SELECT count(*) FROM tgsis.gmap_dart").fetchone() == (0,)


def test_classes_of_gmaps_need_a_cell_level_and_others_refuse_one(conn: Conn) -> None:
    with pytest.raises(tgsis.InvalidInputError, match="needs the level of the cells"):
        F.create_feature_class(conn, "nolevel", "GMAP", time_model="GMAP")
    conn.rollback()
    with pytest.raises(tgsis.InvalidInputError, match="not to cells of a level"):
        F.create_feature_class(conn, "static", "SURFACE", cell_level=2)
    conn.rollback()
    fc = _class(conn, level=3)
    with pytest.raises(tgsis.InvalidGMapError, match="3-cells, which a 2-G-map does not have"):
        F.insert_feature(conn, fc, gmaps.GMap.from_triangles(*icosahedron()))


def test_deleting_a_feature_removes_every_model_4_row(conn: Conn) -> None:
    fc = _class(conn)
    geoid = F.insert_feature(conn, fc, _evolving())
    assert F.delete_feature(conn, fc, geoid)
    for table in (
        "gmap",
        "gmap_timem",
        "gmap_timet",
        "gmap_node",
        "gmap_vertex",
        "gmap_dart",
        "gmap_alpha",
        "gmap_cell",
    ):
        assert conn.execute(f"SELECT count(*) FROM tgsis.{table}").fetchone() == (0,), table
    assert conn.execute("SELECT count(*) FROM blocks_cellpros").fetchone() == (0,)


def test_gmaps_are_versioned_with_the_features(conn: Conn) -> None:
    fc = _class(conn)
    base = F.insert_feature(conn, fc, _evolving())
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        added = F.insert_feature(conn, fc, _faces(gmaps.GMap.from_triangles(*icosahedron())))
        conn.execute(
            "UPDATE tgsis.gmap_vertex SET coordinate = ARRAY[9, 9, 9]::float8[] "
            "WHERE geoid = %s AND timet = 3 AND nodeid = 4",
            (base,),
        )
        conn.commit()
        moved = G.gmap_at(conn, base, 3.0)
        assert moved is not None and moved.points[0].tolist() == [9.0, 9.0, 9.0]  # node 4: period 1's first
        assert G.fetch_gmap(conn, fc, added).at(0.0) is not None
    conn.commit()  # (the block's reads left a transaction open: its end put DEFAULT back inside it)
    # DEFAULT sees neither the new G-map nor the moved point
    with pytest.raises(tgsis.NotFoundError):
        G.fetch_gmap(conn, fc, added)
    assert np.array_equal(G.fetch_gmap(conn, fc, base).at(3.0).points, _evolving().at(3.0).points)  # type: ignore[union-attr]
    tgsis.merge_version(conn, "edit")
    conn.commit()
    assert G.fetch_gmap(conn, fc, added).at(0.0) is not None
    merged = G.fetch_gmap(conn, fc, base)
    assert 9.0 in merged.periods[1].positions[2]


def test_a_reader_reads_checks_and_cuts_but_cannot_store(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as admin:
        fc = _class(admin)
        geoid = F.insert_feature(admin, fc, _evolving())
        admin.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader", "nora": "pg_read_all_settings"}) as roles:
        rita = roles.connect("rita")
        assert G.gmap_at(rita, geoid, 2.0) is not None
        assert G.gmap_check(rita, geoid) == []
        assert len(G.gmap_cells(rita, geoid, 2, 2.0)[0]) > 0  # its work table is a temporary one
        with pytest.raises(tgsis.MissingPrivilegeError):
            F.insert_feature(rita, fc, _faces(gmaps.GMap.from_triangles(*icosahedron())))
        rita.rollback()
        nora = roles.connect("nora")  # no tgsis role: nothing to read
        with pytest.raises(tgsis.MissingPrivilegeError):
            G.gmap_check(nora, geoid)
    with psycopg.connect(db_dsn) as admin:
        assert admin.execute("SELECT count(*) FROM tgsis.gmap").fetchone() == (1,)


def test_two_versions_moving_one_point_conflict_and_the_merge_takes_a_side(conn: Conn) -> None:
    fc = _class(conn)
    geoid = F.insert_feature(conn, fc, _evolving())
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "other")
    move = "UPDATE tgsis.gmap_vertex SET coordinate = %s::float8[] WHERE geoid = %s AND timet = 3 AND nodeid = 4"
    conn.execute(move, ([7, 7, 7], geoid))
    conn.commit()
    with tgsis.in_version(conn, "other"):
        conn.execute(move, ([8, 8, 8], geoid))
        conn.commit()
    conn.commit()
    conflicts = tgsis.find_conflicts(conn, "other")
    assert [(c.objectclass, c.objectkey) for c in conflicts] == [("feature", str(geoid))]
    tgsis.resolve_conflict(conn, "other", "feature", str(geoid), "child")
    tgsis.merge_version(conn, "other")
    conn.commit()
    merged = G.gmap_at(conn, geoid, 3.0)
    assert merged is not None and merged.points[0].tolist() == [8.0, 8.0, 8.0]


def test_features_at_t_follow_the_g_maps_life(conn: Conn) -> None:
    fc = _class(conn)
    rising = F.insert_feature(conn, fc, _evolving())  # from t = 0, alive
    ended = F.insert_feature(conn, fc, gmaps.EvolvingGMap(_evolving().periods[:1], alive=False))  # t in [0, 1]
    lasting = F.insert_feature(conn, fc, _faces(gmaps.GMap.from_triangles(*icosahedron())))  # t = 0 on, alive
    assert tgsis.features_at(conn, fc, -1.0) == []
    assert tgsis.features_at(conn, fc, 0.5) == [rising, ended, lasting]
    assert tgsis.features_at(conn, fc, 7.0) == [rising, lasting]
    assert conn.execute("SELECT tgsis.exists_at(%s, 1.5), tgsis.exists_at(%s, 1.5)", (rising, ended)).fetchone() == (
        True,
        False,
    )


def test_a_reader_denied_one_class_still_finds_a_feature_of_another(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as admin:
        F.create_feature_class(admin, "aaa_secret", "GMAP", time_model="GMAP", cell_level=2)  # listed first
        fc = _class(admin)
        geoid = F.insert_feature(admin, fc, _evolving())
        admin.execute("REVOKE SELECT ON aaa_secret FROM tgsis_reader")
        admin.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as roles:
        rita = roles.connect("rita")
        assert class_of_feature(rita, geoid).name == "blocks"
        assert G.gmap_at(rita, geoid, 2.0) is not None  # finds its class as gmap_at does
        with pytest.raises(tgsis.NotFoundError, match=r"among those this role may read \(1 it may not\)"):
            class_of_feature(rita, geoid + 1000)


def test_a_reader_denied_a_schema_still_finds_a_feature_of_another_class(db_dsn: str) -> None:
    # was: permission denied for schema vault (has_table_privilege of every class's table by name)
    with psycopg.connect(db_dsn) as admin:
        admin.execute("CREATE SCHEMA vault")
        F.create_feature_class(admin, "aaa_secret", "GMAP", time_model="GMAP", cell_level=2, schema="vault")
        fc = _class(admin)
        geoid = F.insert_feature(admin, fc, _evolving())
        admin.execute("REVOKE ALL ON SCHEMA vault FROM PUBLIC, tgsis_reader")
        admin.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as roles:
        rita = roles.connect("rita")
        assert class_of_feature(rita, geoid).name == "blocks"
        assert G.gmap_at(rita, geoid, 2.0) is not None
        secret = next(c for c in tgsis.list_feature_classes(rita) if c.name == "aaa_secret")
        assert may_read_features(rita, secret) is False
        with pytest.raises(tgsis.NotFoundError, match=r"among those this role may read \(1 it may not\)"):
            class_of_feature(rita, geoid + 1000)
