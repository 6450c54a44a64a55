"""GEOMETRYCOLLECTION features: the mesh type, storage with owned members, fetch, delete, files, command line."""

from __future__ import annotations

import datetime
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest

import tgsis
from tgsis import formats
from tgsis.cli import main
from tgsis.db import _static, _transfer
from tgsis.db import features as F
from tgsis.errors import reraise
from tgsis.formats.vtk import parse_vtu, read_vtu_collection
from tgsis.mesh import GeometryCollection, LineSet, Mesh, PointSet, Surface, TetraMesh

Conn = psycopg.Connection[Any]
rng = np.random.default_rng(7)

GEOMETRY_TABLES = ("tgsis.geometry", "tgsis.vrtx", "tgsis.point", "tgsis.segment", "tgsis.trgl", "tgsis.tetra")


def _counts(conn: Conn, *tables: str) -> dict[str, int]:
    """Rows of the model-1 tables and of ``tables`` (NULL where a table does not exist)."""
    result = {}
    for table in (*GEOMETRY_TABLES, *tables):
        exists = conn.execute("SELECT to_regclass(%s) IS NOT NULL", (table,)).fetchone()
        row = conn.execute(f"SELECT count(*) FROM {table}").fetchone() if exists and exists[0] else None
        result[table] = -1 if row is None else int(row[0])
    return result


def _with_props(mesh: Mesh, alignment: str, code_dtype: Any = np.int32) -> Mesh:
    """``mesh`` with the properties ``value`` (float64) and ``code`` per vertex or per cell."""
    count = mesh.n_vertices if alignment == "VERTEX" else mesh.n_cells
    props = {"value": rng.random(count), "code": rng.integers(-5, 5, count).astype(code_dtype)}
    return type(mesh)(
        mesh.vertices,
        mesh.cells,
        name=mesh.name,
        vertex_properties=props if alignment == "VERTEX" else None,
        cell_properties=props if alignment == "CELL" else None,
    )


def _surface(side: int = 4, z: float = 0.0, name: str = "top") -> Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), z + rng.random(side * side)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]), name=name)


def _members(alignment: str | None = None, shift: float = 0.0) -> list[Mesh]:
    """A surface, lines, points and a tetrahedral solid, apart from each other; ``shift`` moves all in x."""
    surface = _surface()
    surface.vertices[0] = [-0.0, 5e-324, np.nextafter(0.0, 1.0)]  # bits that only an exact round trip keeps
    lines = LineSet([[10.0, 0, 0], [11.0, 0, 0], [12, 1, 0.5]], [[0, 1], [1, 2]], name="trace")
    points = PointSet([[20, 20, 20], [21, 20, 20], [22, 21, 19]], name="samples")
    solid = TetraMesh(
        [[0, 0, -10], [1, 0, -10], [0, 1, -10], [0, 0, -9], [1, 1, -9]], [[0, 1, 2, 3], [1, 2, 3, 4]], name="body"
    )
    meshes: list[Mesh] = [surface, lines, points, solid]
    for mesh in meshes:
        mesh.vertices[:, 0] += shift
    return [_with_props(m, alignment) for m in meshes] if alignment else meshes


def _collection(alignment: str | None = None, shift: float = 0.0, name: str = "block") -> GeometryCollection:
    return GeometryCollection(_members(alignment, shift), name=name)


def _rocks(conn: Conn, alignment: str = "VERTEX") -> F.FeatureClass:
    fc = F.create_feature_class(
        conn,
        "rocks",
        "GEOMETRYCOLLECTION",
        feature_properties=[("note", "text"), ("age", "float8")],
        cell_properties=[("value", "double precision"), ("code", "integer")],
        alignment=alignment,  # type: ignore[arg-type]  # the tests pass both alignments as str
    )
    conn.commit()
    return fc


# --------------------------------------------------------------------------- the type (no database)


