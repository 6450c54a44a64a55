"""Upload into, and download from, a versioned class whose properties are in chunks (issue 40, plan G area W).

docs/storage.md, "The bulk paths of property chunks": ``insert_feature`` of a versioned class whose property
table is the face of ``tgsis.store_class_in_chunks`` writes each new object's property rows in one call
(``tgsis.write_property_rows``: its chunks written once in the working revision), where the face rewrote a
chunk per row; ``fetch_feature`` reads the chunk versions the session sees directly. Each result is compared
bit for bit with a twin class on rows. The property tables are rows or chunks whatever model 1's storage is,
so the file runs unmarked.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.db._property_chunks import property_request
from tgsis.db.classes import get_feature_class
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


NAN_PAYLOAD = struct.unpack(">d", struct.pack(">Q", 0x7FF8000000000ABC))[0]
TWINS = ("inchunks", "onrows")


def _surface(side: int = 55, shift: float = 0.0) -> Surface:
    surface = curved_surface(side)  # 3,025 vertices: three chunks of 1,024
    porosity = surface.vertex_properties["porosity"].copy() + shift
    if surface.n_vertices > 2000:
        porosity[3], porosity[2000] = -0.0, NAN_PAYLOAD
    return Surface(
        surface.vertices,
        surface.cells,
        vertex_properties={"porosity": porosity, "facies": (np.arange(surface.n_vertices, dtype=np.int32) % 7) - 3},
    )


def _classes(conn: Conn) -> None:
    """Twin versioned classes (porosity, facies), each with one small feature; ``inchunks``'s properties in chunks;
    version e1."""
    for name in TWINS:
        tgsis.create_feature_class(
            conn, name, "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
        )
    tgsis.enable_feature_versioning(conn)
    for name in TWINS:
        F.insert_feature(conn, name, _surface(10))
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()


def _rows(conn: Conn, name: str, geoid: int) -> list[tuple[Any, ...]]:
    return [
        tuple(r)
        for r in conn.execute(
            f"SELECT _idx, float8send(porosity), facies FROM public.{name}_cellpros WHERE _geoid = %s ORDER BY _idx",
            (geoid,),
        ).fetchall()
    ]


def _chunk_writes(conn: Conn) -> int:
    """Tuples inserted, updated or deleted in inchunks' chunk table by the session's transactions not yet counted."""
    row = conn.execute(
        "SELECT n_tup_ins + n_tup_upd + n_tup_del FROM pg_stat_xact_user_tables "
        "WHERE relid = 'public.inchunks_cellpros_chunk'::regclass"
    ).fetchone()
    assert row is not None
    return int(row[0])


def _bits(mesh: Any) -> tuple[bytes, bytes]:
    assert isinstance(mesh, Surface)
    return mesh.vertex_properties["porosity"].tobytes(), mesh.vertex_properties["facies"].astype(np.int32).tobytes()


def test_an_upload_in_a_version_writes_each_chunk_once_and_equals_rows(conn: Conn) -> None:
    """insert_feature in e1 of a 3,025-vertex surface: its three property chunks written once each (through the
    face: a chunk rewrite per row, thousands of tuples), e1 sees the values of the twin on rows bit for bit (-0.0,
    a NaN payload), DEFAULT does not see the object; both read back by fetch_feature from the chunks."""
    _classes(conn)
    geoids = {}
    with tgsis.in_version(conn, "e1"):
        for name in TWINS:
            conn.commit()
            # the caller's transaction: the upload's writes are counted in it (a difference: the counts of an
            # earlier transaction may not be flushed yet, and then show in pg_stat_xact_user_tables too)
            before = _chunk_writes(conn)
            geoids[name] = F.insert_feature(conn, name, _surface())
            if name == "inchunks":
                assert _chunk_writes(conn) - before == 3  # three new chunks, one version each
            conn.commit()
        seen = {name: _rows(conn, name, geoids[name]) for name in TWINS}
        assert [r[1:] for r in seen["inchunks"]] == [r[1:] for r in seen["onrows"]]
        assert len(seen["inchunks"]) == 3025
        assert seen["inchunks"][3][1] == struct.pack(">d", -0.0)
        assert seen["inchunks"][2000][1] == struct.pack(">Q", 0x7FF8000000000ABC)
        fc = get_feature_class(conn, "inchunks")
        # the download of a versioned class in chunks reads the chunk versions (not the face)
        assert property_request(conn, fc, "inchunks_cellpros", ["porosity"], [geoids["inchunks"]]) is not None
        fetched = {name: F.fetch_feature(conn, name, geoids[name]).mesh for name in TWINS}
        assert _bits(fetched["inchunks"]) == _bits(fetched["onrows"]) == _bits(_surface())
        conn.commit()
    assert conn.execute(
        "SELECT count(*) FROM public.inchunks_cellpros_chunk WHERE _geoid = %s AND revision <> 0",
        (geoids["inchunks"],),
    ).fetchone() == (3,)
    assert _rows(conn, "inchunks", geoids["inchunks"]) == []  # DEFAULT does not see e1's new object


def test_a_child_version_reads_its_own_values_from_the_chunks(conn: Conn) -> None:
    """An object uploaded in DEFAULT, changed in e2 (made after it): fetch_feature in e2 reads e2's values, in
    DEFAULT DEFAULT's, as the twin on rows."""
    _classes(conn)
    geoids = {name: F.insert_feature(conn, name, _surface()) for name in TWINS}
    tgsis.create_version(conn, "e2")
    conn.commit()
    with tgsis.in_version(conn, "e2"):
        for name in TWINS:
            mesh = F.fetch_feature(conn, name, geoids[name]).mesh
            assert isinstance(mesh, Surface)
            porosity = mesh.vertex_properties["porosity"].copy()
            porosity[1500:1600] = 7.25
            conn.commit()
            tgsis.save_feature(
                conn,
                name,
                geoids[name],
                Surface(
                    mesh.vertices,
                    mesh.cells,
                    vertex_properties={"porosity": porosity, "facies": mesh.vertex_properties["facies"]},
                ),
            )
            conn.commit()
        child = {name: _bits(F.fetch_feature(conn, name, geoids[name]).mesh) for name in TWINS}
        conn.commit()
    parent = {name: _bits(F.fetch_feature(conn, name, geoids[name]).mesh) for name in TWINS}
    assert child["inchunks"] == child["onrows"] and parent["inchunks"] == parent["onrows"]
    assert parent["inchunks"] == _bits(_surface()) and child["inchunks"] != parent["inchunks"]
    assert np.all(np.frombuffer(child["inchunks"][0], dtype=np.float64)[1500:1600] == 7.25)


