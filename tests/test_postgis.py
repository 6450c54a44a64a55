"""PostGIS, when it is installed (issue 19, part 2; docs/postgis.md).

tgsis features as PostGIS ``TIN Z`` / ``POLYHEDRALSURFACE Z`` /
``MULTILINESTRING Z`` / ``MULTIPOINT Z`` with the class's SRS, answered on by
PostGIS's own functions (ST_NPoints, ST_3DDistance, ST_3DIntersects, ST_SRID,
ST_AsText); their snapshots at t; the per-class view QGIS lists; PostGIS
geometries stored as features (SQL and Python); and PostGIS optional: tgsis
installs without it, with it before or after, dumps and restores.

PostGIS exists only for the system PostgreSQL 15 (as in CI and the Docker
image). Whichever server the rest of the suite runs on, these tests start a
throwaway cluster of it, as ``tests/test_install_commands.py`` does, and
fail, not skip, when PostGIS is missing there. The tests of tgsis without
PostGIS also run on the session's own server (PostgreSQL 18 has none).
"""

from __future__ import annotations

import contextlib
import math
import struct
import subprocess
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.roles import login_roles
from tests.synthetic import flat_grid
from tests.temporal_data import evolving, series
from tgsis.db.local import LocalServer, find_binaries
from tgsis.db.sqlsource import ExtensionSources
from tgsis.errors import reraise
from tgsis.postgis import mesh_from_wkb, mesh_to_ewkb
from tgsis.testing import default_storage

Conn = psycopg.Connection[Any]


class GisServer:
    """A throwaway cluster of the system PostgreSQL with PostGIS, and databases on it."""

    def __init__(self, server: LocalServer) -> None:
        self.server = server
        self.bindir = server.binaries.bindir
        self.template = "gis_template"
        server.ensure_database(self.template)
        with psycopg.connect(server.dsn(self.template)) as conn:  # tgsis first, PostGIS after it
            tgsis.install(conn, method="sql", storage=default_storage())  # TGSIS_TEST_STORAGE's (docs/testing.md)
            conn.execute("CREATE EXTENSION postgis")
        with psycopg.connect(server.dsn("postgres"), autocommit=True) as conn:
            conn.execute(sql.SQL("ALTER DATABASE {} IS_TEMPLATE true").format(sql.Identifier(self.template)))

    @contextlib.contextmanager
    def database(self, template: str | None = None) -> Iterator[str]:
        """A new database (from the template with tgsis and PostGIS, or ``template0``), dropped afterwards."""
        name = f"gis_{uuid.uuid4().hex[:10]}"
        with psycopg.connect(self.server.dsn("postgres"), autocommit=True) as conn:
            conn.execute(
                sql.SQL("CREATE DATABASE {} TEMPLATE {}").format(
                    sql.Identifier(name), sql.Identifier(template or self.template)
                )
            )
        try:
            yield self.server.dsn(name)
        finally:
            with psycopg.connect(self.server.dsn("postgres"), autocommit=True) as conn:
                conn.execute(sql.SQL("DROP DATABASE IF EXISTS {} WITH (FORCE)").format(sql.Identifier(name)))

    def extension_files(self) -> str | None:
        """Why CREATE EXTENSION tgsis cannot run this checkout's SQL on this cluster, or None."""
        sharedir = self.server.binaries.sharedir
        assert sharedir is not None
        installed = sharedir / "extension" / f"tgsis--{ExtensionSources.default().version}.sql"
        if not installed.exists() or installed.read_text(encoding="utf-8") != ExtensionSources.default().script():
            return f"{installed} is not this checkout's SQL (the throwaway cluster's own share folder)"
        return None


@pytest.fixture(scope="module")
def gis() -> Iterator[GisServer]:
    binaries = find_binaries("system")
    sharedir = binaries.sharedir
    assert sharedir is not None, f"{binaries.describe()} has no pg_config"
    if not (sharedir / "extension" / "postgis.control").exists():
        pytest.fail(
            f"PostGIS is not installed for {binaries.describe()}: apt-get install postgresql-15-postgis-3 "
            "(CI and the Docker image have it)",
            pytrace=False,
        )
    server = LocalServer.throwaway(binaries)
    try:
        yield GisServer(server)
    finally:
        server.destroy()


@pytest.fixture
def gconn(gis: GisServer) -> Iterator[Conn]:
    """A connection to a fresh database with tgsis and PostGIS, PostGIS functions enabled."""
    with gis.database() as dsn, psycopg.connect(dsn, autocommit=True) as conn:
        tgsis.enable_postgis(conn)
        yield conn


def _one(conn: Conn, query: str, params: tuple[Any, ...] = ()) -> Any:
    """The one value of a query; errors as tgsis's exceptions (tgsis.errors.reraise), as a client sees them."""
    with reraise():
        row = conn.execute(query, params).fetchone()
    assert row is not None
    return row[0]


def _random_surface(rng: np.random.Generator, n: int = 6) -> tgsis.Surface:
    surface = flat_grid(n, 0.0)
    vertices = (
        surface.vertices * 1000.0 + rng.normal(scale=1.0, size=surface.vertices.shape) + [326126.29688, 3.8e6, -1200]
    )
    return tgsis.Surface(vertices, surface.cells)


def _tetra_block() -> tgsis.TetraMesh:
    """A unit cube cut into five tetrahedra, some of them listed with a negative orientation."""
    cube = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]], float)
    tetras = np.array([[0, 1, 2, 4], [1, 3, 2, 7], [1, 4, 5, 7], [2, 7, 6, 4], [1, 2, 4, 7]])
    return tgsis.TetraMesh(cube + [500.0, 600.0, -50.0], tetras)


def _signed_volume(mesh: tgsis.Surface) -> float:
    p, t = mesh.vertices, mesh.cells
    return float(np.einsum("ij,ij->i", p[t[:, 0]], np.cross(p[t[:, 1]], p[t[:, 2]])).sum() / 6.0)


# ---------------------------------------------------------------- features as PostGIS geometries


def test_a_surface_is_a_tin_z_with_the_class_srid_bit_for_bit(gconn: Conn) -> None:
    rng = np.random.default_rng(19)
    surface = _random_surface(rng)
    tgsis.create_feature_class(gconn, "faults", "SURFACE", feature_properties={"release": "text"}, srs=32611)
    fid = tgsis.insert_feature(gconn, "faults", surface, {"release": "5.3"})
    kind, srid, npoints, ngeoms, ndims = gconn.execute(
        "SELECT ST_GeometryType(g), ST_SRID(g), ST_NPoints(g), ST_NumGeometries(g), ST_NDims(g) "
        "FROM tgsis.postgis_geometry('faults', %s) g",
        (fid,),
    ).fetchone()  # type: ignore[misc]
    assert (kind, srid, ndims) == ("ST_Tin", 32611, 3)
    assert ngeoms == len(surface.cells) and npoints == 4 * len(surface.cells)  # each triangle's ring closes
    # PostGIS's own EWKB of it is tgsis's, byte for byte, and Python writes the same
    ours = bytes(_one(gconn, "SELECT ST_AsEWKB(tgsis.postgis_geometry('faults', %s), 'XDR')", (fid,)))
    assert ours == mesh_to_ewkb(surface, 32611) == tgsis.fetch_ewkb(gconn, "faults", fid)
    # and every coordinate is the stored double: PostGIS reads them back exactly
    back = mesh_from_wkb(_one(gconn, "SELECT tgsis.postgis_geometry('faults', %s)", (fid,)))
    assert isinstance(back, tgsis.Surface) and back.metadata["srid"] == 32611
    # (vertices numbered by first appearance in the triangles: the same triangles, corner for corner)
    assert np.array_equal(back.vertices[back.cells], surface.vertices[surface.cells])
    assert len(back.vertices) == len(surface.vertices)
    # a text round trip through PostGIS gives the same TIN
    assert _one(
        gconn,
        "SELECT ST_AsText(ST_GeomFromText(ST_AsText(g, 17))) = ST_AsText(g, 17) "
        "FROM tgsis.postgis_geometry('faults', %s) g",
        (fid,),
    )
    assert _one(gconn, "SELECT ST_AsText(g) FROM tgsis.postgis_geometry('faults', %s) g", (fid,)).startswith(
        "TIN Z ((("
    )


