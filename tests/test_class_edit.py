"""Editing a feature class: add, rename and drop properties (tgsis.add_property, rename_property, drop_property).

On a plain class and on a versioned one (the storage <table>_ver, its view
and its generated trigger rebuilt: writes through the view, merges and
check-ins carry the new column; every version keeps its values); bad input
changes nothing; roles without tgsis_admin are refused; a writer and an
editor of the class at the same time lose no value; and per-class
versioning is refused with the reason (docs/versioning.md, "Versioning per
class").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.roles import login_roles
from tests.sessions import Background, connect, wait_until_blocked
from tests.storage_data import storage_of
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


def _grid(side: int = 4, z: float = 0.0) -> tgsis.Surface:
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


def _horizons(conn: Conn, *, versioned: bool) -> tuple[F.FeatureClass, int]:
    fc = F.create_feature_class(
        conn, "horizons", "SURFACE", feature_properties={"creator": "text"}, cell_properties={"porosity": "float8"}
    )
    fid = F.insert_feature(conn, fc, _grid(), {"creator": "ann"})
    if versioned:
        tgsis.enable_feature_versioning(conn)
    conn.commit()
    return fc, fid


def _definition(conn: Conn) -> list[Any]:
    """What an edit of class horizons changes: its catalog row, the columns (and comments) of its relations."""
    catalog = conn.execute(
        "SELECT feature_properties, cell_properties, instant_properties FROM tgsis.catalog WHERE classname = 'horizons'"
    ).fetchall()
    columns = conn.execute(
        "SELECT c.relname, a.attname, format_type(a.atttypid, a.atttypmod), a.attnotnull, "
        "       col_description(c.oid, a.attnum) "
        "  FROM pg_class c JOIN pg_attribute a ON a.attrelid = c.oid AND a.attnum > 0 AND NOT a.attisdropped "
        " WHERE c.relnamespace = 'public'::regnamespace AND c.relname LIKE 'horizons%' ORDER BY 1, a.attnum"
    ).fetchall()
    return [catalog, columns]


def _comment(conn: Conn, relation: str, column: str) -> str | None:
    row = conn.execute(
        "SELECT col_description(%s::regclass, (SELECT attnum FROM pg_attribute "
        "WHERE attrelid = %s::regclass AND attname = %s))",
        (relation, relation, column),
    ).fetchone()
    return None if row is None else row[0]


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_add_rename_drop_keeps_the_features(conn: Conn, versioned: bool) -> None:
    _, fid = _horizons(conn, versioned=versioned)
    fc = tgsis.add_property(conn, "horizons", ("permeability", "float4"), default=0.5)
    fc = tgsis.add_property(conn, "horizons", ("age", "int"), kind="feature")
    fc = tgsis.add_property(conn, "horizons", ("slip", "float8", 3), default=-1)
    assert [p.name for p in fc.cell_properties] == ["porosity", "permeability", "slip"]
    assert [(p.name, p.type) for p in fc.feature_properties] == [("creator", "text"), ("age", "integer")]
    assert fc == F.get_feature_class(conn, "horizons")
    # the stored feature has the new properties: the default per vertex, none for the feature
    feature = F.fetch_feature(conn, fc, fid)
    assert feature.properties == {"creator": "ann", "age": None} and isinstance(feature.mesh, tgsis.Mesh)
    assert feature.mesh.vertex_properties["permeability"].dtype == np.float32
    assert np.all(feature.mesh.vertex_properties["permeability"] == 0.5)
    assert np.all(feature.mesh.vertex_properties["slip"] == -1) and feature.mesh.vertex_properties["slip"].shape == (
        16,
        3,
    )
    # commented as at registration; the class view shows the feature property
    # the relation holding the row definition: <table>_ver or the table on rows, <table>_shape on chunks
    row = conn.execute(
        "SELECT CASE WHEN tgsis.stored_in_chunks('public', 'horizons_cellpros') THEN 'public.horizons_cellpros_shape' "
        "ELSE tgsis.storage_table('public', 'horizons_cellpros') END"
    ).fetchone()
    assert row is not None
    storage = str(row[0])
    assert _comment(conn, "horizons_cellpros", "permeability") == "vertex property (real)"
    assert _comment(conn, storage, "permeability") == "vertex property (real)"
    assert _comment(conn, "horizons_v", "age") == "per-feature property (integer)"
    assert conn.execute("SELECT creator, age FROM horizons_v WHERE _geoid = %s", (fid,)).fetchone() == ("ann", None)

    # saved with values of the new properties, fetched back
    mesh = feature.mesh
    mesh.vertex_properties["permeability"] = np.arange(16, dtype=np.float32)
    tgsis.save_feature(conn, fc, fid, mesh, {"age": 12})
    again = F.fetch_feature(conn, fc, fid)
    assert again.properties == {"creator": "ann", "age": 12} and isinstance(again.mesh, tgsis.Mesh)
    assert np.array_equal(again.mesh.vertex_properties["permeability"], np.arange(16))
    # a new feature stored after the edit carries them too
    new = _grid(3, 1.0)
    new.vertex_properties.update(permeability=np.ones(9, dtype=np.float32), slip=np.zeros((9, 3)))
    other = F.insert_feature(conn, fc, new, {"creator": "bob", "age": 3})
    assert F.fetch_feature(conn, fc, other).properties == {"creator": "bob", "age": 3}

    # renamed: the values go with the name
    fc = tgsis.rename_property(conn, "horizons", "permeability", "k")
    fc = tgsis.rename_property(conn, "horizons", "age", "Age_Ma", kind="feature")
    renamed = F.fetch_feature(conn, fc, fid)
    assert renamed.properties == {"creator": "ann", "Age_Ma": 12} and isinstance(renamed.mesh, tgsis.Mesh)
    assert np.array_equal(renamed.mesh.vertex_properties["k"], np.arange(16))
    assert "permeability" not in renamed.mesh.vertex_properties
    assert _comment(conn, "horizons_cellpros", "k") == "vertex property (real)"
    assert conn.execute('SELECT "Age_Ma" FROM horizons_v WHERE _geoid = %s', (fid,)).fetchone() == (12,)

    # dropped: values would be lost, so only with force
    with pytest.raises(tgsis.InUseError, match=r"cell property 'k' of feature class horizons holds 25 value"):
        tgsis.drop_property(conn, "horizons", "k")
    fc = tgsis.drop_property(conn, "horizons", "k", force=True)
    fc = tgsis.drop_property(conn, "horizons", "slip", force=True)
    fc = tgsis.drop_property(conn, "horizons", "Age_Ma", force=True)
    assert [p.name for p in fc.cell_properties] == ["porosity"] and [p.name for p in fc.feature_properties] == [
        "creator"
    ]
    dropped = F.fetch_feature(conn, fc, fid)
    assert dropped.properties == {"creator": "ann"} and isinstance(dropped.mesh, tgsis.Mesh)
    assert set(dropped.mesh.vertex_properties) == {"porosity"}
    # a property nobody gave a value is dropped without force
    tgsis.add_property(conn, "horizons", ("note", "text"), kind="feature")
    tgsis.drop_property(conn, "horizons", "note")
    if versioned:  # the versioned views and their triggers are the ones tgsis made, over the storage's columns
        # (a property table in chunks is a face over its chunk table, versioned as chunks: its own tests)
        chunked = conn.execute("SELECT tgsis.stored_in_chunks('public', 'horizons_cellpros')").fetchone() == (True,)
        for table in ("horizons",) if chunked else ("horizons", "horizons_cellpros"):
            triggers = conn.execute(
                "SELECT array_agg(tgname::text ORDER BY tgname) FROM pg_trigger "
                "WHERE tgrelid = %s::regclass AND NOT tgisinternal",
                (table,),
            ).fetchone()
            assert triggers == (["tgsis_versioning", "tgsis_versioning_flush", "tgsis_versioning_rights"],)
            # the queue of set-based updates was made anew with the table: one new and one old value per column
            written = conn.execute(
                "SELECT count(*) FROM pg_attribute WHERE attrelid = %s::regclass AND attnum > 0 "
                "AND NOT attisdropped AND attgenerated = '' "
                "AND attname NOT IN ('revision', 'lastrevs', 'revclosed')",
                (f"{table}_ver",),
            ).fetchone()
            queued = conn.execute(
                "SELECT count(*) FROM pg_attribute WHERE attrelid = %s::regclass AND attnum > 0 AND NOT attisdropped",
                (f"{table}_ver_queue",),
            ).fetchone()
            assert written is not None and queued == (2 + 2 * written[0],)  # transaction, generation


def test_every_version_keeps_its_values(conn: Conn) -> None:
    fc, fid = _horizons(conn, versioned=True)
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        conn.execute("UPDATE horizons SET creator = 'carl' WHERE _geoid = %s", (fid,))
        conn.execute("UPDATE horizons_cellpros SET porosity = 9 WHERE _geoid = %s AND _idx = 0", (fid,))
    conn.commit()
    tgsis.add_property(conn, "horizons", ("k", "float8"), default=2)
    tgsis.add_property(conn, "horizons", ("basin", "text"), kind="feature", default="Paris")
    conn.commit()

    def state(version: str) -> tuple[Any, ...]:
        with tgsis.in_version(conn, version):
            feature = conn.execute("SELECT creator, basin FROM horizons WHERE _geoid = %s", (fid,)).fetchone()
            vertex = conn.execute(
                "SELECT porosity, k FROM horizons_cellpros WHERE _geoid = %s AND _idx = 0", (fid,)
            ).fetchone()
        return feature, vertex

    # every row version got the default: the child's own rows and DEFAULT's
    assert state("DEFAULT") == (("ann", "Paris"), (0.0, 2.0))
    assert state("v1") == (("carl", "Paris"), (9.0, 2.0))
    # a write through the versioned view in the child sets the new column (the trigger knows it)
    with tgsis.in_version(conn, "v1"):
        conn.execute("UPDATE horizons_cellpros SET k = 7 WHERE _geoid = %s AND _idx = 0", (fid,))
        conn.execute("UPDATE horizons SET basin = 'Aquitaine' WHERE _geoid = %s", (fid,))
    conn.commit()
    assert state("v1") == (("carl", "Aquitaine"), (9.0, 7.0)) and state("DEFAULT") == (("ann", "Paris"), (0.0, 2.0))
    # renamed: each version keeps its own values under the new name
    tgsis.rename_property(conn, "horizons", "k", "permeability")
    conn.commit()
    with tgsis.in_version(conn, "v1"):
        assert conn.execute(
            "SELECT permeability FROM horizons_cellpros WHERE _geoid = %s AND _idx = 0", (fid,)
        ).fetchone() == (7.0,)
    assert conn.execute(
        "SELECT permeability FROM horizons_cellpros WHERE _geoid = %s AND _idx = 0", (fid,)
    ).fetchone() == (2.0,)
    # older revisions too (tgsis.rows_at reads the storage as of any revision)
    revisions = conn.execute(
        "SELECT v.name, r.revision FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) ORDER BY 2"
    ).fetchall()
    assert len(revisions) >= 3
    for version, revision in revisions:
        rows = conn.execute(
            "SELECT count(*), count(*) FILTER (WHERE permeability IS NULL) FROM "
            "tgsis.rows_at(NULL::horizons_cellpros, %s, %s)",
            (version, revision),
        ).fetchone()
        assert rows == (16, 0), (version, revision)
    # the merge carries the child's values of the new columns into DEFAULT
    tgsis.merge_version(conn, "v1")
    conn.commit()
    assert conn.execute("SELECT creator, basin FROM horizons WHERE _geoid = %s", (fid,)).fetchone() == (
        "carl",
        "Aquitaine",
    )
    assert conn.execute(
        "SELECT porosity, permeability FROM horizons_cellpros WHERE _geoid = %s AND _idx = 0", (fid,)
    ).fetchone() == (9.0, 7.0)
    fetched = F.fetch_feature(conn, F.get_feature_class(conn, "horizons"), fid)
    assert isinstance(fetched.mesh, tgsis.Mesh) and fetched.mesh.vertex_properties["permeability"][0] == 7.0
    # feature versioning switched off: the plain tables keep the edited columns with DEFAULT's values
    tgsis.disable_feature_versioning(conn, force=True)
    conn.commit()
    plain = F.fetch_feature(conn, F.get_feature_class(conn, "horizons"), fid)
    assert plain.properties == {"creator": "carl", "basin": "Aquitaine"} and isinstance(plain.mesh, tgsis.Mesh)
    assert plain.mesh.vertex_properties["permeability"][0] == 7.0
    assert conn.execute("SELECT count(*) FROM horizons_cellpros").fetchone() == (16,)


def test_checkout_and_checkin_see_a_new_property(conn: Conn) -> None:
    _, fid = _horizons(conn, versioned=True)
    tgsis.create_version(conn, "edit")
    conn.commit()
    before = tgsis.checkout(conn, fid)  # of the old columns
    tgsis.add_property(conn, "horizons", ("k", "float8"), default=1)
    tgsis.add_property(conn, "horizons", ("basin", "text"), kind="feature")
    conn.commit()
    with tgsis.in_version(conn, "edit"):
        out = tgsis.checkout(conn, fid)
        assert out.mesh is not None and np.all(out.mesh.vertex_properties["k"] == 1)
        edited = out.mesh.copy()
        edited.vertex_properties["k"] = np.full(16, 5.0)
        tgsis.checkin(conn, out, edited, {"basin": "Paris"})
        conn.commit()
        mine = F.fetch_feature(conn, F.get_feature_class(conn, "horizons"), fid)
    conn.commit()  # (the version set back at the end of in_version, for good)
    assert mine.properties["basin"] == "Paris" and isinstance(mine.mesh, tgsis.Mesh)
    assert np.all(mine.mesh.vertex_properties["k"] == 5)
    default = F.fetch_feature(conn, F.get_feature_class(conn, "horizons"), fid)
    assert default.properties["basin"] is None and isinstance(default.mesh, tgsis.Mesh)
    assert np.all(default.mesh.vertex_properties["k"] == 1)
    # a check-out of the old columns is of another state of the feature: its check-in is refused, nothing written
    with pytest.raises(tgsis.CheckoutConflictError, match=f"feature {fid} was changed in version 'DEFAULT'"):
        tgsis.checkin(conn, before, before.mesh)
    conn.rollback()
    unchanged = F.fetch_feature(conn, F.get_feature_class(conn, "horizons"), fid)
    assert unchanged.properties == default.properties and unchanged.mesh is not None
    assert unchanged.mesh.same_as(default.mesh)


def test_a_property_of_the_other_alignment_and_the_rights_on_the_views(db_dsn: str) -> None:
    with login_roles(db_dsn, {"viewer": "tgsis_nobody"}) as roles, psycopg.connect(db_dsn) as conn:
        fc = F.create_feature_class(
            conn,
            "horizons",
            "SURFACE",
            cell_properties=[("porosity", "float8"), tgsis.Property("facies", "int", alignment="CELL")],
        )
        fid = F.insert_feature(conn, fc, _with_facies(_grid(3)))
        tgsis.enable_feature_versioning(conn)
        conn.execute(f"GRANT SELECT ON horizons_v, horizons_simplexpros TO {roles.name('viewer')}")
        conn.commit()
        fc = tgsis.add_property(conn, "horizons", tgsis.Property("rank", "smallint", alignment="CELL"), default=2)
        assert fc.cell_properties[-1] == tgsis.Property("rank", "smallint", alignment="CELL")
        assert _comment(conn, "horizons_simplexpros", "rank") == "cell property (smallint)"
        feature = F.fetch_feature(conn, fc, fid)
        assert isinstance(feature.mesh, tgsis.Mesh) and feature.mesh.cell_properties["rank"].tolist() == [2] * 8
        assert feature.mesh.vertex_properties.keys() == {"porosity"}
        # the rights granted on the class's views are kept
        for view in ("horizons_v", "horizons_simplexpros"):
            assert conn.execute(
                "SELECT has_table_privilege(%s, %s, 'SELECT')", (roles.name("viewer"), view)
            ).fetchone() == (True,), view
        conn.rollback()


def _with_facies(mesh: tgsis.Surface) -> tgsis.Surface:
    mesh.cell_properties = {"facies": np.arange(len(mesh.cells), dtype=np.int32)}
    return mesh


def test_temporal_class_gets_per_instant_and_vertex_properties(conn: Conn) -> None:
    tgsis.create_feature_class(
        conn, "moving", "SURFACE", time_model="EVOLVING", time_unit="Ma", instant_properties={"throw": "float8"}
    )
    fc = tgsis.add_property(conn, "moving", ("phase", "text"), kind="instant", default="rift")
    fc = tgsis.add_property(conn, "moving", ("strain", "float8"))
    assert [p.name for p in fc.instant_properties] == ["throw", "phase"]
    assert [p.name for p in fc.cell_properties] == ["strain"]
    assert _comment(conn, "moving_pros", "phase") == "per-instant feature property (text)"
    with pytest.raises(tgsis.InvalidPropertyError, match="temporal feature class moving takes no vector"):
        tgsis.add_property(conn, "moving", ("slip", "float8", 3))
    F.create_feature_class(conn, "still", "SURFACE")
    with pytest.raises(tgsis.InvalidInputError, match="static feature class still has no per-instant properties"):
        tgsis.add_property(conn, "still", ("phase", "text"), kind="instant")


def test_bad_input_changes_nothing(conn: Conn) -> None:
    _horizons(conn, versioned=True)
    tgsis.add_property(conn, "horizons", ("porosity", "float8"), kind="feature")  # a name in two lists
    conn.commit()
    before = _definition(conn)
    cases: list[tuple[Any, type[tgsis.Error], str]] = [
        (
            lambda: tgsis.add_property(conn, "nope", ("k", "float8")),
            tgsis.NotFoundError,
            "feature class 'nope' does not",
        ),
        (
            lambda: tgsis.rename_property(conn, "horizons", "nope", "x"),
            tgsis.InvalidPropertyError,
            "feature class horizons has no property 'nope'",
        ),
        (
            lambda: tgsis.drop_property(conn, "horizons", "nope", kind="cell"),
            tgsis.InvalidPropertyError,
            "has no cell property 'nope'",
        ),
        (
            lambda: tgsis.drop_property(conn, "horizons", "porosity"),
            tgsis.InvalidPropertyError,
            "has more than one property 'porosity'",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("creator", "text"), kind="feature"),
            tgsis.AlreadyExistsError,
            "has a feature property 'creator' already",
        ),
        (
            lambda: tgsis.rename_property(conn, "horizons", "creator", "porosity", kind="feature"),
            tgsis.AlreadyExistsError,
            "has a feature property 'porosity' already",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("k", "geometry")),
            tgsis.InvalidPropertyError,
            "has type 'geometry', which is not allowed",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("k", "text")),
            tgsis.InvalidPropertyError,
            "vertex and cell properties must be numbers or booleans",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("k", "float8")),
            tgsis.InvalidPropertyError,
            "has stored rows in horizons_cellpros, which need a value",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("k", "int"), default="1.5e"),
            tgsis.InvalidPropertyError,
            "default '1.5e' of property 'k' is not a valid integer",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ('k"; DROP TABLE horizons; --', "int"), default=1),
            tgsis.InvalidNameError,
            "property name .* is not allowed",
        ),
        (
            lambda: tgsis.rename_property(conn, "horizons", "creator", 'a"b'),
            tgsis.InvalidNameError,
            "property name 'a\"b' is not allowed",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("bbox", "text"), kind="feature"),
            tgsis.InvalidNameError,
            "feature property name 'bbox' is taken by tgsis",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("revision", "int"), default=0),
            tgsis.InvalidNameError,
            "'revision' is taken by tgsis",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("part", "int"), default=0),
            tgsis.InvalidNameError,
            "'part' is taken by tgsis",
        ),
        (
            lambda: tgsis.drop_property(conn, "horizons", "_geoid"),
            tgsis.InvalidNameError,
            "column '_geoid' of feature class horizons is a key, time or versioning column",
        ),
        (lambda: tgsis.rename_property(conn, "horizons", "_idx", "idx"), tgsis.InvalidNameError, "is a key, time"),
        (lambda: tgsis.drop_property(conn, "horizons", "revision"), tgsis.InvalidNameError, "versioning column"),
        (
            lambda: tgsis.add_property(conn, "horizons", tgsis.Property("facies", "int", alignment="CELL"), default=0),
            tgsis.InvalidPropertyError,
            "feature class horizons has no table for cell properties",
        ),
        (
            lambda: tgsis.add_property(conn, "horizons", ("k", "float8"), kind="vertex"),  # type: ignore[arg-type]
            tgsis.InvalidInputError,
            "property kind 'vertex' must be feature, cell or instant",
        ),
    ]
    for call, error, message in cases:
        with pytest.raises(error, match=message) as caught:
            call()
        assert caught.value.sqlstate == error.code, message
        conn.rollback()
        assert _definition(conn) == before, message
    # a view of someone else's over the class's tables: refused, nothing changed
    conn.execute("CREATE VIEW my_pros AS SELECT _geoid, porosity FROM horizons_cellpros")
    conn.commit()
    with pytest.raises(tgsis.InUseError, match="other objects depend on table public.horizons_cellpros") as caught:
        tgsis.drop_property(conn, "horizons", "porosity", kind="cell", force=True)
    assert caught.value.hint == "drop the views that read the class's tables, change the class, then create them again"
    conn.rollback()
    assert _definition(conn) == before
    # hints say what to do in SQL terms
    with pytest.raises(tgsis.InUseError) as caught:
        tgsis.drop_property(conn, "horizons", "creator")
    assert caught.value.hint == "drop it with p_force => true to delete its values"


def test_roles_without_tgsis_admin_are_refused(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as owner:
        _horizons(owner, versioned=True)
        before = _definition(owner)
        storage = storage_of(owner, "horizons_cellpros", "public")
    with login_roles(db_dsn, {"eve": "tgsis_editor"}) as roles:
        eve = roles.connect("eve")
        calls: list[Callable[[], object]] = [
            lambda: tgsis.add_property(eve, "horizons", ("k", "float8"), default=1),
            lambda: tgsis.rename_property(eve, "horizons", "porosity", "phi"),
            lambda: tgsis.drop_property(eve, "horizons", "porosity", force=True),
        ]
        for call in calls:
            with pytest.raises(tgsis.MissingPrivilegeError, match="may not .* properties of feature classes") as caught:
                call()
            assert caught.value.hint is not None and caught.value.hint.startswith("a DBA may run: GRANT tgsis_admin TO")
            eve.rollback()
        # nor can they reach the helpers' work directly: the storage and the view are tgsis's
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            eve.execute(f"ALTER TABLE {storage} ADD COLUMN k float8")
        eve.rollback()
    with psycopg.connect(db_dsn) as owner:
        assert _definition(owner) == before


def test_a_writer_during_an_edit_loses_nothing(db_dsn: str) -> None:
    """An edit waits for a writer through the view; a writer waits for an edit and then writes the new columns."""
    with psycopg.connect(db_dsn) as conn:
        _, fid = _horizons(conn, versioned=True)
        tgsis.create_version(conn, "v1")
        conn.commit()
        # 1. a writer in the child holds its row; the edit waits for it, then every row version has the default
        writer = connect(db_dsn, "writer")
        tgsis.goto_version(writer, "v1")
        writer.execute("UPDATE horizons SET creator = 'bob' WHERE _geoid = %s", (fid,))
        edit = Background(
            db_dsn,
            "editor",
            lambda c: tgsis.add_property(c, "horizons", ("basin", "text"), kind="feature", default="Paris"),
        )
        wait_until_blocked(conn, edit.pid, writer.info.backend_pid)
        writer.commit()
        edit.finish()
        with tgsis.in_version(conn, "v1"):
            assert conn.execute("SELECT creator, basin FROM horizons WHERE _geoid = %s", (fid,)).fetchone() == (
                "bob",
                "Paris",
            )
        assert conn.execute("SELECT creator, basin FROM horizons WHERE _geoid = %s", (fid,)).fetchone() == (
            "ann",
            "Paris",
        )
        conn.rollback()  # (the observer's reads hold the view until its transaction ends)
        # 2. an edit in flight; a writer through the view waits, then writes through the new view and trigger:
        # its new row version keeps the column's value (the old trigger would have left it NULL)
        editor = connect(db_dsn, "editor")
        editor.execute("SELECT tgsis.add_property('horizons', 'feature', '[\"depth\", \"float8\"]', '100')")

        def write(c: Conn) -> None:
            c.execute("UPDATE horizons SET creator = 'carl' WHERE _geoid = %s", (fid,))

        late = Background(db_dsn, "writer", write, version="v1")
        wait_until_blocked(conn, late.pid, editor.info.backend_pid)
        editor.commit()
        late.finish()
        with tgsis.in_version(conn, "v1"):
            assert conn.execute("SELECT creator, basin, depth FROM horizons WHERE _geoid = %s", (fid,)).fetchone() == (
                "carl",
                "Paris",
                100.0,
            )
        conn.rollback()
        # and the same for an edit that renames: the waiting writer's row keeps every value
        editor.execute("SELECT tgsis.rename_property('horizons', 'basin', 'region')")
        late = Background(
            db_dsn,
            "writer",
            lambda c: c.execute("UPDATE horizons SET creator = 'dan' WHERE _geoid = %s", (fid,)),
            version="v1",
        )
        wait_until_blocked(conn, late.pid, editor.info.backend_pid)
        editor.commit()
        late.finish()
        with tgsis.in_version(conn, "v1"):
            assert conn.execute("SELECT creator, region, depth FROM horizons WHERE _geoid = %s", (fid,)).fetchone() == (
                "dan",
                "Paris",
                100.0,
            )
        writer.close()
        editor.close()


def test_a_class_cannot_be_versioned_while_feature_versioning_is_off(conn: Conn) -> None:
    with pytest.raises(
        tgsis.VersioningError, match="feature class 'wells' cannot be versioned on its own: feature versioning is off"
    ):
        F.create_feature_class(conn, "wells", "MULTILINESTRING", versioned=True)
    conn.rollback()
    assert conn.execute("SELECT count(*) FROM tgsis.catalog").fetchone() == (0,)
    assert conn.execute("SELECT to_regclass('wells')").fetchone() == (None,)
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    fc = F.create_feature_class(conn, "wells", "MULTILINESTRING", versioned=True)
    assert fc.versioned
    assert {t.table for t in tgsis.versioned_tables(conn)} >= {fc.featuretable, fc.cellprotable}
    # (classes without versioning: tests/test_unversioned_classes.py)