def test_collection_facts_copies_and_reports() -> None:
    members = _members()
    c = GeometryCollection(members, name="block", metadata={"source": "test"})
    assert len(c) == 4 and list(c) == members and c[2] is members[2]
    assert c.geotype is tgsis.Geotype.GEOMETRYCOLLECTION
    assert c.geotypes == (
        tgsis.Geotype.SURFACE,
        tgsis.Geotype.MULTILINESTRING,
        tgsis.Geotype.MULTIPOINT,
        tgsis.Geotype.MULTITETRA,
    )
    assert c.n_vertices == 16 + 3 + 3 + 5 and c.n_cells == 18 + 2 + 3 + 2
    assert c.bounds().tolist() == [[-0.0, 0.0, -10.0], [22.0, 21.0, 20.0]]
    assert repr(c) == (
        "GeometryCollection(name='block', members=[Surface, LineSet, PointSet, TetraMesh], n_vertices=27, n_cells=25)"
    )

    twin = c.copy()
    assert twin.same_as(c) and twin.name == "block" and twin.metadata == {"source": "test"}
    assert all(a is not b for a, b in zip(twin, c))
    twin.members[1].vertices[0, 0] = 99.0
    assert not twin.same_as(c) and c.members[1].vertices[0, 0] == 10.0
    assert not c.same_as(GeometryCollection(members[:3]))  # fewer members
    assert not c.same_as(GeometryCollection([members[1], members[0], *members[2:]]))  # other order
    assert not c.same_as(members[0])

    flawed = LineSet([[0, 0, 0], [0, 0, 0], [1, 0, 0]], [[0, 2], [1, 2]], name="dup")
    reports = GeometryCollection([members[0], flawed]).report()
    assert [r.ok for r in reports] == [True, False]
    assert reports[1].duplicate_vertices.tolist() == [[0, 1]]
    assert GeometryCollection([flawed]).report(tolerance=2.0)[0].degenerate_cells.tolist() == [0, 1]
    assert GeometryCollection([members[3]]).bounds().tolist() == [[0, 0, -10], [1, 1, -9]]
    with pytest.raises(tgsis.InvalidGeometryError, match="has no vertex: no bounding box"):
        GeometryCollection([PointSet(np.empty((0, 3)))]).bounds()


@pytest.mark.parametrize(
    ("members", "message"),
    [
        ([], "collection 'c' has no member"),
        (
            [_surface(), GeometryCollection([_surface()])],
            "member 1 of collection 'c' is a GeometryCollection: collections do not nest",
        ),
        ([_surface(), np.zeros((3, 3))], "member 1 of collection 'c' is a ndarray, not a PointSet, LineSet"),
        ([tgsis.Mesh.__new__(tgsis.Mesh)], "member 0 of collection 'c' is a Mesh, not a PointSet"),
        (_surface(), "a sequence of meshes, got one Surface"),
    ],
)
def test_bad_collections_are_refused(members: Any, message: str) -> None:
    with pytest.raises(tgsis.InvalidGeometryError, match=message):
        GeometryCollection(members, name="c")


def test_collection_is_exported_and_mesh_class_stays_for_single_meshes() -> None:
    assert tgsis.GeometryCollection is GeometryCollection and "GeometryCollection" in tgsis.__all__
    with pytest.raises(tgsis.InvalidGeometryError, match="a GEOMETRYCOLLECTION is a GeometryCollection"):
        tgsis.mesh_class("GEOMETRYCOLLECTION")


# --------------------------------------------------------------------------- storage


