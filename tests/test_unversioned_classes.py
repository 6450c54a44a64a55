"""Feature classes registered without versioning beside versioned ones (docs/versioning.md, "Versioning per class").

Their tables stay plain; their features' rows in the storage every class
shares carry revision 0, which every revision set holds: one state that
every version and revision sees, changed in place, written in DEFAULT only.
A pg_dump and restore of them is part of tests/test_backup.py's scenario.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.fetched import mesh_of
from tests.gmaps_shapes import block_tetrahedra
from tests.roles import login_roles
from tests.storage_data import row_versions
from tests.temporal_data import evolving, series
from tgsis.cli import main

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
    )


def _classes(conn: Conn) -> tuple[tgsis.FeatureClass, tgsis.FeatureClass]:
    """``horizons`` (versioned) and ``wells`` (without versioning: boreholes nobody edits in versions)."""
    tgsis.enable_feature_versioning(conn)
    horizons = tgsis.create_feature_class(
        conn, "horizons", "SURFACE", feature_properties={"creator": "text"}, cell_properties={"porosity": "float8"}
    )
    wells = tgsis.create_feature_class(
        conn,
        "wells",
        "SURFACE",
        feature_properties={"creator": "text"},
        cell_properties={"porosity": "float8"},
        versioned=False,
    )
    conn.commit()
    return horizons, wells


def _stored(conn: Conn, geoid: int) -> list[tuple[Any, ...]]:
    """(table, revision, closed) of every stored row of ``geoid`` in model 1's storage."""
    return [
        tuple(r)
        for r in conn.execute(
            "SELECT 'geometry', revision, revclosed FROM tgsis.geometry_ver WHERE geoid = %(g)s "
            f"UNION ALL SELECT 'vrtx', revision, revclosed FROM {row_versions(conn, 'vrtx')} v WHERE geoid = %(g)s "
            f"UNION ALL SELECT 'trgl', revision, revclosed FROM {row_versions(conn, 'trgl')} v WHERE geoid = %(g)s",
            {"g": geoid},
        ).fetchall()
    ]


def _z(conn: Conn, geoid: int) -> float:
    return float(conn.execute("SELECT max(z) FROM tgsis.vrtx WHERE geoid = %s", (geoid,)).fetchone()[0])  # type: ignore[index]


def test_a_class_without_versioning_keeps_plain_tables_and_rows_of_no_version(conn: Conn) -> None:
    horizons, wells = _classes(conn)
    assert (horizons.versioned, wells.versioned) == (True, False)
    assert tgsis.get_feature_class(conn, "wells").versioned is False
    tables = {t.table for t in tgsis.versioned_tables(conn)}
    assert {"horizons", "horizons_cellpros"} <= tables
    assert not {"wells", "wells_cellpros"} & tables
    well = tgsis.insert_feature(conn, wells, _grid(3), {"creator": "ann"})
    horizon = tgsis.insert_feature(conn, horizons, _grid(3), {"creator": "ann"})
    conn.commit()
    assert conn.execute("SELECT classname FROM tgsis.unversioned_features").fetchall() == [("wells",)]
    assert conn.execute("SELECT geoid FROM tgsis.unversioned_features").fetchall() == [(well,)]
    assert {r[1] for r in _stored(conn, well)} == {0}
    # the other class's rows are labelled with DEFAULT's working revision as before
    assert {r[1] for r in _stored(conn, horizon)} == {tgsis.working_revision(conn)}
    # the psql user's view of the class joins its plain table with the shared storage
    assert conn.execute("SELECT _geoid, creator, nvrtx FROM wells_v").fetchall() == [(well, "ann", 9)]