def test_postgis_measures_distances_and_intersections_between_tgsis_surfaces(gconn: Conn) -> None:
    tgsis.create_feature_class(gconn, "horizons", "SURFACE", srs=2056)
    low = tgsis.insert_feature(gconn, "horizons", flat_grid(4, 0.0))
    high = tgsis.insert_feature(gconn, "horizons", flat_grid(4, 7.5))
    tilted = flat_grid(4, 0.0)
    tilted.vertices[:, 2] = tilted.vertices[:, 0] * 5.0 - 5.0  # from -5 to 10: crosses both
    cross = tgsis.insert_feature(gconn, "horizons", tilted)
    g = "tgsis.postgis_geometry('horizons', {})".format
    assert _one(gconn, f"SELECT ST_3DDistance({g(low)}, {g(high)})") == pytest.approx(7.5)
    assert _one(gconn, f"SELECT ST_3DIntersects({g(low)}, {g(high)})") is False
    assert _one(gconn, f"SELECT ST_3DIntersects({g(low)}, {g(cross)})") is True
    assert _one(gconn, f"SELECT ST_3DIntersects({g(high)}, {g(cross)})") is True
    # a well, as a PostGIS line, meets the lower horizon only where it reaches it
    well = "ST_GeomFromText('LINESTRING Z (1.5 1.5 -3, 1.5 1.5 3)', 2056)"
    short = "ST_GeomFromText('LINESTRING Z (1.5 1.5 2, 1.5 1.5 3)', 2056)"
    assert _one(gconn, f"SELECT ST_3DIntersects({g(low)}, {well})") is True
    assert _one(gconn, f"SELECT ST_3DIntersects({g(low)}, {short})") is False
    assert _one(gconn, f"SELECT ST_3DDistance({g(low)}, {short})") == pytest.approx(2.0)
    # two SRIDs do not mix silently: PostGIS refuses
    tgsis.create_feature_class(gconn, "other", "SURFACE", srs=4326)
    elsewhere = tgsis.insert_feature(gconn, "other", flat_grid(2, 0.0))
    with pytest.raises(psycopg.Error, match="SRID"):
        gconn.execute(f"SELECT ST_3DDistance({g(low)}, tgsis.postgis_geometry('other', {elsewhere}))")


def test_a_solid_is_the_closed_polyhedral_surface_of_its_boundary_facing_outwards(gconn: Conn) -> None:
    block = _tetra_block()
    tgsis.create_feature_class(gconn, "bodies", "MULTITETRA", srs=32632)
    fid = tgsis.insert_feature(gconn, "bodies", block)
    kind, srid, faces, closed = gconn.execute(
        "SELECT ST_GeometryType(g), ST_SRID(g), ST_NumGeometries(g), ST_IsClosed(g) "
        "FROM tgsis.postgis_geometry('bodies', %s) g",
        (fid,),
    ).fetchone()  # type: ignore[misc]
    assert (kind, srid, faces, closed) == ("ST_PolyhedralSurface", 32632, 12, True)  # 6 squares, 2 triangles each
    boundary = mesh_from_wkb(_one(gconn, "SELECT tgsis.postgis_geometry('bodies', %s)", (fid,)))
    assert isinstance(boundary, tgsis.Surface) and len(boundary.vertices) == 8
    assert _signed_volume(boundary) == pytest.approx(1.0)  # outward faces enclose +1; inward would be -1
    assert bytes(tgsis.fetch_ewkb(gconn, "bodies", fid) or b"") == mesh_to_ewkb(block, 32632)
    inside = "ST_GeomFromText('POINT Z (500.5 600.5 -49.5)', 32632)"
    assert _one(gconn, f"SELECT ST_3DDistance(tgsis.postgis_geometry('bodies', {fid}), {inside})") == pytest.approx(0.5)


def test_lines_points_and_collections_become_their_postgis_types(gconn: Conn) -> None:
    tgsis.create_feature_class(gconn, "traces", "MULTILINESTRING", srs=32611)
    tgsis.create_feature_class(gconn, "picks", "MULTIPOINT", srs=32611)
    tgsis.create_feature_class(gconn, "groups", "GEOMETRYCOLLECTION", srs=32611)
    line = tgsis.LineSet([[0, 0, 0], [1, 0, 0], [1, 1, 2]], [[0, 1], [1, 2]])
    points = tgsis.PointSet([[5.0, 5, 5], [6, 6, 6.25]])
    lid = tgsis.insert_feature(gconn, "traces", line)
    pid = tgsis.insert_feature(gconn, "picks", points)
    gid = tgsis.insert_feature(gconn, "groups", tgsis.GeometryCollection([line, points, flat_grid(2, 1.0)]))
    text = "SELECT ST_AsText(tgsis.postgis_geometry(%s, %s))"
    assert _one(gconn, text, ("traces", lid)) == "MULTILINESTRING Z ((0 0 0,1 0 0),(1 0 0,1 1 2))"
    assert _one(gconn, text, ("picks", pid)) == "MULTIPOINT Z ((5 5 5),(6 6 6.25))"
    kinds = gconn.execute(
        "SELECT ST_GeometryType((d).geom), ST_SRID((d).geom) FROM ST_Dump(tgsis.postgis_geometry('groups', %s)) d",
        (gid,),
    ).fetchall()
    assert kinds == [("ST_LineString", 32611)] * 2 + [("ST_Point", 32611)] * 2 + [("ST_Triangle", 32611)] * 2
    assert _one(gconn, "SELECT GeometryType(tgsis.postgis_geometry('groups', %s))", (gid,)) == "GEOMETRYCOLLECTION"


