"""Model 1 and feature classes under versioning: one object class 'feature', meshes edited in versions."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


def _grid(side: int, z: float = 0.0) -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.full(side * side, z)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        vertices,
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        vertex_properties={"porosity": np.linspace(0, 1, side * side)},
        name=f"z{z}",
    )


@pytest.fixture
def horizons(conn: Conn) -> F.FeatureClass:
    fc = F.create_feature_class(
        conn, "horizons", "SURFACE", feature_properties={"creator": "text"}, cell_properties={"porosity": "float8"}
    )
    storage = conn.execute("SELECT count(*) FROM tgsis.model_tables").fetchone()[0]  # type: ignore[index]
    assert storage == 31  # the core's 3, models 1-5: 7, 3, 5, 8, 5
    assert tgsis.enable_feature_versioning(conn) == storage + 2  # + the class's 2
    return fc


def _stored(conn: Conn, table: str, schema: str = "tgsis") -> str:
    """The relation storing a table's rows (``tgsis.storage_table``): ``<t>_ver``, or ``<t>_chunk`` in chunks."""
    return str(conn.execute("SELECT tgsis.storage_table(%s, %s)", (schema, table)).fetchone()[0])  # type: ignore[index]


def _decoded(conn: Conn, table: str) -> str:
    """A relation of the stored versions of a model table's rows, one row each: ``<t>_ver`` or ``<t>_chunk_rows``."""
    row = conn.execute("SELECT tgsis.storage_row_versions('tgsis', %s)", (table,)).fetchone()
    assert row is not None
    return str(row[0])


def _rows(conn: Conn) -> dict[str, int]:
    """Stored rows (of a table stored in chunks: chunk versions) of the tables a feature of the class has."""
    tables = [("tgsis", "geometry"), ("tgsis", "vrtx"), ("tgsis", "trgl"), ("public", "horizons")]
    return {
        f"{schema}.{t}": int(conn.execute(f"SELECT count(*) FROM {_stored(conn, t, schema)}").fetchone()[0])  # type: ignore[index]
        for schema, t in [*tables, ("public", "horizons_cellpros")]
    }


def test_all_tables_form_object_class_feature(conn: Conn, horizons: F.FeatureClass) -> None:
    tables = {(t.table, t.objectkeyfield, t.iudorder) for t in tgsis.versioned_tables(conn)}
    assert tables == {
        ("geometry", "geoid", 0),
        ("model_object", "geoid", 1),
        ("model", "modelid", 0),
        ("vrtx", "geoid", 1),
        ("point", "geoid", 2),
        ("segment", "geoid", 2),
        ("trgl", "geoid", 2),
        ("tetra", "geoid", 2),
        ("atom", "geoid", 2),
        ("part", "geoid", 2),
        ("horizons", "_geoid", 3),
        ("horizons_cellpros", "_geoid", 4),
        ("times", "geoid", 1),
        ("times_vrtx", "geoid", 2),
        ("times_trgl", "geoid", 2),
        ("timem", "geoid", 1),
        ("timet", "geoid", 2),
        ("node", "geoid", 2),
        ("d4dtrgl", "geoid", 2),
        ("d4dvrtx", "geoid", 2),
        ("gmap", "geoid", 1),
        ("gmap_timem", "geoid", 1),
        ("gmap_timet", "geoid", 2),
        ("gmap_node", "geoid", 2),
        ("gmap_vertex", "geoid", 2),
        ("gmap_dart", "geoid", 2),
        ("gmap_alpha", "geoid", 2),
        ("gmap_cell", "geoid", 2),
        ("md_gmap", "geoid", 1),
        ("md_vertex", "geoid", 2),
        ("md_dart", "geoid", 2),
        ("md_alpha", "geoid", 2),
        ("md_cell", "geoid", 2),
    }
    assert {t.objectclass for t in tgsis.versioned_tables(conn)} == {"feature", "model"}
    assert [t.table for t in tgsis.versioned_tables(conn) if t.objectclass == "model"] == ["model"]
    # a class registered later is versioned as it is created, and its view reads the versioned tables
    F.create_feature_class(conn, "faults", "SURFACE")
    assert {t.table for t in tgsis.versioned_tables(conn)} >= {"faults", "faults_cellpros"}
    assert conn.execute("SELECT count(*) FROM faults_v").fetchone() == (0,)


