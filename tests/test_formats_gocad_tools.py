"""GOCAD files as GOCAD, SKUA and other tools write them (issue 16, part 2).

Control-node flags on vertex lines, quoted names, files that mix objects tgsis
reads with ones it does not (SGrid, Model3d, groups), keywords tgsis does not
know inside an object, and SKUA's LightTSolid. The files are in
``tests/data/gocad`` (README.md there says what each holds and where its
layout comes from); the real CFM files of ``data/cfm`` are read with the flags
GOCAD adds.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import tgsis
from tests.shared_data import cfm
from tgsis import formats
from tgsis.errors import FileFormatError, SkippedObjectWarning
from tgsis.formats.gocad import (
    VERTEX_FLAGS,
    format_gocad,
    parse_gocad,
    quote_word,
    read_gocad,
    read_tsurf,
    split_words,
    write_gocad,
)
from tgsis.mesh import LineSet, PointSet, Surface, TetraMesh

DATA = Path(__file__).resolve().parent / "data" / "gocad"


def read_quietly(path: Path, **options: bool) -> list[tgsis.Mesh]:
    """read_gocad, failing the test on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return read_gocad(path, **options)


def write(tmp_path: Path, text: str, name: str = "f.ts") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# ---------------------------------------------------------------- the tokeniser


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("a b  c", ["a", "b", "c"]),
        ('" default property"  def-prop', [" default property", "def-prop"]),
        ('"Real Number" X "Real Number"', ["Real Number", "X", "Real Number"]),
        (
            'none +"horizon_1_fault_fract 1" -(boundary)"fracture 1"',
            ["none", "+horizon_1_fault_fract 1", "-(boundary)fracture 1"],
        ),
        ('""', [""]),
        ('"open quote', ["open", "quote"]),
        ("", []),
    ],
)
def test_split_words_takes_a_quoted_text_as_one_word(text: str, words: list[str]) -> None:
    assert split_words(text) == words


@pytest.mark.parametrize("word", ["plain", " default property", "Real Number", ""])
def test_quote_word_is_read_back_by_split_words(word: str) -> None:
    assert split_words(quote_word(word)) == [word]


# ---------------------------------------------------------------- control-node flags


def test_control_node_flags_are_read_per_vertex() -> None:
    [solid] = read_quietly(DATA / "control_nodes.so")
    assert isinstance(solid, TetraMesh)
    assert (solid.n_vertices, solid.n_cells) == (7, 3)  # nothing lost: 6 VRTX, 1 ATOM, 3 TETRA
    assert solid.vertices[:2].tolist() == [[0, 0, 0], [1, 0, 0]]
    # VRTX 1, 2, 4, 6 and ATOM 7 carry CNXYZ; VRTX 3 (blank after z) and VRTX 5 do not
    assert solid.metadata["gocad_vertex_flags"] == {"CNXYZ": [[0, 2], [3, 4], [5, 7]]}
    assert solid.metadata["gocad_atoms"] == [[6, 1]]
    assert solid.cell_properties["part"].tolist() == [0, 0, 1]
    assert solid.metadata["gocad_part_names"] == ["upper", "lower"]
    # the model section names boundary triangles of the tetrahedra: known, counted, not geometry of the mesh
    assert solid.metadata["gocad_ignored"] == {
        "MODEL": 1,
        "SURFACE": 1,
        "TFACE": 1,
        "KEYVERTICES": 1,
        "TRGL": 1,
        "MODEL_REGION": 2,
    }


def test_flags_and_part_names_are_written_back(tmp_path: Path) -> None:
    [solid] = read_quietly(DATA / "control_nodes.so")
    write_gocad(solid, tmp_path / "back.so")
    text = (tmp_path / "back.so").read_text()
    assert "VRTX 1 0.0 0.0 0.0 CNXYZ\n" in text and "VRTX 3 0.0 1.0 0.0\n" in text
    assert "ATOM 7 2 CNXYZ\n" in text
    assert "TVOLUME upper\n" in text and "TVOLUME lower\n" in text
    [back] = read_quietly(tmp_path / "back.so")
    assert back.same_as(solid)
    for key in ("gocad_vertex_flags", "gocad_atoms", "gocad_part_names"):
        assert back.metadata[key] == solid.metadata[key]