def test_the_shape_at_t_is_the_snapshot_python_computes(gconn: Conn) -> None:
    rng = np.random.default_rng(7)
    tgsis.create_feature_class(gconn, "moving", "SURFACE", time_model="EVOLVING", time_unit="Ma", srs=32611)
    tgsis.create_feature_class(gconn, "steps", "SURFACE", time_model="INSTANTS", srs=32611)
    mid = tgsis.insert_feature(gconn, "moving", evolving(rng, [-10.0, -5.0]))
    sid = tgsis.insert_feature(gconn, "steps", series(rng, [0.0, 1.0, 2.0]))
    for class_name, fid, t in [
        ("moving", mid, -7.25),
        ("moving", mid, -5.0),
        ("moving", mid, -4.5),
        ("steps", sid, 0.5),
        ("steps", sid, 2.0),
    ]:
        shape = tgsis.get_at(gconn, fid, t)
        assert shape is not None
        geom = _one(gconn, "SELECT ST_AsEWKB(tgsis.postgis_geometry_at(%s, %s, %s), 'XDR')", (class_name, fid, t))
        assert bytes(geom) == mesh_to_ewkb(shape, 32611), (class_name, t)
        assert _one(
            gconn, "SELECT ST_NumGeometries(tgsis.postgis_geometry_at(%s, %s, %s))", (class_name, fid, t)
        ) == len(shape.cells)
    # outside its life a feature has no geometry: NULL, as get_at gives None
    assert _one(gconn, "SELECT tgsis.postgis_geometry_at('moving', %s, -11)", (mid,)) is None
    assert _one(gconn, "SELECT tgsis.postgis_geometry_at('moving', %s, 99)", (mid,)) is None
    assert tgsis.fetch_ewkb(gconn, "moving", mid, -11.0) is None
    # a temporal feature has no shape without a time; a bad time is refused
    with pytest.raises(tgsis.InvalidInputError, match="depends on the time") as err:
        _one(gconn, "SELECT tgsis.postgis_geometry('moving', %s)", (mid,))
    assert err.value.sqlstate == "TG100" and "postgis_geometry_at" in (err.value.hint or "")
    with pytest.raises(tgsis.InvalidInputError):
        _one(gconn, "SELECT tgsis.postgis_geometry_at('moving', %s, 'NaN')", (mid,))
    with pytest.raises(tgsis.InvalidInputError):
        tgsis.fetch_ewkb(gconn, "moving", mid, -7.0, convention="middle")  # type: ignore[arg-type]


def test_a_wrong_class_or_feature_is_named(gconn: Conn) -> None:
    tgsis.create_feature_class(gconn, "faults", "SURFACE", srs=32611)
    tgsis.create_feature_class(gconn, "others", "SURFACE", srs=4326)
    fid = tgsis.insert_feature(gconn, "faults", flat_grid(2, 0.0))
    with pytest.raises(tgsis.NotFoundError, match="feature class 'nope' does not exist"):
        _one(gconn, "SELECT tgsis.postgis_geometry('nope', %s)", (fid,))
    # the feature of another class would get that class's SRID: refused
    with pytest.raises(tgsis.NotFoundError, match=f"feature {fid} of class others does not exist"):
        _one(gconn, "SELECT tgsis.postgis_geometry('others', %s)", (fid,))
    with pytest.raises(tgsis.NotFoundError):
        tgsis.fetch_ewkb(gconn, "faults", fid + 1000)


def test_g_maps_have_no_postgis_form_and_say_so(gconn: Conn) -> None:
    from tgsis import gmaps

    tgsis.create_feature_class(gconn, "blocks", "GMAP", time_model="GMAP", cell_level=2)
    square = gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    period = gmaps.GMapPeriod([0.0, 1.0], square, np.stack([square.points, square.points + [0, 0, 1]]), level=2)
    fid = tgsis.insert_gmap(gconn, "blocks", gmaps.EvolvingGMap([period]))
    for query in ("SELECT tgsis.postgis_geometry('blocks', %s)", "SELECT tgsis.postgis_geometry_at('blocks', %s, 0.5)"):
        with pytest.raises(tgsis.InvalidInputError, match="GMAP .* has no PostGIS form"):
            _one(gconn, query, (fid,))
    with pytest.raises(tgsis.InvalidInputError, match="GMAP features, which have no PostGIS form"):
        tgsis.create_postgis_view(gconn, "blocks")


# ---------------------------------------------------------------- the view QGIS lists


def test_the_class_view_is_a_postgis_layer_and_follows_versions(gconn: Conn) -> None:
    tgsis.create_feature_class(gconn, "faults", "SURFACE", feature_properties={"release": "text"}, srs=32611)
    a = tgsis.insert_feature(gconn, "faults", flat_grid(3, 0.0), {"release": "5.3"})
    b = tgsis.insert_feature(gconn, "faults", flat_grid(3, 10.0), {"release": "6.1"})
    assert tgsis.create_postgis_view(gconn, "faults") == "faults_postgis"
    # what QGIS reads to list a layer: type, SRID and dimension of the column
    assert gconn.execute(
        "SELECT type, srid, coord_dimension FROM geometry_columns "
        "WHERE f_table_name = 'faults_postgis' AND f_geometry_column = 'geom'"
    ).fetchall() == [("TIN", 32611, 3)]
    rows = gconn.execute(
        "SELECT _geoid, release, ST_3DDistance(geom, ST_GeomFromText('POINT Z (1 1 4)', 32611)) "
        "FROM faults_postgis ORDER BY _geoid"
    ).fetchall()
    assert rows == [(a, "5.3", pytest.approx(4.0)), (b, "6.1", pytest.approx(6.0))]
    assert "tgsis PostGIS view" in _one(gconn, "SELECT obj_description('faults_postgis'::regclass)")
    # feature versioning replaces the feature table by a view: the layer shows each version's rows
    tgsis.enable_feature_versioning(gconn)
    tgsis.create_version(gconn, "lifted")
    with tgsis.in_version(gconn, "lifted"):
        gconn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (a,))
        assert _one(gconn, "SELECT ST_ZMax(geom) FROM faults_postgis WHERE _geoid = %s", (a,)) == 1.0
    assert _one(gconn, "SELECT ST_ZMax(geom) FROM faults_postgis WHERE _geoid = %s", (a,)) == 0.0
    # an edit of the class re-creates the layer with the new columns
    tgsis.add_property(gconn, "faults", ("basin", "text"), kind="feature", default="Mojave")
    tgsis.rename_property(gconn, "faults", "release", "release_ma")
    assert gconn.execute(
        "SELECT _geoid, release_ma, basin, ST_ZMax(geom) FROM faults_postgis ORDER BY _geoid"
    ).fetchall() == [(a, "5.3", "Mojave", 0.0), (b, "6.1", "Mojave", 10.0)]
    assert "tgsis PostGIS view" in _one(gconn, "SELECT obj_description('faults_postgis'::regclass)")
    # created again (e.g. after a class change) it replaces itself; a foreign relation of that name is kept
    tgsis.create_postgis_view(gconn, "faults")
    tgsis.create_feature_class(gconn, "wells", "MULTILINESTRING")
    gconn.execute("CREATE TABLE wells_postgis (x int)")
    with pytest.raises(tgsis.AlreadyExistsError, match="wells_postgis exists"):
        tgsis.create_postgis_view(gconn, "wells")
    # dropping the class drops its view (and only its own)
    tgsis.drop_feature_class(gconn, "faults", force=True)
    assert _one(gconn, "SELECT to_regclass('faults_postgis')") is None
    tgsis.drop_feature_class(gconn, "wells", force=True)
    assert _one(gconn, "SELECT to_regclass('wells_postgis')") is not None


def test_a_temporal_class_view_has_a_row_per_instant(gconn: Conn) -> None:
    rng = np.random.default_rng(3)
    tgsis.create_feature_class(gconn, "moving", "SURFACE", time_model="EVOLVING", time_unit="Ma", srs=32611)
    surface = evolving(rng, [-10.0, -5.0])
    fid = tgsis.insert_feature(gconn, "moving", surface)
    tgsis.create_postgis_view(gconn, "moving")
    rows = gconn.execute(
        "SELECT _t, ST_AsEWKB(geom, 'XDR') FROM moving_postgis WHERE _geoid = %s ORDER BY _t", (fid,)
    ).fetchall()
    instants = [t for t, _ in tgsis.instants(gconn, fid)]
    assert [r[0] for r in rows] == instants
    for t, geom in rows:
        shape = tgsis.get_at(gconn, fid, t)
        assert shape is not None and bytes(geom) == mesh_to_ewkb(shape, 32611)


