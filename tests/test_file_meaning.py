"""What a file means survives storage (issue 16, part 1).

Each file here is imported into the database and exported again; the export
must be the file tgsis's reader and writer give without the database (same
text), and the re-read model the same as the original: bit-exact coordinates,
the z convention (ZPOSITIVE Depth), the coordinate-system block, name, colour,
parts (TFACE/TVOLUME/ILINE), shared vertices (ATOM/PATOM), and properties
with their names, sizes (ESIZES), no-data values, classes and units.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.cli import main
from tgsis.db import features as F
from tgsis.errors import InvalidGeometryError
from tgsis.formats.gocad import format_gocad, parse_gocad, read_gocad
from tgsis.mesh import LineSet, Mesh, Surface, TetraMesh

from .shared_data import cfm

Conn = psycopg.Connection[Any]

# A fault picked in depth: two TFACEs sharing a vertex through a PATOM, a scalar property with
# a mixed-case name and a no-data value, a 3-component vector property, a colour with alpha,
# the coordinate-system block with ZPOSITIVE Depth and a z of -0.0 (bit-exact sign).
DEPTH_TSURF = """GOCAD TSurf 1
HEADER {
name:Fault_A depth
*solid*color:0.8 0.25 0.1 1
mesh:on
}
GOCAD_ORIGINAL_COORDINATE_SYSTEM
NAME "UTM 11N depth"
AXIS_NAME "X" "Y" "Z"
AXIS_UNIT "m" "m" "m"
ZPOSITIVE Depth
END_ORIGINAL_COORDINATE_SYSTEM
GEOLOGICAL_FEATURE Fault_A
GEOLOGICAL_TYPE fault
PROPERTIES Porosity Slip_Vector
PROP_LEGAL_RANGES **none** **none** **none** **none**
NO_DATA_VALUES -99999 -99999
PROPERTY_CLASSES porosity slip_vector
PROPERTY_KINDS Porosity "Length"
PROPERTY_SUBCLASSES QUANTITY Float VECTOR Float
ESIZES 1 3
UNITS fraction m
TFACE
PVRTX 1 405000.125 3760000.5 -0.0 0.21 0.1 0.2 -0.3
PVRTX 2 405100.25 3760000.5 1250.75 -99999 0.1 0.25 -0.35
PVRTX 3 405000.125 3760100.125 1300.0000000000002 0.19 0.15 0.2 -0.3
TRGL 1 2 3
TFACE
PVRTX 4 405100.25 3760100.125 1400.5 0.17 0.2 0.3 -0.4
PATOM 5 2
PATOM 6 3 0.33 0.1 0.2 -0.3
TRGL 5 4 6
END
"""

# The same fault in elevation (z = -depth): the same physical place.
ELEVATION_TSURF = DEPTH_TSURF.replace("ZPOSITIVE Depth", "ZPOSITIVE Elevation").replace(
    "name:Fault_A depth", "name:Fault_A elevation"
)
for _depth in ("-0.0", "1250.75", "1300.0000000000002", "1400.5"):
    ELEVATION_TSURF = ELEVATION_TSURF.replace(f" {_depth} ", f" {-float(_depth)!r} ")

# A solid of two TVOLUMEs without properties, and a line of two ILINEs sharing a vertex by ATOM.
TWO_VOLUMES = """GOCAD TSolid 1
HEADER {
name:block
*solid*color:0.5 0.5 1
}
TVOLUME
VRTX 1 0 0 0
VRTX 2 1 0 0
VRTX 3 0 1 0
VRTX 4 0 0 1
TETRA 1 2 3 4
TVOLUME
VRTX 5 1 1 1
TETRA 2 3 4 5
END
"""

TWO_LINES = """GOCAD PLine 1
HEADER {
name:trace
*line*color:0 0 1
}
GOCAD_ORIGINAL_COORDINATE_SYSTEM
NAME Default
AXIS_NAME "X" "Y" "Z"
AXIS_UNIT "ft" "ft" "ft"
ZPOSITIVE Depth
END_ORIGINAL_COORDINATE_SYSTEM
ILINE
VRTX 1 0 0 10
VRTX 2 1 0 11
VRTX 3 2 0 12
SEG 1 2
SEG 2 3
ILINE
ATOM 4 3
VRTX 5 3 1 13
SEG 4 5
END
"""

VECTOR_PROPERTIES: list[tuple[str, str] | tuple[str, str, int]] = [
    ("Porosity", "double precision"),
    ("Slip_Vector", "double precision", 3),
]


def _class(
    conn: Conn, name: str, geotype: str, properties: list[tuple[str, str] | tuple[str, str, int]] | None = None
) -> F.FeatureClass:
    fc = F.create_feature_class(conn, name, geotype, cell_properties=properties)
    conn.commit()
    return fc


def _stored_and_exported(conn: Conn, fc: F.FeatureClass, text: str) -> tuple[Mesh, int, Mesh]:
    """The mesh read from ``text``, its feature id, and the mesh fetched back from the database."""
    [mesh] = parse_gocad(text)
    fid = F.insert_feature(conn, fc, mesh)
    conn.commit()
    back = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(back, Mesh)
    return mesh, fid, back


def _same_model(a: Mesh, b: Mesh) -> None:
    assert a.same_as(b)  # bit-exact vertices, cells, properties (NaN = NaN)
    assert a.name == b.name
    assert json.loads(json.dumps(a.metadata)) == json.loads(json.dumps(b.metadata))


def test_depth_surface_round_trips_through_the_database(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    mesh, fid, back = _stored_and_exported(conn, fc, DEPTH_TSURF)
    _same_model(mesh, back)
    assert np.signbit(back.vertices[0, 2]) and back.vertices[0, 2] == 0.0  # -0.0 as written
    # the export is what reader and writer give without the database, and reads back as the file
    assert format_gocad(back) == format_gocad(mesh)
    [again] = parse_gocad(format_gocad(back))
    _same_model(mesh, again)
    exported = format_gocad(back)
    for line in (
        "ZPOSITIVE Depth",
        'NAME "UTM 11N depth"',
        "*solid*color:0.8 0.25 0.1 1",
        "name:Fault_A depth",
        "PROPERTIES Porosity Slip_Vector",
        "ESIZES 1 3",
        "UNITS fraction m",
        "PATOM 5 2",
        "PATOM 6 3 0.33 0.1 0.2 -0.3",
        "PROPERTY_KINDS Porosity Length",
        "GEOLOGICAL_TYPE fault",
    ):
        assert line in exported.splitlines(), line
    assert exported.count("TFACE") == 2
    # what SQL users see: the convention, the block, name and colour in columns, parts and atoms in rows
    row = conn.execute(
        "SELECT zpositive, crs, geoname, colorred, colorgreen, colorblue FROM tgsis.geometry WHERE geoid = %s", (fid,)
    ).fetchone()
    assert row is not None
    assert row[0] == "Depth" and row[1][-1] == "ZPOSITIVE Depth" and row[2] == "Fault_A depth"
    assert [round(c, 6) for c in row[3:]] == [0.8, 0.25, 0.1]
    assert conn.execute(
        "SELECT vrtxid, refid, patom FROM tgsis.atom WHERE geoid = %s ORDER BY vrtxid", (fid,)
    ).fetchall() == [(4, 1, True), (5, 2, True)]
    assert conn.execute(
        "SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (fid,)
    ).fetchall() == [(0, 0, 0), (1, 1, 1)]
    # property names as the file wrote them, quoted columns of the class
    # and the vector property (ESIZES 3) one array column of 3 components, an (n, 3) array in Python
    assert conn.execute(
        'SELECT "Porosity", "Slip_Vector" FROM faults_cellpros WHERE _geoid = %s AND _idx = 0', (fid,)
    ).fetchone() == (0.21, [0.1, 0.2, -0.3])
    assert {k: v.shape for k, v in back.vertex_properties.items()} == {"Porosity": (6,), "Slip_Vector": (6, 3)}
    assert F.get_feature_class(conn, "faults").cell_properties[1] == F.Property("Slip_Vector", "double precision", 3)
    # stored z is elevation: depth 1250.75 is z -1250.75, -0.0 is 0.0 (negation only flips the sign bit)
    zs = [r[0] for r in conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (fid,))]
    assert zs[:2] == [0.0, -1250.75] and not np.signbit(zs[0])
    assert struct.pack(">d", -zs[2]) == struct.pack(">d", 1300.0000000000002)


def test_depth_and_elevation_features_meet_in_the_same_box(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    depth, did, depth_back = _stored_and_exported(conn, fc, DEPTH_TSURF)
    elevation, eid, elevation_back = _stored_and_exported(conn, fc, ELEVATION_TSURF)
    # the same place: one box query in elevation finds both, a box at the depths' numbers finds neither
    assert F.features_in_box(conn, fc, [[404000, 3759000, -1500], [406000, 3761000, -1000]]) == [did, eid]
    assert F.features_in_box(conn, fc, [[404000, 3759000, 1000], [406000, 3761000, 1500]]) == []
    stored = conn.execute(
        "SELECT geoid, array_agg(z ORDER BY vrtxid) FROM tgsis.vrtx GROUP BY geoid ORDER BY geoid"
    ).fetchall()
    assert stored[0][1] == stored[1][1]  # like with like: the same stored z
    # each exports as it was read, in its own convention
    assert format_gocad(depth_back) == format_gocad(depth) and "ZPOSITIVE Depth" in format_gocad(depth_back)
    assert format_gocad(elevation_back) == format_gocad(elevation)
    assert "ZPOSITIVE Elevation" in format_gocad(elevation_back)
    _same_model(depth, depth_back)
    _same_model(elevation, elevation_back)


def test_parts_without_properties_and_atoms_of_lines(conn: Conn) -> None:
    solids = _class(conn, "blocks", "MULTITETRA")  # no part column: parts go to tgsis.part
    lines = _class(conn, "traces", "MULTILINESTRING")
    solid, _, solid_back = _stored_and_exported(conn, solids, TWO_VOLUMES)
    line, lid, line_back = _stored_and_exported(conn, lines, TWO_LINES)
    assert isinstance(solid_back, TetraMesh) and isinstance(line_back, LineSet)
    for original, back in ((solid, solid_back), (line, line_back)):
        _same_model(original, back)
        assert format_gocad(back) == format_gocad(original)
    assert solid_back.cell_properties["part"].tolist() == [0, 1]
    assert format_gocad(solid_back).count("TVOLUME") == 2 and format_gocad(line_back).count("ILINE") == 2
    assert "ATOM 4 3" in format_gocad(line_back).splitlines()
    assert conn.execute("SELECT zpositive FROM tgsis.geometry WHERE geoid = %s", (lid,)).fetchone() == ("Depth",)


@pytest.mark.parametrize(
    "relative",
    [
        "formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts",
        "formats/SAFS-SAFZ-MULT-San_Andreas_fault_Fuis-ALT6_500m.ts",
        "cfm5.3/GRFS-GRFZ-WEST-Garlock_fault-CFM5_1000m.ts",
    ],
)
def test_real_files_round_trip(conn: Conn, relative: str) -> None:
    fc = _class(conn, "cfm", "SURFACE")
    meshes = read_gocad(cfm(relative))
    ids = [F.insert_feature(conn, fc, m, drop_extra_properties=True) for m in meshes]
    conn.commit()
    for mesh, fid in zip(meshes, ids):
        back = F.fetch_feature(conn, fc, fid).mesh
        assert isinstance(back, Mesh)
        mesh.vertex_properties = {}  # the class stores none (dropped on insert)
        mesh.cell_properties = {k: v for k, v in mesh.cell_properties.items() if k == "part"}
        _same_model(mesh, back)
        assert format_gocad(back) == format_gocad(mesh)


def test_names_with_capitals_and_keywords_are_columns(conn: Conn) -> None:
    fc = F.create_feature_class(
        conn,
        "wells",
        "MULTIPOINT",
        feature_properties=[("Operator", "text")],
        cell_properties=[("Order", "double precision"), ("order", "real")],
    )
    text = (
        "GOCAD VSet 1\nHEADER {\nname:picks\n}\nPROPERTIES Order order\n"
        "PVRTX 1 0 0 -5 1 0.5\nPVRTX 2 1 0 -6 2 0.25\nEND\n"
    )
    [points] = parse_gocad(text)
    assert list(points.vertex_properties) == ["Order", "order"]
    fid = F.insert_feature(conn, fc, points, {"Operator": "ACME"})
    conn.commit()
    feature = F.fetch_feature(conn, fc, fid)
    assert feature.properties == {"Operator": "ACME"} and isinstance(feature.mesh, Mesh)
    _same_model(points, feature.mesh)
    assert format_gocad(feature.mesh) == format_gocad(points)
    assert conn.execute('SELECT "Order", "order" FROM wells_cellpros ORDER BY _idx').fetchall() == [(1, 0.5), (2, 0.25)]
    assert feature.mesh.vertex_properties["order"].dtype == np.float32  # the column's kind


def test_colour_and_convention_edited_in_sql_are_exported(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    _, fid, _ = _stored_and_exported(conn, fc, DEPTH_TSURF)
    conn.execute(
        "UPDATE tgsis.geometry SET colorred = 0.5, colorgreen = 0.5, colorblue = 0.5, geoname = 'renamed' "
        "WHERE geoid = %s",
        (fid,),
    )
    conn.commit()
    back = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(back, Mesh)
    text = format_gocad(back).splitlines()
    assert "*solid*color:0.5 0.5 0.5" in text and "name:renamed" in text


def test_cli_import_export_gives_the_file_back(
    conn: Conn, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    source = tmp_path / "fault.ts"
    source.write_text(DEPTH_TSURF)
    assert main(["--dsn", db_dsn, "import", str(source), "--class", "faults"]) == 0
    fid = int(capsys.readouterr().out.splitlines()[1].split()[0])
    assert main(["--dsn", db_dsn, "export", str(fid), str(tmp_path / "out.ts")]) == 0
    [original] = read_gocad(source)
    [exported] = read_gocad(tmp_path / "out.ts")
    _same_model(original, exported)
    assert (tmp_path / "out.ts").read_text() == format_gocad(original)


def test_vector_properties_of_the_wrong_shape_are_refused(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    [mesh] = parse_gocad(DEPTH_TSURF)
    mesh.vertex_properties["Slip_Vector"] = mesh.vertex_properties["Slip_Vector"][:, :2]
    with pytest.raises(
        tgsis.InvalidPropertyError,
        match="'Slip_Vector' of the mesh has a vector of 2 values per "
        "element, but feature class faults stores a vector of 3",
    ):
        F.insert_feature(conn, fc, mesh)
    mesh.vertex_properties["Slip_Vector"] = mesh.vertex_properties["Slip_Vector"][:, 0]
    with pytest.raises(tgsis.InvalidPropertyError, match="has one value per element"):
        F.insert_feature(conn, fc, mesh)
    assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == (0,)
    for spec, message in (
        (["v", "float8", 0], "has size 0"),
        (["v", "float8", 2.5], "has size 2.5"),
        (["v", "float8", "3"], 'has size "3"'),
    ):
        with pytest.raises(psycopg.Error) as caught:
            conn.execute(
                "SELECT tgsis.register_feature_class('bad', 'SURFACE', '[]', %s::jsonb)", (json.dumps([spec]),)
            )
        assert caught.value.sqlstate == "TG103" and message in str(caught.value), str(caught.value)
        conn.rollback()
    with pytest.raises(tgsis.InvalidPropertyError, match="only vertex and cell properties may be vectors"):
        F.create_feature_class(conn, "bad", "SURFACE", feature_properties=[("v", "float8", 3)])


def test_bad_convention_is_refused_and_nothing_is_written(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    [mesh] = parse_gocad(DEPTH_TSURF)
    mesh.metadata["zpositive"] = "Sideways"
    before = conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone()
    with pytest.raises(InvalidGeometryError, match="'Sideways'.*'Elevation' or 'Depth'"):
        F.insert_feature(conn, fc, mesh)
    assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == before
    with pytest.raises(psycopg.Error) as caught:
        conn.execute("SELECT tgsis.new_geometry('SURFACE', 'x', NULL, 0, 0, p_zpositive => 'Up')")
    assert caught.value.sqlstate == "TG102" and "z convention 'Up'" in str(caught.value)
    conn.rollback()
    with pytest.raises(psycopg.Error) as caught:
        conn.execute("SELECT tgsis.new_geometry('SURFACE', 'x', NULL, 0, 0, p_crs => '{\"a\": 1}')")
    assert caught.value.sqlstate == "TG102"
    conn.rollback()


def test_check_geometry_reports_broken_atoms_and_parts(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    _, fid, _ = _stored_and_exported(conn, fc, DEPTH_TSURF)
    assert conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (fid,)).fetchall() == []
    conn.execute("UPDATE tgsis.vrtx SET x = x + 1 WHERE geoid = %s AND vrtxid = 5", (fid,))
    conn.execute("INSERT INTO tgsis.atom (geoid, vrtxid, refid) VALUES (%s, 3, 99)", (fid,))
    conn.execute("INSERT INTO tgsis.part (geoid, firstid, lastid, part) VALUES (%s, -5, 0, 2)", (fid,))
    problems = {r[0]: r[2] for r in conn.execute("SELECT * FROM tgsis.check_geometry(%s)", (fid,))}
    assert problems["atom refers to a missing vertex"] == "3"
    assert problems["atom is not at the place of the vertex it repeats"] == "5"
    assert problems["part ranges overlap"] == "-5"
    conn.rollback()


def test_delete_and_drop_remove_atoms_and_parts(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    _, first, _ = _stored_and_exported(conn, fc, DEPTH_TSURF)
    _stored_and_exported(conn, fc, ELEVATION_TSURF)
    assert F.delete_feature(conn, fc, first)
    assert conn.execute("SELECT count(*) FROM tgsis.atom WHERE geoid = %s", (first,)).fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.part WHERE geoid = %s", (first,)).fetchone() == (0,)
    F.drop_feature_class(conn, "faults", force=True)
    assert conn.execute("SELECT (SELECT count(*) FROM tgsis.atom), (SELECT count(*) FROM tgsis.part)").fetchone() == (
        0,
        0,
    )


def test_save_feature_keeps_the_meaning(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    mesh, fid, back = _stored_and_exported(conn, fc, DEPTH_TSURF)
    back.vertices[3, 2] += 10.0  # deepen the lone vertex of the second TFACE (no atom repeats it)
    tgsis.save_feature(conn, fc, fid, back)
    conn.commit()
    again = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(again, Mesh)
    _same_model(back, again)
    assert again.vertices[3, 2] == 1410.5  # in depth, as edited
    assert conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 3", (fid,)).fetchone() == (-1410.5,)


def test_versioned_edit_with_parts_atoms_and_properties(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    mesh, fid, _ = _stored_and_exported(conn, fc, DEPTH_TSURF)
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "reinterpretation")
    with tgsis.in_version(conn, "reinterpretation"):
        edited = F.fetch_feature(conn, fc, fid).mesh
        assert isinstance(edited, Surface)
        _same_model(mesh, edited)
        edited.vertices[3, 2] += 10.0
        edited.vertex_properties["Porosity"][3] = 0.5
        edited.metadata["gocad_header"] = [*edited.metadata["gocad_header"], "ivolmap:false"]
        tgsis.save_feature(conn, fc, fid, edited)
        conn.commit()
        child = F.fetch_feature(conn, fc, fid).mesh
        assert isinstance(child, Mesh)
        _same_model(edited, child)
        assert format_gocad(child) == format_gocad(edited)
    default = F.fetch_feature(conn, fc, fid).mesh  # DEFAULT still holds the file as read
    assert isinstance(default, Mesh)
    _same_model(mesh, default)
    tgsis.merge_version(conn, "reinterpretation")
    conn.commit()
    merged = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(merged, Mesh)
    _same_model(edited, merged)
    assert format_gocad(merged) == format_gocad(edited)
    assert "PATOM 6 3 0.33 0.1 0.2 -0.3" in format_gocad(merged).splitlines()


def test_checkout_gives_the_file_convention_and_checkin_keeps_it(conn: Conn) -> None:
    fc = _class(conn, "faults", "SURFACE", VECTOR_PROPERTIES)
    mesh, fid, _ = _stored_and_exported(conn, fc, DEPTH_TSURF)
    checked = tgsis.checkout(conn, fid)
    _same_model(mesh, checked.mesh)  # depths, ZPOSITIVE Depth, coordinate system, parts, atoms
    assert format_gocad(checked.mesh) == format_gocad(mesh)
    checked.mesh.vertices[3, 2] += 10.0
    result = tgsis.checkin(conn, checked)
    conn.commit()
    assert not result.conflict
    again = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(again, Mesh)
    _same_model(checked.mesh, again)
    assert conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 3", (fid,)).fetchone() == (-1410.5,)
    assert conn.execute("SELECT zpositive FROM tgsis.geometry WHERE geoid = %s", (fid,)).fetchone() == ("Depth",)