@pytest.mark.parametrize("alignment", ["VERTEX", "CELL"])
def test_round_trip_with_every_member_type(conn: Conn, alignment: str) -> None:
    fc = _rocks(conn, alignment)
    original = _collection(alignment)
    cid = F.insert_feature(conn, fc, original, {"note": "mixed"})
    conn.commit()

    row = conn.execute(
        "SELECT geotype, geoname, geoids, collection, nvrtx, ncell, bbox::text FROM tgsis.geometry WHERE geoid = %s",
        (cid,),
    ).fetchone()
    assert row is not None
    geotype, geoname, member_ids, owner, nvrtx, ncell, bbox = row
    assert (geotype, geoname, owner, nvrtx, ncell) == ("GEOMETRYCOLLECTION", "block", None, 27, 25)
    assert conn.execute(
        "SELECT bbox = cube(ARRAY[0, 0, -10], ARRAY[22, 21, 20]) FROM tgsis.geometry WHERE geoid = %s", (cid,)
    ).fetchone() == (True,), bbox
    members = conn.execute(
        "SELECT geoid, geotype, geoname, collection, nvrtx, ncell, cube_ll_coord(bbox, 3), "
        "cube_ur_coord(bbox, 1) FROM tgsis.geometry WHERE geoid = ANY(%s) ORDER BY geoid",
        (member_ids,),
    ).fetchall()
    assert [m[0] for m in members] == member_ids  # stored in member order
    assert [m[1:] for m in members] == [
        ("SURFACE", "top", cid, 16, 18, original[0].vertices[:, 2].min(), 3.0),
        ("MULTILINESTRING", "trace", cid, 3, 2, 0.0, 12.0),
        ("MULTIPOINT", "samples", cid, 3, 3, 19.0, 22.0),
        ("MULTITETRA", "body", cid, 5, 2, -10.0, 1.0),
    ]
    assert conn.execute("SELECT _geoid, note FROM rocks").fetchall() == [(cid, "mixed")]
    per_member = conn.execute("SELECT _geoid, count(*) FROM rocks_cellpros GROUP BY 1 ORDER BY 1").fetchall()
    sizes = [m.n_vertices if alignment == "VERTEX" else m.n_cells for m in original]
    assert per_member == list(zip(member_ids, sizes))
    for geoid in (cid, *member_ids):
        assert conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (geoid,)).fetchall() == []

    got = F.fetch_feature(conn, "rocks", cid)
    assert isinstance(got.mesh, GeometryCollection)
    assert got.mesh.same_as(original) and got.name == got.mesh.name == "block"
    assert [m.name for m in got.mesh] == ["top", "trace", "samples", "body"]
    assert got.mesh[0].vertices[0].tobytes() == original[0].vertices[0].tobytes()
    props: Callable[[Mesh], dict[str, npt.NDArray[Any]]]
    props = (lambda m: m.vertex_properties) if alignment == "VERTEX" else (lambda m: m.cell_properties)
    assert all(props(m)["code"].dtype == np.int32 and props(m)["value"].dtype == np.float64 for m in got.mesh)
    assert got.properties == {"note": "mixed", "age": None}


def test_fetching_many_members_takes_one_query_for_all_tables(conn: Conn, monkeypatch: pytest.MonkeyPatch) -> None:
    fc = _rocks(conn)
    originals = [
        GeometryCollection(
            [
                _with_props(_surface(3 + i % 3, z=i, name=f"s{i}"), "VERTEX")
                if i % 2
                else _with_props(LineSet(rng.random((i + 2, 3)), [[j, j + 1] for j in range(i + 1)]), "VERTEX")
                for i in range(k, k + 20)
            ],
            name=f"c{k}",
        )
        for k in (0, 20)
    ]
    ids = [F.insert_feature(conn, fc, c) for c in originals]
    queries: list[list[str]] = []
    real = _transfer.columns_out_all  # what _static imports

    def spy(conn: Conn, requests: Any) -> list[list[npt.NDArray[Any]]]:
        queries.append([request.source.as_string(conn) for request in requests])
        return real(conn, requests)

    monkeypatch.setattr(_static, "columns_out_all", spy)
    got = F.fetch_features(conn, fc, ids[::-1])
    assert [f.id for f in got] == ids[::-1]
    assert all(isinstance(f.mesh, GeometryCollection) and f.mesh.same_as(c) for f, c in zip(got, originals[::-1]))
    # 40 members of 2 geotypes, one query: vertices, segments, triangles, properties (a part each)
    assert len(queries) == 1 and len(queries[0]) == 4, queries
    # the vertices' rows, or (stored in chunks) their chunks: never the face
    chunked = conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,)
    vertices = "tgsis.vrtx_chunk" if chunked else "tgsis.vrtx"
    assert sum(q.replace('"', "") == vertices for q in queries[0]) == 1, queries
    assert sum("rocks_cellpros" in q for q in queries[0]) == 1


