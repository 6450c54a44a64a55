"""Feature classes and features of model 1: registration, upload, download, queries, deletion."""

from __future__ import annotations

import datetime
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.db import features as F
from tgsis.mesh import LineSet, PointSet, Surface, TetraMesh

Conn = psycopg.Connection[Any]
rng = np.random.default_rng(42)


def _counts(conn: Conn) -> tuple[int, ...]:
    row = conn.execute(
        "SELECT (SELECT count(*) FROM tgsis.geometry), (SELECT count(*) FROM tgsis.vrtx), "
        "(SELECT count(*) FROM tgsis.trgl), (SELECT count(*) FROM tgsis.catalog), "
        "(SELECT count(*) FROM pg_class WHERE relnamespace = 'public'::regnamespace)"
    ).fetchone()
    assert row is not None
    return tuple(int(v) for v in row)


def _grid(side: int = 4, z: float = 0.0) -> Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.full(side * side, z) + rng.random(side * side)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))


@pytest.fixture
def horizons(conn: Conn) -> F.FeatureClass:
    fc = F.create_feature_class(
        conn,
        "horizons",
        "SURFACE",
        feature_properties=[("creator", "text"), ("note", "varchar"), ("age", "float8")],
        cell_properties=[("porosity", "double precision"), ("facies", "int")],
        srs=32611,
        description="seismic horizons",
    )
    conn.commit()
    return fc


def _horizon(side: int = 4, z: float = 0.0) -> Surface:
    s = _grid(side, z)
    return Surface(
        s.vertices,
        s.cells,
        name=f"h{z}",
        vertex_properties={"porosity": rng.random(s.n_vertices), "facies": rng.integers(0, 5, s.n_vertices)},
    )


# --------------------------------------------------------------------------- classes


def test_register_creates_tables_view_and_catalog_row(conn: Conn, horizons: F.FeatureClass) -> None:
    assert horizons.geotype is tgsis.Geotype.SURFACE and horizons.alignment == "VERTEX" and horizons.srs == 32611
    assert [p.type for p in horizons.feature_properties] == ["text", "text", "double precision"]
    assert [(p.name, p.type) for p in horizons.cell_properties] == [
        ("porosity", "double precision"),
        ("facies", "integer"),
    ]
    # the row definition: the table, or its <table>_shape when the class is in chunks (model 1 in chunks)
    columns = conn.execute(
        "SELECT attname, format_type(atttypid, atttypmod), attnotnull FROM pg_attribute "
        "WHERE attrelid = (CASE WHEN tgsis.stored_in_chunks('public', 'horizons_cellpros') "
        "THEN 'horizons_cellpros_shape' ELSE 'horizons_cellpros' END)::regclass AND attnum > 0 ORDER BY attnum"
    ).fetchall()
    assert columns == [
        ("_geoid", "bigint", True),
        ("_idx", "bigint", True),
        ("porosity", "double precision", True),
        ("facies", "integer", True),
    ]
    pk = conn.execute(
        "SELECT pg_get_constraintdef(oid) FROM pg_constraint WHERE conrelid = 'horizons'::regclass ORDER BY contype"
    ).fetchall()
    assert ("FOREIGN KEY (_geoid) REFERENCES tgsis.geometry(geoid) ON DELETE CASCADE",) in pk
    assert ("PRIMARY KEY (_geoid)",) in pk
    assert conn.execute(
        "SELECT obj_description('horizons'::regclass), obj_description('horizons_v'::regclass)"
    ).fetchone() == (
        "tgsis feature class horizons: one row per SURFACE feature (_geoid = tgsis.geometry.geoid)",
        "tgsis feature class horizons: features with their name, geotype, counts and bounding box",
    )
    assert [c.name for c in F.list_feature_classes(conn)] == ["horizons"]
    assert F.get_feature_class(conn, "horizons") == horizons


