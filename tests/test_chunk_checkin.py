"""Check-in, save by difference and the merge reads on model-1 tables stored in chunks (issue 40).

After the storage switch (``tgsis.store_in_chunks``) an edit of an object no
longer closes rows and COPies new ones: ``tgsis.write_object_rows`` rewrites
each touched chunk once, in the session's working revision, after the checks
of the row path (db/_chunk_write.py); the merge by region reads the changed
chunk versions decoded (``tgsis.<table>_chunk_rows``). The databases here are
switched by the test itself (after loading the data as rows when the template
is not switched already), so these tests run on chunks whatever
``TGSIS_TEST_STORAGE`` says.
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.conftest import BuiltOnce, cloned_or_built
from tests.roles import login_roles
from tests.test_merge_states_read import assert_identical, edit, reference_states
from tgsis.db import _chunk_write, _merge_states
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

SIDE = 33  # 1,089 vertices (2 vertex chunks: 0..1023, 1024..1088) and 2,048 triangles (2 chunks, full)


def _grid(side: int = SIDE) -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    rng = np.random.default_rng(7)
    vertices = np.stack([u.ravel() * 1.25, v.ravel() * 0.75, rng.random(side * side)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        vertices,
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        vertex_properties={"porosity": rng.random(side * side)},
        name="grid",
    )


def _switch(conn: Conn) -> None:
    """Store every model table registered for chunks in chunks (those the template did not switch), committed."""
    conn.execute(
        "SELECT tgsis.store_in_chunks(tablename) FROM tgsis.model_tables"
        " WHERE chunkdefault AND NOT tgsis.stored_in_chunks(tablename) ORDER BY model, iudorder, tablename"
    )
    conn.commit()
    assert conn.execute("SELECT tgsis.stored_in_chunks('vrtx') AND tgsis.stored_in_chunks('trgl')").fetchone() == (
        True,
    )


def make_loaded(conn: Conn) -> int:
    """A versioned class ``horizons`` holding the grid, stored in chunks; its geoid."""
    F.create_feature_class(conn, "horizons", "SURFACE", cell_properties={"porosity": "float8"})
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "horizons", _grid())
    conn.commit()
    _switch(conn)
    return geoid


BUILT_ONCE = {"loaded": make_loaded}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def loaded(request: pytest.FixtureRequest, conn: Conn, built_once: BuiltOnce) -> int:
    """``make_loaded``'s geoid, already in the test's database (cloned, not built again)."""
    return cloned_or_built(request, conn, built_once, "loaded", make_loaded)


def _chunk_versions(conn: Conn, table: str, geoid: int, revision: int) -> tuple[list[int], list[int]]:
    """(chunks written in ``revision``, chunks closed in it) of the object in ``tgsis.<table>_chunk``."""
    query = sql.SQL(
        "SELECT coalesce(array_agg(chunk ORDER BY chunk) FILTER (WHERE revision = %s), '{{}}'), "
        "coalesce(array_agg(chunk ORDER BY chunk) FILTER (WHERE %s = ANY (lastrevs)), '{{}}') "
        "FROM {} WHERE geoid = %s"
    ).format(sql.Identifier("tgsis", f"{table}_chunk"))
    row = conn.execute(query, (revision, revision, geoid)).fetchone()
    assert row is not None
    return list(row[0]), list(row[1])


def _working(conn: Conn, version: str) -> int:
    row = conn.execute("SELECT workingrevision FROM tgsis.versions WHERE name = %s", (version,)).fetchone()
    assert row is not None
    return int(row[0])


def _fetch(conn: Conn, geoid: int, version: str = "DEFAULT") -> tgsis.Surface:
    with tgsis.in_version(conn, version):
        mesh = F.fetch_feature(conn, "horizons", geoid).mesh
    conn.commit()
    assert isinstance(mesh, tgsis.Surface)
    return mesh


def _same(a: tgsis.Mesh, b: tgsis.Mesh) -> bool:
    """The same mesh in the same order, coordinates and property values bit for bit."""
    return (
        a.vertices.tobytes() == b.vertices.tobytes()
        and np.array_equal(a.cells, b.cells)
        and a.vertex_properties.keys() == b.vertex_properties.keys()
        and all(a.vertex_properties[k].tobytes() == b.vertex_properties[k].tobytes() for k in a.vertex_properties)
    )


def test_a_save_in_a_child_rewrites_only_the_touched_chunks_and_leaves_the_parent(conn: Conn, loaded: int) -> None:
    """One vertex moved (chunk 0 of vrtx), one triangle removed (chunk 1 of trgl): one chunk version each.

    Failed before: the save closed rows with tgsis.delete_object_rows and
    COPied vertex rows into tgsis.vrtx_chunk, which has no such columns.
    """
    base = _fetch(conn, loaded)
    edited = tgsis.Surface(
        base.vertices.copy(), base.cells[:-1].copy(), vertex_properties=dict(base.vertex_properties), name="grid"
    )
    edited.vertices[5, 2] = -0.0  # bit-exact: -0.0 is not 0.0
    tgsis.create_version(conn, "v1")
    conn.commit()
    with tgsis.in_version(conn, "v1"):
        result = tgsis.save_feature(conn, "horizons", loaded, edited)
    conn.commit()
    assert (result.rows_deleted, result.rows_inserted, result.vertices_moved, result.cells_removed) == (2, 1, 1, 1)
    w = _working(conn, "v1")
    assert _chunk_versions(conn, "vrtx", loaded, w) == ([0], [0])
    assert _chunk_versions(conn, "trgl", loaded, w) == ([1], [1])
    assert _same(_fetch(conn, loaded, "v1"), edited)
    assert np.signbit(_fetch(conn, loaded, "v1").vertices[5, 2])
    assert _same(_fetch(conn, loaded), base)
    noted = conn.execute(
        "SELECT array_agg(tablename::text ORDER BY tablename) FROM tgsis.revision_objects "
        "WHERE revision = %s AND schemaname = 'tgsis' AND objectkey = %s",
        (w, str(loaded)),
    ).fetchone()
    assert noted is not None and {"trgl", "vrtx"} <= set(noted[0])
    # the same mesh saved again writes nothing
    with tgsis.in_version(conn, "v1"):
        again = tgsis.save_feature(conn, "horizons", loaded, edited)
    conn.commit()
    assert again.rows_written == 0
    assert _chunk_versions(conn, "vrtx", loaded, w) == ([0], [0])


def test_new_ids_come_above_every_id_the_object_ever_had_in_any_chunk_version(conn: Conn, loaded: int) -> None:
    """The last vertex removed in a child, then a vertex added there: it gets the next id, not the removed one's."""
    base = _fetch(conn, loaded)
    last = base.n_vertices - 1
    keep = np.flatnonzero(~np.any(base.cells == last, axis=1))
    without = tgsis.Surface(
        base.vertices[:last],
        base.cells[keep],
        vertex_properties={"porosity": base.vertex_properties["porosity"][:last]},
    )
    tgsis.create_version(conn, "v1")
    conn.commit()
    with tgsis.in_version(conn, "v1"):
        tgsis.save_feature(conn, "horizons", loaded, without)
        conn.commit()
        added = tgsis.Surface(
            np.concatenate([without.vertices, [[100.0, 200.0, 3.0]]]),
            np.concatenate([without.cells, [[0, 1, last]]]),
            vertex_properties={"porosity": np.append(without.vertex_properties["porosity"], 0.5)},
        )
        tgsis.save_feature(conn, "horizons", loaded, added)
        conn.commit()
        ids = [int(r[0]) for r in conn.execute("SELECT vrtxid FROM tgsis.vrtx WHERE geoid = %s", (loaded,))]
        cells = [int(r[0]) for r in conn.execute("SELECT trglid FROM tgsis.trgl WHERE geoid = %s", (loaded,))]
    conn.commit()
    assert last not in ids and last + 1 in ids and len(ids) == base.n_vertices
    assert max(cells) == base.n_cells  # above the triangles removed with the vertex, too
    assert _same(_fetch(conn, loaded, "v1"), added)


