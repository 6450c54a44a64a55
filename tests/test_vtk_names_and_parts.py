"""VTK files keep array names as they were and take GOCAD models with parts (issue 37, part 5).

* An array name with blanks read from a VTK file (kept in
  ``metadata["vtk_array_names"]``) is written back as it was: as the
  ``Name`` attribute of ``.vtu``/``.vtp`` (XML allows blanks), and in legacy
  ``.vtk``, where a name is one word, encoded as VTK's own writer encodes it
  (``%20``) and decoded on read.
* A collection whose members have parts on only some of them (a GOCAD file of
  faults, some of several TFACEs) is written to ``.vtu`` and ``.vtk``: the
  ``part`` cell array covers every member, -1 for the cells of a member
  without parts, and reading the file gives each member back as it was.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import psycopg
import pytest
import pyvista as pv

from tgsis import formats
from tgsis.cli import main
from tgsis.cli._hints import to_cli
from tgsis.errors import FileFormatError
from tgsis.mesh import GeometryCollection, Mesh, Surface

# two faults in one GOCAD file: the first of two TFACEs, the second of one
TWO_FAULTS = """GOCAD TSurf 1
HEADER {
name:split fault
}
TFACE
VRTX 1 0 0 0
VRTX 2 1 0 0
VRTX 3 0 1 0
TRGL 1 2 3
TFACE
VRTX 4 1 1 0
TRGL 2 4 3
END
GOCAD TSurf 1
HEADER {
name:plain fault
}
TFACE
VRTX 1 0 0 -5
VRTX 2 1 0 -5
VRTX 3 0 1 -5
TRGL 1 2 3
END
"""


def _pyvista_file_with_blanks(path: Path) -> None:
    sphere = pv.Sphere(theta_resolution=8, phi_resolution=6)
    sphere.point_data.clear()
    sphere.cell_data.clear()
    sphere.point_data["rock type"] = np.arange(sphere.n_points, dtype=np.float64)
    sphere.cell_data["fault throw (m)"] = np.linspace(0.0, 1.0, sphere.n_cells)
    sphere.cast_to_unstructured_grid().save(path)


@pytest.mark.parametrize("target", ["out.vtu", "out.vtp", "out.vtk"])
def test_array_names_with_blanks_are_written_as_they_were(tmp_path: Path, target: str) -> None:
    _pyvista_file_with_blanks(tmp_path / "in.vtu")
    [mesh] = formats.read(tmp_path / "in.vtu")
    assert set(mesh.vertex_properties) == {"rock_type"}  # a mesh property name has no blank
    assert mesh.metadata["vtk_array_names"] == {
        "point_data": {"rock_type": "rock type"},
        "cell_data": {"fault_throw__m_": "fault throw (m)"},
    }
    formats.write(mesh, tmp_path / target)
    back = pv.read(tmp_path / target)  # what ParaView shows: the names of the file read
    assert list(back.point_data) == ["rock type"] and list(back.cell_data) == ["fault throw (m)"]
    assert np.array_equal(back.point_data["rock type"], mesh.vertex_properties["rock_type"])
    [again] = formats.read(tmp_path / target)
    assert again.same_as(mesh) and again.metadata["vtk_array_names"] == mesh.metadata["vtk_array_names"]


def test_legacy_names_are_percent_encoded_as_vtk_does(tmp_path: Path) -> None:
    _pyvista_file_with_blanks(tmp_path / "in.vtu")
    [mesh] = formats.read(tmp_path / "in.vtu")
    content = formats.format_vtk(mesh, ascii=True)
    assert b"\nrock%20type 1 " in content and b"\nfault%20throw%20(m) 1 " in content
    # a name that is not a mesh property name any more (renamed, dropped) is not looked up
    mesh.metadata["vtk_array_names"]["point_data"]["gone"] = "gone away"
    mesh.metadata["vtk_array_names"]["cell_data"]["fault_throw__m_"] = 'bad"name'
    content = formats.format_vtk(mesh, ascii=True)
    assert b"gone" not in content and b"bad%22name 1 " in content
    again = formats.parse_vtk(content)
    assert list(again.cell_properties) == ["bad_name"]
    assert again.metadata["vtk_array_names"]["cell_data"] == {"bad_name": 'bad"name'}


def test_gocad_property_names_with_blanks_go_to_vtk_files_as_they_were(tmp_path: Path) -> None:
    [fault] = formats.read(Path(__file__).parent / "data" / "gocad" / "skua_properties.ts")
    assert set(fault.vertex_properties) == {"default_property", "throw"}
    assert fault.metadata["property_names"]["default_property"] == " default property"
    formats.write(fault, tmp_path / "fault.vtu")
    assert sorted(pv.read(tmp_path / "fault.vtu").point_data) == [" default property", "throw"]
    formats.write(fault, tmp_path / "fault.vtk")
    assert b"\n%20default%20property 1 " in (tmp_path / "fault.vtk").read_bytes()
    assert formats.read_one(tmp_path / "fault.vtk").same_as(fault)


def test_names_survive_the_database(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _pyvista_file_with_blanks(tmp_path / "in.vtu")
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "create",
                "rocks",
                "--geotype",
                "SURFACE",
                "--property",
                "rock_type:float8",
            ]
        )
        == 0
    )
    assert (
        main(["--dsn", db_dsn, "import", str(tmp_path / "in.vtu"), "--class", "rocks", "--drop-extra-properties"]) == 0
    )
    with psycopg.connect(db_dsn) as conn:
        row = conn.execute("SELECT _geoid FROM rocks").fetchone()
    assert row is not None
    capsys.readouterr()
    for target in ("out.vtu", "out.vtk"):
        assert main(["--dsn", db_dsn, "export", str(row[0]), str(tmp_path / target)]) == 0, capsys.readouterr().err
        back = pv.read(tmp_path / target)
        assert list(back.point_data) == ["rock type"]  # the cell data: no column of the class


def test_two_names_that_would_clash_keep_the_mesh_names(tmp_path: Path) -> None:
    surface = Surface(
        np.eye(3),
        np.array([[0, 1, 2]]),
        vertex_properties={"a_b": np.zeros(3), "c": np.ones(3)},
        metadata={"vtk_array_names": {"point_data": {"c": "a_b"}}},
    )
    formats.write(surface, tmp_path / "clash.vtu")
    assert sorted(pv.read(tmp_path / "clash.vtu").point_data) == ["a_b", "c"]  # no two arrays of one name


def test_a_collection_with_parts_on_some_members_is_written_to_vtk_files(tmp_path: Path) -> None:
    split, plain = formats.parse_gocad(TWO_FAULTS)
    assert "part" in split.cell_properties and "part" not in plain.cell_properties
    collection = GeometryCollection([split, plain], name="faults")
    for target in ("faults.vtu", "faults.vtk"):
        formats.write(collection, tmp_path / target)  # failed before: 'part' is on some members only
        grid = pv.read(tmp_path / target)
        assert grid.cell_data["part"].tolist() == [0, 1, -1]  # -1: a member without parts
        back = formats.read(tmp_path / target)
        assert [m.name for m in back] == ["split fault", "plain fault"]
        assert back[0].cell_properties["part"].tolist() == [0, 1]
        assert "part" not in back[1].cell_properties
        assert back[0].same_as(split) and back[1].same_as(plain)


def test_a_property_on_some_members_only_has_a_hint_the_command_line_can_follow(tmp_path: Path) -> None:
    split, plain = formats.parse_gocad(TWO_FAULTS)
    split.vertex_properties["slip"] = np.zeros(split.n_vertices)
    with pytest.raises(FileFormatError, match="vertex property 'slip' is on some members") as refused:
        formats.write(GeometryCollection([split, plain]), tmp_path / "faults.vtu")
    hint = to_cli(refused.value.hint) or ""
    assert ".ts" in hint and "remove it" not in hint


def test_cli_exports_a_gocad_model_with_parts_to_vtu(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "faults.ts").write_text(TWO_FAULTS)
    assert main(["--dsn", db_dsn, "class", "create", "models", "--geotype", "GEOMETRYCOLLECTION"]) == 0
    assert main(["--dsn", db_dsn, "import", str(tmp_path / "faults.ts"), "--class", "models"]) == 0
    with psycopg.connect(db_dsn) as conn:
        row = conn.execute("SELECT _geoid FROM models").fetchone()
    assert row is not None
    capsys.readouterr()
    for target in ("faults.vtu", "faults.vtk"):
        assert main(["--dsn", db_dsn, "export", str(row[0]), str(tmp_path / target)]) == 0, capsys.readouterr().err
        back = formats.read(tmp_path / target)
        assert [m.cell_properties.get("part", np.empty(0)).tolist() for m in back] == [[0, 1], []]
        originals = formats.parse_gocad(TWO_FAULTS)
        assert all(isinstance(m, Mesh) and np.array_equal(m.vertices, o.vertices) for m, o in zip(back, originals))
    # and back into the database: the same parts, the member without parts without them
    assert main(["--dsn", db_dsn, "import", str(tmp_path / "faults.vtu"), "--class", "models", "--name", "again"]) == 0
    with psycopg.connect(db_dsn) as conn:
        again = conn.execute("SELECT max(_geoid) FROM models").fetchone()
    assert again is not None and again[0] != row[0]
    assert main(["--dsn", db_dsn, "export", str(again[0]), str(tmp_path / "again.ts")]) == 0, capsys.readouterr().err
    text = (tmp_path / "again.ts").read_text()
    assert text.count("TFACE") == 3 and text.count("GOCAD TSurf") == 2