# ---------------------------------------------------------------- PostGIS geometries into tgsis


def test_postgis_geometries_are_stored_as_features_in_sql(gconn: Conn) -> None:
    tgsis.create_feature_class(gconn, "faults", "SURFACE", feature_properties={"release": "text"}, srs=32611)
    tgsis.create_feature_class(gconn, "traces", "MULTILINESTRING", srs=32611)
    tin = "TIN Z (((0 0 0,1 0 0,0 1 0.5,0 0 0)),((1 0 0,1 1 1,0 1 0.5,1 0 0)))"
    fid = _one(
        gconn,
        "SELECT tgsis.insert_postgis_feature('faults', ST_GeomFromText(%s, 32611), '{\"release\": \"7\"}', 'imported')",
        (tin,),
    )
    assert _one(gconn, "SELECT ST_AsText(tgsis.postgis_geometry('faults', %s))", (fid,)) == tin
    feature = tgsis.fetch_feature(gconn, "faults", fid)
    assert feature.properties["release"] == "7" and isinstance(feature.mesh, tgsis.Mesh)
    assert feature.mesh.name == "imported"
    assert len(feature.mesh.vertices) == 4  # shared corners are one vertex
    assert _one(gconn, "SELECT nvrtx FROM tgsis.geometry WHERE geoid = %s", (fid,)) == 4
    assert tgsis.features_in_box(gconn, "faults", [[0, 0, 0], [1, 1, 1]]) == [fid]
    # a polyhedral surface with a quad face: the quad is two triangles
    quad = "POLYHEDRALSURFACE Z (((0 0 5,1 0 5,1 1 5,0 1 5,0 0 5)))"
    qid = _one(gconn, "SELECT tgsis.insert_postgis_feature('faults', %s::geometry)", (quad,))
    assert (
        _one(gconn, "SELECT ST_AsText(tgsis.postgis_geometry('faults', %s))", (qid,))
        == "TIN Z (((0 0 5,1 0 5,1 1 5,0 0 5)),((0 0 5,1 1 5,0 1 5,0 0 5)))"
    )
    line = "MULTILINESTRING Z ((0 0 0,1 0 0,1 1 1),(5 5 5,6 6 6))"
    lid = _one(gconn, "SELECT tgsis.insert_postgis_feature('traces', %s::geometry)", (line,))
    assert (
        _one(gconn, "SELECT ST_AsText(tgsis.postgis_geometry('traces', %s))", (lid,))
        == "MULTILINESTRING Z ((0 0 0,1 0 0),(1 0 0,1 1 1),(5 5 5,6 6 6))"
    )
    mesh = gconn.execute(
        "SELECT geotype, vertices, cells FROM tgsis.mesh_from_postgis(%s::geometry)", (line,)
    ).fetchone()
    assert mesh == (
        "MULTILINESTRING",
        [[0, 0, 0], [1, 0, 0], [1, 1, 1], [5, 5, 5], [6, 6, 6]],
        [[0, 1], [1, 2], [3, 4]],
    )


def test_python_and_sql_read_a_postgis_geometry_alike(gconn: Conn) -> None:
    rng = np.random.default_rng(5)
    surface = _random_surface(rng, 9)
    cases = [
        mesh_to_ewkb(surface, 32611).hex(),  # regular: one numpy step
        _one(
            gconn,
            "SELECT ST_GeomFromText('POLYHEDRALSURFACE Z (((0 0 0,2 0 0,2 2 0,0 2 0,0 0 0)),"
            "((0 0 0,0 2 0,-1 3 1,-2 1 1,-1 -1 1,0 0 0)),((2 0 0,2 2 0,3 1 2,2 0 0)))')",
        ),  # faces of 4, 5, 3
        _one(gconn, "SELECT 'MULTILINESTRING Z ((0 0 0,1 0 0,1 1 1),(1 1 1,5 5 5))'::geometry"),
        _one(gconn, "SELECT 'POINT Z (1 2 3)'::geometry"),
        _one(gconn, "SELECT 'TRIANGLE Z ((0 0 0,1 0 0,0 1 1,0 0 0))'::geometry"),
    ]
    for case in cases:
        mesh = mesh_from_wkb(case)
        geotype, vertices, cells = gconn.execute(
            "SELECT geotype, vertices, cells FROM tgsis.mesh_from_postgis(%s::geometry)", (case,)
        ).fetchone()  # type: ignore[misc]
        assert mesh.geotype.value == geotype
        assert np.array_equal(mesh.vertices, np.array(vertices)), geotype
        assert np.array_equal(mesh.cells, np.array(cells)), geotype


def test_reading_a_large_tin_in_sql_takes_linear_time(gconn: Conn) -> None:
    """Self-joins of the points made tgsis.mesh_from_postgis quadratic: 3,042 triangles took 26 s (measured).

    No timing assert on the linear case: a statement timeout far above its
    time (about 1 s) and below the quadratic one (minutes) stops a regression
    instead of letting it hang the suite. It is still a bound in seconds,
    but one only a machine about 100x slower than this one would miss.
    """
    n = 80
    u, v = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel() / 7)], axis=1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    surface = tgsis.Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))
    gconn.execute("SET statement_timeout = '120s'")  # the connection is this test's (autocommit)
    cells = _one(
        gconn,
        "SELECT array_length(cells, 1) FROM tgsis.mesh_from_postgis(%s::bytea::geometry)",
        (mesh_to_ewkb(surface, 0),),
    )
    assert cells == len(surface.cells) == 12482
    gconn.execute("RESET statement_timeout")


def test_every_geotype_gets_its_layer_type(gconn: Conn) -> None:
    classes: dict[str, tuple[str, tgsis.Mesh | tgsis.GeometryCollection, str]] = {
        "bodies": ("MULTITETRA", _tetra_block(), "POLYHEDRALSURFACE"),
        "traces": ("MULTILINESTRING", tgsis.LineSet([[0, 0, 0], [1, 0, 0]], [[0, 1]]), "MULTILINESTRING"),
        "picks": ("MULTIPOINT", tgsis.PointSet([[5, 5, 5]]), "MULTIPOINT"),
        "groups": ("GEOMETRYCOLLECTION", tgsis.GeometryCollection([tgsis.PointSet([[5, 5, 5]])]), "GEOMETRYCOLLECTION"),
    }
    for name, (geotype, mesh, _) in classes.items():
        tgsis.create_feature_class(gconn, name, geotype, srs=3857)
        tgsis.insert_feature(gconn, name, mesh)
        tgsis.create_postgis_view(gconn, name)
    found = dict(
        gconn.execute(
            "SELECT f_table_name, type FROM geometry_columns WHERE srid = 3857 AND coord_dimension = 3"
        ).fetchall()
    )
    assert found == {f"{name}_postgis": kind for name, (_, _, kind) in classes.items()}
    for name in classes:
        assert _one(gconn, f"SELECT count(geom) FROM {name}_postgis") == 1


def test_a_postgis_feature_stored_in_a_version_stays_there(gconn: Conn) -> None:
    tgsis.create_feature_class(gconn, "faults", "SURFACE", srs=32611)
    tgsis.enable_feature_versioning(gconn)
    tgsis.create_version(gconn, "draft")
    with tgsis.in_version(gconn, "draft"):
        fid = _one(
            gconn, "SELECT tgsis.insert_postgis_feature('faults', 'TIN Z (((0 0 0,1 0 0,0 1 0,0 0 0)))'::geometry)"
        )
        assert _one(gconn, "SELECT ST_NPoints(tgsis.postgis_geometry('faults', %s))", (fid,)) == 4
    with pytest.raises(tgsis.NotFoundError):  # DEFAULT does not see it
        _one(gconn, "SELECT tgsis.postgis_geometry('faults', %s)", (fid,))