def test_every_version_and_revision_sees_the_one_current_state(conn: Conn) -> None:
    horizons, wells = _classes(conn)
    well = tgsis.insert_feature(conn, wells, _grid(3), {"creator": "ann"})
    conn.commit()
    first = tgsis.save_revision(conn, "before_the_survey")
    tgsis.create_version(conn, "v1")
    conn.commit()
    edited = _grid(3, z=5.0)
    result = tgsis.save_feature(conn, wells, well, edited)
    conn.commit()
    assert result.rows_updated > 0
    # changed in place: no closed row, no second row version
    assert {(r[1], r[2]) for r in _stored(conn, well)} == {(0, False)}
    assert _z(conn, well) == 5.0
    with tgsis.in_version(conn, "v1"):
        assert _z(conn, well) == 5.0
        assert np.array_equal(mesh_of(tgsis.fetch_feature(conn, wells, well)).vertices, edited.vertices)
    with tgsis.at_revision(conn, first, "DEFAULT"):
        assert _z(conn, well) == 5.0  # it has no history: the old revision sees it as it is
    # nothing of it is a difference between versions, nor a change to merge
    assert not [d for d in tgsis.diff_versions(conn, "DEFAULT", "v1") if d.objectkey == str(well)]
    tgsis.merge_version(conn, "v1")
    conn.commit()
    assert {(r[1], r[2]) for r in _stored(conn, well)} == {(0, False)}
    tgsis.compress_versions(conn)
    conn.commit()
    assert {(r[1], r[2]) for r in _stored(conn, well)} == {(0, False)}
    assert _z(conn, well) == 5.0


def test_writes_in_another_version_are_refused_and_change_nothing(conn: Conn) -> None:
    horizons, wells = _classes(conn)
    well = tgsis.insert_feature(conn, wells, _grid(3), {"creator": "ann"})
    tgsis.create_version(conn, "v1")
    conn.commit()
    before = _stored(conn, well)
    with tgsis.in_version(conn, "v1"):
        with pytest.raises(
            tgsis.NotVersionedError,
            match="features of class wells are not versioned: a write in "
            "version 'v1' would change them in every version",
        ):
            tgsis.insert_feature(conn, wells, _grid(2))
    with tgsis.in_version(conn, "v1"):
        with pytest.raises(tgsis.NotVersionedError, match="class wells"):
            tgsis.save_feature(conn, wells, well, _grid(3, z=1.0))
    with tgsis.in_version(conn, "v1"):
        with pytest.raises(tgsis.NotVersionedError, match="class wells"):
            tgsis.delete_feature(conn, wells, well)
    # from psql: through the shared views, and by the SQL write functions
    conn.execute("SELECT tgsis.goto_version('v1')")
    conn.commit()
    for statement in (
        "UPDATE tgsis.vrtx SET z = 7 WHERE geoid = %s",
        "DELETE FROM tgsis.trgl WHERE geoid = %s",
        "SELECT tgsis.delete_geometry(%s)",
    ):
        with pytest.raises(psycopg.Error, match="features of class wells are not versioned") as caught:
            conn.execute(statement, (well,))
        assert caught.value.sqlstate == "TG305"
        assert "goto_version('DEFAULT')" in str(caught.value.diag.message_hint)
        conn.rollback()
    with pytest.raises(psycopg.Error, match="class wells") as caught:
        conn.execute("SELECT tgsis.new_geometry('SURFACE', 'w', NULL, 0, 0, p_class => 'wells')")
    assert caught.value.sqlstate == "TG305"
    conn.rollback()
    # a versioned class's features are written in v1 as ever
    horizon = tgsis.insert_feature(conn, horizons, _grid(2), {"creator": "bob"})
    conn.commit()
    conn.execute("SELECT tgsis.goto_version('DEFAULT')")
    conn.commit()
    assert _stored(conn, well) == before
    assert conn.execute("SELECT count(*) FROM tgsis.unversioned_features").fetchone() == (1,)
    assert conn.execute("SELECT count(*) FROM horizons WHERE _geoid = %s", (horizon,)).fetchone() == (0,)