def test_property_spellings_and_json_forms(conn: Conn) -> None:
    conn.execute("""SELECT tgsis.register_feature_class('wells', 'MULTILINESTRING',
                        '{"operator": "TEXT", "spud": "date"}', '[{"name": "gamma", "type": "REAL"}]', 'vertex')""")
    fc = F.get_feature_class(conn, "wells")
    assert {p.name: p.type for p in fc.feature_properties} == {"operator": "text", "spud": "date"}
    assert fc.cell_properties == (F.Property("gamma", "real"),) and fc.alignment == "VERTEX"


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"name": "Horizons"}, tgsis.InvalidNameError, "feature class name 'Horizons' is not allowed"),
        ({"name": "select"}, tgsis.InvalidNameError, "feature class name 'select' is not allowed"),
        ({"name": "a-b"}, tgsis.InvalidNameError, "is not allowed"),
        ({"name": "x" * 60}, tgsis.InvalidNameError, "is not allowed"),
        ({"geotype": "POLYGON"}, tgsis.InvalidInputError, "unknown geotype 'POLYGON'"),
        ({"alignment": "FACE"}, tgsis.InvalidInputError, "must be VERTEX or CELL"),
        ({"srs": -4}, tgsis.InvalidInputError, "SRS -4"),
        ({"schema": "nowhere"}, tgsis.NotFoundError, "schema 'nowhere' does not exist"),
        (
            {"feature_properties": {"note": "text; drop table x"}},
            tgsis.InvalidPropertyError,
            "has type 'text; drop table x', which is not allowed",
        ),
        ({"feature_properties": {"No-te": "text"}}, tgsis.InvalidNameError, "feature property name 'No-te'"),
        ({"feature_properties": {"9lives": "text"}}, tgsis.InvalidNameError, "feature property name '9lives'"),
        ({"feature_properties": {"_idx": "text"}}, tgsis.InvalidNameError, "'_idx' is not allowed"),
        ({"feature_properties": [("a", "text"), ("a", "int")]}, tgsis.InvalidPropertyError, "given twice"),
        (
            {"cell_properties": {"label": "text"}},
            tgsis.InvalidPropertyError,
            "vertex and cell properties must be numbers or booleans",
        ),
    ],
)
def test_bad_class_definitions_change_nothing(
    conn: Conn, kwargs: dict[str, Any], error: type[tgsis.Error], message: str
) -> None:
    before = _counts(conn)
    args: dict[str, Any] = {"name": "layers", "geotype": "SURFACE", **kwargs}
    with pytest.raises(error, match=message):
        F.create_feature_class(conn, args.pop("name"), args.pop("geotype"), **args)
    assert _counts(conn) == before


def test_duplicate_class_or_table_is_refused(conn: Conn, horizons: F.FeatureClass) -> None:
    with pytest.raises(tgsis.AlreadyExistsError, match="feature class horizons exists already"):
        F.create_feature_class(conn, "horizons", "SURFACE")
    conn.execute("CREATE TABLE public.faults (id int)")
    conn.commit()
    with pytest.raises(tgsis.AlreadyExistsError, match="exists already in schema public"):
        F.create_feature_class(conn, "faults", "SURFACE")


def test_class_in_another_schema(conn: Conn) -> None:
    conn.execute("CREATE SCHEMA geo")
    fc = F.create_feature_class(
        conn, "bodies", "MULTITETRA", cell_properties={"density": "real"}, alignment="CELL", schema="geo"
    )
    solid = TetraMesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]],
        [[0, 1, 2, 3], [1, 2, 3, 4]],
        cell_properties={"density": np.array([2.5, 2.7], dtype=np.float32)},
    )
    fid = F.insert_feature(conn, fc, solid)
    assert conn.execute("SELECT count(*) FROM geo.bodies_cellpros WHERE _geoid = %s", (fid,)).fetchone() == (2,)
    assert F.fetch_feature(conn, "bodies", fid).mesh.same_as(solid)  # type: ignore[union-attr]


