"""`tgsis import` of files as real tools write them (issue 16, part 2): nothing is ever stored partially with exit 0.

Mixed files (warnings, --strict), keywords tgsis does not know, objects without
vertices, point files, control-node flags and --reject-flagged with GOCAD ATOMs.
"""

from __future__ import annotations

from pathlib import Path

import psycopg
import pytest

from tests.shared_data import cfm
from tgsis.cli import main

DATA = Path(__file__).resolve().parent / "data"
MIXED = DATA / "gocad" / "mixed.ts"  # SGrid, TSurf, Model3d, PLine


def stored(dsn: str) -> tuple[int, int]:
    """Geometries and vertices in the database: what an import that fails must leave as it was."""
    with psycopg.connect(dsn) as conn:
        row = conn.execute("SELECT (SELECT count(*) FROM tgsis.geometry), (SELECT count(*) FROM tgsis.vrtx)").fetchone()
    assert row is not None
    return int(row[0]), int(row[1])


def create(dsn: str, name: str, geotype: str, *extra: str) -> None:
    assert main(["--dsn", dsn, "class", "create", name, "--geotype", geotype, *extra]) == 0


def test_a_mixed_file_is_imported_with_one_warning_line_per_skipped_object(
    db_dsn: str, capsys: pytest.CaptureFixture[str]
) -> None:
    create(db_dsn, "models", "GEOMETRYCOLLECTION")
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "import", str(MIXED), "--class", "models"]) == 0
    out, err = capsys.readouterr()
    assert err.splitlines() == [
        f"tgsis: warning: {MIXED}:1: skipped the GOCAD SGrid object 'porosity grid' (lines 1-20): tgsis reads "
        "TSurf, PLine, VSet, TSolid, LightTSolid",
        f"tgsis: warning: {MIXED}:31: skipped the GOCAD Model3d object 'structural model' (lines 31-38): tgsis "
        "reads TSurf, PLine, VSet, TSolid, LightTSolid",
    ]
    assert out.splitlines()[1].endswith("\tGEOMETRYCOLLECTION\t5\t2\t\t2 members")
    assert stored(db_dsn) == (3, 5)