def test_box_query_and_class_view(conn: Conn) -> None:
    fc = _rocks(conn)
    near = F.insert_feature(conn, fc, _collection("VERTEX"), {"note": "near"})
    far = F.insert_feature(conn, fc, _collection("VERTEX", shift=1000.0, name="far"), {"note": "far"})
    # the box of a collection is the union of its members' boxes
    assert F.features_in_box(conn, fc, [[21.5, 20.5, 18], [30.0, 30, 30]]) == [near]  # near its points
    assert F.features_in_box(conn, fc, [[1000.2, 0.2, -9.9], [1000.3, 0.3, -9.8]]) == [far]  # inside its solid
    assert F.features_in_box(conn, fc, [[-1, -1, -20], [2000, 50, 50]]) == [near, far]
    assert F.features_in_box(conn, fc, [[500, 500, 500], [600, 600, 600]]) == []
    rows = conn.execute("SELECT geoname, _geoid, note, geotype, nvrtx, ncell FROM rocks_v ORDER BY _geoid").fetchall()
    assert rows == [
        ("block", near, "near", "GEOMETRYCOLLECTION", 27, 25),
        ("far", far, "far", "GEOMETRYCOLLECTION", 27, 25),
    ]


def test_delete_removes_the_members_with_their_rows(conn: Conn) -> None:
    fc = _rocks(conn)
    plain = F.create_feature_class(conn, "tops", "SURFACE", cell_properties={"value": "float8"})
    top = _surface(name="alone")
    top = Surface(top.vertices, top.cells, name="alone", vertex_properties={"value": rng.random(16)})
    sid = F.insert_feature(conn, plain, top)
    keep = _collection("VERTEX", shift=50.0, name="keep")
    kid = F.insert_feature(conn, fc, keep)
    before = _counts(conn, "rocks", "rocks_cellpros", "tops_cellpros")
    cid = F.insert_feature(conn, fc, _collection("VERTEX"))
    conn.commit()
    after_insert = _counts(conn, "rocks", "rocks_cellpros", "tops_cellpros")
    assert {t: after_insert[t] - before[t] for t in before} == {
        "tgsis.geometry": 5,
        "tgsis.vrtx": 27,
        "tgsis.point": 3,
        "tgsis.segment": 2,
        "tgsis.trgl": 18,
        "tgsis.tetra": 2,
        "rocks": 1,
        "rocks_cellpros": 27,
        "tops_cellpros": 0,
    }

    assert F.delete_feature(conn, "rocks", cid) is True
    assert _counts(conn, "rocks", "rocks_cellpros", "tops_cellpros") == before
    assert F.delete_feature(conn, "rocks", cid) is False
    fetched = F.fetch_feature(conn, fc, kid).mesh
    assert fetched is not None and fetched.same_as(keep)
    alone = F.fetch_feature(conn, plain, sid).mesh
    assert alone is not None and alone.same_as(top)


def test_drop_class_force_removes_members(conn: Conn) -> None:
    fc = _rocks(conn, "CELL")
    plain = F.create_feature_class(conn, "tops", "SURFACE")
    sid = F.insert_feature(conn, plain, _surface())
    before = _counts(conn)
    for shift in (0.0, 100.0):
        F.insert_feature(conn, fc, _collection("CELL", shift=shift))
    conn.commit()
    assert F.drop_feature_class(conn, "rocks", force=True) == 2
    assert _counts(conn) == before
    assert conn.execute("SELECT to_regclass('rocks_cellpros')").fetchone() == (None,)
    assert F.fetch_feature(conn, plain, sid).mesh is not None


