"""Model 1's SQL readers on chunked storage (issue 40, the storage switch): the same answers as on rows.

Each database here is built on rows (unless ``TGSIS_TEST_STORAGE=chunks`` switched the template already), the
readers' answers are taken, every model-1 table is switched to chunks (``tgsis.store_in_chunks``) and the answers
are taken again: the rows' answers are the oracle. The readers that reached ``<table>_ver`` directly
(``tgsis.mesh_changes`` at a revision set, ``tgsis.table_fingerprint`` of versioned storage) failed on chunks
before they read the chunk versions.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.db import features as F
from tgsis.mesh import LineSet, PointSet, Surface, TetraMesh

from .roles import login_roles

Conn = psycopg.Connection[Any]


def _switch(conn: Conn) -> None:
    """Store every table registered for chunks in chunks (a no-op for those the template switched)."""
    conn.execute(
        "SELECT tgsis.store_in_chunks(tablename) FROM tgsis.model_tables"
        " WHERE chunkdefault AND NOT tgsis.stored_in_chunks(tablename) ORDER BY model, iudorder, tablename"
    )
    conn.commit()
    assert conn.execute("SELECT tgsis.stored_in_chunks('vrtx') AND tgsis.stored_in_chunks('trgl')").fetchone() == (
        True,
    )


def _grid(side: int, lift: float = 0.0) -> Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel()) * np.cos(v.ravel()) + lift], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))


def _load(conn: Conn) -> dict[str, int]:
    """Surfaces over three vertex chunks, a tetrahedral solid, lines and points; versioned, edited in a child."""
    surfaces = F.create_feature_class(conn, "horizons", "SURFACE")
    solids = F.create_feature_class(conn, "blocks", "MULTITETRA")
    lines = F.create_feature_class(conn, "traces", "MULTILINESTRING")
    points = F.create_feature_class(conn, "picks", "MULTIPOINT")
    g = {
        "grid": F.insert_feature(conn, surfaces, _grid(46)),  # 2,116 vertices: 3 chunks; 4,050 triangles: 4 chunks
        "other": F.insert_feature(conn, surfaces, _grid(46, lift=0.5)),
        "bad": F.insert_feature(conn, surfaces, _grid(4)),
        "solid": F.insert_feature(
            conn,
            solids,
            TetraMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], [[0, 1, 2, 3], [1, 2, 3, 4]]),
        ),
        "line": F.insert_feature(
            conn, lines, LineSet(np.array([[0, 0, 0], [1, 2, 3], [4, 5, -0.0]]), [[0, 1], [1, 2]])
        ),
        "points": F.insert_feature(conn, points, PointSet([[0, 0, 0], [1, 1, 1], [2, 2, 2]])),
    }
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        grid, bad = g["grid"], g["bad"]
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid IN (5, 1500)", (grid,))
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid IN (7, 3000)", (grid,))
        conn.execute("INSERT INTO tgsis.vrtx VALUES (%s, 5000, 2.5, 2.5, 7)", (grid,))  # a chunk of its own
        conn.execute("INSERT INTO tgsis.trgl VALUES (%s, 9000, 5000, 100, 101)", (grid,))
        # a vertex id past 2^31: its triangle's chunk keeps absolute ids (the _wide columns), with holes before it
        conn.execute("INSERT INTO tgsis.vrtx VALUES (%s, 3000000000, 1, 1, 1)", (grid,))
        conn.execute("INSERT INTO tgsis.trgl VALUES (%s, 9001, 3000000000, 100, 101)", (grid,))
        conn.commit()
        g["first"] = tgsis.save_revision(conn, "first")
        conn.execute("UPDATE tgsis.vrtx SET x = x + 0.5 WHERE geoid = %s AND vrtxid = 77", (grid,))
        # the check's problems: a NaN, a triangle of a missing vertex, a stale box
        conn.execute("UPDATE tgsis.vrtx SET y = 'NaN' WHERE geoid = %s AND vrtxid = 1", (bad,))
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 5", (bad,))
        conn.commit()
    return g


def _answers(conn: Conn, g: dict[str, int]) -> dict[str, Any]:
    """What every model-1 reader of this area says, in DEFAULT and in the child version."""
    out: dict[str, Any] = {}

    def q(key: str, sql: str, params: tuple[Any, ...]) -> None:
        out[key] = conn.execute(sql, params).fetchall()

    grid, other, bad = g["grid"], g["other"], g["bad"]
    for version in ("DEFAULT", "edit"):
        with tgsis.in_version(conn, version):
            q(f"{version} compare", "SELECT * FROM tgsis.compare_geometries(%s, %s)", (grid, other))
            q(f"{version} changes", "SELECT * FROM tgsis.geometry_changes(%s, %s) ORDER BY 1, 2, 3, 4", (other, grid))
            for name in ("grid", "bad", "solid", "line", "points"):
                q(
                    f"{version} extent {name}",
                    "SELECT bbox::text, nvrtx, ncell FROM tgsis.static_extent(%s)",
                    (g[name],),
                )
                q(f"{version} check {name}", "SELECT * FROM tgsis.check_static_geometry(%s) ORDER BY 1", (g[name],))
                q(f"{version} ewkb {name}", "SELECT md5(tgsis.ewkb_geometry(%s, 4326))", (g[name],))
            q(
                f"{version} at",
                "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vertices_at(%s, 0) ORDER BY 1",
                (grid,),
            )
            q(f"{version} triangles at", "SELECT * FROM tgsis.triangles_at(%s, 0) ORDER BY 1", (grid,))
            q(
                f"{version} vertices",
                "SELECT vrtxid, float8send(x) FROM tgsis.vertices(%s, ARRAY[5000, 0, 1500, 15, 77, -1, 4999, 2115])",
                (grid,),
            )
            q(f"{version} vertices bad", "SELECT vrtxid, float8send(y) FROM tgsis.vertices(%s, ARRAY[1, 5, 0])", (bad,))
    for old, new in (
        (("DEFAULT", None), ("edit", None)),
        (("edit", g["first"]), ("edit", None)),
        (("DEFAULT", 0), ("edit", 0)),
    ):
        q(
            f"versions {old} {new}",
            "SELECT * FROM tgsis.geometry_version_changes(%s, %s, %s, %s, %s) ORDER BY 1, 2, 3, 4",
            (grid, old[0], new[0], old[1], new[1]),
        )
    return out


def test_the_readers_answer_on_chunks_what_they_answered_on_rows(conn: Conn, db_dsn: str) -> None:
    g = _load(conn)
    before = _answers(conn, g)
    # the answers mean something: the child's edits are seen, the check finds its problems
    assert before["DEFAULT compare"] != before["edit compare"]
    assert before["versions ('DEFAULT', None) ('edit', None)"] != before["versions ('DEFAULT', 0) ('edit', 0)"]
    assert [r[0] for r in before["edit check bad"]] == [
        "bounding box or counts out of date (run tgsis.refresh_geometry)",
        "trgl refers to a missing vertex (vrtxid1)",
        "trgl refers to a missing vertex (vrtxid2)",
        "trgl refers to a missing vertex (vrtxid3)",
        "vertex with a NaN or infinite coordinate",
    ]
    assert before["edit extent grid"] != before["DEFAULT extent grid"]
    assert [r[0] for r in before["edit vertices"]] == [5000, 0, 1500, 15, 77, 2115]
    _switch(conn)
    assert conn.execute(
        "SELECT count(*) FROM tgsis.trgl_chunk WHERE geoid = %s AND vbase IS NULL AND holes IS NOT NULL", (g["grid"],)
    ).fetchone() == (1,)
    after = _answers(conn, g)
    assert [k for k in before if before[k] != after[k]] == []
    # a reader reads the chunks too (their grants and row-level security are the row storage's)
    with login_roles(db_dsn, {"ann": "tgsis_reader"}) as roles:
        reader = roles.connect("ann")
        got = reader.execute(
            "SELECT * FROM tgsis.geometry_version_changes(%s, 'DEFAULT', 'edit') ORDER BY 1, 2, 3, 4", (g["grid"],)
        ).fetchall()
        assert got == before["versions ('DEFAULT', None) ('edit', None)"]
        assert reader.execute("SELECT nvrtx FROM tgsis.static_extent(%s)", (g["grid"],)).fetchall() == [(2116,)]


def _fingerprint(conn: Conn, geoid: int) -> str:
    row = conn.execute("SELECT tgsis.object_fingerprint(%s)", (geoid,)).fetchone()
    assert row is not None and row[0] is not None
    return str(row[0])


def test_the_fingerprint_of_chunks_follows_the_content_the_session_sees(conn: Conn, db_dsn: str) -> None:
    g = _load(conn)
    _switch(conn)
    grid = g["grid"]
    default = _fingerprint(conn, grid)
    tgsis.goto_version(conn, "edit")
    conn.commit()
    edit = _fingerprint(conn, grid)
    assert edit != default and _fingerprint(conn, grid) == edit
    # another session, other settings, sees the same
    with psycopg.connect(db_dsn) as other:
        other.execute("SET extra_float_digits = 3; SET TimeZone = 'Asia/Kolkata'")
        tgsis.goto_version(other, "edit")
        assert _fingerprint(other, grid) == edit
    # a write of the same value writes no chunk and changes nothing
    conn.execute("UPDATE tgsis.vrtx SET z = z WHERE geoid = %s AND vrtxid = 3", (grid,))
    assert _fingerprint(conn, grid) == edit
    # one bit of one vertex, one corner of one triangle, a vertex removed: each seen, and undone: gone
    for change, undo in (
        (
            "UPDATE tgsis.vrtx SET x = '-0'::float8 WHERE geoid = %s AND vrtxid = 0",
            "UPDATE tgsis.vrtx SET x = 0.0 WHERE geoid = %s AND vrtxid = 0",
        ),
        (
            "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1 WHERE geoid = %s AND trglid = 2000",
            "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1 WHERE geoid = %s AND trglid = 2000",
        ),
        (
            "UPDATE tgsis.vrtx SET z = z + 1e-12 WHERE geoid = %s AND vrtxid = 2115",
            "UPDATE tgsis.vrtx SET z = z - 1e-12 WHERE geoid = %s AND vrtxid = 2115",
        ),
        (
            "DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 5000",
            "INSERT INTO tgsis.vrtx VALUES (%s, 5000, 2.5, 2.5, 7)",
        ),
    ):
        conn.execute(change, (grid,))
        assert _fingerprint(conn, grid) != edit, change
        conn.execute(undo, (grid,))
        assert _fingerprint(conn, grid) == edit, undo
    conn.rollback()
    tgsis.goto_version(conn, "DEFAULT")
    conn.commit()
    # the other object's chunks, and a change in another version, leave the fingerprint alone
    conn.execute("UPDATE tgsis.vrtx SET z = 1 WHERE geoid = %s AND vrtxid = 0", (g["other"],))
    conn.commit()
    with tgsis.in_version(conn, "edit"):
        assert _fingerprint(conn, grid) == edit
    conn.execute("UPDATE tgsis.vrtx SET z = 1 WHERE geoid = %s AND vrtxid = 0", (grid,))
    conn.commit()
    assert _fingerprint(conn, grid) != default
    with tgsis.in_version(conn, "edit"):
        assert _fingerprint(conn, grid) == edit
    # a reader's fingerprint is the editor's (same chunks, same hashes)
    with login_roles(db_dsn, {"ann": "tgsis_reader"}) as roles:
        reader = roles.connect("ann")
        tgsis.goto_version(reader, "edit")
        assert _fingerprint(reader, grid) == edit


@pytest.mark.parametrize("versioned", [False, True])
def test_a_check_in_from_a_stale_check_out_is_refused_on_chunks(conn: Conn, versioned: bool) -> None:
    fc = F.create_feature_class(conn, "horizons", "SURFACE")
    geoid = F.insert_feature(conn, fc, _grid(40))
    conn.commit()
    if versioned:
        tgsis.enable_feature_versioning(conn)
    _switch(conn)
    taken = _fingerprint(conn, geoid)
    assert conn.execute("SELECT nvrtx, ncell FROM tgsis.static_extent(%s)", (geoid,)).fetchone() == (1600, 2 * 39 * 39)
    conn.execute("SELECT tgsis.check_unchanged(%s, %s)", (geoid, taken))
    conn.rollback()
    conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 1599", (geoid,))
    conn.commit()
    with pytest.raises(psycopg.Error) as err:
        conn.execute("SELECT tgsis.check_unchanged(%s, %s)", (geoid, taken))
    assert err.value.sqlstate == "TG304"
    conn.rollback()


@pytest.mark.parametrize("versioned", [False, True])
def test_a_role_granted_the_faces_only_counts_through_them(conn: Conn, db_dsn: str, versioned: bool) -> None:
    """A role of no tgsis group granted SELECT on the model relations (the faces after the switch) and one class:
    tgsis.static_extent and the keyed reads answer it as before the switch (they read the chunk tables: 42501); a
    class it may not read stays hidden."""
    fc = F.create_feature_class(conn, "horizons", "SURFACE")
    hidden = F.create_feature_class(conn, "secrets", "SURFACE")
    geoid = F.insert_feature(conn, fc, _grid(40))
    secret = F.insert_feature(conn, hidden, _grid(3))
    conn.commit()
    if versioned:
        tgsis.enable_feature_versioning(conn)
    _switch(conn)
    conn.execute("REVOKE ALL ON secrets FROM tgsis_reader, tgsis_editor, tgsis_admin, PUBLIC")
    conn.commit()
    with login_roles(db_dsn, {"outsider": "pg_read_all_settings", "reader": "tgsis_reader"}) as roles:
        # a reader reads the chunk tables themselves (their row-level security hides the revoked class)
        reader = roles.connect("reader")
        assert reader.execute("SELECT has_table_privilege('tgsis.vrtx_chunk', 'SELECT')").fetchone() == (True,)
        last = conn.execute("SELECT x, y, z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 1599", (geoid,)).fetchall()
        assert reader.execute("SELECT * FROM tgsis.vertex(%s, 1599)", (geoid,)).fetchall() == last != []
        assert reader.execute("SELECT * FROM tgsis.vertices(%s, '{0, 1}')", (secret,)).fetchall() == []
        assert reader.execute("SELECT nvrtx FROM tgsis.static_extent(%s)", (geoid,)).fetchone() == (1600,)
        outsider = roles.name("outsider")
        conn.execute(f"GRANT USAGE ON SCHEMA tgsis TO {outsider}")
        conn.execute(
            f"GRANT SELECT ON tgsis.catalog, tgsis.versions, tgsis.revisions, tgsis.versioned_tables TO {outsider}"
        )
        conn.execute(f"GRANT SELECT ON tgsis.geometry, tgsis.vrtx, tgsis.trgl, public.horizons TO {outsider}")
        conn.commit()
        other = roles.connect("outsider")
        assert other.execute("SELECT has_table_privilege('tgsis.vrtx_chunk', 'SELECT')").fetchone() == (False,)
        assert other.execute("SELECT nvrtx, ncell FROM tgsis.static_extent(%s)", (geoid,)).fetchone() == (
            1600,
            2 * 39 * 39,
        )
        assert other.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (secret,)).fetchone() == (0,)
        # the keyed reads too (through the face), and nothing of the hidden class
        keyed = "SELECT vrtxid, x, y, z FROM tgsis.vertices(%s, ARRAY[1599, 0, 7, 1600])"
        assert other.execute(keyed, (geoid,)).fetchall() == conn.execute(keyed, (geoid,)).fetchall() != []
        assert other.execute("SELECT count(*) FROM tgsis.vertex(%s, 0)", (secret,)).fetchone() == (0,)


def test_the_extent_of_a_geometry_that_is_not_there_is_refused_by_name(conn: Conn) -> None:
    # (it failed with "null values cannot be formatted as an SQL identifier", on rows as on chunks)
    with pytest.raises(psycopg.Error, match="geometry 987654 does not exist") as caught:
        conn.execute("SELECT * FROM tgsis.static_extent(987654)")
    assert caught.value.sqlstate == "TG200"
    conn.rollback()