def test_writes_through_the_views_change_rows_in_place_in_default(conn: Conn) -> None:
    _, wells = _classes(conn)
    well = tgsis.insert_feature(conn, wells, _grid(3), {"creator": "ann"})
    tgsis.create_version(conn, "v1")  # DEFAULT's working revision is no longer 0
    conn.commit()
    assert tgsis.working_revision(conn) > 0
    conn.execute("UPDATE tgsis.vrtx SET z = 3 WHERE geoid = %s AND vrtxid = 0", (well,))
    conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 0", (well,))
    conn.execute("INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, 100, 0, 1, 4)", (well,))
    conn.commit()
    rows = conn.execute(
        f"SELECT revision, lastrevs FROM {row_versions(conn, 'trgl')} v WHERE geoid = %s AND trglid IN (0, 100)",
        (well,),
    ).fetchall()
    assert rows == [(0, [])]  # trglid 0 gone for good, 100 of no version
    assert conn.execute(
        f"SELECT count(*), min(revision), max(revision) FROM {row_versions(conn, 'vrtx')} v WHERE geoid = %s", (well,)
    ).fetchone() == (9, 0, 0)
    with tgsis.in_version(conn, "v1"):
        assert conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 0", (well,)).fetchone() == (3.0,)
    # one statement cannot move rows between a feature of no version and a versioned one
    horizons = tgsis.get_feature_class(conn, "horizons")
    horizon = tgsis.insert_feature(conn, horizons, _grid(2))
    conn.commit()
    with pytest.raises(psycopg.Error, match="one write cannot move rows between feature") as caught:
        conn.execute("UPDATE tgsis.vrtx SET geoid = %s WHERE geoid = %s AND vrtxid = 8", (horizon, well))
    assert caught.value.sqlstate == "TG300"
    conn.rollback()


def test_deleting_a_feature_leaves_no_row_and_no_record(conn: Conn) -> None:
    _, wells = _classes(conn)
    well = tgsis.insert_feature(conn, wells, _grid(3), {"creator": "ann"})
    tgsis.create_version(conn, "v1")
    conn.commit()
    assert tgsis.delete_feature(conn, wells, well)
    conn.commit()
    assert _stored(conn, well) == []
    assert conn.execute("SELECT count(*) FROM wells").fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.unversioned_features").fetchone() == (0,)
    with tgsis.in_version(conn, "v1"):
        assert conn.execute("SELECT count(*) FROM tgsis.geometry WHERE geoid = %s", (well,)).fetchone() == (0,)


def test_a_class_registered_before_feature_versioning_stays_without_it(conn: Conn) -> None:
    wells = tgsis.create_feature_class(
        conn, "wells", "SURFACE", cell_properties={"porosity": "float8"}, versioned=False
    )
    well = tgsis.insert_feature(conn, wells, _grid(3))
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    assert not {"wells", "wells_cellpros"} & {t.table for t in tgsis.versioned_tables(conn)}
    assert {r[1] for r in _stored(conn, well)} == {0}
    tgsis.create_version(conn, "v1")
    conn.commit()
    assert tgsis.save_feature(conn, wells, well, _grid(3, z=2.0)).version == "DEFAULT"
    conn.commit()
    with tgsis.in_version(conn, "v1"):
        assert _z(conn, well) == 2.0
    # back to plain tables: the key to tgsis.geometry is restored
    tgsis.delete_version(conn, "v1")
    tgsis.disable_feature_versioning(conn)
    conn.commit()
    assert conn.execute(
        "SELECT count(*) FROM pg_constraint WHERE conrelid = 'wells'::regclass AND contype = 'f'"
    ).fetchone() == (1,)
    assert _z(conn, well) == 2.0


def test_a_role_writing_storage_directly_must_label_rows_right(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as owner:
        _, wells = _classes(owner)
        well = tgsis.insert_feature(owner, wells, _grid(3))
        tgsis.create_version(owner, "v1")
        owner.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor", "reader": "tgsis_reader"}) as roles:
        ed = roles.connect("ed")
        working = tgsis.working_revision(ed)
        assert working > 0
        # one vertex written into storage itself: a row of tgsis.vrtx_ver (vertex 99), or in chunks a chunk version
        # of its own (chunk 99: vertex 99 * 1024); the storage's guard checks the labels alike
        chunked = ed.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,)
        direct = (
            "INSERT INTO tgsis.vrtx_chunk (geoid, chunk, x, y, z, revision) VALUES (%s, 99, '{0}', '{0}', '{0}', %s)"
            if chunked
            else "INSERT INTO tgsis.vrtx_ver (geoid, vrtxid, x, y, z, revision) VALUES (%s, 99, 0, 0, 0, %s)"
        )
        # rows of a feature of no version carry revision 0, the others the working revision
        for revision, geoid in ((working, well), (0, None)):
            target = geoid if geoid is not None else tgsis.insert_feature(ed, "horizons", _grid(2))
            with pytest.raises(psycopg.Error, match="are not live rows of revision") as caught:
                ed.execute(direct, (target, revision))
            assert caught.value.sqlstate == "TG002"
            if geoid is not None:
                assert "revision = 0" in str(caught.value.diag.message_detail)
            ed.rollback()
        ed.execute(direct, (well, 0))
        ed.commit()
        # claiming geoids of no version needs the right to add features to the class
        reader = roles.connect("reader")
        with pytest.raises(psycopg.Error, match="may not add features to class wells") as caught:
            reader.execute("SELECT tgsis.claim_unversioned_geoid('wells')")
        assert caught.value.sqlstate == "TG002"
        reader.rollback()
        # and nobody writes the registry but tgsis
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            ed.execute("INSERT INTO tgsis.unversioned_features VALUES (12345, 'wells')")
        ed.rollback()
        # a reader sees the features of no version in any version, as the others
        assert reader.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (well,)).fetchone() == (10,)