def test_a_hand_made_collection_does_not_own_what_it_lists(conn: Conn) -> None:
    tops = F.create_feature_class(conn, "tops", "SURFACE", cell_properties={"value": "float8"})
    surfaces = [
        Surface(s.vertices, s.cells, name=s.name, vertex_properties={"value": rng.random(s.n_vertices)})
        for s in (_surface(name="a"), _surface(z=5, name="b"))
    ]
    a, b = (F.insert_feature(conn, tops, s) for s in surfaces)
    groups = F.create_feature_class(conn, "groups", "GEOMETRYCOLLECTION")
    conn.commit()
    before = _counts(conn, "tops", "tops_cellpros")

    def hand_made(name: str) -> int:
        row = conn.execute(
            "SELECT tgsis.new_geometry('GEOMETRYCOLLECTION', %s, NULL, 0, 0, ARRAY[%s, %s]::bigint[])", (name, b, a)
        ).fetchone()
        assert row is not None
        conn.execute("SELECT tgsis.refresh_geometry(%s)", (row[0],))
        conn.execute("INSERT INTO groups (_geoid) VALUES (%s)", (row[0],))
        conn.commit()
        return int(row[0])

    cid = hand_made("pair")
    assert conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (cid,)).fetchall() == []
    assert conn.execute("SELECT nvrtx, ncell FROM tgsis.geometry WHERE geoid = %s", (cid,)).fetchone() == (32, 36)
    got = F.fetch_feature(conn, groups, cid).mesh
    assert isinstance(got, GeometryCollection) and [m.name for m in got] == ["b", "a"]
    assert all(m.same_as(Surface(s.vertices, s.cells)) for m, s in zip(got, surfaces[::-1]))  # no class properties
    assert F.features_in_box(conn, groups, [[0, 0, 5.5], [1, 1, 5.6]]) == [cid]

    assert F.delete_feature(conn, groups, cid) is True
    assert _counts(conn, "tops", "tops_cellpros") == before
    hand_made("again")
    assert F.drop_feature_class(conn, "groups", force=True) == 1
    assert _counts(conn, "tops", "tops_cellpros") == before
    assert [f.mesh.same_as(s) for f, s in zip(F.fetch_features(conn, tops), surfaces)] == [True, True]  # type: ignore[union-attr]


def test_an_owned_member_goes_only_with_its_collection(conn: Conn) -> None:
    fc = _rocks(conn)
    cid = F.insert_feature(conn, fc, _collection("VERTEX"))
    conn.commit()
    member = conn.execute("SELECT geoids[2] FROM tgsis.geometry WHERE geoid = %s", (cid,)).fetchone()
    assert member is not None
    before = _counts(conn, "rocks", "rocks_cellpros")
    with pytest.raises(tgsis.InUseError, match=f"geometry {member[0]} is a member of collection {cid}") as info:
        with reraise():
            conn.execute("SELECT tgsis.delete_geometry(%s)", member)
    assert info.value.hint == f"SELECT tgsis.delete_geometry({cid}) deletes the collection with its members"
    conn.rollback()
    with pytest.raises(psycopg.errors.ForeignKeyViolation):
        conn.execute("DELETE FROM tgsis.geometry WHERE geoid = %s", (cid,))  # plain SQL cannot orphan members
    conn.rollback()
    assert _counts(conn, "rocks", "rocks_cellpros") == before