def test_a_check_in_merged_with_a_change_since_check_out_on_chunks(conn: Conn, loaded: int) -> None:
    """Bob saves a move in chunk 1 after Ann's check-out; Ann's move in chunk 0 is merged with it by region."""
    checked_out = tgsis.checkout(conn, loaded)
    conn.commit()
    bob = _fetch(conn, loaded)
    bob.vertices[1080, 2] += 5.0
    tgsis.save_feature(conn, "horizons", loaded, bob)
    conn.commit()
    ann = checked_out.mesh.copy()
    ann.vertices[3, 2] += 7.0
    result = tgsis.checkin(conn, checked_out, ann, on_conflict="merge")
    conn.commit()
    assert result.merged
    now = _fetch(conn, loaded)
    assert now.vertices[1080, 2] == bob.vertices[1080, 2] and now.vertices[3, 2] == ann.vertices[3, 2]
    expected = bob.vertices.copy()
    expected[3, 2] = ann.vertices[3, 2]
    assert now.vertices.tobytes() == expected.tobytes()


def test_a_role_may_save_on_chunks_only_with_the_rights_of_the_row_path(conn: Conn, loaded: int, db_dsn: str) -> None:
    """A reader is refused; an editor without the right on the class too; an editor with it saves (a vertex moved,
    one added with a triangle: its new ids read from the chunk tables as the editor); nothing else moves."""
    base = _fetch(conn, loaded)
    edited = tgsis.Surface(
        np.concatenate([base.vertices, [[-5.0, -5.0, 1.0]]]),
        np.concatenate([base.cells, [[0, 1, base.n_vertices]]]),
        vertex_properties={"porosity": np.append(base.vertex_properties["porosity"], 0.25)},
        name="grid",
    )
    edited.vertices[10, 0] += 1.0
    with login_roles(db_dsn, {"rita": "tgsis_reader", "ed": "tgsis_editor"}) as made:
        rita, ed = made.connect("rita"), made.connect("ed")
        with pytest.raises((tgsis.Error, psycopg.Error)):
            tgsis.save_feature(rita, "horizons", loaded, edited)
        rita.rollback()
        conn.execute("REVOKE UPDATE ON horizons FROM tgsis_editor")
        conn.commit()
        with pytest.raises((tgsis.Error, psycopg.errors.InsufficientPrivilege), match="horizons"):
            tgsis.save_feature(ed, "horizons", loaded, edited)
        ed.rollback()
        assert _same(_fetch(conn, loaded), base)
        conn.execute("GRANT UPDATE ON horizons TO tgsis_editor")
        conn.commit()
        tgsis.save_feature(ed, "horizons", loaded, edited)
        ed.commit()
    assert _same(_fetch(conn, loaded), edited)