def test_two_sessions_editing_one_feature_of_no_version(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as owner:
        _, wells = _classes(owner)
        well = tgsis.insert_feature(owner, wells, _grid(3))
        owner.commit()
    with psycopg.connect(db_dsn) as a, psycopg.connect(db_dsn) as b:
        a.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 4", (well,))
        b.execute("SET lock_timeout = '200ms'")
        with pytest.raises(psycopg.errors.LockNotAvailable):
            b.execute("UPDATE tgsis.vrtx SET z = z + 10 WHERE geoid = %s AND vrtxid = 4", (well,))
        b.rollback()
        a.commit()
        b.execute("UPDATE tgsis.vrtx SET z = z + 10 WHERE geoid = %s AND vrtxid = 4", (well,))
        b.commit()
        assert a.execute(
            f"SELECT z, (SELECT count(*) FROM {row_versions(a, 'vrtx')} v WHERE geoid = %s AND vrtxid = 4) "
            "FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 4",
            (well, well),
        ).fetchone() == (11.0, 1)


def test_only_default_locks_features_of_no_version(conn: Conn) -> None:
    horizons, wells = _classes(conn)
    well = tgsis.insert_feature(conn, wells, _grid(2))
    horizon = tgsis.insert_feature(conn, horizons, _grid(2))
    tgsis.create_version(conn, "v1")
    conn.commit()
    with pytest.raises(tgsis.NotVersionedError, match=f"features {well} are of classes without versioning"):
        tgsis.lock_objects(conn, "v1", "feature", [horizon, well])
    conn.rollback()
    with pytest.raises(tgsis.NotFoundError, match="has no object"):
        tgsis.lock_objects(conn, "v1", "feature", [horizon + 1000])
    conn.rollback()
    assert tgsis.lock_objects(conn, "DEFAULT", "feature", [well]) == 1
    assert tgsis.lock_objects(conn, "v1", "feature", [horizon]) == 1


def test_temporal_and_gmap_classes_without_versioning(conn: Conn) -> None:
    rng = np.random.default_rng(3)
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "stepped", "SURFACE", time_model="INSTANTS", versioned=False)
    tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING", versioned=False)
    tgsis.create_feature_class(conn, "blocks", "GMAP", time_model="GMAP", cell_level=3, versioned=False)
    stepped = tgsis.insert_feature(conn, "stepped", series(rng, [0.0, 1.0]))
    moving = tgsis.insert_feature(conn, "moving", evolving(rng, [0.0, 2.0]))
    solid = tgsis.GMap.from_tetrahedra(*block_tetrahedra(1))
    block = tgsis.insert_feature(conn, "blocks", solid)
    tgsis.create_version(conn, "v1")
    conn.commit()
    tgsis.add_instant(conn, "stepped", stepped, 2.0, series(rng, [0.0]).surfaces[0])
    conn.commit()
    revisions = conn.execute(
        "SELECT array_agg(DISTINCT revision) FROM (SELECT revision FROM tgsis.times_ver WHERE geoid = %(s)s "
        "UNION ALL SELECT revision FROM tgsis.timem_ver WHERE geoid = %(m)s "
        f"UNION ALL SELECT revision FROM {row_versions(conn, 'd4dvrtx')} v WHERE geoid = %(m)s "
        "UNION ALL SELECT revision FROM tgsis.gmap_ver WHERE geoid = %(b)s "
        "UNION ALL SELECT revision FROM tgsis.geometry_ver WHERE geoid IN (%(s)s, %(m)s, %(b)s)) r",
        {"s": stepped, "m": moving, "b": block},
    ).fetchone()
    assert revisions == ([0],)
    with tgsis.in_version(conn, "v1"):
        assert [float(t) for t, _ in tgsis.instants(conn, stepped)] == [0.0, 1.0, 2.0]
        assert tgsis.gmap_check(conn, block) == []
        with pytest.raises(tgsis.NotVersionedError, match="class stepped"):
            tgsis.add_instant(conn, "stepped", stepped, 3.0, series(rng, [0.0]).surfaces[0])
    with tgsis.in_version(conn, "v1"), pytest.raises(tgsis.NotVersionedError, match="not versioned"):
        tgsis.delete_instant(conn, stepped, 1.0)
    assert tgsis.delete_instant(conn, stepped, 1.0)
    conn.commit()
    with tgsis.in_version(conn, "v1"):
        assert [float(t) for t, _ in tgsis.instants(conn, stepped)] == [0.0, 2.0]
    assert conn.execute("SELECT count(*) FROM tgsis.times_ver WHERE geoid = %s", (stepped,)).fetchone() == (2,)