def test_members_with_different_properties_round_trip(conn: Conn) -> None:
    # a file of several objects, each with properties of its own (issue 16): each member keeps its own
    fc = _rocks(conn)
    surface, lines, points, solid = _members("VERTEX")
    points.vertex_properties = {"value": points.vertex_properties["value"]}  # no code
    lines.vertex_properties = {}  # none at all
    solid.vertex_properties = {"code": solid.vertex_properties["code"]}  # no value
    collection = GeometryCollection([surface, lines, points, solid], name="mixed")
    fid = F.insert_feature(conn, fc, collection)
    conn.commit()
    back = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(back, GeometryCollection) and back.same_as(collection)
    assert [sorted(m.vertex_properties) for m in back] == [["code", "value"], [], ["value"], ["code"]]
    assert all("tgsis_properties" not in m.metadata for m in back)
    # a psql user sees NULL where a member has no such property
    rows = conn.execute(
        "SELECT count(*) FILTER (WHERE value IS NULL), count(*) FILTER (WHERE code IS NULL), count(*) "
        "FROM rocks_cellpros"
    ).fetchone()
    assert rows == (5, 3, 16 + 3 + 5)
    # a member's rows of the properties it has come back, also next to members with all of them
    full = _collection("VERTEX")
    again = F.fetch_features(conn, fc, [fid, F.insert_feature(conn, fc, full)])
    assert again[0].mesh.same_as(collection) and again[1].mesh.same_as(full)  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("make", "error", "message"),
    [
        (
            lambda: GeometryCollection(
                [
                    _members("VERTEX")[0],
                    LineSet(
                        [[0, 0, 0], [1, 0, 0]],
                        [[0, 1]],
                        vertex_properties={"value": [1.0, 2.0], "code": [1, 2], "extra": [0, 0]},
                    ),
                ]
            ),
            tgsis.InvalidPropertyError,
            r"has no column for properties \['extra'\] of member 1 \(LineSet\)",
        ),
        (
            lambda: GeometryCollection(
                [
                    *_members("VERTEX")[:3],
                    TetraMesh(
                        _members()[3].vertices,
                        _members()[3].cells,
                        name="body",
                        vertex_properties={"value": np.zeros(5), "code": np.full(5, 1.5)},
                    ),
                ]
            ),
            tgsis.InvalidPropertyError,
            r"property 'code' has values that are not integer in member 3 \(TetraMesh 'body'\)",
        ),
        (
            lambda: _members("VERTEX")[0],
            tgsis.InvalidGeometryError,
            r"feature class rocks holds GEOMETRYCOLLECTION features, not SURFACE \(Surface\)",
        ),
    ],
)
def test_bad_collection_features_write_nothing(
    conn: Conn, make: Callable[[], Any], error: type[tgsis.Error], message: str
) -> None:
    fc = _rocks(conn)
    before = _counts(conn, "rocks", "rocks_cellpros")
    geometry = make()
    with pytest.raises(error, match=message):
        F.insert_feature(conn, fc, geometry)
    assert _counts(conn, "rocks", "rocks_cellpros") == before


def test_collections_only_go_to_collection_classes_and_failures_roll_back(conn: Conn) -> None:
    fc = _rocks(conn)
    plain = F.create_feature_class(conn, "tops", "SURFACE")
    conn.commit()
    before = _counts(conn, "rocks", "rocks_cellpros", "tops")
    with pytest.raises(
        tgsis.InvalidGeometryError,
        match=r"feature class tops holds SURFACE features, not GEOMETRYCOLLECTION \(GeometryCollection\)",
    ):
        F.insert_feature(conn, plain, GeometryCollection([_surface()]))
    with pytest.raises(tgsis.DatabaseError, match="is of type double precision but expression is of type date"):
        F.insert_feature(conn, fc, _collection("VERTEX"), {"age": datetime.date(2020, 1, 1)})  # after every member
    assert _counts(conn, "rocks", "rocks_cellpros", "tops") == before


def test_sql_refuses_nested_or_foreign_ownership(conn: Conn) -> None:
    plain = F.create_feature_class(conn, "tops", "SURFACE")
    sid = F.insert_feature(conn, plain, _surface())
    cid = conn.execute("SELECT tgsis.new_geometry('GEOMETRYCOLLECTION', 'c', NULL, 0, 0, '{}')").fetchone()
    assert cid is not None
    conn.commit()
    before = _counts(conn)
    for args, error, message in [
        (("GEOMETRYCOLLECTION", cid[0]), tgsis.InvalidGeometryError, "collections do not nest"),
        (("SURFACE", sid), tgsis.InvalidGeometryError, f"geometry {sid} is a SURFACE, not a GEOMETRYCOLLECTION"),
        (("SURFACE", 987654), tgsis.NotFoundError, "collection 987654 of a new SURFACE geometry does not exist"),
    ]:
        with pytest.raises(error, match=message), reraise():
            conn.execute("SELECT tgsis.new_geometry(%s, 'm', NULL, 0, 0, NULL, %s)", args)
        conn.rollback()
    with pytest.raises(psycopg.errors.CheckViolation, match="geometry_members_do_not_nest"):
        conn.execute("UPDATE tgsis.geometry SET collection = %s WHERE geoid = %s", (cid[0], cid[0]))
    conn.rollback()
    assert _counts(conn) == before