def test_the_sql_writer_refuses_by_name(conn: Conn, loaded: int, db_dsn: str) -> None:
    """Shapes that do not match the columns, a table not in chunks, an id deleted and written, a planted table."""

    def refused(statement: str, params: Any = ()) -> tuple[str | None, str]:
        try:
            with conn.transaction():
                conn.execute(statement, params)
        except psycopg.Error as exc:
            return exc.sqlstate, str(exc)
        return None, ""

    call = "SELECT tgsis.write_object_rows(%s, %s, %s::bigint[], %s::bigint[], %s::float8[], %s::bigint[])"
    assert refused(call, ("vrtx", loaded, [], [1], [[1.0], [2.0]], None))[0] == "TG100"  # two rows for x, y, z
    assert refused(call, ("vrtx", loaded, [], [1, 2], [[1.0], [2.0], [3.0]], None))[0] == "TG100"  # one value, 2 ids
    assert refused(call, ("trgl", loaded, [], [1], None, None))[0] == "TG100"  # no vertex ids
    assert refused(call, ("vrtx", loaded, [], [1], [[1.0], [2.0], [3.0]], [[1]]))[0] == "TG100"  # refs for vertices
    assert refused(call, ("vrtx", loaded, [1], [1], [[1.0], [2.0], [3.0]], None))[0] == "TG100"  # deleted and written
    assert refused(call, ("atom", loaded, [1], [], None, None))[0] == "TG100"  # stored as rows
    assert refused(call, ("vrtx", loaded, [], [-1], [[1.0], [2.0], [3.0]], None))[0] == "TG100"  # negative id
    conn.rollback()
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:  # a table the session made itself is not read
        ed = made.connect("ed")
        ed.execute(
            "CREATE TEMP TABLE tgsis_object_rows_vrtx "
            "(geoid bigint, vrtxid bigint, x float8, y float8, z float8, _delete boolean)"
        )
        with pytest.raises(psycopg.errors.InsufficientPrivilege, match="tgsis_object_rows_vrtx"):
            ed.execute(call, ("vrtx", loaded, [], [1], [[1.0], [2.0], [3.0]], None))
        ed.rollback()
    conn.rollback()
    base = _fetch(conn, loaded)
    # a write that works, in DEFAULT: one chunk rewritten, the object noted
    row = conn.execute(call, ("vrtx", loaded, [], [1], [[1.0], [2.0], [-3.0]], None)).fetchone()
    conn.commit()
    assert row == (1,)
    now = _fetch(conn, loaded)
    assert now.vertices[1].tolist() == [1.0, 2.0, -3.0]
    assert np.delete(now.vertices, 1, axis=0).tobytes() == np.delete(base.vertices, 1, axis=0).tobytes()
    # the client's call sends the doubles bit for bit: a NaN's payload, a subnormal, -0.0
    bits = np.array([0x7FF8_0000_DEAD_BEEF, 1, 0x8000_0000_0000_0000], dtype=np.uint64).view(np.float64)
    assert _chunk_write.write_object_rows(conn, "vrtx", loaded, [], [2], floats=bits.reshape(1, 3)) == 1
    sent = conn.execute(
        "SELECT float8send(x) || float8send(y) || float8send(z) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 2",
        (loaded,),
    ).fetchone()
    conn.rollback()
    assert sent is not None and bytes(sent[0]) == bits.astype(">f8").tobytes()


