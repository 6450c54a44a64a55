"""Alignment is per property: a feature class may hold vertex and cell properties side by side (issue 16).

The class's own alignment (``proalignment``) keeps its properties in
``<class>_cellpros`` as before; the properties of the other alignment are in
``<class>_simplexpros`` (a VERTEX class) or ``<class>_vertexpros`` (a CELL
class), with the same keys.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis import formats
from tgsis.cli import main
from tgsis.db import features as F
from tgsis.mesh import Mesh, Surface

Conn = psycopg.Connection[Any]

PROPERTIES: list[tuple[str, str] | F.Property] = [
    ("porosity", "double precision"),
    F.Property("Facies", "integer", alignment="CELL"),
    F.Property("normal", "real", 3, "CELL"),
]


def _surface(z: float = 0.0) -> Surface:
    u, v = np.meshgrid(np.arange(4.0), np.arange(4.0))
    vertices = np.stack([u.ravel(), v.ravel(), np.full(16, z) + 0.1 * u.ravel() * v.ravel()], axis=1)
    idx = np.arange(16).reshape(4, 4)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    m = len(triangles)
    return Surface(
        vertices,
        triangles,
        name=f"s{z}",
        vertex_properties={"porosity": np.linspace(0.1, 0.3, 16)},
        cell_properties={
            "Facies": np.arange(m, dtype=np.int32) % 3,
            "normal": np.tile(np.array([0, 0, 1], dtype=np.float32), (m, 1)),
            "part": np.repeat([0, 1], [9, m - 9]),
        },
    )


@pytest.fixture
def horizons(conn: Conn) -> F.FeatureClass:
    fc = F.create_feature_class(conn, "horizons", "SURFACE", cell_properties=PROPERTIES)
    conn.commit()
    return fc


def test_a_vertex_class_with_cell_properties(conn: Conn, horizons: F.FeatureClass) -> None:
    assert horizons.alignment == "VERTEX" and horizons.otherprotable == "horizons_simplexpros"
    assert [horizons.alignment_of(p) for p in horizons.cell_properties] == ["VERTEX", "CELL", "CELL"]
    row = conn.execute("SELECT cell_properties FROM tgsis.catalog WHERE classname = 'horizons'").fetchone()
    assert row is not None and row[0] == [
        {"name": "porosity", "type": "double precision"},
        {"name": "Facies", "type": "integer", "alignment": "CELL"},
        {"name": "normal", "type": "real", "size": 3, "alignment": "CELL"},
    ]
    columns = {
        t: [
            r[0]
            for r in conn.execute(
                "SELECT attname FROM pg_attribute WHERE attrelid = %s::regclass AND attnum > 0 ORDER BY attnum", (t,)
            )
        ]
        for t in ("horizons_cellpros", "horizons_simplexpros")
    }
    assert columns == {
        "horizons_cellpros": ["_geoid", "_idx", "porosity"],
        "horizons_simplexpros": ["_geoid", "_idx", "Facies", "normal"],
    }
    surface = _surface()
    fid = F.insert_feature(conn, horizons, surface)
    conn.commit()
    back = F.fetch_feature(conn, horizons, fid).mesh
    assert isinstance(back, Surface) and back.same_as(surface)  # vertex and cell properties, and the parts
    assert conn.execute(
        'SELECT count(*), sum("Facies") FROM horizons_simplexpros WHERE _geoid = %s', (fid,)
    ).fetchone() == (18, int(surface.cell_properties["Facies"].sum()))
    assert conn.execute("SELECT count(*) FROM horizons_cellpros WHERE _geoid = %s", (fid,)).fetchone() == (16,)


def test_a_cell_class_with_vertex_properties_from_a_vtk_file(conn: Conn, tmp_path: Path) -> None:
    fc = F.create_feature_class(
        conn,
        "blocks",
        "SURFACE",
        alignment="CELL",
        cell_properties=[("Facies", "integer"), F.Property("porosity", "float8", 1, "VERTEX")],
    )
    assert fc.otherprotable == "blocks_vertexpros"
    surface = _surface()
    surface.cell_properties = {"Facies": surface.cell_properties["Facies"]}
    formats.write(surface, tmp_path / "s.vtu")
    [read] = formats.read(tmp_path / "s.vtu")
    fid = F.insert_feature(conn, fc, read)
    conn.commit()
    back = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(back, Mesh) and back.same_as(read)
    assert set(back.vertex_properties) == {"porosity"} and set(back.cell_properties) == {"Facies"}


def test_missing_and_extra_properties_are_named_per_alignment(conn: Conn, horizons: F.FeatureClass) -> None:
    surface = _surface()
    del surface.cell_properties["Facies"]
    with pytest.raises(
        tgsis.InvalidPropertyError, match=r"needs triangle properties \['Facies'\], which the mesh lacks"
    ):
        F.insert_feature(conn, horizons, surface)
    surface = _surface()
    surface.vertex_properties["Facies"] = np.zeros(16, dtype=np.int32)  # the right name on the wrong alignment
    with pytest.raises(tgsis.InvalidPropertyError, match=r"has no column for properties \['Facies'\]"):
        F.insert_feature(conn, horizons, surface)
    assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == (0,)
    fid = F.insert_feature(conn, horizons, surface, drop_extra_properties=True)
    assert F.fetch_feature(conn, horizons, fid).mesh.same_as(_surface())  # type: ignore[union-attr]


def test_edits_in_a_child_version_and_merge(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _surface())
    tgsis.enable_feature_versioning(conn)
    assert {t.table for t in tgsis.versioned_tables(conn)} >= {"horizons_cellpros", "horizons_simplexpros"}
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        edited = F.fetch_feature(conn, horizons, fid).mesh
        assert isinstance(edited, Surface)
        edited.cell_properties["Facies"][4] = 7
        edited.vertex_properties["porosity"][2] = 0.9
        edited.vertices[5, 2] += 1.0
        result = tgsis.save_feature(conn, horizons, fid, edited)
        conn.commit()
        assert result.property_rows_changed == 2  # one vertex row and one cell row
        child = F.fetch_feature(conn, horizons, fid).mesh
        assert isinstance(child, Surface) and child.same_as(edited)
    default = F.fetch_feature(conn, horizons, fid).mesh
    assert isinstance(default, Surface) and default.same_as(_surface())
    tgsis.merge_version(conn, "edit")
    conn.commit()
    merged = F.fetch_feature(conn, horizons, fid).mesh
    assert isinstance(merged, Surface) and merged.same_as(edited)


def test_checkin_sees_a_change_of_the_other_alignment(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _surface())
    conn.commit()
    checked = tgsis.checkout(conn, fid)
    conn.execute('UPDATE horizons_simplexpros SET "Facies" = 9 WHERE _geoid = %s AND _idx = 0', (fid,))
    conn.commit()
    checked.mesh.vertices[0, 2] += 1.0
    with pytest.raises(tgsis.CheckoutConflictError):
        tgsis.checkin(conn, checked)
    conn.rollback()


def test_delete_and_drop_remove_both_property_tables(conn: Conn, horizons: F.FeatureClass) -> None:
    first = F.insert_feature(conn, horizons, _surface())
    F.insert_feature(conn, horizons, _surface(10.0))
    assert F.delete_feature(conn, horizons, first)
    assert conn.execute("SELECT count(*) FROM horizons_simplexpros WHERE _geoid = %s", (first,)).fetchone() == (0,)
    tgsis.enable_feature_versioning(conn)
    F.drop_feature_class(conn, "horizons", force=True)
    conn.commit()
    assert conn.execute(
        "SELECT to_regclass('horizons_simplexpros'), to_regclass('horizons_simplexpros_ver')"
    ).fetchone() == (None, None)
    assert conn.execute("SELECT count(*) FROM tgsis.versioned_tables WHERE tablename LIKE 'horizons%'").fetchone() == (
        0,
    )


@pytest.mark.parametrize(
    ("properties", "kwargs", "message"),
    [
        ([{"name": "f", "type": "int", "alignment": "FACE"}], {}, "has alignment 'FACE'"),
        (
            [],
            {"feature_properties": [{"name": "f", "type": "int", "alignment": "CELL"}]},
            "only vertex and cell properties",
        ),
        ([{"name": "f", "type": "int", "alignment": "CELL"}], {"time_model": "EVOLVING"}, "nor properties of another"),
    ],
)
def test_bad_alignments_change_nothing(
    conn: Conn, properties: list[dict[str, str]], kwargs: dict[str, Any], message: str
) -> None:
    with pytest.raises(tgsis.InvalidPropertyError, match=message):
        F.create_feature_class(conn, "bad", "SURFACE", cell_properties=properties, **kwargs)
    assert conn.execute("SELECT count(*) FROM tgsis.catalog").fetchone() == (0,)
    assert conn.execute("SELECT to_regclass('bad'), to_regclass('bad_simplexpros')").fetchone() == (None, None)


def test_cli_creates_a_class_with_both_alignments(conn: Conn, db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "create",
                "wells",
                "--geotype",
                "SURFACE",
                "--property",
                "porosity:float8",
                "--property",
                "Facies:int:CELL",
                "--property",
                "slip:float8:3",
            ]
        )
        == 0
    )
    assert "tables wells, wells_cellpros, wells_simplexpros, view wells_v" in capsys.readouterr().out
    assert main(["--dsn", db_dsn, "class", "list"]) == 0
    assert (
        "vertex: porosity double precision, Facies integer (cell), slip double precision[3]" in capsys.readouterr().out
    )
    assert main(["--dsn", db_dsn, "class", "create", "bad", "--geotype", "SURFACE", "--property", "f:int:FACE"]) == 1
    assert "'FACE' is neither a number of components nor VERTEX or CELL" in capsys.readouterr().err