def test_the_command_line_creates_lists_and_describes_a_class_without_versioning(
    db_dsn: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with psycopg.connect(db_dsn) as conn:
        tgsis.enable_feature_versioning(conn)
        conn.commit()
    assert main(["--dsn", db_dsn, "class", "create", "wells", "--geotype", "SURFACE", "--no-versioning"]) == 0
    assert "without versioning: one state in every version, written in DEFAULT" in capsys.readouterr().out
    assert main(["--dsn", db_dsn, "class", "list", "--json"]) == 0
    assert [c["versioned"] for c in json.loads(capsys.readouterr().out)["classes"]] == [False]
    with psycopg.connect(db_dsn) as conn:
        well = tgsis.insert_feature(conn, "wells", _grid(2), drop_extra_properties=True)
        tgsis.create_version(conn, "v1")
        conn.commit()
    assert main(["--dsn", db_dsn, "info", str(well)]) == 0
    out = capsys.readouterr().out
    assert "class wells is not versioned: every version sees this state" in out
    assert "versions where it differs" not in out
    assert main(["--dsn", db_dsn, "info", str(well), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["versioned"] is False


def test_bad_classes_are_refused_and_nothing_is_claimed(conn: Conn) -> None:
    _classes(conn)
    claimed = "SELECT count(*), (SELECT last_value FROM tgsis.geometry_geoid_seq) FROM tgsis.unversioned_features"
    before = conn.execute(claimed).fetchone()
    for call, sqlstate, message in (
        (
            "SELECT tgsis.new_geometry('SURFACE', 'w', NULL, 0, 0, p_class => 'nope')",
            "TG200",
            "feature class 'nope' of a new geometry does not exist",
        ),
        ("SELECT tgsis.claim_unversioned_geoid('nope')", "TG200", "feature class 'nope' does not exist"),
        ("SELECT tgsis.claim_unversioned_geoid(NULL)", "TG200", "feature class NULL does not exist"),
        (
            "SELECT tgsis.claim_unversioned_geoid('horizons')",
            "TG300",
            "feature class horizons is versioned: its features take geoids of their own",
        ),
    ):
        with pytest.raises(psycopg.Error, match=message) as caught:
            conn.execute(call)
        assert caught.value.sqlstate == sqlstate
        conn.rollback()
    assert conn.execute(claimed).fetchone() == before
    # a geometry stored for a versioned class is versioned, as one stored for no class
    geoid = conn.execute("SELECT tgsis.new_geometry('SURFACE', 'h', NULL, 0, 0, p_class => 'horizons')").fetchone()
    assert geoid is not None
    assert conn.execute("SELECT revision FROM tgsis.geometry_ver WHERE geoid = %s", geoid).fetchone() == (
        tgsis.working_revision(conn),
    )
    assert conn.execute(claimed).fetchone()[0] == 0  # type: ignore[index]