def test_a_save_is_refused_in_an_older_revision(conn: Conn, loaded: int) -> None:
    """An older revision viewed: TG301 as on rows, nothing written."""
    base = _fetch(conn, loaded)
    edited = base.copy()
    edited.vertices[0, 2] += 1.0
    tgsis.create_version(conn, "v1")
    conn.commit()
    conn.execute("SELECT tgsis.goto_revision('DEFAULT', %s)", (_working(conn, "DEFAULT") - 1,))
    with pytest.raises(tgsis.ReadOnlyRevisionError):
        tgsis.save_feature(conn, "horizons", loaded, edited)
    conn.rollback()
    conn.execute("SELECT tgsis.goto_version('DEFAULT')")
    conn.commit()
    assert _same(_fetch(conn, loaded), base)


@pytest.fixture
def faults(conn: Conn) -> int:
    """The class of tests/test_merge_states_read.py with one fault, stored in chunks; a version e1 of it."""
    from tests.merge_data import curved_surface

    F.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[("porosity", "float8"), tgsis.Property("facies", "int", alignment="CELL")],
    )
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "faults", curved_surface())
    conn.commit()
    _switch(conn)
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def _sides(conn: Conn, version: str) -> dict[str, tuple[str, int]]:
    _versionid, parent, initrevision, working, parent_working = _merge_states.version_row(conn, version)
    return {"base": (version, initrevision), "parent": (parent, parent_working), "child": (version, working)}