def test_an_upgrade_makes_the_postgis_functions_again(gis: GisServer, tmp_path: Path) -> None:
    import shutil

    from tgsis.db.sqlsource import find_sql_dir

    def sources_at(version: str, updates: dict[str, str]) -> ExtensionSources:
        root = tmp_path / f"sql-{version}"
        shutil.copytree(find_sql_dir(), root, ignore=shutil.ignore_patterns("build"))
        control = root / "tgsis.control"
        control.write_text(control.read_text().replace(f"'{tgsis.__version__}'", f"'{version}'"))
        (root / "updates").mkdir(exist_ok=True)
        for name, text in updates.items():
            (root / "updates" / name).write_text(text)
        return ExtensionSources(root)

    # an upgrade that changes a wrapper's signature: the script drops the old one, install() makes the new
    script = """\\echo Use "CREATE EXTENSION tgsis" to load this file. \\quit
DROP FUNCTION IF EXISTS tgsis.postgis_geometry_at(text, bigint, double precision, text);
INSERT INTO tgsis.installation (version, method) VALUES ('0.1.1', 'sql');
"""
    old = sources_at("0.0.9", {})
    new = sources_at("0.1.1", {"tgsis--0.0.9--0.1.1.sql": script})
    with gis.database("template0") as dsn, psycopg.connect(dsn, autocommit=True) as conn:
        conn.execute("CREATE EXTENSION postgis")
        tgsis.install(conn, method="sql", sources=old)
        tgsis.enable_postgis(conn)
        assert tgsis.install(conn, sources=new).action == "upgraded"
        assert (
            _one(
                conn,
                "SELECT to_regprocedure('tgsis.postgis_geometry_at(text, bigint, double precision, text)') IS NOT NULL",
            )
            is True
        )


@pytest.mark.parametrize(
    "geom, error, words",
    [
        ("'TIN (((0 0,1 0,0 1,0 0)))'::geometry", tgsis.InvalidGeometryError, "not x, y, z"),
        (
            "'POLYGON Z ((0 0 0,9 0 0,0 9 0,0 0 0),(1 1 0,2 1 0,1 2 0,1 1 0))'::geometry",
            tgsis.InvalidGeometryError,
            "holes",
        ),
        ("'TIN Z (((0 0 0,0 0 0,0 1 0,0 0 0)))'::geometry", tgsis.InvalidGeometryError, "repeats a vertex"),
        ("'TIN Z EMPTY'::geometry", tgsis.InvalidGeometryError, "empty"),
        ("'MULTIPOINT Z ((0 0 0))'::geometry", tgsis.InvalidInputError, "holds SURFACE features"),
        ("'GEOMETRYCOLLECTION Z (POINT Z (0 0 0))'::geometry", tgsis.InvalidGeometryError, "no tgsis geotype"),
        ("'TIN Z (((0 0 0,1 0 0,0 1 0,0 0 0)))'::text", tgsis.InvalidInputError, "is not a PostGIS geometry"),
    ],
)
def test_a_geometry_tgsis_cannot_store_is_refused_and_nothing_is_written(
    gconn: Conn, geom: str, error: type, words: str
) -> None:
    tgsis.create_feature_class(gconn, "faults", "SURFACE", feature_properties={"release": "text"})
    with pytest.raises(error, match=words):
        _one(gconn, f"SELECT tgsis.insert_postgis_feature('faults', {geom})")
    assert _one(gconn, "SELECT count(*) FROM tgsis.geometry") == 0
    assert _one(gconn, "SELECT count(*) FROM faults") == 0


def test_properties_and_classes_a_geometry_cannot_fill_are_refused(gconn: Conn) -> None:
    tin = "'TIN Z (((0 0 0,1 0 0,0 1 0,0 0 0)))'::geometry"
    tgsis.create_feature_class(gconn, "faults", "SURFACE", feature_properties={"release": "text"})
    tgsis.create_feature_class(gconn, "porous", "SURFACE", cell_properties={"porosity": "float8"})
    tgsis.create_feature_class(gconn, "moving", "SURFACE", time_model="EVOLVING")
    with pytest.raises(tgsis.InvalidPropertyError, match="no feature properties colour") as err:
        _one(gconn, f"SELECT tgsis.insert_postgis_feature('faults', {tin}, '{{\"colour\": 1}}')")
    assert "release" in (err.value.hint or "")
    with pytest.raises(tgsis.InvalidPropertyError, match="vertex or cell properties"):
        _one(gconn, f"SELECT tgsis.insert_postgis_feature('porous', {tin})")
    with pytest.raises(tgsis.InvalidInputError, match="EVOLVING"):
        _one(gconn, f"SELECT tgsis.insert_postgis_feature('moving', {tin})")
    assert _one(gconn, "SELECT count(*) FROM tgsis.geometry") == 0


def test_postgis_geometries_are_read_and_stored_from_python(gconn: Conn) -> None:
    tgsis.create_feature_class(gconn, "faults", "SURFACE", feature_properties={"release": "text"}, srs=32611)
    # what psycopg hands over for a geometry column: hex EWKB text
    hexed = _one(
        gconn,
        "SELECT ST_GeomFromText('POLYHEDRALSURFACE Z (((0 0 0,1 0 0,1 1 0,0 1 0,0 0 0)),"
        "((0 0 0,0 1 0,0 0 1,0 0 0)))', 32611)",
    )
    assert isinstance(hexed, str)
    mesh = mesh_from_wkb(hexed)
    assert isinstance(mesh, tgsis.Surface) and mesh.metadata["srid"] == 32611
    assert mesh.cells.tolist() == [[0, 1, 2], [0, 2, 3], [0, 3, 4]]
    fid = tgsis.insert_wkb_feature(gconn, "faults", hexed, {"release": "x"}, name="from postgis")
    assert (
        _one(gconn, "SELECT ST_AsText(tgsis.postgis_geometry('faults', %s))", (fid,))
        == "TIN Z (((0 0 0,1 0 0,1 1 0,0 0 0)),((0 0 0,1 1 0,0 1 0,0 0 0)),((0 0 0,0 1 0,0 0 1,0 0 0)))"
    )
    # little-endian ISO WKB (ST_AsBinary) reads the same
    iso = bytes(_one(gconn, "SELECT ST_AsBinary(tgsis.postgis_geometry('faults', %s), 'NDR')", (fid,)))
    again = mesh_from_wkb(iso)
    assert np.array_equal(again.vertices, mesh.vertices) and "srid" not in again.metadata
    lines = mesh_from_wkb(_one(gconn, "SELECT 'LINESTRING Z (0 0 0, 1 1 1, 2 2 2)'::geometry"))
    assert isinstance(lines, tgsis.LineSet) and lines.cells.tolist() == [[0, 1], [1, 2]]


@pytest.mark.parametrize(
    "data, words",
    [
        ("00000000", "ends at byte 4"),
        ("zz", "not hex-encoded"),
        ("0300000001", "not a byte order"),
        ("0101000000" + "00" * 16, "no z coordinates"),
        ("01" + struct.pack("<I", 1008).hex() + "00000000", "type 8 is none"),
    ],
)
def test_python_refuses_wkb_it_cannot_read(data: str, words: str) -> None:
    with pytest.raises(tgsis.InvalidInputError, match=words):
        mesh_from_wkb(data)