def test_flags_follow_vertices_when_atoms_are_merged() -> None:
    [solid] = read_gocad(DATA / "control_nodes.so", merge_atoms=True)
    assert solid.n_vertices == 6  # ATOM 7 is vertex 2 again; its flag goes with it
    assert solid.metadata["gocad_vertex_flags"] == {"CNXYZ": [[0, 2], [3, 4], [5, 6]]}


def test_flags_after_property_values() -> None:
    [surface] = read_quietly(DATA / "skua_properties.ts")
    assert surface.metadata["gocad_vertex_flags"] == {"CNXYZ": [[0, 3]]}
    assert surface.vertex_properties["throw"].tolist()[1:] == [12.5, 13.0, 14.0]
    assert "PVRTX 2 110.0 200.0 50.0 1.5 12.5 CNXYZ\n" in format_gocad(surface)


@pytest.mark.parametrize(
    "relative",
    [
        "formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts",
        "formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts",
        "formats/ETRA-LSBM-MULT-Burnt_Mountain-East_Wide_Canyon_fault-CFM2.ts",
    ],
)
def test_real_files_with_a_flag_on_every_vertex_read_the_same(relative: str, tmp_path: Path) -> None:
    source = cfm(relative)
    lines = source.read_text().splitlines()
    flagged = [
        line.rstrip() + " CNXYZ" if line.split()[:1] in (["VRTX"], ["PVRTX"], ["ATOM"]) else line for line in lines
    ]
    [plain] = read_quietly(source)
    [with_flags] = read_quietly(write(tmp_path, "\n".join(flagged) + "\n"))
    assert with_flags.same_as(plain)
    assert with_flags.metadata["gocad_vertex_flags"] == {"CNXYZ": [[0, plain.n_vertices]]}
    assert {k: v for k, v in with_flags.metadata.items() if k != "gocad_vertex_flags"} == plain.metadata


def test_every_flag_word_is_kept(tmp_path: Path) -> None:
    flags = sorted(VERTEX_FLAGS)
    text = "GOCAD VSet 1\n" + "".join(f"VRTX {i + 1} {i} 0 0 {flag}\n" for i, flag in enumerate(flags)) + "END\n"
    [points] = read_quietly(write(tmp_path, text, "f.vs"))
    assert points.metadata["gocad_vertex_flags"] == {flag: [[i, i + 1]] for i, flag in enumerate(flags)}
    assert format_gocad(points).count("VRTX") == len(flags)
    [back] = parse_gocad(format_gocad(points))
    assert back.metadata["gocad_vertex_flags"] == points.metadata["gocad_vertex_flags"]


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("VRTX 2 1 0 0 CNFOO", "VRTX has 5 values, expected 4"),
        ("VRTX 2 CNXYZ 1 0 0", "VRTX has 5 values, expected 4"),
        ("VRTX 2 CNXYZ 1 0", "VRTX has a non-numeric value 'CNXYZ'"),
        ("VRTX 2 1 0 0 CNXYZ CNXYZ", "VRTX has 5 values, expected 4"),
    ],
)
def test_a_word_that_is_not_a_trailing_flag_is_still_an_error(line: str, message: str, tmp_path: Path) -> None:
    path = write(tmp_path, f"GOCAD VSet 1\nVRTX 1 0 0 0 CNXYZ\n{line}\nEND\n")
    with pytest.raises(FileFormatError, match=re.escape(message)) as info:
        read_gocad(path)
    assert info.value.line == 3


def test_flags_metadata_edited_by_hand_is_checked_before_writing() -> None:
    points = PointSet(
        [[0, 0, 0], [1, 0, 0]],
        metadata={"gocad_vertex_flags": {"CNXYZ": [[0, 1], [1, 9], "x"], "rm -rf": [[0, 2]], "XYZ": "all"}},
    )
    assert format_gocad(points).splitlines()[-3:] == ["VRTX 1 0.0 0.0 0.0 CNXYZ", "VRTX 2 1.0 0.0 0.0", "END"]


# ---------------------------------------------------------------- quoted names (SKUA)