def test_the_merge_reads_the_changed_chunks_decoded_and_gets_the_three_full_reads(conn: Conn, faults: int) -> None:
    """Both sides move vertices, add and remove cells, change values: the read by change equals three full reads.

    The reads themselves (``_read_states``, ``_read_change``), without the
    conflict check before them. Failed before: they selected vrtxid, x, y, z
    from tgsis.vrtx_chunk.
    """
    fc = tgsis.get_feature_class(conn, "faults")
    storages = _merge_states._readable_storages(conn, _merge_states._tables(fc)[0])
    assert storages is not None and storages[:2] == ["tgsis.vrtx_chunk_rows", "tgsis.trgl_chunk_rows"]
    conn.rollback()
    for version, steps in (
        ("DEFAULT", [("move", [0, 1], 1.0), ("remove cells", [7], None), ("vertex value", [2], 0.25)]),
        ("e1", [("move", [140, 141], -1.0), ("add vertices", [3, 4], None), ("cell value", [9], 3)]),
    ):
        for step in steps:
            edit(conn, fc, version, faults, step)
            conn.commit()
    reference = reference_states(conn, "e1", faults)
    conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    fast = _merge_states._states(fc, faults, _merge_states._read_states(conn, fc, faults, _sides(conn, "e1")))
    conn.rollback()
    for side in reference:
        assert_identical(fast[side], reference[side])
    conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    change = _merge_states._read_change(conn, fc, faults, _sides(conn, "e1"))
    conn.rollback()
    assert change is not None
    rows, top = change
    assert top == (int(reference["child"].vertex_ids.max()), int(reference["child"].cell_ids.max()))
    for side, read in rows.items():
        full = reference[side]
        at = np.searchsorted(full.vertex_ids, read.vertex_ids)
        assert np.array_equal(full.vertex_ids[at], read.vertex_ids)
        assert full.vertices[at].tobytes() == read.vertices.tobytes()
        at = np.searchsorted(full.cell_ids, read.cell_ids)
        assert np.array_equal(full.cell_ids[at], read.cell_ids) and np.array_equal(full.cells[at], read.cells)
    # the moved vertices and their one-ring are in the sides read
    child, base = reference["child"], reference["base"]
    common, at_child, at_base = np.intersect1d(child.vertex_ids, base.vertex_ids, return_indices=True)
    moved = common[child.vertices[at_child, 2] != base.vertices[at_base, 2]]
    assert len(moved) and np.isin(moved, rows["child"].vertex_ids).all()


def test_a_face_writer_of_the_object_waits_for_a_save_and_both_changes_stay(
    conn: Conn, loaded: int, db_dsn: str
) -> None:
    """Two sessions: a save holds the object's write lock; an UPDATE of another vertex of it through the face waits,
    then writes on top of the saved chunk (no lost update of either: the save's vertex 5 and the face's vertex 6)."""
    base = _fetch(conn, loaded)
    edited = base.copy()
    edited.vertices[5, 2] = 42.0
    other = psycopg.connect(db_dsn)
    try:
        conn.execute("SELECT 1")  # a transaction of the caller's: the save runs in it (a savepoint) and stays open
        tgsis.save_feature(conn, "horizons", loaded, edited)
        failures: list[BaseException] = []

        def update() -> None:
            try:
                other.execute("UPDATE tgsis.vrtx SET z = -42.0 WHERE geoid = %s AND vrtxid = 6", (loaded,))
                other.commit()
            except BaseException as exc:  # noqa: BLE001 - reported below
                failures.append(exc)

        pid = other.info.backend_pid
        worker = threading.Thread(target=update)
        worker.start()
        waiting = False
        for _ in range(600):  # until the other session waits for a lock (not a timing assert: a bounded poll)
            with psycopg.connect(db_dsn, autocommit=True) as probe:
                row = probe.execute("SELECT wait_event_type FROM pg_stat_activity WHERE pid = %s", (pid,)).fetchone()
            if row is not None and row[0] == "Lock":
                waiting = True
                break
            worker.join(0.05)
            if not worker.is_alive():
                break
        assert waiting, "the face's UPDATE did not wait for the save's lock"
        conn.commit()
        worker.join()
        assert not failures, failures
    finally:
        other.close()
    now = _fetch(conn, loaded)
    assert now.vertices[5, 2] == 42.0 and now.vertices[6, 2] == -42.0
    expected = edited.vertices.copy()
    expected[6, 2] = -42.0
    assert now.vertices.tobytes() == expected.tobytes()