def test_a_role_with_fewer_rights_is_refused_by_name_and_nothing_is_written(db_dsn: str, conn: Conn) -> None:
    """A reader's upload is refused (MissingPrivilegeError), an editor's in a version it may not write too;
    nothing is written."""
    from tests.roles import login_roles

    _classes(conn)
    chunks = conn.execute("SELECT count(*) FROM public.inchunks_cellpros_chunk").fetchone()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        with pytest.raises(tgsis.MissingPrivilegeError):
            F.insert_feature(reader, "inchunks", _surface())
        reader.rollback()
        editor = roles.connect("editor")
        tgsis.goto_version(editor, "e1")
        editor.commit()
        with pytest.raises(tgsis.Error):
            F.insert_feature(editor, "inchunks", _surface())
        editor.rollback()
        tgsis.goto_version(editor, "DEFAULT")
        editor.commit()
        g = F.insert_feature(editor, "inchunks", _surface())
        editor.commit()
    assert conn.execute("SELECT count(*) FROM public.inchunks_cellpros_chunk").fetchone() == ((chunks or (0,))[0] + 3,)
    assert _bits(F.fetch_feature(conn, "inchunks", g).mesh) == _bits(_surface())


def test_two_sessions_upload_into_one_version_and_both_are_kept(db_dsn: str, conn: Conn) -> None:
    """Session A uploads in e1 and has not committed; session B uploads another object in e1 and commits (not
    blocked: new objects, new chunks); A commits: both objects are in e1 with their own values."""
    from tests.sessions import connect

    _classes(conn)
    first, second = connect(db_dsn, "first"), connect(db_dsn, "second")
    for session in (first, second):
        tgsis.goto_version(session, "e1")
        session.commit()
    a = F.insert_feature(first, "inchunks", _surface(shift=1.0))
    b = F.insert_feature(second, "inchunks", _surface(shift=2.0))
    second.commit()
    first.commit()
    first.close()
    second.close()
    with tgsis.in_version(conn, "e1"):
        assert _bits(F.fetch_feature(conn, "inchunks", a).mesh) == _bits(_surface(shift=1.0))
        assert _bits(F.fetch_feature(conn, "inchunks", b).mesh) == _bits(_surface(shift=2.0))
        conn.commit()


def test_a_collection_in_a_version_members_missing_properties_are_null(conn: Conn) -> None:
    """A collection uploaded in e1 whose second member lacks facies: its chunks hold NULL facies (no holes), each
    member's values those of the twin on rows, read back from the chunks."""
    for name in ("crows", "cchunks"):
        tgsis.create_feature_class(
            conn, name, "GEOMETRYCOLLECTION", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
        )
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('cchunks')")
    conn.commit()
    full = _surface()
    members = [
        full,
        Surface(full.vertices, full.cells, vertex_properties={"porosity": full.vertex_properties["porosity"]}),
    ]
    seen = {}
    with tgsis.in_version(conn, "e1"):
        for name in ("crows", "cchunks"):
            geoid = F.insert_feature(conn, name, tgsis.GeometryCollection(members))
            conn.commit()
            ids = conn.execute("SELECT geoids FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone()
            assert ids is not None
            seen[name] = [[r[1:] for r in _rows(conn, name, g)] for g in ids[0]]
            back = F.fetch_feature(conn, name, geoid).mesh
            assert isinstance(back, tgsis.GeometryCollection)
            assert _bits(back.members[0]) == _bits(full)
            assert (
                back.members[1].vertex_properties["porosity"].tobytes() == full.vertex_properties["porosity"].tobytes()
            )
            assert "facies" not in back.members[1].vertex_properties
            conn.commit()
    assert seen["cchunks"] == seen["crows"]
    assert all(r[1] is None for r in seen["cchunks"][1]) and len(seen["cchunks"][1]) == 3025
