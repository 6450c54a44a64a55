"""GOCAD blocks that real files carry keep their meaning (issue 37, part 5).

* ``PROPERTY_CN <property>`` ... ``CNP <vertex id>`` ... ``END_PROPERTY_CN``
  (the control nodes of a property, as SCEC CFM faults carry them) are read
  and written back, also through the database.
* ``PROPERTY_CLASS_HEADER`` blocks (clip ranges, colour maps, kind and unit of
  X/Y/Z) survive a write of an object without properties and a trip through
  the database; SKUA's ``PROPERTY_SUBCLASSES ... LINEARFUNCTION Float 1 0``
  (four words for one property, where ``QUANTITY Float`` has two) is kept.
* ``.ml`` files (a GOCAD ``Model3d`` with its TSurfs) are read: the surfaces,
  which TFACEs of the model they are, and a warning (or, strict, an error)
  naming what tgsis does not store (the model's regions and layers).
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

from tgsis import formats
from tgsis.cli import main
from tgsis.db import features as F
from tgsis.errors import FileFormatError, SkippedObjectWarning
from tgsis.formats.gocad import format_gocad, parse_gocad
from tgsis.mesh import GeometryCollection, Mesh, Surface

from .shared_data import cfm

Conn = psycopg.Connection[Any]
DATA = Path(__file__).parent / "data" / "gocad"
PALM_SPRINGS = "formats/SAFS-SGPR-MTSJ-Palm_Springs_blind_fault-CRNA-CFM5.ts"


def _blocks(text: str, keyword: str, end: str) -> list[list[str]]:
    """The blocks of ``text`` from a ``keyword`` line to its ``end`` line (both included), words per line."""
    blocks: list[list[str]] = []
    current: list[str] | None = None
    for line in text.splitlines():
        words = " ".join(line.split())
        if words.split(" ")[0] == keyword:
            current = [words]
        elif current is not None:
            current.append(words)
            if words == end:
                blocks.append(current)
                current = None
    return blocks


def _fetched(conn: Conn, fc: F.FeatureClass, mesh: Mesh, **options: Any) -> Mesh:
    fid = F.insert_feature(conn, fc, mesh, **options)
    conn.commit()
    back = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(back, Mesh)
    return back


# ---------------------------------------------------------------- PROPERTY_CN


def test_property_cn_blocks_of_a_real_scec_fault_are_read_and_written_back() -> None:
    path = cfm(PALM_SPRINGS)
    [fault] = formats.read(path)  # failed before: unknown keyword 'PROPERTY_CN'
    original = path.read_text()
    nodes = fault.metadata["gocad_property_control_nodes"]
    assert list(nodes) == ["M", "XERR", "YERR", "ZERR"]
    ids = [6, 42, 49, 65, 82, 85, 122, 124, 134, 140, 143, 160, 175, 204, 207]
    assert all(nodes[name] == [i - 1 for i in ids] for name in nodes)  # vertex indices (ids 1..n in this file)
    written = format_gocad(fault)
    assert _blocks(written, "PROPERTY_CN", "END_PROPERTY_CN") == _blocks(original, "PROPERTY_CN", "END_PROPERTY_CN")
    # where the real file has them: after the vertices, before the triangles
    lines = written.splitlines()
    first_block, first_trgl = lines.index("PROPERTY_CN M"), next(i for i, w in enumerate(lines) if w.startswith("TRGL"))
    assert max(i for i, w in enumerate(lines) if w.startswith("PVRTX")) < first_block < first_trgl
    [again] = parse_gocad(written)
    assert again.same_as(fault)
    assert again.metadata == {k: v for k, v in fault.metadata.items() if k != "gocad_ignored"}  # BSTONE, BORDER


def test_property_cn_survives_the_database(conn: Conn) -> None:
    [fault] = formats.read(cfm(PALM_SPRINGS))
    fc = F.create_feature_class(
        conn, "faults", "SURFACE", cell_properties=[(n, "double precision") for n in ("M", "XERR", "YERR", "ZERR")]
    )
    back = _fetched(conn, fc, fault)
    assert format_gocad(back) == format_gocad(fault)
    assert back.metadata["gocad_property_control_nodes"] == fault.metadata["gocad_property_control_nodes"]


def test_property_cn_of_a_property_no_longer_written_is_left_out() -> None:
    [fault] = formats.read(cfm(PALM_SPRINGS))
    del fault.vertex_properties["XERR"]
    blocks = _blocks(format_gocad(fault), "PROPERTY_CN", "END_PROPERTY_CN")
    assert [b[0] for b in blocks] == ["PROPERTY_CN M", "PROPERTY_CN YERR", "PROPERTY_CN ZERR"]
    fault.vertex_properties = {}
    assert "PROPERTY_CN" not in format_gocad(fault)


_CN_TSURF = """GOCAD TSurf 1
HEADER {
name:cn
}
PROPERTIES slip
TFACE
PVRTX 10 0 0 0 1
PVRTX 20 1 0 0 2
PVRTX 30 0 1 0 3
PROPERTY_CN slip
CNP 20
CNP 30
END_PROPERTY_CN
TRGL 10 20 30
END
"""


def test_property_cn_ids_are_file_ids_and_bad_blocks_are_refused() -> None:
    [surface] = parse_gocad(_CN_TSURF)
    assert surface.metadata["gocad_property_control_nodes"] == {"slip": [1, 2]}
    assert "PROPERTY_CN slip\nCNP 2\nCNP 3\nEND_PROPERTY_CN\n" in format_gocad(surface)
    with pytest.raises(FileFormatError, match="CNP refers to vertex 40, which is not defined") as bad:
        parse_gocad(_CN_TSURF.replace("CNP 30", "CNP 40"))
    assert bad.value.line == 12
    with pytest.raises(FileFormatError, match="PROPERTY_CN names the property 'dip', which PROPERTIES does not"):
        parse_gocad(_CN_TSURF.replace("PROPERTY_CN slip", "PROPERTY_CN dip"))
    with pytest.raises(FileFormatError, match="unknown keyword 'VRTX' in the PROPERTY_CN block"):
        parse_gocad(_CN_TSURF.replace("CNP 30", "VRTX 30"))
    with pytest.raises(FileFormatError, match="PROPERTY_CN block is not closed by 'END_PROPERTY_CN'"):
        parse_gocad(_CN_TSURF.replace("END_PROPERTY_CN\nTRGL 10 20 30\n", ""))
    with pytest.raises(FileFormatError, match="unknown keyword 'TRGL' in the PROPERTY_CN block begun at line 10"):
        parse_gocad(_CN_TSURF.replace("END_PROPERTY_CN\n", ""))
    with pytest.raises(FileFormatError, match="CNP has a vertex id that is not an integer"):
        parse_gocad(_CN_TSURF.replace("CNP 30", "CNP x"))


# ---------------------------------------------------------------- PROPERTY_CLASS_HEADER, PROPERTY_SUBCLASSES


def test_class_headers_of_a_surface_without_properties_are_written_back() -> None:
    with pytest.warns(SkippedObjectWarning, match="REGION 'Upper'"):
        [horizon, _] = formats.read(DATA / "two_surfaces.ml")
    assert horizon.vertex_properties == {}
    written = format_gocad(horizon)
    assert _blocks(written, "PROPERTY_CLASS_HEADER", "}") == [
        ["PROPERTY_CLASS_HEADER X {", "kind: X", "unit: m", "}"],
        ["PROPERTY_CLASS_HEADER Z {", "kind: Depth", "unit: m", "is_z: on", "}"],
    ]
    # a real CFM fault without properties (PROPERTY_CLASS_HEADER Z with its clip range)
    [pitas] = formats.read(cfm("formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts"))
    assert pitas.vertex_properties == {}
    assert "PROPERTY_CLASS_HEADER Z {\nlow_clip:-10610.913086\n" in format_gocad(pitas)


def test_class_headers_survive_the_database_when_the_class_keeps_no_property(conn: Conn) -> None:
    fc = F.create_feature_class(conn, "faults", "SURFACE")
    conn.commit()
    [fault] = formats.read(cfm("formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts"))
    original = _blocks(
        cfm("formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts").read_text(), "PROPERTY_CLASS_HEADER", "}"
    )
    assert [b[0] for b in original] == [
        "PROPERTY_CLASS_HEADER Z {",
        "PROPERTY_CLASS_HEADER azimuth {",
        "PROPERTY_CLASS_HEADER dip {",
    ]
    back = _fetched(conn, fc, fault, drop_extra_properties=True)  # azi and dip are not columns of the class
    # Z stays (kind, clip range of the geometry); the headers of the properties left behind go with them
    assert _blocks(format_gocad(back), "PROPERTY_CLASS_HEADER", "}") == original[:1]
    with_properties = F.create_feature_class(
        conn, "faults2", "SURFACE", cell_properties=[("azi", "double precision"), ("dip", "double precision")]
    )
    conn.commit()
    back = _fetched(conn, with_properties, fault)
    assert format_gocad(back) == format_gocad(fault)
    assert _blocks(format_gocad(back), "PROPERTY_CLASS_HEADER", "}") == original


def test_a_class_header_of_no_property_is_kept_beside_properties() -> None:
    text = (
        (DATA / "skua_properties.ts")
        .read_text()
        .replace(
            "PROPERTY_CLASS_HEADER throw {",
            "PROPERTY_CLASS_HEADER vector3d {\nkind: Length\nunit: m\n}\nPROPERTY_CLASS_HEADER throw {",
        )
    )
    [surface] = parse_gocad(text)
    heads = [b[0] for b in _blocks(format_gocad(surface), "PROPERTY_CLASS_HEADER", "}")]
    assert heads == [
        "PROPERTY_CLASS_HEADER default property {",
        "PROPERTY_CLASS_HEADER vector3d {",
        "PROPERTY_CLASS_HEADER throw {",
    ]


_SKUA_LINEAR = """GOCAD TSurf 1
HEADER {
name:skua linear
}
PROPERTIES thickness " default property" age
PROP_LEGAL_RANGES **none** **none** **none** **none** 0 100
NO_DATA_VALUES -99999 -99999 -99999
PROPERTY_CLASSES thickness " default property" age
PROPERTY_KINDS Length " Real Number" Time
PROPERTY_SUBCLASSES LINEARFUNCTION Float 1  0 QUANTITY Float LINEARFUNCTION Double 0.5 -3
ESIZES 1  1  1
UNITS m unitless Ma
PROPERTY_CLASS_HEADER age {
kind: Time
unit: Ma
}
TFACE
PVRTX 1 0 0 0 10 0.5 1
PVRTX 2 1 0 0 20 1.5 2
PVRTX 3 0 1 0 30 2.5 3
TRGL 1 2 3
END
"""


def test_linearfunction_subclasses_are_kept(conn: Conn) -> None:
    [surface] = parse_gocad(_SKUA_LINEAR)
    info = surface.metadata["gocad_property_info"]
    assert info["PROPERTY_SUBCLASSES"] == {
        "thickness": "LINEARFUNCTION Float 1 0",
        " default property": "QUANTITY Float",
        "age": "LINEARFUNCTION Double 0.5 -3",
    }
    assert info["PROP_LEGAL_RANGES"]["age"] == "0 100"
    line = "PROPERTY_SUBCLASSES LINEARFUNCTION Float 1 0 QUANTITY Float LINEARFUNCTION Double 0.5 -3"
    assert line in format_gocad(surface).splitlines()
    # one property left out: the others keep theirs
    del surface.vertex_properties["thickness"]
    assert "PROPERTY_SUBCLASSES QUANTITY Float LINEARFUNCTION Double 0.5 -3" in format_gocad(surface).splitlines()
    [surface] = parse_gocad(_SKUA_LINEAR)
    fc = F.create_feature_class(
        conn,
        "skua",
        "SURFACE",
        cell_properties=[
            ("thickness", "double precision"),
            ("default_property", "double precision"),
            ("age", "double precision"),
        ],
    )
    back = _fetched(conn, fc, surface)
    assert format_gocad(back) == format_gocad(surface)
    assert line in format_gocad(back).splitlines()


def test_a_subclass_line_that_cannot_be_cut_per_property_is_written_back_as_it_was() -> None:
    text = _SKUA_LINEAR.replace(" LINEARFUNCTION Double 0.5 -3", "")  # 2 subclasses for 3 properties
    [surface] = parse_gocad(text)
    assert "PROPERTY_SUBCLASSES" not in surface.metadata["gocad_property_info"]  # not cut in 3 pairs of words
    assert "PROPERTY_SUBCLASSES LINEARFUNCTION Float 1 0 QUANTITY Float" in format_gocad(surface).splitlines()
    assert parse_gocad(format_gocad(surface))[0].metadata == surface.metadata
    del surface.vertex_properties["age"]  # the line is no longer true of the properties written: left out
    assert "PROPERTY_SUBCLASSES" not in format_gocad(surface)


# ---------------------------------------------------------------- .ml (GOCAD Model3d)


def test_ml_files_are_read_by_extension_with_the_tfaces_of_the_model() -> None:
    assert formats.format_for("model.ml").name == "gocadmodel"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        horizon, side = formats.read(DATA / "two_surfaces.ml")
    assert isinstance(horizon, Surface) and isinstance(side, Surface)
    assert (horizon.name, side.name) == ("horizon", "box side")
    assert side.cell_properties["part"].tolist() == [0, 1]
    assert horizon.metadata["gocad_model"] == {"name": "small model", "tfaces": [[1, "top"]]}
    assert side.metadata["gocad_model"] == {"name": "small model", "tfaces": [[2, "boundary"], [3, "boundary"]]}
    [warning] = [w.message for w in caught if isinstance(w.message, SkippedObjectWarning)]
    text = str(warning)
    assert warning.object_type == "Model3d" and warning.name == "small model" and warning.line == 1
    for named in ("REGION 'Upper'", "REGION 'Lower'", "LAYER 'Cover'", "SURFACE 'box'"):
        assert named in text, text
    assert "Universe" not in text  # the outside of the model: nothing is lost
    assert "not the volumes" in text
    with pytest.raises(FileFormatError, match="REGION 'Upper'"):
        formats.read(DATA / "two_surfaces.ml", skip_unsupported=False)


def test_an_ml_file_that_names_surfaces_it_does_not_hold_is_refused(tmp_path: Path) -> None:
    text = (DATA / "two_surfaces.ml").read_text()
    cut = text[: text.index("GOCAD TSurf 1", text.index("name: horizon"))]
    (tmp_path / "alone.ml").write_text(cut)
    with pytest.raises(FileFormatError, match="TSURF 'box side'") as refused:
        formats.read(tmp_path / "alone.ml")
    assert "the .ts files" in (refused.value.hint or "")
    (tmp_path / "wrong.ml").write_text(text.replace("TFACE 3  boundary box side", "TFACE 3  boundary horizon"))
    with pytest.raises(FileFormatError, match="gives the TSurf 'horizon' 2 TFACEs, the TSurf has 1"):
        formats.read(tmp_path / "wrong.ml")
    (tmp_path / "none.ml").write_text((DATA / "samples.vs").read_text())
    with pytest.raises(FileFormatError, match="holds no GOCAD Model3d"):
        formats.read(tmp_path / "none.ml")
    (tmp_path / "bad.ml").write_text(text.replace("LAYER Cover", "FAULT_BLOK Cover"))
    with pytest.raises(FileFormatError, match="unknown keyword 'FAULT_BLOK' in the Model3d"):
        formats.read(tmp_path / "bad.ml")
    (tmp_path / "keys.ml").write_text(text.replace("  10 0 0 \n", "  10 0 \n"))
    with pytest.raises(FileFormatError, match="TFACE 2 of the Model3d needs three key vertices") as bad:
        formats.read(tmp_path / "keys.ml")
    assert bad.value.line == 19
    (tmp_path / "open.ml").write_text(text.replace("  -1  +2  +3 \n  0\n", "  -1  +2  +3 \n  x\n"))
    with pytest.raises(FileFormatError, match="the REGION begun at line 29 lists ids up to a 0, found 'x'"):
        formats.read(tmp_path / "open.ml")


def test_ml_files_are_not_written(tmp_path: Path) -> None:
    with pytest.warns(SkippedObjectWarning):
        horizon, _ = formats.read(DATA / "two_surfaces.ml")
    with pytest.raises(FileFormatError, match="does not write GOCAD models") as refused:
        formats.write(horizon, tmp_path / "out.ml")
    assert ".ts" in (refused.value.hint or "")
    with pytest.raises(FileFormatError, match="does not write GOCAD models"):
        formats.write(GeometryCollection([horizon]), tmp_path / "out.ml")
    assert not (tmp_path / "out.ml").exists()
    # hints name the formats that write: not .ml (nor .lso, .gp)
    lines = formats.parse_gocad((DATA / "two_lines.pl").read_text())[0]
    with pytest.raises(FileFormatError) as wrong:
        formats.write(lines, tmp_path / "lines.ml")
    assert ".pl" in (wrong.value.hint or "") and ".ml" not in (wrong.value.hint or "")
    with pytest.raises(FileFormatError) as one:
        formats.write(GeometryCollection([horizon]), tmp_path / "x.obj")
    assert ".ts" in (one.value.hint or "") and ".ml" not in (one.value.hint or "")
    assert ".gp" not in (one.value.hint or "")


def test_cli_imports_an_ml_file_and_strict_refuses_it(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["--dsn", db_dsn, "class", "create", "model", "--geotype", "SURFACE"]) == 0
    capsys.readouterr()
    path = str(DATA / "two_surfaces.ml")
    assert main(["--dsn", db_dsn, "import", path, "--class", "model", "--strict"]) == 1
    err = capsys.readouterr().err
    assert "refused, nothing imported" in err and "REGION 'Upper'" in err
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT count(*) FROM model").fetchone() == (0,)
    assert main(["--dsn", db_dsn, "import", path, "--class", "model"]) == 0
    err = capsys.readouterr().err
    assert "warning" in err and "REGION 'Lower'" in err
    with psycopg.connect(db_dsn) as conn:
        rows = conn.execute(
            "SELECT g.geoname, g.metadata FROM model m JOIN tgsis.geometry g ON g.geoid = m._geoid ORDER BY g.geoid"
        ).fetchall()
    assert [r[0] for r in rows] == ["horizon", "box side"]
    meta = rows[1][1] if isinstance(rows[1][1], dict) else json.loads(rows[1][1])
    assert meta["gocad_model"]["tfaces"] == [[2, "boundary"], [3, "boundary"]]
    out = tmp_path / "side.ts"
    with psycopg.connect(db_dsn) as conn:
        side_id = conn.execute("SELECT _geoid FROM model ORDER BY _geoid DESC LIMIT 1").fetchone()
    assert side_id is not None
    assert main(["--dsn", db_dsn, "export", str(side_id[0]), str(out)]) == 0
    [back] = formats.read(out)
    with pytest.warns(SkippedObjectWarning):
        side = formats.read(DATA / "two_surfaces.ml")[1]
    assert back.cell_properties["part"].tolist() == [0, 1] and np.array_equal(back.vertices, side.vertices)