def test_quoted_property_names_are_read() -> None:
    [surface] = read_quietly(DATA / "skua_properties.ts")
    assert list(surface.vertex_properties) == ["default_property", "throw"]
    assert surface.metadata["property_names"] == {"default_property": " default property", "throw": "throw"}
    values = surface.vertex_properties["default_property"]
    assert values[:3].tolist() == [0.5, 1.5, 2.5] and np.isnan(values[3])  # -99999 is no data
    assert surface.metadata["gocad_property_info"]["PROPERTY_KINDS"] == {
        " default property": '" Real Number"',
        "throw": "Length",
    }
    assert surface.metadata["gocad_ignored"] == {"BSTONE": 1, "BORDER": 1}


def test_quoted_names_are_written_back_quoted(tmp_path: Path) -> None:
    [surface] = read_quietly(DATA / "skua_properties.ts")
    text = format_gocad(surface)
    assert 'PROPERTIES " default property" throw\n' in text
    assert 'PROPERTY_CLASSES " default property" throw\n' in text
    assert 'PROPERTY_KINDS " Real Number" Length\n' in text
    assert "PROPERTY_CLASS_HEADER default property {\nname: default property\n}\n" in text
    [back] = read_quietly(write(tmp_path, text))
    assert back.same_as(surface)
    assert back.metadata["property_names"] == surface.metadata["property_names"]
    assert back.metadata["gocad_property_info"] == surface.metadata["gocad_property_info"]


def test_esizes_errors_count_quoted_names_as_one(tmp_path: Path) -> None:
    path = write(tmp_path, 'GOCAD VSet 1\nPROPERTIES "rock type" porosity\nESIZES 1\nEND\n', "f.vs")
    with pytest.raises(FileFormatError, match=r"ESIZES gives 1 sizes for 2 properties \(rock type porosity\)"):
        read_gocad(path)


# ---------------------------------------------------------------- files that mix objects


def test_a_mixed_file_gives_its_surfaces_and_warns_for_the_rest() -> None:
    path = DATA / "mixed.ts"
    with pytest.warns(SkippedObjectWarning) as caught:
        meshes = read_gocad(path)
    assert [type(m) for m in meshes] == [Surface, LineSet]
    assert [m.name for m in meshes] == ["horizon", "trace"]
    assert meshes[0].n_cells == 1 and meshes[1].n_cells == 1
    skipped = [w.message for w in caught]
    assert all(isinstance(w, SkippedObjectWarning) for w in skipped)
    assert [(w.line, w.object_type, w.name) for w in skipped] == [  # type: ignore[union-attr]
        (1, "SGrid", "porosity grid"),
        (31, "Model3d", "structural model"),
    ]
    assert str(skipped[0]) == (
        f"{path}:1: skipped the GOCAD SGrid object 'porosity grid' (lines 1-20): "
        "tgsis reads TSurf, PLine, VSet, TSolid, LightTSolid"
    )
    assert tgsis.SkippedObjectWarning is SkippedObjectWarning


def test_skip_unsupported_false_refuses_a_mixed_file() -> None:
    with pytest.raises(
        FileFormatError,
        match="unsupported GOCAD SGrid object 'porosity grid' "
        r"\(lines 1-20\)",
    ) as info:
        read_gocad(DATA / "mixed.ts", skip_unsupported=False)
    assert info.value.line == 1 and "skip_unsupported=True" in str(info.value)
    with pytest.raises(FileFormatError, match="unsupported GOCAD SGrid"):
        formats.read(DATA / "mixed.ts", skip_unsupported=False)


def test_a_file_of_unsupported_objects_only_is_an_error_naming_them(tmp_path: Path) -> None:
    text = "GOCAD SGrid 1\nHEADER {\nname:g\n}\nEND\n\nGOCAD Voxet 1\nEND\n"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an error, not a warning and then an error
        with pytest.raises(FileFormatError) as info:
            read_gocad(write(tmp_path, text))
    assert info.value.line == 1
    assert (
        "unsupported GOCAD object type 'SGrid': the file holds no object tgsis reads (GOCAD SGrid object 'g' "
        "(lines 1-5); GOCAD Voxet object (lines 7-8)"
    ) in str(info.value)


def test_an_unsupported_object_cut_short_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="the GOCAD SGrid object begun at line 1 has no END before the next"):
        read_gocad(write(tmp_path, "GOCAD SGrid 1\nAXIS_N 2 2 2\nGOCAD TSurf 1\nEND\n"))
    with pytest.raises(FileFormatError, match=r"has no END \(the file ends first\)"):
        read_gocad(write(tmp_path, "GOCAD SGrid 1\nAXIS_N 2 2 2\n"))