def test_broken_stored_collections_give_clear_errors(conn: Conn) -> None:
    groups = F.create_feature_class(conn, "groups", "GEOMETRYCOLLECTION")
    rows = {}
    for name, geoids in (("empty", "{}"), ("dangling", "{424242}")):
        row = conn.execute(
            "SELECT tgsis.new_geometry('GEOMETRYCOLLECTION', %s, NULL, 0, 0, %s)", (name, geoids)
        ).fetchone()
        assert row is not None
        conn.execute("INSERT INTO groups (_geoid) VALUES (%s)", row)
        rows[name] = row[0]
    with pytest.raises(
        tgsis.InvalidGeometryError,
        match=rf"feature\(s\) \[{rows['empty']}\] of class groups are "
        "collections without members",
    ):
        F.fetch_feature(conn, groups, rows["empty"])
    with pytest.raises(
        tgsis.InvalidGeometryError,
        match=rf"member 0 \(geometry 424242\) of feature "
        rf"{rows['dangling']} of class groups does not exist",
    ):
        F.fetch_feature(conn, groups, rows["dangling"])
    assert conn.execute("SELECT problem, example FROM tgsis.check_geometry(%s)", (rows["dangling"],)).fetchall() == [
        ("member geometry does not exist", "424242")
    ]


# --------------------------------------------------------------------------- files (no database)


@pytest.mark.parametrize("encoding", ["binary", "appended"])
def test_vtu_holds_a_mixed_collection_bit_exact(tmp_path: Path, encoding: str) -> None:
    original = _collection("CELL")
    original.members[1].name = None
    path = tmp_path / "block.vtu"
    formats.write(original, path, encoding=encoding)
    back = read_vtu_collection(path)
    assert back.same_as(original) and back.name == "block"
    assert [m.name for m in back] == ["top", None, "samples", "body"]
    assert all(m.cell_properties["code"].dtype == np.int32 for m in back)
    assert [m.same_as(o) for m, o in zip(formats.read(path), original)] == [True] * 4
    root = ET.fromstring(
        path.read_bytes().split(b"<AppendedData")[0] + b"</VTKFile>" if encoding == "appended" else path.read_bytes()
    )
    piece = root.find("UnstructuredGrid/Piece")
    assert piece is not None and piece.get("NumberOfPoints") == "27" and piece.get("NumberOfCells") == "25"
    with pytest.raises(tgsis.FileFormatError, match="holds a GEOMETRYCOLLECTION of 4 members, not one mesh"):
        parse_vtu(path.read_bytes())
    single = _surface()
    formats.write(single, tmp_path / "one.vtu")
    assert read_vtu_collection(tmp_path / "one.vtu").same_as(GeometryCollection([single]))


def test_vtu_cell_types_are_the_members(tmp_path: Path) -> None:
    path = tmp_path / "block.vtu"
    formats.write(_collection(), path, compression=None)  # the raw layout, decoded here by hand
    text = path.read_text()
    types = ET.fromstring(text).find("UnstructuredGrid/Piece/Cells/DataArray[@Name='types']")
    assert types is not None
    import base64

    raw = base64.b64decode(types.text or "")[8:]
    assert np.frombuffer(raw, dtype=np.uint8).tolist() == [5] * 18 + [3] * 2 + [1] * 3 + [10] * 2


def test_vtu_collection_needs_every_property_on_every_member(tmp_path: Path) -> None:
    members = _members()
    members[2] = PointSet(members[2].vertices, vertex_properties={"grade": [1.0, 2.0, 3.0]})
    with pytest.raises(
        tgsis.FileFormatError,
        match=r"vertex property 'grade' is on some members of the collection "
        r"but not on members \[0, 1, 3\]",
    ):
        formats.write(GeometryCollection(members), tmp_path / "bad.vtu")
    assert not (tmp_path / "bad.vtu").exists()