def test_surface_edited_in_a_child_is_invisible_in_default(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(317)  # 100,489 vertices, 200,000 triangles
    fid = F.insert_feature(conn, horizons, base, {"creator": "ann"})
    tgsis.create_version(conn, "edit")
    before = _rows(conn)
    with tgsis.in_version(conn, "edit"):
        # a psql user moves one vertex with plain SQL in the child version
        conn.execute("UPDATE tgsis.vrtx SET z = 5 WHERE geoid = %s AND vrtxid = 42", (fid,))
        conn.execute("UPDATE horizons SET creator = 'bob' WHERE _geoid = %s", (fid,))
        conn.commit()
        edited = F.fetch_feature(conn, horizons, fid)
    assert _rows(conn) == {
        **before,
        "tgsis.vrtx": before["tgsis.vrtx"] + 1,
        "public.horizons": before["public.horizons"] + 1,
    }  # one row (or chunk) each, not 100,000
    assert edited.properties == {"creator": "bob"} and isinstance(edited.mesh, tgsis.Mesh)
    assert edited.mesh.vertices[42, 2] == 5 and np.count_nonzero(edited.mesh.vertices != base.vertices) == 1
    default = F.fetch_feature(conn, horizons, fid)
    assert default.mesh is not None and default.mesh.same_as(base) and default.properties == {"creator": "ann"}


def test_upload_and_delete_inside_a_version(conn: Conn, horizons: F.FeatureClass) -> None:
    kept = F.insert_feature(conn, horizons, _grid(5, 1.0))
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        new = F.insert_feature(conn, horizons, _grid(6, 2.0), {"creator": "v1"})
        assert F.delete_feature(conn, horizons, kept)
        assert [f.id for f in F.fetch_features(conn, horizons)] == [new]
        got = F.fetch_feature(conn, horizons, new).mesh
        assert got is not None and got.same_as(_grid(6, 2.0))
        assert F.features_in_box(conn, horizons, [[-1, -1, 1.5], [10, 10, 2.5]]) == [new]
    assert [f.id for f in F.fetch_features(conn, horizons)] == [kept]
    assert F.features_in_box(conn, horizons, [[-1, -1, 1.5], [10, 10, 2.5]]) == []
    # the child's rows were copied in by COPY with its working revision, not through triggers
    for table in ("vrtx", "trgl"):
        assert conn.execute(
            f"SELECT DISTINCT revision FROM {_stored(conn, table)} WHERE geoid = %s", (new,)
        ).fetchall() == [(2,)]
    assert conn.execute(
        f"SELECT count(*) FROM {_decoded(conn, 'vrtx')} WHERE geoid = %s AND lastrevs = '{{2}}'", (kept,)
    ).fetchone() == (25,)


def test_writes_while_viewing_an_old_revision_write_nothing(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _grid(4))  # revision 0, seen by v1
    tgsis.create_version(conn, "v1")
    tgsis.goto_revision(conn, "v1", 0)
    conn.commit()
    before = _rows(conn)
    with pytest.raises(tgsis.ReadOnlyRevisionError, match="viewed at revision 0"):
        F.insert_feature(conn, horizons, _grid(4))
    with pytest.raises(tgsis.ReadOnlyRevisionError, match="viewed at revision 0"):
        F.delete_feature(conn, horizons, fid)
    conn.rollback()
    assert _rows(conn) == before


def test_drop_class_removes_its_features_from_every_version(conn: Conn, horizons: F.FeatureClass) -> None:
    F.insert_feature(conn, horizons, _grid(4))
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        F.insert_feature(conn, horizons, _grid(5))
    with pytest.raises(tgsis.InUseError, match="still has 2 feature"):
        F.drop_feature_class(conn, "horizons")
    assert F.drop_feature_class(conn, "horizons", force=True) == 2
    assert conn.execute(f"SELECT count(*) FROM {_stored(conn, 'vrtx')}").fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.versioned_tables WHERE tablename LIKE 'horizons%'").fetchone() == (
        0,
    )
    assert conn.execute("SELECT to_regclass('horizons_ver')").fetchone() == (None,)


def test_disable_feature_versioning_keeps_default(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _grid(4), {"creator": "ann"})
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        F.insert_feature(conn, horizons, _grid(5))
    with pytest.raises(tgsis.InUseError, match="versions other than DEFAULT changed"):
        tgsis.disable_feature_versioning(conn)
    tgsis.disable_feature_versioning(conn, force=True)
    assert tgsis.versioned_tables(conn) == []
    assert [f.id for f in F.fetch_features(conn, horizons)] == [fid]
    fk = conn.execute(
        "SELECT pg_get_constraintdef(oid) FROM pg_constraint WHERE conrelid = 'horizons'::regclass AND contype = 'f'"
    ).fetchone()
    assert fk == ("FOREIGN KEY (_geoid) REFERENCES tgsis.geometry(geoid) ON DELETE CASCADE",)
    assert conn.execute("SELECT count(*) FROM horizons_v").fetchone() == (1,)


def test_a_collection_added_and_deleted_in_a_version(conn: Conn) -> None:
    F.create_feature_class(conn, "blocks", "GEOMETRYCOLLECTION", cell_properties={"porosity": "float8"})
    tgsis.enable_feature_versioning(conn)
    line = tgsis.LineSet([[0, 0, 0], [1, 1, 1]], [[0, 1]], vertex_properties={"porosity": [0.5, 0.25]})
    block = tgsis.GeometryCollection([_grid(3), line], name="block")
    kept = F.insert_feature(conn, "blocks", block)
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        added = F.insert_feature(conn, "blocks", block)
        assert F.delete_feature(conn, "blocks", kept)
        assert [f.id for f in F.fetch_features(conn, "blocks")] == [added]
        got = F.fetch_feature(conn, "blocks", added).mesh
        assert isinstance(got, tgsis.GeometryCollection) and got.same_as(block)
    default = F.fetch_features(conn, "blocks")
    assert [f.id for f in default] == [kept]
    assert isinstance(default[0].mesh, tgsis.GeometryCollection) and default[0].mesh.same_as(block)
    # the members the collection owns are closed in v1 with it, not deleted from DEFAULT
    members = conn.execute("SELECT geoids FROM tgsis.geometry WHERE geoid = %s", (kept,)).fetchone()
    assert members is not None and conn.execute(
        "SELECT count(*) FROM tgsis.geometry WHERE geoid = ANY (%s)", (members[0],)
    ).fetchone() == (2,)