def test_drop_class_refuses_while_features_exist_unless_forced(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _horizon())
    conn.commit()
    with pytest.raises(tgsis.InUseError, match="feature class horizons still has 1 feature") as info:
        F.drop_feature_class(conn, "horizons")
    assert "force" in (info.value.hint or "")
    assert conn.execute("SELECT to_regclass('horizons') IS NOT NULL").fetchone() == (True,)
    assert F.drop_feature_class(conn, "horizons", force=True) == 1
    assert conn.execute(
        "SELECT to_regclass('horizons'), to_regclass('horizons_cellpros'), to_regclass('horizons_v')"
    ).fetchone() == (None, None, None)
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fid,)).fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == (0,)
    with pytest.raises(tgsis.NotFoundError, match="feature class 'horizons' does not exist"):
        F.drop_feature_class(conn, "horizons")


# --------------------------------------------------------------------------- features


@pytest.mark.parametrize(
    "mesh",
    [
        PointSet([[0, 0, 0], [1, 2, 3], [4, 5, 6]], vertex_properties={"value": [1.0, 2.0, 3.0]}),
        LineSet([[0, 0, 0], [1, 0, 0], [2, 1, 0]], [[0, 1], [1, 2]], vertex_properties={"value": [0.0, 0.5, -1.0]}),
        TetraMesh(
            [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3]], vertex_properties={"value": np.ones(4)}
        ),
    ],
    ids=["points", "lines", "tetra"],
)
def test_every_geotype_round_trips(conn: Conn, mesh: tgsis.Mesh) -> None:
    fc = F.create_feature_class(conn, "things", mesh.geotype, cell_properties={"value": "float8"})
    fid = F.insert_feature(conn, fc, mesh, name="thing")
    got = F.fetch_feature(conn, fc, fid)
    assert got.name == "thing" and got.mesh is not None and got.mesh.same_as(mesh)


def test_surface_round_trip_is_bit_exact_with_properties(conn: Conn, horizons: F.FeatureClass) -> None:
    surface = _horizon(30)
    surface.vertices[0] = [-0.0, 5e-324, np.nextafter(1.0, 2.0)]
    fid = F.insert_feature(conn, horizons, surface, {"creator": "ana", "age": -12.5})
    conn.commit()
    got = F.fetch_feature(conn, "horizons", fid)
    assert isinstance(got.mesh, Surface) and got.mesh.same_as(surface)
    assert got.mesh.vertex_properties["facies"].dtype == np.int32
    assert got.properties == {"creator": "ana", "note": None, "age": -12.5}
    row = conn.execute("SELECT nvrtx, ncell, bbox::text FROM tgsis.geometry WHERE geoid = %s", (fid,)).fetchone()
    assert row is not None and row[:2] == (900, 2 * 29 * 29)
    assert conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (fid,)).fetchall() == []


def test_cell_aligned_properties(conn: Conn) -> None:
    fc = F.create_feature_class(
        conn, "units", "SURFACE", cell_properties={"facies": "smallint", "wet": "boolean"}, alignment="CELL"
    )
    s = _grid(5)
    s = Surface(
        s.vertices, s.cells, cell_properties={"facies": np.arange(s.n_cells) % 3, "wet": np.arange(s.n_cells) % 2 == 0}
    )
    fid = F.insert_feature(conn, fc, s)
    got = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(got, Surface) and got.same_as(s) and got.cell_properties["wet"].dtype == np.bool_


@pytest.mark.parametrize(
    ("change", "error", "message"),
    [
        (
            lambda s: TetraMesh(s.vertices, [[0, 1, 2, 3]]),
            tgsis.InvalidGeometryError,
            "holds SURFACE features, not MULTITETRA",
        ),
        (
            lambda s: Surface(s.vertices, s.cells, vertex_properties={"porosity": s.vertex_properties["porosity"]}),
            tgsis.InvalidPropertyError,
            r"needs vertex properties \['facies'\], which the mesh lacks",
        ),
        (
            lambda s: Surface(s.vertices, s.cells, vertex_properties={**s.vertex_properties, "extra": np.zeros(16)}),
            tgsis.InvalidPropertyError,
            r"has no column for properties \['extra'\]",
        ),
        (
            lambda s: Surface(
                s.vertices, s.cells, vertex_properties={**s.vertex_properties, "facies": np.full(16, 1.5)}
            ),
            tgsis.InvalidPropertyError,
            "property 'facies' has values that are not integer",
        ),
    ],
)
def test_bad_features_write_nothing(
    conn: Conn, horizons: F.FeatureClass, change: Any, error: type[tgsis.Error], message: str
) -> None:
    before = _counts(conn)
    with pytest.raises(error, match=message):
        F.insert_feature(conn, horizons, change(_horizon()))
    assert _counts(conn) == before