def test_gocad_takes_collections_of_its_type_and_refuses_others(tmp_path: Path) -> None:
    surfaces = GeometryCollection([_surface(name="a"), _surface(z=3, name="b")])
    formats.write(surfaces, tmp_path / "two.ts")
    back = formats.read(tmp_path / "two.ts")
    assert [m.name for m in back] == ["a", "b"] and all(m.same_as(s) for m, s in zip(back, surfaces))
    with pytest.raises(
        tgsis.FileFormatError,
        match=r"tsurf files hold objects of one type \(SURFACE\); a "
        "GEOMETRYCOLLECTION of 4 members mixes SURFACE, MULTILINESTRING, "
        "MULTIPOINT, MULTITETRA",
    ) as info:
        formats.write(_collection(), tmp_path / "mixed.ts")
    assert "vtu" in (info.value.hint or "")
    lines = GeometryCollection(_members()[1:2])
    with pytest.raises(tgsis.FileFormatError, match="tsurf files store SURFACE, not MULTILINESTRING") as info:
        formats.write(lines, tmp_path / "lines.ts")
    assert "pline (.pl)" in (info.value.hint or "")
    formats.write(lines, tmp_path / "lines.pl")
    assert formats.read(tmp_path / "lines.pl")[0].same_as(lines[0])
    with pytest.raises(tgsis.FileFormatError, match="obj files hold one object, not a GEOMETRYCOLLECTION of 2"):
        formats.write(surfaces, tmp_path / "two.obj")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lines.pl", "two.ts"]


# --------------------------------------------------------------------------- command line


def test_cli_import_export_round_trip(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    def run(*args: str) -> int:
        return main(["--dsn", db_dsn, *args])

    assert run("class", "create", "blocks", "--geotype", "GEOMETRYCOLLECTION", "--property", "value:float8") == 0
    surfaces = GeometryCollection(
        [
            Surface(s.vertices, s.cells, name=s.name, vertex_properties={"value": rng.random(s.n_vertices)})
            for s in (_surface(name="upper"), _surface(z=7, name="lower"))
        ]
    )
    source = tmp_path / "horizons.ts"
    formats.write(surfaces, source)
    capsys.readouterr()
    assert run("import", str(source), "--class", "blocks") == 0
    header, first, *member_lines = capsys.readouterr().out.splitlines()
    assert header == "id\tname\tgeotype\tvertices\tcells\treplaced\tdefects"
    fid, name, geotype, *_, count = first.split("\t")
    assert (name, geotype, count) == ("horizons", "GEOMETRYCOLLECTION", "2 members")
    assert [line.split("\t")[1:3] for line in member_lines] == [["member 0", "upper"], ["member 1", "lower"]]
    assert run("ls", "--class", "blocks", "--no-header") == 0
    assert capsys.readouterr().out == f"{fid}\tblocks\thorizons\tGEOMETRYCOLLECTION\t32\t36\t2\t\t\n"  # no properties

    assert run("export", fid, str(tmp_path / "back.ts")) == 0
    assert "in 2 members" in capsys.readouterr().out
    back = formats.read(tmp_path / "back.ts")
    assert [m.name for m in back] == ["upper", "lower"] and all(m.same_as(s) for m, s in zip(back, surfaces))

    # a mixed collection: GOCAD refuses it, VTU takes it, and it comes back in as an equal feature
    with psycopg.connect(db_dsn) as conn:
        mixed = GeometryCollection(
            [
                type(m)(m.vertices, m.cells, name=m.name, vertex_properties={"value": rng.random(m.n_vertices)})
                for m in _members()
            ],
            name="mixed",
        )
        mid = F.insert_feature(conn, "blocks", mixed)
        conn.commit()
    assert run("export", str(mid), str(tmp_path / "mixed.ts")) == 1
    err = capsys.readouterr().err
    assert "tsurf files hold objects of one type (SURFACE)" in err
    assert "mixes SURFACE, MULTILINESTRING, MULTIPOINT, MULTITETRA" in err
    assert not (tmp_path / "mixed.ts").exists()
    assert run("export", str(mid), str(tmp_path / "mixed.vtu")) == 0
    capsys.readouterr()
    assert run("import", str(tmp_path / "mixed.vtu"), "--class", "blocks", "--name", "again") == 0
    again = int(capsys.readouterr().out.splitlines()[1].split("\t")[0])
    with psycopg.connect(db_dsn) as conn:
        stored = F.fetch_feature(conn, "blocks", again)
    assert isinstance(stored.mesh, GeometryCollection) and stored.mesh.same_as(mixed) and stored.name == "again"