def test_a_feature_of_a_class_without_versioning_is_saved_in_revision_0_in_place(conn: Conn) -> None:
    """Feature versioning on, the class registered without it: its chunk versions stay revision 0, rewritten in place,
    and no revision notes the object; a save from another version is refused (NotVersionedError), nothing written."""
    F.create_feature_class(conn, "loose", "SURFACE", versioned=False)
    tgsis.enable_feature_versioning(conn)
    base = _grid(12)
    geoid = F.insert_feature(conn, "loose", tgsis.Surface(base.vertices, base.cells))
    conn.commit()
    _switch(conn)
    edited = tgsis.Surface(base.vertices.copy(), base.cells)
    edited.vertices[3, 2] = 9.5
    tgsis.create_version(conn, "v1")
    conn.commit()
    with tgsis.in_version(conn, "v1"), pytest.raises(tgsis.NotVersionedError):
        tgsis.save_feature(conn, "loose", geoid, edited)
    conn.rollback()
    before = conn.execute("SELECT count(*) FROM tgsis.revision_objects WHERE objectkey = %s", (str(geoid),)).fetchone()
    tgsis.save_feature(conn, "loose", geoid, edited)
    conn.commit()
    versions = conn.execute(
        "SELECT array_agg(DISTINCT revision), count(*), bool_or(revclosed) FROM tgsis.vrtx_chunk WHERE geoid = %s",
        (geoid,),
    ).fetchone()
    assert versions == ([0], 1, False)
    after = conn.execute("SELECT count(*) FROM tgsis.revision_objects WHERE objectkey = %s", (str(geoid),)).fetchone()
    assert after == before
    for version in ("DEFAULT", "v1"):
        with tgsis.in_version(conn, version):
            z = conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 3", (geoid,)).fetchone()
        conn.commit()
        assert z == (9.5,)


def test_a_save_in_a_repeatable_read_session_answers_as_on_rows(conn: Conn, loaded: int) -> None:
    """A session whose transactions are REPEATABLE READ saves as on rows: an edit that changes stored rows closes
    them there (tgsis.close_object_rows), which needs READ COMMITTED, so it is refused by name (TG300) and writes
    nothing; an edit that only adds is written (the writer keeps the snapshot; a chunk changed after it would be
    40001). Before: both refused on chunks."""
    base = _fetch(conn, loaded)
    grown = tgsis.Surface(
        np.concatenate([base.vertices, [[-5.0, -5.0, 1.0]]]),
        np.concatenate([base.cells, [[0, 1, base.n_vertices]]]),
        vertex_properties={"porosity": np.append(base.vertex_properties["porosity"], 0.25)},
        name="grid",
    )
    moved = grown.copy()
    moved.vertices[3, 2] += 1.0
    conn.execute("SET default_transaction_isolation = 'repeatable read'")
    conn.commit()
    tgsis.save_feature(conn, "horizons", loaded, grown)
    conn.commit()
    assert _same(_fetch(conn, loaded), grown)
    with pytest.raises(tgsis.VersioningError, match="REPEATABLE READ") as refused:
        tgsis.save_feature(conn, "horizons", loaded, moved)
    assert refused.value.sqlstate == "TG300"
    conn.rollback()
    conn.execute("SET default_transaction_isolation = 'read committed'")
    conn.commit()
    assert _same(_fetch(conn, loaded), grown)
    tgsis.save_feature(conn, "horizons", loaded, moved)  # READ COMMITTED again: written
    conn.commit()
    assert _same(_fetch(conn, loaded), moved)