def test_unknown_feature_property_writes_nothing(conn: Conn, horizons: F.FeatureClass) -> None:
    before = _counts(conn)
    with pytest.raises(tgsis.InvalidPropertyError, match=r"has no feature properties \['colour'\]"):
        F.insert_feature(conn, horizons, _horizon(), {"colour": "red"})
    assert _counts(conn) == before


def test_a_failure_inside_the_upload_rolls_everything_back(conn: Conn, horizons: F.FeatureClass) -> None:
    before = _counts(conn)
    # a date for a float8 column passes the client's checks (a text value would be refused first, naming the property)
    with pytest.raises(tgsis.DatabaseError, match="is of type double precision but expression is of type date"):
        F.insert_feature(conn, horizons, _horizon(), {"age": datetime.date(2020, 1, 1)})  # fails at the last statement
    assert _counts(conn) == before


def test_extra_properties_can_be_dropped(conn: Conn, horizons: F.FeatureClass) -> None:
    s = _horizon()
    s.cell_properties["quality"] = np.zeros(s.n_cells, dtype=np.int64)
    # the part of each cell is no property of the class: it is kept in tgsis.part (issue 16)
    s.cell_properties["part"] = np.repeat([0, 1], [10, s.n_cells - 10])
    fid = F.insert_feature(conn, horizons, s, drop_extra_properties=True)
    back = F.fetch_feature(conn, horizons, fid).mesh
    assert isinstance(back, Surface) and set(back.cell_properties) == {"part"}
    np.testing.assert_array_equal(back.cell_properties["part"], s.cell_properties["part"])


def test_fetch_many_box_query_and_delete(conn: Conn, horizons: F.FeatureClass) -> None:
    ids = [F.insert_feature(conn, horizons, _horizon(4 + i, z=100.0 * i), {"note": f"n{i}"}) for i in range(4)]
    conn.commit()
    features = F.fetch_features(conn, "horizons", [ids[2], ids[0]])
    assert [f.id for f in features] == [ids[2], ids[0]]
    assert [f.mesh.n_vertices for f in features] == [36, 16]  # type: ignore[union-attr]
    assert [f.properties["note"] for f in F.fetch_features(conn, "horizons")] == ["n0", "n1", "n2", "n3"]
    assert F.features_in_box(conn, "horizons", [[-1, -1, 150], [10, 10, 250]]) == [ids[2]]
    assert F.features_in_box(conn, "horizons", [[-1, -1, -1], [10, 10, 500]]) == ids
    # 4 rows: only forbidding the seq scan shows the index is usable
    conn.execute("SET enable_seqscan = off; SET jit = off")
    plan = "\n".join(
        r[0]
        for r in conn.execute(
            "EXPLAIN SELECT geoid FROM tgsis.geometry WHERE bbox && cube(ARRAY[0,0,0], ARRAY[1,1,1])"
            " AND NOT tgsis.cube_has_nan(bbox)"  # the partial index's predicate (tgsis.geometries_in_box's)
        ).fetchall()
    )
    assert "geometry_bbox_idx" in plan
    conn.execute("RESET enable_seqscan")
    assert F.delete_feature(conn, "horizons", ids[1]) is True
    assert F.delete_feature(conn, "horizons", ids[1]) is False
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (ids[1],)).fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM horizons_cellpros WHERE _geoid = %s", (ids[1],)).fetchone() == (0,)
    with pytest.raises(tgsis.NotFoundError, match=rf"has no feature\(s\) \[{ids[1]}\]"):
        F.fetch_feature(conn, "horizons", ids[1])
    with pytest.raises(tgsis.InvalidGeometryError, match="a box is"):
        F.features_in_box(conn, "horizons", [[0, 0], [1, 1]])