# ---------------------------------------------------------------- PostGIS is optional; roles


def test_without_postgis_tgsis_says_how_to_get_it_and_ewkb_still_works(conn: Conn) -> None:
    """On the session's own server (PostgreSQL 18 has no PostGIS; the PG15 template has none installed)."""
    assert _one(conn, "SELECT count(*) FROM pg_extension WHERE extname = 'postgis'") == 0
    with pytest.raises(tgsis.InstallationError, match="PostGIS is not installed") as err:
        tgsis.enable_postgis(conn)
    assert "CREATE EXTENSION postgis" in (err.value.hint or "")
    with pytest.raises(tgsis.InstallationError):
        tgsis.create_feature_class(conn, "faults", "SURFACE", srs=32611)
        conn.commit()
        tgsis.create_postgis_view(conn, "faults")
    conn.rollback()
    # the EWKB functions need no PostGIS: a client with a PostGIS of its own can still use them
    tgsis.create_feature_class(conn, "faults2", "SURFACE", srs=32611)
    surface = flat_grid(3, 2.0)
    fid = tgsis.insert_feature(conn, "faults2", surface)
    assert tgsis.fetch_ewkb(conn, "faults2", fid) == mesh_to_ewkb(surface, 32611)
    assert tgsis.postgis_enabled(conn) is False


def test_postgis_before_tgsis_and_the_extension_route(gis: GisServer) -> None:
    reason = gis.extension_files()
    if reason is not None:
        pytest.fail(reason, pytrace=False)
    with gis.database("template0") as dsn, psycopg.connect(dsn, autocommit=True) as conn:
        conn.execute("CREATE EXTENSION postgis")
        assert tgsis.install(conn, method="extension").method == "extension"
        assert tgsis.enable_postgis(conn) == "public"
        tgsis.create_feature_class(conn, "faults", "SURFACE", srs=32611)
        fid = tgsis.insert_feature(conn, "faults", flat_grid(3, 0.0))
        assert _one(conn, "SELECT ST_NPoints(tgsis.postgis_geometry('faults', %s))", (fid,)) == 8 * 4
        # the wrappers are no extension members (a restore's CREATE EXTENSION would not make them)
        assert (
            _one(
                conn,
                "SELECT count(*) FROM pg_depend WHERE refclassid = 'pg_extension'::regclass "
                "AND objid = 'tgsis.postgis_geometry(text, bigint)'::regprocedure",
            )
            == 0
        )
        # PostGIS in a schema of its own works too (the wrappers follow it when enabled again)
        conn.execute("CREATE SCHEMA gis")
        conn.execute(
            "DROP FUNCTION tgsis.postgis_geometry(text, bigint), "
            "tgsis.postgis_geometry_at(text, bigint, double precision, text)"
        )
        conn.execute("DROP EXTENSION postgis")
        conn.execute("CREATE EXTENSION postgis SCHEMA gis")
        assert tgsis.enable_postgis(conn) == "gis"
        assert _one(conn, "SELECT gis.ST_NPoints(tgsis.postgis_geometry('faults', %s))", (fid,)) == 32


def test_readers_read_editors_import_admins_enable(gis: GisServer) -> None:
    with gis.database() as dsn, psycopg.connect(dsn, autocommit=True) as admin:
        tgsis.create_feature_class(admin, "faults", "SURFACE", srs=32611)
        fid = tgsis.insert_feature(admin, "faults", flat_grid(3, 0.0))
        with login_roles(dsn, {"rita": "tgsis_reader", "ed": "tgsis_editor", "ada": "tgsis_admin"}) as roles:
            rita, ed, ada = roles.connect("rita"), roles.connect("ed"), roles.connect("ada")
            for who in (rita, ed):
                with pytest.raises(tgsis.MissingPrivilegeError):
                    tgsis.enable_postgis(who)
                who.rollback()
            assert tgsis.enable_postgis(ada) == "public"
            for who in (rita, ed):
                with pytest.raises(tgsis.MissingPrivilegeError):
                    tgsis.create_postgis_view(who, "faults")
                who.rollback()
            tgsis.create_postgis_view(ada, "faults")
            assert _one(rita, "SELECT ST_NPoints(geom) FROM faults_postgis WHERE _geoid = %s", (fid,)) == 32
            assert _one(rita, "SELECT ST_SRID(tgsis.postgis_geometry('faults', %s))", (fid,)) == 32611
            with pytest.raises(tgsis.MissingPrivilegeError):
                _one(
                    rita,
                    "SELECT tgsis.insert_postgis_feature('faults', 'TIN Z (((0 0 0,1 0 0,0 1 0,0 0 0)))'::geometry)",
                )
            rita.rollback()
            new = _one(
                ed, "SELECT tgsis.insert_postgis_feature('faults', 'TIN Z (((0 0 0,1 0 0,0 1 0,0 0 0)))'::geometry)"
            )
            ed.commit()
            assert _one(rita, "SELECT count(*) FROM faults_postgis") == 2 and new > fid


def test_a_view_another_role_made_to_look_like_the_layer_is_neither_replaced_nor_dropped(gis: GisServer) -> None:
    with gis.database() as dsn, psycopg.connect(dsn, autocommit=True) as admin:
        tgsis.enable_postgis(admin)
        tgsis.create_feature_class(admin, "wells", "MULTILINESTRING")
        with login_roles(dsn, {"eve": "tgsis_editor"}) as roles:
            admin.execute(f"GRANT CREATE ON SCHEMA public TO {roles.name('eve')}")
            eve = roles.connect("eve")
            eve.execute("CREATE VIEW wells_postgis AS SELECT 1 AS trap")
            eve.execute("COMMENT ON VIEW wells_postgis IS 'tgsis PostGIS view of feature class wells: forged'")
            eve.commit()
            with pytest.raises(tgsis.AlreadyExistsError, match="not the PostGIS view of class wells"):
                tgsis.create_postgis_view(admin, "wells")
            tgsis.drop_feature_class(admin, "wells", force=True)
            assert _one(
                admin, "SELECT pg_get_userbyid(relowner) FROM pg_class WHERE oid = 'wells_postgis'::regclass"
            ) == roles.name("eve")
            eve.execute("DROP VIEW wells_postgis")
            eve.commit()
            admin.execute(f"REVOKE CREATE ON SCHEMA public FROM {roles.name('eve')}")


# ---------------------------------------------------------------- the name geometry in psql