def test_members_of_a_group_are_read(tmp_path: Path) -> None:
    surface, points = read_quietly(DATA / "group.gp")
    assert isinstance(surface, Surface) and surface.name == "member surface" and surface.n_cells == 1
    assert isinstance(points, PointSet) and points.vertices.tolist() == [[5, 5, 5], [6, 6, 6]]
    assert [m.name for m in formats.read(DATA / "group.gp")] == ["member surface", "member points"]
    with pytest.raises(FileFormatError, match="does not write groups"):
        formats.write(surface, tmp_path / "out.gp")


def test_groups_nest(tmp_path: Path) -> None:
    inner = (DATA / "group.gp").read_text().replace("GOCAD HeterogeneousGroup", "GOCAD HomogeneousGroup")
    text = "GOCAD HeterogeneousGroup 1\nHEADER {\nname:outer\n}\nBEGIN_MEMBERS\n" + inner + "END_MEMBERS\nEND\n"
    assert [m.name for m in read_quietly(write(tmp_path, text, "nested.gp"))] == ["member surface", "member points"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("GOCAD HomogeneousGroup 1\nHEADER {\nname:g\n}\nEND\n", "has no BEGIN_MEMBERS line"),
        ("GOCAD HomogeneousGroup 1\nBEGIN_MEMBERS\nGOCAD VSet 1\nVRTX 1 0 0 0\nEND\n", "has no END_MEMBERS"),
        ("GOCAD HomogeneousGroup 1\nBEGIN_MEMBERS\nGOCAD VSet 1\nVRTX 1 0 0 0\nEND\nEND_MEMBERS\n", "no END after"),
    ],
)
def test_broken_groups_are_errors(text: str, message: str, tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match=message):
        read_gocad(write(tmp_path, text))


# ---------------------------------------------------------------- keywords tgsis does not know


def test_unknown_keywords_refuse_the_file_naming_line_and_keyword() -> None:
    path = DATA / "unknown_keywords.ts"
    with pytest.raises(FileFormatError) as info:
        read_gocad(path)
    assert info.value.line == 8
    assert str(info.value).startswith(f"{path}:8: unknown keyword 'VERTEX' in the TSurf begun at line 1")


@pytest.mark.parametrize(
    ("text", "line", "keyword"),
    [
        ("GOCAD TSurf 1\nTFACE\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nSEG 1 2\nEND\n", 5, "SEG"),
        ("GOCAD PLine 1\nILINE\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\nTRGL 1 2 3\nEND\n", 6, "TRGL"),
        ("GOCAD TSurf 1\nVERTEX 1 0 0 0\nTFACE\nEND\n", 2, "VERTEX"),  # before the geometry too
        ("GOCAD VSet 1\nVRTX 1 0 0 0\nvrtx 2 1 0 0\nEND\n", 3, "vrtx"),
        ("GOCAD TSolid 1\nTVOLUME\nVRTX 1 0 0 0\nTRIANGLE 1 2 3\nEND\n", 4, "TRIANGLE"),
    ],
)
def test_unknown_keyword_cases(text: str, line: int, keyword: str, tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match=f"unknown keyword {keyword!r}") as info:
        read_gocad(write(tmp_path, text))
    assert info.value.line == line


def test_known_harmless_keywords_are_still_read_past() -> None:
    text = (
        "GOCAD TSurf 1\nGEOLOGICAL_TYPE fault\nTFACE\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\nTRGL 1 2 3\n"
        "BSTONE 1\nBORDER 4 1 2\nSTRATIGRAPHIC_POSITION Late 2\nEND\n"
        "GOCAD VSet 1\nVRTX 1 0 0 0\nSUBVSET\nVRTX 2 1 0 0\nEND\n"
    )
    surface, points = parse_gocad(text)
    assert surface.metadata["gocad_extra_lines"] == ["GEOLOGICAL_TYPE fault", "STRATIGRAPHIC_POSITION Late 2"]
    assert surface.metadata["gocad_ignored"] == {"BSTONE": 1, "BORDER": 1}
    assert points.n_vertices == 2 and points.metadata["gocad_ignored"] == {"SUBVSET": 1}


# ---------------------------------------------------------------- SKUA's LightTSolid