def test_psql_users_see_features_in_the_class_view(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _horizon(), {"creator": "ana"}, name="top reservoir")
    row = conn.execute("SELECT geoname, _geoid, creator, geotype, nvrtx, ncell FROM horizons_v").fetchone()
    assert row == ("top reservoir", fid, "ana", "SURFACE", 16, 18)
    vertices = conn.execute(
        "SELECT v.vrtxid, v.x, p.porosity FROM tgsis.vrtx v JOIN horizons_cellpros p "
        "ON p._geoid = v.geoid AND p._idx = v.vrtxid WHERE v.geoid = %s ORDER BY v.vrtxid",
        (fid,),
    ).fetchall()
    assert len(vertices) == 16


def test_refresh_and_check_after_plain_sql_edits(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _horizon())
    conn.execute("UPDATE tgsis.vrtx SET z = 1000 WHERE geoid = %s AND vrtxid = 0", (fid,))
    conn.execute("INSERT INTO tgsis.trgl VALUES (%s, 99, 0, 1, 77)", (fid,))
    problems = conn.execute("SELECT problem, count, example FROM tgsis.check_geometry(%s)", (fid,)).fetchall()
    assert ("trgl refers to a missing vertex (vrtxid3)", 1, "99") in problems
    assert ("bounding box or counts out of date (run tgsis.refresh_geometry)", 1, None) in problems
    conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 99", (fid,))
    row = conn.execute("SELECT cube_ur_coord(bbox, 3), ncell FROM tgsis.refresh_geometry(%s)", (fid,)).fetchone()
    assert row == (1000.0, 18)
    assert conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (fid,)).fetchall() == []
    with pytest.raises(psycopg.Error, match="geometry 123456 does not exist"):
        conn.execute("SELECT tgsis.refresh_geometry(123456)")


def test_upload_writes_the_storage_itself(conn: Conn, horizons: F.FeatureClass) -> None:
    """Rows by COPY into the table, or (stored in chunks) chunks by COPY into tgsis.<t>_chunk: never row by row
    through the face's INSTEAD OF triggers, which rewrite a chunk per row (before the storage switch's upload:
    2,500 updates of 3 chunks)."""
    mesh = _horizon(50)  # 2,500 vertices: 3 chunks; 4,802 triangles: 5 chunks
    counts = "SELECT n_tup_ins, n_tup_upd + n_tup_del FROM pg_stat_xact_user_tables WHERE relid = %s::regclass"
    with conn.transaction():
        # a backend reports its table counts when idle, at most once a second: those of the transactions just
        # before are still pending and added to this one's, so the upload's are a difference inside it
        stored = {
            table: conn.execute(
                "SELECT tgsis.storage_table('tgsis', %s), tgsis.stored_in_chunks(%s)", (table, table)
            ).fetchone()
            for table in ("vrtx", "trgl")
        }
        pending = {table: conn.execute(counts, (row[0],)).fetchone() for table, row in stored.items() if row}
        F.insert_feature(conn, horizons, mesh)
        for table, rows in (("vrtx", mesh.n_vertices), ("trgl", mesh.n_cells)):
            name, chunked = stored[table]  # type: ignore[misc]
            written, before = conn.execute(counts, (name,)).fetchone(), pending[table]
            assert written is not None and before is not None
            assert (written[0] - before[0], written[1] - before[1]) == (
                (rows + 1023) // 1024 if chunked else rows,
                0,
            ), table
    back = F.fetch_features(conn, horizons)[0].mesh
    assert back is not None and back.same_as(mesh)


def test_a_mesh_changed_into_a_degenerate_one_is_refused_by_name(conn: Conn, horizons: F.FeatureClass) -> None:
    """Cells naming a vertex twice (a mesh's cells changed after it was checked): the row table's CHECK refused
    them with a raw 23514, the chunk table has no such CHECK; both are refused by the client, naming the cell."""
    mesh = _horizon()
    mesh.cells[3] = [2, 5, 2]
    before = _counts(conn)
    with pytest.raises(tgsis.InvalidGeometryError, match=r"triangle 3 uses a vertex twice: \[2, 5, 2\]"):
        F.insert_feature(conn, horizons, mesh)
    assert _counts(conn) == before