def test_strict_refuses_a_mixed_file(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    create(db_dsn, "models", "GEOMETRYCOLLECTION")
    capsys.readouterr()
    before = stored(db_dsn)
    assert main(["--dsn", db_dsn, "import", str(MIXED), "--class", "models", "--strict"]) == 1
    err = capsys.readouterr().err
    assert err.startswith(
        f"tgsis: error: {MIXED}: refused, nothing imported: it holds objects tgsis does not "
        "read: GOCAD SGrid object 'porosity grid' at line 1; GOCAD Model3d object 'structural "
        "model' at line 31\n"
    )
    assert "HINT: import without --strict" in err and "Warning" not in err
    assert stored(db_dsn) == before


def test_a_file_of_unsupported_objects_only_is_refused(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    create(db_dsn, "faults", "SURFACE")
    path = tmp_path / "grid.sg"
    path.write_text("GOCAD SGrid 1\nHEADER {\nname:g\n}\nAXIS_N 2 2 2\nEND\n")
    capsys.readouterr()
    before = stored(db_dsn)
    assert main(["--dsn", db_dsn, "import", str(path), "--class", "faults", "--format", "ts"]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"tgsis: error: {path}:1: unsupported GOCAD object type 'SGrid': the file holds no object")
    assert stored(db_dsn) == before


def test_an_unknown_keyword_refuses_the_file(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    create(db_dsn, "faults", "SURFACE")
    source = DATA / "gocad" / "unknown_keywords.ts"
    capsys.readouterr()
    before = stored(db_dsn)
    assert main(["--dsn", db_dsn, "import", str(source), "--class", "faults"]) == 1
    assert capsys.readouterr().err.startswith(
        f"tgsis: error: {source}:8: unknown keyword 'VERTEX' in the TSurf begun at line 1\n"
    )
    assert stored(db_dsn) == before


def test_an_object_without_vertices_is_refused(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    create(db_dsn, "faults", "SURFACE")
    path = tmp_path / "two.ts"
    path.write_text(
        "GOCAD TSurf 1\nHEADER {\nname:full\n}\nTFACE\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\n"
        "TRGL 1 2 3\nEND\nGOCAD TSurf 1\nHEADER {\nname:hollow\n}\nTFACE\nEND\n"
    )
    capsys.readouterr()
    before = stored(db_dsn)
    assert main(["--dsn", db_dsn, "import", str(path), "--class", "faults"]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"tgsis: error: {path}: refused, nothing imported: object 'hollow' has no vertex\n")
    assert stored(db_dsn) == before  # not even the object that has vertices


def test_point_files_are_imported_as_points(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    create(db_dsn, "samples", "MULTIPOINT", "--property", "porosity:float8")
    create(db_dsn, "faults", "SURFACE")
    capsys.readouterr()
    before = stored(db_dsn)
    assert main(["--dsn", db_dsn, "import", str(DATA / "trimesh" / "points.obj"), "--class", "faults"]) == 1
    assert "holds SURFACE features, not MULTIPOINT" in capsys.readouterr().err  # never a 0-vertex surface
    assert stored(db_dsn) == before
    assert main(["--dsn", db_dsn, "import", str(DATA / "trimesh" / "points.ply"), "--class", "samples"]) == 0
    assert "\tpoints\tMULTIPOINT\t3\t3\t" in capsys.readouterr().out
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT count(*) FROM samples").fetchone() == (1,)
    assert main(["--dsn", db_dsn, "import", str(DATA / "trimesh" / "empty.obj"), "--class", "samples"]) == 1
    assert "the OBJ file holds no vertex" in capsys.readouterr().err


def test_files_with_control_nodes_and_quoted_names_are_imported(
    db_dsn: str, capsys: pytest.CaptureFixture[str]
) -> None:
    create(db_dsn, "blocks", "MULTITETRA", "--alignment", "CELL", "--property", "part:int8")
    create(db_dsn, "faults", "SURFACE", "--property", "default_property:float8", "--property", "throw:float8")
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "import", str(DATA / "gocad" / "control_nodes.so"), "--class", "blocks"]) == 0
    assert "\tcontrol nodes\tMULTITETRA\t7\t3\t" in capsys.readouterr().out
    assert main(["--dsn", db_dsn, "import", str(DATA / "gocad" / "skua_properties.ts"), "--class", "faults"]) == 0
    assert "\tskua fault\tSURFACE\t4\t2\t" in capsys.readouterr().out


def test_reject_flagged_does_not_count_gocad_atoms(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    create(db_dsn, "faults", "SURFACE")
    capsys.readouterr()
    # a real CFM fault with one ATOM (a vertex repeated on purpose): clean
    source = cfm("formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts")
    assert (
        main(
            ["--dsn", db_dsn, "import", str(source), "--class", "faults", "--reject-flagged", "--drop-extra-properties"]
        )
        == 0
    )  # its two TFACE parts
    assert capsys.readouterr().out.splitlines()[1].endswith("no duplicate vertices, no degenerate cells")

    # an ATOM of an ATOM is no defect either; a vertex that merely lies on another still is
    path = tmp_path / "atoms.ts"
    path.write_text(
        "GOCAD TSurf 1\nHEADER {\nname:cut\n}\nTFACE\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\n"
        "ATOM 4 2\nATOM 5 4\nVRTX 6 1 1 0\nTRGL 1 2 3\nTRGL 4 6 3\nTRGL 5 6 1\nEND\n"
    )
    assert main(["--dsn", db_dsn, "import", str(path), "--class", "faults", "--reject-flagged"]) == 0
    assert capsys.readouterr().out.splitlines()[1].endswith("no duplicate vertices, no degenerate cells")
    path.write_text(
        path.read_text()
        .replace("VRTX 6 1 1 0\n", "VRTX 6 1 1 0\nVRTX 7 1 0 0\n")
        .replace("TRGL 5 6 1\n", "TRGL 5 6 1\nTRGL 7 6 1\n")
    )
    before = stored(db_dsn)
    assert main(["--dsn", db_dsn, "import", str(path), "--class", "faults", "--reject-flagged"]) == 1
    assert "object 'cut': 1 duplicate vertices, 0 degenerate cells" in capsys.readouterr().err
    assert stored(db_dsn) == before


def test_other_commands_that_read_files_warn_in_one_line_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """tgsis corners reads the first surface of a mixed file: the skipped objects are one line each, not a dump."""
    from tgsis.cli import main

    assert main(["corners", str(MIXED)]) in (0, 1)
    err = capsys.readouterr().err
    assert f"tgsis: warning: {MIXED}:1: skipped the GOCAD SGrid object 'porosity grid'" in err
    assert "SkippedObjectWarning" not in err and "warnings.warn" not in err


def test_a_broken_surface_file_is_refused_naming_file_and_line(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A truncated OFF (9 of its 18 faces) and an OBJ with index 0 are refused whole (issue 36, point 7):
    trimesh read the first with 9 faces and the second with another vertex, and the import said nothing."""
    create(db_dsn, "surfaces", "SURFACE")
    off = tmp_path / "cut.off"
    vertices = [f"{i % 4} {i // 4} {0.1 * i}" for i in range(16)]
    faces = [f"3 {a} {a + 1} {a + 4}" for a in (0, 1, 2, 4, 5, 6, 8, 9, 10)]
    faces += [f"3 {a + 1} {a + 5} {a + 4}" for a in (0, 1, 2, 4, 5, 6, 8, 9, 10)]
    off.write_text("\n".join(["OFF", "16 18 0", *vertices, *faces[:9]]) + "\n")
    obj = tmp_path / "zero.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
    before = stored(db_dsn)
    capsys.readouterr()
    for path, message in (
        (off, f"{off}:27: the OFF file ends after 9 of the 18 faces its header declares"),
        (obj, f"{obj}:4: an OBJ face uses vertex index 0"),
    ):
        assert main(["--dsn", db_dsn, "import", str(path), "--class", "surfaces"]) == 1
        err = capsys.readouterr().err
        assert err.startswith(f"tgsis: error: {message}"), err
    assert stored(db_dsn) == before