def test_light_tsolid_is_read_as_a_tetrahedral_mesh() -> None:
    [solid] = read_quietly(DATA / "light_solid.lso")
    assert isinstance(solid, TetraMesh) and solid.name == "small light solid"
    assert solid.metadata["gocad_kind"] == "LightTSolid"
    assert solid.n_vertices == 7  # 6 PVRTX and a SHAREDPVRTX, which is a PATOM: same place, own values
    assert solid.vertices[6].tolist() == solid.vertices[1].tolist() == [1, 0, 0]
    assert solid.metadata["gocad_atoms"] == [[6, 1]]
    assert solid.cells.tolist() == [[0, 1, 2, 3], [1, 2, 3, 4], [6, 2, 4, 5]]
    # "# CTETRA <region>" after each TETRA: the regions are the parts
    assert solid.cell_properties["part"].tolist() == [0, 1, 0]
    assert solid.metadata["gocad_part_names"] == ["R1", "R2"]
    props = solid.vertex_properties
    assert list(props) == ["wf_structural_resolution_map", "vec"]  # vec (ESIZES 2): one (n, 2) property
    assert props["vec"][:, 0].tolist() == [1, 1, 1, 1, 1, 1, 3] and props["vec"][6, 1] == 4
    assert np.isnan(props["wf_structural_resolution_map"][4])
    assert solid.metadata["gocad_vertex_flags"] == {"XYZ": [[0, 5]]}
    assert solid.metadata["gocad_extra_lines"] == ["FIXED 0 1", "REGION interpolation_region 0"]
    assert solid.metadata["gocad_ignored"] == {
        "BEGIN_VERTEX_REGION_INDICATORS": 1,
        "MODEL": 1,
        "SURFACE": 2,
        "TFACE": 2,
        "KEYVERTICES": 2,
        "TRGL": 2,
        "MODEL_REGION": 2,
    }


def test_light_tsolid_through_the_registry_and_back_as_tsolid(tmp_path: Path) -> None:
    [solid] = formats.read(DATA / "light_solid.lso")
    assert isinstance(solid, TetraMesh)
    with pytest.raises(FileFormatError, match="writes tetrahedra as GOCAD TSolid") as info:
        formats.write(solid, tmp_path / "out.lso")
    assert "write a .so file" in str(info.value)
    formats.write(solid, tmp_path / "out.so")
    [back] = read_quietly(tmp_path / "out.so")
    assert isinstance(back, TetraMesh)
    assert back.metadata["gocad_kind"] == "TSolid"
    assert back.metadata["gocad_part_names"] == ["R1", "R2"]
    assert back.vertices.tobytes() == solid.vertices.tobytes()

    def by_part(mesh: TetraMesh) -> list[tuple[int, list[int]]]:
        return sorted((int(p), c) for p, c in zip(mesh.cell_properties["part"], mesh.cells.tolist()))

    assert by_part(back) == by_part(solid)  # cells come back grouped by part, each with its region


@pytest.mark.parametrize(
    ("body", "line", "message"),
    [
        ("# CTETRA R1 none none none none\n", 6, "must follow a TETRA line"),
        ("TETRA 1 2 3 4\n# CTETRA\n", 7, "must follow a TETRA line and name a region"),
    ],
)
def test_light_tsolid_errors(body: str, line: int, message: str, tmp_path: Path) -> None:
    text = "GOCAD LightTSolid 1\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\nVRTX 4 0 0 1\n" + body + "END\n"
    with pytest.raises(FileFormatError, match=message) as info:
        read_gocad(write(tmp_path, text, "f.lso"))
    assert info.value.line == line


def test_read_tsurf_passes_the_options_on() -> None:
    with pytest.warns(SkippedObjectWarning):
        with pytest.raises(FileFormatError, match=r"expected exactly one TSurf, found 2 objects \(TSurf, PLine\)"):
            read_tsurf(DATA / "mixed.ts")
    with pytest.raises(FileFormatError, match="unsupported GOCAD SGrid"):
        read_tsurf(DATA / "mixed.ts", skip_unsupported=False)


def test_a_quoted_header_name_loses_its_quotes(tmp_path: Path) -> None:
    text = 'GOCAD VSet 1\nHEADER {\nname: "Fault 1 east"\n}\nVRTX 1 0 0 0\nEND\n'
    [points] = read_quietly(write(tmp_path, text, "f.vs"))
    assert points.name == "Fault 1 east"
    assert "name:Fault 1 east\n" in format_gocad(points)
