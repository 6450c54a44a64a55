"""Adding a vertex or cell property to a class whose features have no property rows (issue 36, point 4).

A class registered without vertex or cell properties stores no rows in its
property tables. tgsis.add_property must give every stored feature (every
collection member that has all the class's properties) a row per vertex or
cell holding the default, in every version and every revision, or refuse
with nothing done; tgsis.fill_property repairs a class left without them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.roles import login_roles
from tests.sessions import Background, connect, wait_until_blocked
from tgsis.cli import main
from tgsis.db import features as F
from tgsis.mesh import GeometryCollection, LineSet, PointSet, Surface, TetraMesh

Conn = psycopg.Connection[Any]


def _grid(side: int = 4, z: float = 0.0) -> Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.full(side * side, z)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]), name=f"z{z}")


def _bare(conn: Conn, *, versioned: bool, alignment: str = "VERTEX") -> tuple[int, int]:
    """Class c2 with no vertex or cell property and two surfaces (4x4 and 3x3 grids)."""
    F.create_feature_class(conn, "c2", "SURFACE", feature_properties={"creator": "text"}, alignment=alignment)  # type: ignore[arg-type]
    first = F.insert_feature(conn, "c2", _grid(4), {"creator": "ann"})
    second = F.insert_feature(conn, "c2", _grid(3, 1.0), {"creator": "bob"})
    if versioned:
        tgsis.enable_feature_versioning(conn)
    conn.commit()
    return first, second


def _values(conn: Conn, fid: int, name: str, alignment: str = "VERTEX") -> list[Any]:
    feature = F.fetch_feature(conn, F.get_feature_class(conn, "c2"), fid)
    assert isinstance(feature.mesh, tgsis.Mesh)
    values = feature.mesh.vertex_properties if alignment == "VERTEX" else feature.mesh.cell_properties
    return list(np.asarray(values[name]).tolist())


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
@pytest.mark.parametrize("alignment", ["VERTEX", "CELL"])
def test_every_stored_feature_gets_the_default(conn: Conn, versioned: bool, alignment: str) -> None:
    first, second = _bare(conn, versioned=versioned, alignment=alignment)
    tgsis.add_property(conn, "c2", ("porosity", "float8"), default=0.2)
    conn.commit()
    n1, n2 = (16, 9) if alignment == "VERTEX" else (18, 8)
    assert _values(conn, first, "porosity", alignment) == [0.2] * n1
    assert _values(conn, second, "porosity", alignment) == [0.2] * n2
    # a vector property too, each component
    tgsis.add_property(conn, "c2", tgsis.Property("dir", "float4", 3), default=1.5)
    conn.commit()
    assert _values(conn, second, "dir", alignment) == [[1.5, 1.5, 1.5]] * n2
    # new features give their own values, as in a class registered with the properties
    count = 16 if alignment == "VERTEX" else 18
    mesh = _grid(4, 2.0)
    values: dict[str, np.ndarray] = {"porosity": np.linspace(0, 1, count), "dir": np.ones((count, 3), dtype=np.float32)}
    mesh = Surface(
        mesh.vertices,
        mesh.cells,
        vertex_properties=values if alignment == "VERTEX" else None,
        cell_properties=values if alignment == "CELL" else None,
    )
    third = F.insert_feature(conn, "c2", mesh, {"creator": "cy"})
    conn.commit()
    assert _values(conn, third, "porosity", alignment) == np.linspace(0, 1, count).tolist()


def _storage_matches_geometry(conn: Conn, table: str = "c2_cellpros", source: str = "tgsis.vrtx") -> None:
    """In every version and revision, the property rows are exactly the vertices (keys and row count)."""
    revisions = conn.execute(
        "SELECT v.name, r.revision FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) ORDER BY 2"
    ).fetchall()
    assert len(revisions) >= 3
    key = "vrtxid" if source == "tgsis.vrtx" else "trglid"
    for version, revision in revisions:
        props = conn.execute(
            f"SELECT _geoid, _idx FROM tgsis.rows_at(NULL::{table}, %s, %s) ORDER BY 1, 2", (version, revision)
        ).fetchall()
        vertices = conn.execute(
            f"SELECT geoid, {key} FROM tgsis.rows_at(NULL::{source}, %s, %s) "
            "WHERE geoid IN (SELECT _geoid FROM tgsis.rows_at(NULL::c2, %s, %s)) ORDER BY 1, 2",
            (version, revision, version, revision),
        ).fetchall()
        assert props == vertices, (version, revision)


def test_every_version_and_revision_gets_the_rows(conn: Conn) -> None:
    first, second = _bare(conn, versioned=True)
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        third = F.insert_feature(conn, "c2", _grid(2, 5.0), {"creator": "cy"})  # only in the child
        conn.execute("UPDATE tgsis.vrtx SET z = 7 WHERE geoid = %s AND vrtxid = 0", (first,))
        assert F.delete_feature(conn, "c2", second)
    conn.commit()
    tgsis.save_revision(conn, "before_property")
    conn.commit()
    with tgsis.in_version(conn, "v1"):  # a second revision of the child moves the vertex again
        conn.execute("UPDATE tgsis.vrtx SET z = 8 WHERE geoid = %s AND vrtxid = 0", (first,))
    conn.commit()
    tgsis.add_property(conn, "c2", ("porosity", "float8"), default=0.25)
    conn.commit()
    assert _values(conn, first, "porosity") == [0.25] * 16
    assert _values(conn, second, "porosity") == [0.25] * 9
    with tgsis.in_version(conn, "v1"):
        assert _values(conn, first, "porosity") == [0.25] * 16
        assert _values(conn, third, "porosity") == [0.25] * 4
        moved = F.fetch_feature(conn, "c2", first).mesh
        assert isinstance(moved, tgsis.Mesh) and moved.vertices[0, 2] == 8
        assert conn.execute("SELECT count(*) FROM c2 WHERE _geoid = %s", (second,)).fetchone() == (0,)
    _storage_matches_geometry(conn)
    # the child's edits and the new rows merge: DEFAULT reads the child's features with the property
    tgsis.merge_version(conn, "v1")
    conn.commit()
    assert _values(conn, third, "porosity") == [0.25] * 4
    assert F.fetch_feature(conn, "c2", first).mesh.vertices[0, 2] == 8  # type: ignore[union-attr]
    _storage_matches_geometry(conn)
    # and versioning switched off keeps readable plain tables
    tgsis.disable_feature_versioning(conn, force=True)
    conn.commit()
    assert _values(conn, third, "porosity") == [0.25] * 4


def test_cell_rows_in_a_child_version(conn: Conn) -> None:
    first, _ = _bare(conn, versioned=True, alignment="CELL")
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        third = F.insert_feature(conn, "c2", _grid(2, 5.0), {"creator": "cy"})
    conn.commit()
    tgsis.add_property(conn, "c2", tgsis.Property("dir", "float8", 2), default=-1)
    conn.commit()
    with tgsis.in_version(conn, "v1"):
        assert _values(conn, third, "dir", "CELL") == [[-1.0, -1.0]] * 2
        assert _values(conn, first, "dir", "CELL") == [[-1.0, -1.0]] * 18
    _storage_matches_geometry(conn, source="tgsis.trgl")


def test_a_class_without_versioning(conn: Conn) -> None:
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "c2", "SURFACE", versioned=False)
    fid = F.insert_feature(conn, "c2", _grid(3))
    conn.commit()
    conn.execute("UPDATE tgsis.vrtx SET z = 4 WHERE geoid = %s AND vrtxid = 0", (fid,))  # a closed row version
    conn.commit()
    tgsis.add_property(conn, "c2", ("porosity", "float8"), default=0.5)
    conn.commit()
    assert _values(conn, fid, "porosity") == [0.5] * 9
    assert conn.execute("SELECT count(*) FROM c2_cellpros").fetchone() == (9,)


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_uploads_at_the_same_time(db_dsn: str, versioned: bool) -> None:
    with psycopg.connect(db_dsn) as conn:
        first, _ = _bare(conn, versioned=versioned)
        # 1. an upload in flight: the change waits for it, then gives its feature rows too
        writer = connect(db_dsn, "writer")
        early = F.insert_feature(writer, "c2", _grid(2, 3.0))
        edit = Background(db_dsn, "editor", lambda c: tgsis.add_property(c, "c2", ("porosity", "float8"), default=1))
        wait_until_blocked(conn, edit.pid, writer.info.backend_pid)
        writer.commit()
        edit.finish()
        assert _values(conn, early, "porosity") == [1.0] * 4
        conn.rollback()
        # 2. an upload that read the class before a change in flight, and writes after it: refused, nothing stored
        F.create_feature_class(conn, "c3", "SURFACE")
        conn.commit()
        stale = F.get_feature_class(conn, "c3")
        conn.rollback()
        editor = connect(db_dsn, "editor")
        editor.execute("SELECT tgsis.add_property('c3', 'cell', '[\"k\", \"float8\"]', '2')")
        late = Background(db_dsn, "writer", lambda c: F.insert_feature(c, stale, _grid(2)))
        wait_until_blocked(conn, late.pid, editor.info.backend_pid)
        editor.commit()
        with pytest.raises(
            tgsis.InUseError,
            match="feature class c3 gained vertex or cell properties while the "
            "feature was written: nothing of it was stored",
        ):
            late.finish()
        assert conn.execute("SELECT count(*) FROM c3").fetchone() == (0,)
        assert conn.execute(
            "SELECT count(*) FROM tgsis.geometry WHERE geoid NOT IN (%s, %s)", (first, early)
        ).fetchone() == (1,)  # the second feature of _bare only
        writer.close()
        editor.close()


def _members() -> list[Any]:
    lines = LineSet([[10.0, 0, 0], [11.0, 0, 0], [12, 1, 0.5]], [[0, 1], [1, 2]], name="trace")
    points = PointSet([[20, 20, 20], [21, 20, 20]], name="samples")
    solid = TetraMesh(
        [[0, 0, -10], [1, 0, -10], [0, 1, -10], [0, 0, -9], [1, 1, -9]], [[0, 1, 2, 3], [1, 2, 3, 4]], name="body"
    )
    return [_grid(3), lines, points, solid]


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
@pytest.mark.parametrize("alignment", ["VERTEX", "CELL"])
def test_collection_members_get_the_rows(conn: Conn, versioned: bool, alignment: str) -> None:
    F.create_feature_class(conn, "rocks", "GEOMETRYCOLLECTION", alignment=alignment)  # type: ignore[arg-type]
    fid = F.insert_feature(conn, "rocks", GeometryCollection(_members(), name="block"))
    if versioned:
        tgsis.enable_feature_versioning(conn)
    conn.commit()
    tgsis.add_property(conn, "rocks", ("code", "int4"), default=3)
    conn.commit()
    fetched = F.fetch_feature(conn, "rocks", fid).mesh
    assert isinstance(fetched, GeometryCollection)
    for member in fetched:
        count = member.n_vertices if alignment == "VERTEX" else member.n_cells
        values = member.vertex_properties if alignment == "VERTEX" else member.cell_properties
        assert values["code"].tolist() == [3] * count, member.name


def test_refused_with_nothing_done(conn: Conn) -> None:
    _bare(conn, versioned=True)
    before = conn.execute("SELECT cell_properties FROM tgsis.catalog WHERE classname = 'c2'").fetchone()
    # no default: the stored features would have no value
    with pytest.raises(
        tgsis.InvalidPropertyError,
        match="feature class c2 has 2 stored geometries without rows in "
        "c2_cellpros, which need a value of the new vertex property "
        "'porosity'",
    ) as caught:
        tgsis.add_property(conn, "c2", ("porosity", "float8"))
    assert caught.value.hint == "give p_default, e.g. '0'"
    conn.rollback()
    # a default that is no value of the type
    with pytest.raises(tgsis.InvalidPropertyError, match="default 'x' of property 'porosity' is not a valid"):
        tgsis.add_property(conn, "c2", ("porosity", "float8"), default="x")
    conn.rollback()
    assert conn.execute("SELECT cell_properties FROM tgsis.catalog WHERE classname = 'c2'").fetchone() == before
    assert conn.execute("SELECT count(*) FROM c2_cellpros_ver").fetchone() == (0,)
    # a class with no feature needs no default
    F.create_feature_class(conn, "empty", "SURFACE")
    conn.commit()
    fc = tgsis.add_property(conn, "empty", ("porosity", "float8"))
    assert [p.name for p in fc.cell_properties] == ["porosity"]


def test_a_temporal_class_without_rows_is_refused(conn: Conn) -> None:
    tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="INSTANTS", time_unit="Ma")
    fid = tgsis.insert_feature(conn, "moving", tgsis.SurfaceSeries([0.0, 1.0], [_grid(3), _grid(3, 1.0)]))
    conn.commit()
    with pytest.raises(
        tgsis.InvalidPropertyError,
        match="feature class moving has 1 stored geometries without rows "
        "in moving_cellpros, and tgsis cannot make them for model 2",
    ):
        tgsis.add_property(conn, "moving", ("strain", "float8"), default=0)
    conn.rollback()
    assert tgsis.get_feature_class(conn, "moving").cell_properties == ()
    assert conn.execute("SELECT count(*) FROM moving_cellpros").fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM moving WHERE _geoid = %s", (fid,)).fetchone() == (1,)


def _break(conn: Conn) -> None:
    """The state tgsis.add_property left before this fix: the column and catalog entry, no rows for the features."""
    conn.execute("""SELECT tgsis.alter_class_table(c, 'c2_cellpros',
                        ARRAY['ADD COLUMN porosity float8 NOT NULL DEFAULT 0', 'ALTER COLUMN porosity DROP DEFAULT'],
                        '[{"name": "porosity", "type": "double precision"}]', 'vertex property')
                      FROM tgsis.catalog c WHERE c.classname = 'c2'""")
    conn.execute("""UPDATE tgsis.catalog SET cell_properties = '[{"name": "porosity", "type": "double precision"}]'
                     WHERE classname = 'c2'""")


def test_a_broken_class_is_repaired(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    with psycopg.connect(db_dsn) as conn:
        first, second = _bare(conn, versioned=True)
        tgsis.create_version(conn, "v1")
        with tgsis.in_version(conn, "v1"):
            third = F.insert_feature(conn, "c2", _grid(2, 5.0), {"creator": "cy"})
        conn.commit()
        _break(conn)
        conn.commit()
        with pytest.raises(tgsis.InvalidPropertyError, match="c2_cellpros has 0 rows for 16 vertices"):
            F.fetch_feature(conn, "c2", first)
        conn.rollback()
        # adding another property refuses, naming the repair
        with pytest.raises(tgsis.InvalidPropertyError, match="though it has vertex properties already") as caught:
            tgsis.add_property(conn, "c2", ("k", "float8"), default=1)
        assert caught.value.hint is not None and "tgsis.fill_property_rows('c2'" in caught.value.hint
        conn.rollback()
    with login_roles(db_dsn, {"admin": "tgsis_admin", "editor": "tgsis_editor"}) as roles:
        editor = roles.connect("editor")
        with pytest.raises(tgsis.MissingPrivilegeError, match="may not fill properties of feature classes"):
            tgsis.fill_property_rows(editor, "c2", {"porosity": 0.5})
        admin = roles.connect("admin")
        with pytest.raises(tgsis.InvalidPropertyError, match="value 'lots' of property 'porosity' is not a valid"):
            tgsis.fill_property_rows(admin, "c2", {"porosity": "lots"})
        admin.rollback()
        assert tgsis.fill_property_rows(admin, "c2", {"porosity": 0.5}) == {"c2_cellpros": (3, 16 + 9 + 4)}
        admin.commit()
        # once repaired, nothing is missing
        assert tgsis.fill_property_rows(admin, "c2", {"porosity": 0.7}) == {"c2_cellpros": (0, 0)}
        admin.commit()
    with psycopg.connect(db_dsn) as conn:
        assert _values(conn, first, "porosity") == [0.5] * 16
        assert _values(conn, second, "porosity") == [0.5] * 9
        with tgsis.in_version(conn, "v1"):
            assert _values(conn, third, "porosity") == [0.5] * 4
        _storage_matches_geometry(conn)


def test_a_role_with_fewer_rights(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as conn:
        first, _ = _bare(conn, versioned=True)
    with login_roles(db_dsn, {"admin": "tgsis_admin", "editor": "tgsis_editor"}) as roles:
        editor = roles.connect("editor")
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.add_property(editor, "c2", ("porosity", "float8"), default=1)
        admin = roles.connect("admin")
        tgsis.add_property(admin, "c2", ("porosity", "float8"), default=1)
        admin.commit()
        assert _values(editor, first, "porosity") == [1.0] * 16


def test_cli_says_what_was_stored(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    with psycopg.connect(db_dsn) as conn:
        _bare(conn, versioned=True)
    # no default: refused in the CLI's words, nothing changed
    assert main(["--dsn", db_dsn, "class", "alter", "c2", "--add-property", "k:float8"]) == 1
    err = capsys.readouterr().err
    assert "feature class c2 has 2 stored geometries without rows in c2_cellpros" in err
    assert "HINT: give the value stored rows get: --add-property NAME:TYPE=VALUE" in err
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "alter",
                "c2",
                "--add-property",
                "porosity:float8=0.2",
                "--add-feature-property",
                "basin:text=Paris",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out.splitlines()
    assert out[:2] == [
        "added feature property basin: 2 feature(s) got the default 'Paris'",
        "added cell property porosity: 25 vertex row(s) of 2 feature(s) got the default 0.2",
    ]
    assert main(["--dsn", db_dsn, "class", "alter", "c2", "--add-property", "k:float8:cell=1", "--json"]) == 1
    assert "has no table for cell properties" in capsys.readouterr().err


def test_cli_repairs_a_broken_class(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    with psycopg.connect(db_dsn) as conn:
        first, _ = _bare(conn, versioned=False)
        conn.execute("ALTER TABLE c2_cellpros ADD COLUMN porosity float8 NOT NULL")
        conn.execute("""UPDATE tgsis.catalog SET cell_properties = '[{"name": "porosity", "type": "double precision"}]'
                         WHERE classname = 'c2'""")
        conn.commit()
    for bad, message in [
        ("porosity", "--fill-property 'porosity' must be NAME=VALUE"),
        ("nope=1", "feature class c2 has no"),
        ("porosity=x", "value 'x' of property 'porosity'"),
    ]:
        assert main(["--dsn", db_dsn, "class", "alter", "c2", "--fill-property", bad]) == 1, bad
        assert message in capsys.readouterr().err, bad
    assert main(["--dsn", db_dsn, "class", "alter", "c2", "--fill-property", "porosity=0.3"]) == 0
    assert (
        capsys.readouterr().out.splitlines()[0]
        == "filled c2_cellpros: 25 row(s) of 2 feature(s) that had none, in every version"
    )
    with psycopg.connect(db_dsn) as conn:
        assert _values(conn, first, "porosity") == [0.3] * 16