def test_psql_with_tgsis_first_in_the_search_path_uses_postgis_types(gis: GisServer, gconn: Conn) -> None:
    tgsis.create_feature_class(gconn, "faults", "SURFACE", srs=32611)
    fid = tgsis.insert_feature(gconn, "faults", flat_grid(3, 0.0))
    dsn = gis.server.dsn(gconn.info.dbname)

    def psql(*statements: str) -> subprocess.CompletedProcess[str]:
        args = [str(gis.bindir / "psql"), "-X", "-q", "-A", "-t", "-v", "ON_ERROR_STOP=1", "-d", dsn]
        for statement in statements:
            args += ["-c", statement]
        return subprocess.run(args, capture_output=True, text=True, check=False)

    # the documented session (docs/postgis.md): PostGIS's schema first, then tgsis: both names work unqualified
    done = psql(
        "SET search_path = public, tgsis",
        "SELECT ST_AsText('POINT Z (1 2 3)'::geometry)",
        "SELECT count(*) FROM geometry",
        f"SELECT ST_3DDistance(postgis_geometry('faults', {fid}), ST_SetSRID('POINT Z (1 1 3)'::geometry, 32611))",
        "CREATE TEMP TABLE wells (trace geometry(LineStringZ, 32611))",
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["POINT", "Z", "(1", "2", "3)", "1", "3"]
    # tgsis first: the bare type name is tgsis.geometry's row type (PostgreSQL allows no other), PostGIS's is
    # public.geometry; everything else of both works unqualified
    done = psql(
        "SET search_path = tgsis, public",
        "SELECT ST_AsText('POINT Z (1 2 3)'::public.geometry)",
        "SELECT ST_AsText(ST_GeomFromText('POINT Z (1 2 3)'))",
        f"SELECT ST_3DDistance(postgis_geometry('faults', {fid}), 'SRID=32611;POINT Z (1 1 3)'::public.geometry)",
        "SELECT count(*) FROM geometry",
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["POINT", "Z", "(1", "2", "3)", "POINT", "Z", "(1", "2", "3)", "3", "1"]
    tripped = psql("SET search_path = tgsis, public", "SELECT 'POINT Z (1 2 3)'::geometry")
    assert tripped.returncode != 0 and "malformed record literal" in tripped.stderr


# ---------------------------------------------------------------- pg_dump and restore (PostgreSQL 15)


@pytest.mark.parametrize("route", ["sql", "extension"])
@pytest.mark.parametrize("fmt", ["plain", "custom"])
def test_dump_and_restore_keep_the_postgis_functions_and_views(
    gis: GisServer, route: str, fmt: str, tmp_path: Path
) -> None:
    if route == "extension":
        reason = gis.extension_files()
        if reason is not None:
            pytest.fail(reason, pytrace=False)
    with gis.database("template0") as dsn, psycopg.connect(dsn, autocommit=True) as conn:
        tgsis.install(conn, method=route)  # type: ignore[arg-type]
        conn.execute("CREATE EXTENSION postgis")  # after tgsis
        tgsis.enable_postgis(conn)
        tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties={"release": "text"}, srs=32611)
        tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING", srs=32611)
        fid = tgsis.insert_feature(conn, "faults", _random_surface(np.random.default_rng(1)), {"release": "5.3"})
        mid = tgsis.insert_feature(conn, "moving", evolving(np.random.default_rng(2), [0.0, 1.0]))
        tgsis.create_postgis_view(conn, "faults")
        tgsis.create_postgis_view(conn, "moving")
        tgsis.enable_feature_versioning(conn)
        before = conn.execute(
            "SELECT _geoid, ST_AsEWKB(geom) FROM faults_postgis UNION ALL "
            "SELECT _geoid, ST_AsEWKB(geom) FROM moving_postgis ORDER BY 1, 2"
        ).fetchall()
        dump = tmp_path / f"dump.{fmt}"
        out = subprocess.run(
            [str(gis.bindir / "pg_dump"), f"--format={fmt}", f"--file={dump}", dsn],
            capture_output=True,
            text=True,
            check=False,
        )
        assert out.returncode == 0, out.stderr
    with gis.database("template0") as restored:
        if fmt == "plain":
            args = [str(gis.bindir / "psql"), "-X", "-q", "-v", "ON_ERROR_STOP=1", "-d", restored, "-f", str(dump)]
        else:
            args = [str(gis.bindir / "pg_restore"), "--exit-on-error", "-d", restored, str(dump)]
        out = subprocess.run(args, capture_output=True, text=True, check=False)
        assert out.returncode == 0 and "ERROR" not in out.stderr, out.stderr
        with psycopg.connect(restored, autocommit=True) as conn:
            after = conn.execute(
                "SELECT _geoid, ST_AsEWKB(geom) FROM faults_postgis UNION ALL "
                "SELECT _geoid, ST_AsEWKB(geom) FROM moving_postgis ORDER BY 1, 2"
            ).fetchall()
            assert after == before and len(after) > 2
            assert _one(conn, "SELECT ST_SRID(tgsis.postgis_geometry_at('moving', %s, 0.5))", (mid,)) == 32611
            assert _one(conn, "SELECT ST_NPoints(tgsis.postgis_geometry('faults', %s))", (fid,)) > 0
            assert tgsis.postgis_enabled(conn)
            # and it goes on: a new feature through SQL, seen by the layer
            new = _one(
                conn, "SELECT tgsis.insert_postgis_feature('faults', 'TIN Z (((0 0 0,1 0 0,0 1 0,0 0 0)))'::geometry)"
            )
            assert _one(conn, "SELECT count(*) FROM faults_postgis WHERE _geoid = %s", (new,)) == 1
            assert math.isfinite(
                _one(
                    conn,
                    "SELECT ST_3DDistance(a.geom, b.geom) FROM faults_postgis a, faults_postgis b "
                    "WHERE a._geoid = %s AND b._geoid = %s",
                    (fid, new),
                )
            )


def test_a_dump_without_postgis_restores_where_there_is_none(gis: GisServer, tmp_path: Path) -> None:
    with gis.database("template0") as dsn, psycopg.connect(dsn, autocommit=True) as conn:
        tgsis.install(conn, method="sql")
        tgsis.create_feature_class(conn, "faults", "SURFACE", srs=32611)
        fid = tgsis.insert_feature(conn, "faults", flat_grid(3, 0.0))
        dump = tmp_path / "dump.sql"
        out = subprocess.run([str(gis.bindir / "pg_dump"), f"--file={dump}", dsn], capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        assert "CREATE EXTENSION IF NOT EXISTS postgis" not in dump.read_text(encoding="utf-8")
    with gis.database("template0") as restored:
        out = subprocess.run(
            [str(gis.bindir / "psql"), "-X", "-q", "-v", "ON_ERROR_STOP=1", "-d", restored, "-f", str(dump)],
            capture_output=True,
            text=True,
        )
        assert out.returncode == 0, out.stderr
        with psycopg.connect(restored, autocommit=True) as conn:
            assert _one(conn, "SELECT count(*) FROM pg_extension WHERE extname = 'postgis'") == 0
            assert tgsis.fetch_ewkb(conn, "faults", fid) == mesh_to_ewkb(flat_grid(3, 0.0), 32611)
            conn.execute("CREATE EXTENSION postgis")  # PostGIS later, on the restored database
            tgsis.enable_postgis(conn)
            assert _one(conn, "SELECT ST_NPoints(tgsis.postgis_geometry('faults', %s))", (fid,)) == 32


def _store_in_chunks(conn: Conn) -> None:
    """The storage switch of model 1, where the template stores rows (TGSIS_TEST_STORAGE=rows) or after versioning."""
    conn.execute(
        "SELECT tgsis.store_in_chunks(tablename) FROM tgsis.model_tables"
        " WHERE chunkdefault AND NOT tgsis.stored_in_chunks(tablename) ORDER BY model, iudorder, tablename"
    )


def _chunk_contents(conn: Conn, table: str, geoid: int) -> list[tuple[Any, ...]]:
    """Every stored chunk version of an object, its arrays as their send forms (bit for bit), but geoid and revision."""
    # (the arrays by their send forms, the scalars as they are: chunk, vbase, vtop, ... whatever the layout holds)
    columns = conn.execute(
        "SELECT a.attname, t.typcategory = 'A' FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid"
        " WHERE a.attrelid = %s::regclass AND a.attnum > 0 AND NOT a.attisdropped"
        " AND a.attname NOT IN ('geoid', 'revision', 'lastrevs', 'revclosed') ORDER BY a.attnum",
        (f"tgsis.{table}_chunk",),
    ).fetchall()
    select = sql.SQL(", ").join(
        sql.SQL("array_send({})").format(sql.Identifier(c)) if is_array else sql.Identifier(c)
        for c, is_array in columns
    )
    query = sql.SQL("SELECT {} FROM tgsis.{} WHERE geoid = %s ORDER BY chunk").format(
        select, sql.Identifier(f"{table}_chunk")
    )
    return conn.execute(query, (geoid,)).fetchall()


@pytest.mark.parametrize("versioned", [False, True])
def test_on_chunks_a_postgis_feature_is_written_as_the_upload_writes_it(gconn: Conn, versioned: bool) -> None:
    """Model 1 stored in chunks: insert_postgis_feature writes each table's chunks in one statement, never row by
    row through the face (its INSTEAD OF trigger ran once per vertex and triangle before), and the chunks are the
    ones tgsis.insert_feature writes for the same mesh, bit for bit; the feature reads back as it went in."""
    tgsis.create_feature_class(gconn, "faults", "SURFACE", srs=32611)
    tgsis.create_feature_class(gconn, "traces", "MULTILINESTRING", srs=32611)
    tgsis.create_feature_class(gconn, "picks", "MULTIPOINT", srs=32611)
    if versioned:
        tgsis.enable_feature_versioning(gconn)
        tgsis.create_version(gconn, "draft")
        tgsis.goto_version(gconn, "draft")
    _store_in_chunks(gconn)
    grid = flat_grid(45, 1.0)  # 2,025 vertices in 2 chunks, 3,872 triangles in 4
    cases = [
        ("faults", "trgl", mesh_to_ewkb(grid, 32611)),
        ("traces", "segment", _one(gconn, "SELECT 'MULTILINESTRING Z ((0 0 0,1 0 0,1 1 1),(5 5 5,6 6 6))'::geometry")),
        ("picks", "point", _one(gconn, "SELECT 'MULTIPOINT Z (1 2 3,4 5 6,-0 0 1)'::geometry")),
    ]
    gconn.execute("SET track_functions = 'all'")
    for name, table, geom in cases:
        face = "SELECT coalesce(sum(calls), 0) FROM pg_stat_xact_user_functions WHERE (funcname IN ('chunk_face_write', 'chunk_face_queue') OR funcname LIKE '%%\\_face\\_row')"
        with gconn.transaction():  # (the view may show calls of earlier transactions not yet reported: a difference)
            before = _one(gconn, face)
            fid = _one(gconn, "SELECT tgsis.insert_postgis_feature(%s, %s::geometry)", (name, geom))
            calls = _one(gconn, face) - before
        assert calls == 0, (name, calls)
        _, vertices, cells = gconn.execute(
            "SELECT geotype, vertices, cells FROM tgsis.mesh_from_postgis(%s::geometry)", (geom,)
        ).fetchone()  # type: ignore[misc]
        mesh = mesh_from_wkb(_one(gconn, "SELECT tgsis.postgis_geometry(%s, %s)", (name, fid)))
        assert np.array_equal(mesh.cells, np.array(cells)) and np.array_equal(mesh.vertices, np.array(vertices))
        assert gconn.execute("SELECT nvrtx, ncell FROM tgsis.geometry WHERE geoid = %s", (fid,)).fetchone() == (
            len(vertices),
            len(cells),
        )
        # the oracle: the same rows written into a new object by tgsis.write_chunk_rows (the faces' writer)
        same = _one(
            gconn,
            "SELECT tgsis.new_geometry(geotype, NULL, NULL, 0, 0, p_class => %s) FROM tgsis.geometry WHERE geoid = %s",
            (name, fid),
        )
        with gconn.transaction():
            for t in ("vrtx", table):
                gconn.execute(
                    f"CREATE TEMP TABLE rows ON COMMIT DROP AS SELECT * FROM tgsis.{t} WHERE geoid = %s", (fid,)
                )
                gconn.execute("UPDATE rows SET geoid = %s", (same,))
                gconn.execute("ALTER TABLE rows ADD COLUMN _delete boolean NOT NULL DEFAULT false")
                gconn.execute("SELECT tgsis.write_chunk_rows(%s, 'pg_temp.rows')", (t,))
                gconn.execute("DROP TABLE rows")
        for t in ("vrtx", table):
            assert _chunk_contents(gconn, t, fid) == _chunk_contents(gconn, t, same), (name, t)
        if versioned:  # noted as changed in the draft's working revision, as a row write is; DEFAULT does not see it
            noted = _one(
                gconn,
                "SELECT array_agg(DISTINCT tablename ORDER BY tablename) FROM tgsis.revision_objects"
                " WHERE objectkey = %s::text AND revision = (SELECT workingrevision FROM tgsis.versions"
                " WHERE name = 'draft')",
                (fid,),
            )
            assert {"vrtx", table} <= set(noted), noted
            with tgsis.in_version(gconn, "DEFAULT"):
                assert _one(gconn, "SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fid,)) == 0
    # a reader may not write, and nothing is written
    stored = _one(gconn, "SELECT count(*) FROM tgsis.vrtx_chunk")
    with login_roles(gconn.info.dsn, {"ann": "tgsis_reader"}) as roles:
        reader = roles.connect("ann")
        if versioned:
            tgsis.goto_version(reader, "draft")
        with pytest.raises(psycopg.Error):
            reader.execute("SELECT tgsis.insert_postgis_feature('picks', 'POINT Z (1 2 3)'::geometry)")
        reader.rollback()
    assert _one(gconn, "SELECT count(*) FROM tgsis.vrtx_chunk") == stored


def test_on_chunks_a_postgis_feature_of_a_class_without_versioning_has_no_history(gconn: Conn) -> None:
    """Feature versioning on, a class without it: its PostGIS feature's chunks are revision 0 (every version sees
    them), written from DEFAULT only (another version is refused by name, nothing written), none noted as changed."""
    tgsis.enable_feature_versioning(gconn)
    tgsis.create_feature_class(gconn, "wells", "SURFACE", versioned=False, srs=32611)
    tgsis.create_version(gconn, "draft")
    _store_in_chunks(gconn)
    tin = "TIN Z (((0 0 0,1 0 0,0 1 0.5,0 0 0)),((1 0 0,1 1 1,0 1 0.5,1 0 0)))"
    fid = _one(gconn, "SELECT tgsis.insert_postgis_feature('wells', %s::geometry)", (tin,))
    for table in ("vrtx", "trgl"):
        assert gconn.execute(
            f"SELECT revision, lastrevs FROM tgsis.{table}_chunk WHERE geoid = %s", (fid,)
        ).fetchall() == [(0, [])]
    assert _one(gconn, "SELECT count(*) FROM tgsis.revision_objects WHERE objectkey = %s::text", (fid,)) == 0
    with tgsis.in_version(gconn, "draft"):
        assert _one(gconn, "SELECT ST_AsText(tgsis.postgis_geometry('wells', %s))", (fid,)) == tin
    stored = _one(gconn, "SELECT count(*) FROM tgsis.vrtx_chunk")
    tgsis.goto_version(gconn, "draft")
    with pytest.raises(tgsis.Error) as err:
        _one(gconn, "SELECT tgsis.insert_postgis_feature('wells', %s::geometry)", (tin,))
    assert err.value.sqlstate == "TG305", err.value
    tgsis.goto_version(gconn, "DEFAULT")
    assert _one(gconn, "SELECT count(*) FROM tgsis.vrtx_chunk") == stored
