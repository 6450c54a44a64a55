"""GOCAD ASCII (TSurf, PLine, VSet, TSolid): real CFM files, hand-written samples, errors, the registry."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pytest

from tests.shared_data import CFM, cfm
from tgsis import formats
from tgsis.errors import FileFormatError
from tgsis.formats.gocad import format_gocad, parse_gocad, read_gocad, read_tsurf, write_gocad, write_gocad_many
from tgsis.mesh import LineSet, Mesh, PointSet, Surface, TetraMesh

DATA = Path(__file__).resolve().parent / "data" / "gocad"

# The CFM files the shared data set is documented to hold (README.md there).
CFM_FILES = [
    "cfm5.3/CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m.ts",
    "cfm5.3/CRFA-SLRS-MULT-San_Luis_Range_fault_system-CFM4_1000m.ts",
    "cfm5.3/GRFS-GRFZ-WEST-Garlock_fault-CFM5_1000m.ts",
    "cfm6.1/CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m.ts",
    "cfm6.1/CRFA-SLRS-MULT-San_Luis_Range_fault_system-CFM4_1000m.ts",
    "cfm6.1/GRFS-GRFZ-WEST-Garlock_fault-CFM5_1000m.ts",
    "formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts",
    "formats/ETRA-LSBM-MULT-Burnt_Mountain-East_Wide_Canyon_fault-CFM2.ts",
    "formats/SAFS-SAFZ-MULT-San_Andreas_fault_Fuis-ALT6_500m.ts",
    "formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts",
]
PROPERTIES_FILE = "formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts"
EIGHT_PARTS_FILE = "formats/ETRA-LSBM-MULT-Burnt_Mountain-East_Wide_Canyon_fault-CFM2.ts"
ATOM_FILE = "formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts"
BIG_FILE = "formats/SAFS-SAFZ-MULT-San_Andreas_fault_Fuis-ALT6_500m.ts"


def keyword_counts(path: Path) -> dict[str, int]:
    """How many lines start with each keyword: an independent count to check the parser against."""
    counts: dict[str, int] = {}
    for line in path.read_text().splitlines():
        words = line.split()
        if words:
            counts[words[0]] = counts.get(words[0], 0) + 1
    return counts


def round_trip(mesh: Mesh, tmp_path: Path, name: str = "out.ts", **options: object) -> Mesh:
    path = tmp_path / name
    write_gocad(mesh, path, **options)  # type: ignore[arg-type]
    [back] = read_gocad(path)
    return back


def write(tmp_path: Path, text: str, name: str = "bad.ts") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# ---------------------------------------------------------------- real CFM files


def test_cfm_data_set_is_complete() -> None:
    found = {p.relative_to(CFM).as_posix() for p in CFM.glob("**/*.ts")} if CFM.is_dir() else set()
    missing = set(CFM_FILES) - found
    assert not missing, f"CFM files missing from {CFM}: {sorted(missing)}"


@pytest.mark.parametrize("relative", CFM_FILES)
def test_cfm_file_loads_with_the_counts_of_its_lines(relative: str) -> None:
    path = cfm(relative)
    counts = keyword_counts(path)
    surface = read_tsurf(path)
    assert isinstance(surface, Surface)
    expected_vertices = sum(counts.get(k, 0) for k in ("VRTX", "PVRTX", "ATOM", "PATOM"))
    assert surface.n_vertices == expected_vertices
    assert surface.n_cells == counts["TRGL"]
    assert surface.name and surface.name in path.read_text()
    assert surface.metadata["zpositive"] == "Elevation"
    # z is kept as written (elevation): CFM faults lie mostly below sea level
    assert np.median(surface.vertices[:, 2]) < 0


@pytest.mark.parametrize("relative", CFM_FILES)
def test_cfm_file_round_trips_bit_exactly(relative: str, tmp_path: Path) -> None:
    original = read_tsurf(cfm(relative))
    back = round_trip(original, tmp_path)
    assert back.same_as(original)
    assert back.name == original.name
    assert back.metadata.get("color") == original.metadata.get("color")
    # the rewritten file reads back to the same text: writing is deterministic
    assert format_gocad(back) == format_gocad(original)


def test_cfm_first_vertex_keeps_every_digit() -> None:
    surface = read_tsurf(cfm("cfm6.1/CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m.ts"))
    assert surface.vertices[0].tolist() == [125841.625, 3957298.0859375, -6152.44189453125]
    # vertex ids are mapped in file order; TRGL ids are 1-based
    assert surface.cells.min() == 0 and surface.cells.max() == surface.n_vertices - 1


def test_cfm_vertex_properties_azi_dip(tmp_path: Path) -> None:
    path = cfm(PROPERTIES_FILE)
    surface = read_tsurf(path)
    assert list(surface.vertex_properties) == ["azi", "dip"]
    assert surface.vertex_properties["azi"].dtype == np.float64
    first = next(line for line in path.read_text().splitlines() if line.startswith("PVRTX 1 "))
    values = [float(w) for w in first.split()[2:]]
    assert surface.vertices[0].tolist() == values[:3]
    assert surface.vertex_properties["azi"][0] == values[3]
    assert surface.vertex_properties["dip"][0] == values[4]
    assert surface.metadata["gocad_no_data_values"] == {"azi": -99999.0, "dip": -99999.0}
    assert surface.metadata["gocad_property_info"]["PROPERTY_CLASSES"] == {"azi": "azimuth", "dip": "dip"}
    assert surface.metadata["gocad_ignored"] == {"BSTONE": 5, "BORDER": 5}
    assert "part" not in surface.cell_properties  # one TFACE: no part property
    back = round_trip(surface, tmp_path)
    assert back.same_as(surface)
    text = (tmp_path / "out.ts").read_text()
    assert "PROPERTIES azi dip\n" in text and "PROPERTY_CLASSES azimuth dip\n" in text
    assert "PROPERTY_CLASS_HEADER azimuth {\n" in text


def test_cfm_eight_tface_parts(tmp_path: Path) -> None:
    path = cfm(EIGHT_PARTS_FILE)
    surface = read_tsurf(path)
    # triangles per part, counted independently from the file
    per_part: list[int] = []
    for line in path.read_text().splitlines():
        if line.startswith("TFACE"):
            per_part.append(0)
        elif line.startswith("TRGL"):
            per_part[-1] += 1
    assert len(per_part) == 8
    part = surface.cell_properties["part"]
    assert part.dtype == np.int64
    assert np.bincount(part).tolist() == per_part
    assert np.all(np.diff(part) >= 0)
    back = round_trip(surface, tmp_path)
    assert back.same_as(surface)
    assert (tmp_path / "out.ts").read_text().count("TFACE\n") == 8


def test_cfm_atom_is_its_own_vertex_by_default(tmp_path: Path) -> None:
    surface = read_tsurf(cfm(ATOM_FILE))
    # ATOM 617 126: ids are 1..685 without gaps here, so index = id - 1
    assert surface.metadata["gocad_atoms"] == [[616, 125]]
    assert surface.vertices[616].tolist() == surface.vertices[125].tolist()
    assert np.isin(616, surface.cells) and np.bincount(surface.cell_properties["part"]).size == 2
    back = round_trip(surface, tmp_path)
    assert back.same_as(surface)
    assert "ATOM 617 126\n" in (tmp_path / "out.ts").read_text()


def test_cfm_atom_merged_onto_its_vertex() -> None:
    kept = read_tsurf(cfm(ATOM_FILE))
    merged = read_tsurf(cfm(ATOM_FILE), merge_atoms=True)
    assert merged.n_vertices == kept.n_vertices - 1
    assert "gocad_atoms" not in merged.metadata
    # the triangles are the same places: vertex 616 became 125, later vertices moved down by one
    remap = np.arange(kept.n_vertices) - (np.arange(kept.n_vertices) > 616)
    remap[616] = 125
    assert np.array_equal(merged.cells, remap[kept.cells])
    assert np.array_equal(merged.vertices, np.delete(kept.vertices, 616, axis=0))


def test_cfm_big_file_parses_fast() -> None:
    path = cfm(BIG_FILE)
    best = math.inf
    for _ in range(3):
        start = time.perf_counter()
        surface = read_tsurf(path)
        best = min(best, time.perf_counter() - start)
    assert (surface.n_vertices, surface.n_cells) == (39268, 76292)
    assert best < 1.0, f"parsing the 39k-vertex file took {best:.2f} s"


def test_two_cfm_files_in_one_file(tmp_path: Path) -> None:
    first, second = read_tsurf(cfm(CFM_FILES[0])), read_tsurf(cfm(PROPERTIES_FILE))
    path = tmp_path / "both.ts"
    path.write_text(cfm(CFM_FILES[0]).read_text() + "\n" + cfm(PROPERTIES_FILE).read_text())
    meshes = read_gocad(path)
    assert [m.name for m in meshes] == [first.name, second.name]
    assert meshes[0].same_as(first) and meshes[1].same_as(second)
    with pytest.raises(FileFormatError, match="expected exactly one TSurf, found 2 objects"):
        read_tsurf(path)


# ---------------------------------------------------------------- hand-written samples


def test_tsurf_two_parts_properties_no_data_and_atom() -> None:
    surface = read_tsurf(DATA / "two_parts_properties.ts")
    assert surface.name == "two parts"
    assert surface.vertices.tolist() == [[0, 0, 100], [1, 0, 100], [0, 1, 100.5], [1, 1, 101], [1, 0, 100]]
    assert surface.cells.tolist() == [[0, 1, 2], [4, 3, 2]]
    assert surface.cell_properties["part"].tolist() == [0, 1]
    props = surface.vertex_properties
    assert list(props) == ["Porosity", "Vel"]  # names as written; Vel (ESIZES 2) is one (n, 2) property
    np.testing.assert_array_equal(props["Porosity"], [0.25, np.nan, 0.3, 0.1, np.nan])
    np.testing.assert_array_equal(props["Vel"][:, 0], [1500, 1510, 1520, 1530, 1510])
    np.testing.assert_array_equal(props["Vel"][:, 1], [1600, np.nan, 1620, 1630, np.nan])
    meta = surface.metadata
    assert meta["property_names"] == {"Porosity": "Porosity", "Vel": "Vel"}
    assert meta["gocad_esizes"] == {"Vel": 2}
    assert meta["gocad_no_data_values"] == {"Porosity": -999.0, "Vel": -1.0}
    assert meta["color"] == (1.0, 0.5, 0.0, 1.0)
    assert meta["zpositive"] == "Depth"  # and z is not flipped (checked above)
    assert meta["gocad_extra_lines"] == ["GEOLOGICAL_FEATURE test_fault"]
    assert meta["gocad_atoms"] == [[4, 1]]
    assert meta["gocad_ignored"] == {"BSTONE": 1, "BORDER": 1}


def test_tsurf_sample_writes_back_names_sizes_and_no_data(tmp_path: Path) -> None:
    surface = read_tsurf(DATA / "two_parts_properties.ts")
    back = round_trip(surface, tmp_path)
    assert back.same_as(surface)
    assert back.metadata["property_names"] == surface.metadata["property_names"]
    text = (tmp_path / "out.ts").read_text()
    for line in (
        "PROPERTIES Porosity Vel",
        "ESIZES 1 2",
        "NO_DATA_VALUES -999 -1",
        "ZPOSITIVE Depth",
        "PROPERTY_CLASSES porosity velocity",
        "UNITS fraction m/s",
        "GEOLOGICAL_FEATURE test_fault",
        "*solid*color:1 0.5 0 1",
        "PVRTX 2 1.0 0.0 100.0 -999.0 1510.0 -1.0",
        "ATOM 5 2",
    ):
        assert line + "\n" in text
    assert text.count("TFACE\n") == 2


def test_tsurf_merge_atoms_sample() -> None:
    surface = read_tsurf(DATA / "two_parts_properties.ts", merge_atoms=True)
    assert surface.n_vertices == 4
    assert surface.cells.tolist() == [[0, 1, 2], [1, 3, 2]]


def test_patom_values_and_atom_chains(tmp_path: Path) -> None:
    text = (
        "GOCAD VSet 1\nPROPERTIES a\nATOM 9 3\nPVRTX 1 0 0 0 5\nPATOM 2 1\nPATOM 3 1 7\nATOM 4 3\nVRTX 5 1 1 1\nEND\n"
    )
    [points] = parse_gocad(text)
    assert points.vertices.tolist() == [[0, 0, 0]] * 5 + [[1, 1, 1]]
    # a PATOM without values and an ATOM repeat their vertex; ATOM 4 and the forward ATOM 9 repeat PATOM 3
    np.testing.assert_array_equal(points.vertex_properties["a"], [7, 5, 5, 7, 7, np.nan])
    assert points.metadata["gocad_atoms"] == [[0, 3], [2, 1], [3, 1], [4, 3]]
    assert points.metadata["gocad_patoms"] == [2, 3]
    back = round_trip(points, tmp_path, "p.vs")
    assert back.same_as(points)
    # only atoms whose vertex comes earlier are written as atoms: in a file with properties as PATOMs,
    # with values of their own where they differ from the vertex they repeat
    assert [line for line in (tmp_path / "p.vs").read_text().splitlines() if "ATOM" in line] == [
        "PATOM 3 2",
        "PATOM 4 2 7.0",
        "ATOM 5 4",
    ]


def test_pline_sample() -> None:
    [lines] = read_gocad(DATA / "two_lines.pl")
    assert isinstance(lines, LineSet)
    assert lines.name == "fault trace"
    assert lines.vertices.tolist() == [[0, 0, 0], [10, 0, 0], [20, 5, -0.5], [0, 10, -5], [10, 10, -5]]
    assert lines.cells.tolist() == [[0, 1], [1, 2], [3, 4]]  # ids 7, 8 map to indices 3, 4
    assert lines.cell_properties["part"].tolist() == [0, 0, 1]
    assert lines.metadata["color"] == (0.0, 0.0, 1.0, 1.0)


def test_vset_sample() -> None:
    [points] = read_gocad(DATA / "samples.vs")
    assert isinstance(points, PointSet)
    assert points.vertices.tolist() == [[100.5, 200.25, -10], [101.5, 201.25, -11], [102.5, 202.25, -12]]
    assert points.cells.tolist() == [[0], [1], [2]]
    np.testing.assert_array_equal(points.vertex_properties["grade"], [1.5, np.nan, 2.5])
    assert points.metadata["color"] == (1.0, 0.0, 0.0, 1.0)


def test_tsolid_sample() -> None:
    [solid] = read_gocad(DATA / "two_volumes.so")
    assert isinstance(solid, TetraMesh)
    assert solid.n_vertices == 6
    assert solid.cells.tolist() == [[0, 1, 2, 3], [1, 2, 3, 4], [1, 2, 4, 5]]
    assert solid.cell_properties["part"].tolist() == [0, 0, 1]


@pytest.mark.parametrize("name", ["two_lines.pl", "samples.vs", "two_volumes.so", "two_parts_properties.ts"])
def test_sample_round_trips(name: str, tmp_path: Path) -> None:
    [mesh] = read_gocad(DATA / name)
    back = round_trip(mesh, tmp_path, name)
    assert type(back) is type(mesh) and back.same_as(mesh)
    assert (
        back.metadata["color" if "color" in mesh.metadata else "gocad_kind"]
        == mesh.metadata["color" if "color" in mesh.metadata else "gocad_kind"]
    )


def test_several_kinds_in_one_file(tmp_path: Path) -> None:
    text = "".join((DATA / n).read_text() for n in ("samples.vs", "two_lines.pl", "two_volumes.so"))
    meshes = parse_gocad(text)
    assert [type(m) for m in meshes] == [PointSet, LineSet, TetraMesh]
    write_gocad_many(meshes, tmp_path / "all.gocad")
    back = read_gocad(tmp_path / "all.gocad")
    assert all(a.same_as(b) for a, b in zip(meshes, back)) and len(back) == 3


# ---------------------------------------------------------------- writing meshes made in Python


def random_meshes() -> list[Mesh]:
    rng = np.random.default_rng(7)
    vertices = rng.uniform(-1e6, 1e6, (40, 3)) * 10.0 ** rng.integers(-8, 3, (40, 1))
    vertices[0] = [-0.0, 5e-324, 1.7976931348623157e308 / 1e3]  # signed zero, a subnormal, a huge value
    props = {"temperature": rng.normal(size=40), "count": np.arange(40), "flag": np.arange(40) % 3 == 0}
    props["temperature"][[3, 9]] = np.nan
    return [
        PointSet(vertices, vertex_properties=props, name="points"),
        LineSet(vertices, np.stack([np.arange(39), np.arange(1, 40)], 1), vertex_properties=props),
        Surface(
            vertices,
            np.stack([np.arange(38), np.arange(1, 39), np.arange(2, 40)], 1),
            vertex_properties=props,
            cell_properties={"part": np.repeat([3, 8], 19)},
            name="tri",
        ),
        TetraMesh(
            vertices,
            np.stack([np.arange(37) + j for j in range(4)], 1),
            vertex_properties=props,
            metadata={"zpositive": "Depth", "color": (0.25, 0.5, 0.75, 1.0)},
        ),
    ]


@pytest.mark.parametrize("index", range(4))
def test_python_meshes_round_trip_bit_exactly(index: int, tmp_path: Path) -> None:
    mesh = random_meshes()[index]
    back = round_trip(mesh, tmp_path)
    if "part" in mesh.cell_properties:
        assert back.cell_properties["part"].tolist() == [0] * 19 + [1] * 19  # parts 3, 8 renumbered 0, 1
        mesh.cell_properties["part"] = back.cell_properties["part"]
    assert type(back) is type(mesh) and back.same_as(mesh)
    assert back.name == mesh.name
    assert back.metadata.get("color") == mesh.metadata.get("color")
    assert back.metadata.get("zpositive") == mesh.metadata.get("zpositive")
    assert all(v.dtype == np.float64 for v in back.vertex_properties.values())  # GOCAD values are floats


def test_no_data_value_avoids_real_values(tmp_path: Path) -> None:
    mesh = PointSet(
        np.zeros((3, 3)) + [[0, 0, 0], [1, 0, 0], [2, 0, 0]], vertex_properties={"v": np.array([-99999.0, np.nan, 1.0])}
    )
    back = round_trip(mesh, tmp_path, "p.vs")
    assert back.same_as(mesh)
    assert "NO_DATA_VALUES -999999\n" in (tmp_path / "p.vs").read_text()


def test_interleaved_parts_come_back_grouped(tmp_path: Path) -> None:
    vertices = np.eye(4)[:, :3] + np.arange(4)[:, None]
    surface = Surface(
        np.vstack([vertices, vertices + 10]),
        [[0, 1, 2], [4, 5, 6], [1, 2, 3], [5, 6, 7]],
        cell_properties={"part": [0, 1, 0, 1]},
    )
    back = round_trip(surface, tmp_path)
    assert back.cells.tolist() == [[0, 1, 2], [1, 2, 3], [4, 5, 6], [5, 6, 7]]
    assert back.cell_properties["part"].tolist() == [0, 0, 1, 1]
    assert np.array_equal(back.vertices, surface.vertices)
    text = (tmp_path / "out.ts").read_text()
    # every vertex comes before the first triangle that uses it
    assert text.index("VRTX 8 ") < text.index("TRGL 5 6 7")


def test_cell_properties_other_than_part_are_refused(tmp_path: Path) -> None:
    surface = Surface(np.eye(3), [[0, 1, 2]], cell_properties={"area": [0.5], "part": [0]})
    with pytest.raises(FileFormatError, match="cannot store the triangle properties area") as info:
        write_gocad(surface, tmp_path / "s.ts")
    assert "drop_cell_properties=True" in str(info.value)
    write_gocad(surface, tmp_path / "s.ts", drop_cell_properties=True)
    assert list(read_tsurf(tmp_path / "s.ts").cell_properties) == []  # one part: no part property


def test_pointset_with_other_cells_is_refused(tmp_path: Path) -> None:
    points = PointSet(np.eye(3), [[2], [0]])
    with pytest.raises(FileFormatError, match="one point per vertex"):
        write_gocad(points, tmp_path / "p.vs")


def test_written_file_is_plain_gocad(tmp_path: Path) -> None:
    surface = Surface([[0.1, 0.2, 0.3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [[0, 1, 2]], name="tiny")
    write_gocad(surface, tmp_path / "t.ts")
    assert (tmp_path / "t.ts").read_text() == (
        "GOCAD TSurf 1\nHEADER {\nname:tiny\n}\nTFACE\n"
        "VRTX 1 0.1 0.2 0.3\nVRTX 2 1.0 0.0 0.0\nVRTX 3 0.0 1.0 0.0\nTRGL 1 2 3\nEND\n"
    )


def test_renamed_property_names_are_written_back(tmp_path: Path) -> None:
    text = "GOCAD VSet 1\nPROPERTIES Rock-Type 2nd type\nPVRTX 1 0 0 0 1 2 3\nEND\n"
    [points] = parse_gocad(text)
    assert list(points.vertex_properties) == ["Rock_Type", "p_2nd", "type"]  # letter case kept
    assert points.metadata["property_names"] == {"Rock_Type": "Rock-Type", "p_2nd": "2nd", "type": "type"}
    assert "PROPERTIES Rock-Type 2nd type\n" in format_gocad(points)


# ---------------------------------------------------------------- errors, each with its line number

TSURF_HEAD = "GOCAD TSurf 1\nHEADER {\nname:bad\n}\nTFACE\n"  # 5 lines


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("\nGOCAD Voxet 1\nEND\n", 2, "unsupported GOCAD object type 'Voxet'"),
        ("GOCAD\nEND\n", 1, "names no object type"),
        ("HEADER {\nname:x\n}\nVRTX 1 0 0 0\nEND\n", 1, "expected a 'GOCAD <type> <version>' line"),
        (
            TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\nTRGL 1 2 17\nEND\n",
            9,
            "TRGL refers to vertex 17, which is not defined",
        ),
        (
            TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 1 0 1 0\nEND\n",
            8,
            "vertex id 1 is defined twice (first at line 6)",
        ),
        (TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 0\nEND\n", 7, "VRTX has 3 values, expected 4"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\nTRGL 1 2\nEND\n", 9, "TRGL has 2 values, expected 3"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\nTRGL 1 2 3 3\nEND\n", 9, "TRGL has 4 values"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 abc 0\nEND\n", 7, "VRTX has a non-numeric value 'abc'"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 nan 0\nEND\n", 7, "VRTX has a non-finite y coordinate 'nan'"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nVRTX x 1 0 0\nEND\n", 7, "VRTX has a vertex id that is not an integer: 'x'"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\nTRGL 1 2 3\n", 9, "has no END (the file ends first)"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nGOCAD TSurf 1\nEND\n", 7, "has no END before the next GOCAD object"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nATOM 2 9\nEND\n", 7, "ATOM refers to vertex 9, which is not defined"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nATOM 2 1 5\nEND\n", 7, "ATOM has 3 values, expected 2"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nATOM 2 3\nATOM 3 2\nEND\n", 7, "ATOM 2 repeats itself through a chain"),
        (TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 0 0\nTRGL 1 2 2\nEND\n", 8, "TRGL 1 2 2 uses one vertex twice"),
        ("GOCAD TSurf 1\nHEADER {\nname:x\nEND\n", 2, "HEADER block is not closed"),
        ("GOCAD TSurf 1\nPROPERTIES a b\nTFACE\nPVRTX 1 0 0 0 1\nEND\n", 4, "PVRTX has 5 values, expected 6"),
        ("GOCAD TSurf 1\nPROPERTIES a\nTFACE\nPVRTX 1 0 0 0 1 2\nEND\n", 4, "PVRTX has 6 values, expected 5"),
        ("GOCAD TSurf 1\nTFACE\nPVRTX 1 0 0 0 7\nEND\n", 3, "PVRTX has 5 values, expected 4"),
        ("GOCAD TSurf 1\nPROPERTIES a b\nESIZES 1\nEND\n", 3, "ESIZES gives 1 sizes for 2 properties"),
        ("GOCAD PLine 1\nILINE\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nSEG 1 3\nEND\n", 5, "SEG refers to vertex 3"),
        (
            "GOCAD TSolid 1\nTVOLUME\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\nVRTX 4 0 0 1\nTETRA 1 2 3 5\nEND\n",
            7,
            "TETRA refers to vertex 5",
        ),
        ("GOCAD VSet 1\nVRTX 1 0 0 0\nVRTX 1 1 0 0\nEND\n", 3, "vertex id 1 is defined twice"),
    ],
)
def test_errors_name_the_problem_and_line(text: str, line: int, message: str, tmp_path: Path) -> None:
    path = write(tmp_path, text)
    with pytest.raises(FileFormatError) as info:
        read_gocad(path)
    assert message in str(info.value)
    assert info.value.line == line
    assert str(info.value).startswith(f"{path}:{line}: ")


def test_empty_and_missing_files(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="no GOCAD object"):
        read_gocad(write(tmp_path, "\n# only a comment\n"))
    with pytest.raises(FileFormatError, match="cannot read the file"):
        read_gocad(tmp_path / "nope.ts")


def test_merged_atom_making_a_degenerate_triangle_is_explained(tmp_path: Path) -> None:
    text = TSURF_HEAD + "VRTX 1 0 0 0\nVRTX 2 1 0 0\nATOM 3 1\nTRGL 1 2 3\nEND\n"
    assert read_tsurf(write(tmp_path, text)).n_vertices == 3
    with pytest.raises(FileFormatError, match="once ATOMs are merged") as info:
        read_tsurf(write(tmp_path, text), merge_atoms=True)
    assert info.value.line == 9


def test_unwritable_path(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="cannot write the file"):
        write_gocad(Surface(np.eye(3), [[0, 1, 2]]), tmp_path / "missing" / "dir" / "s.ts")


# ---------------------------------------------------------------- registry


def test_registry_picks_gocad_by_extension(tmp_path: Path) -> None:
    for name, kind in (
        ("two_lines.pl", LineSet),
        ("samples.vs", PointSet),
        ("two_volumes.so", TetraMesh),
        ("two_parts_properties.ts", Surface),
    ):
        mesh = formats.read_one(DATA / name)
        assert type(mesh) is kind
        assert formats.format_for(DATA / name).geotypes == (kind.geotype,)
        formats.write(mesh, tmp_path / name)
        assert formats.read_one(tmp_path / name).same_as(mesh)
    assert formats.read(cfm(ATOM_FILE), merge_atoms=True)[0].n_vertices == 684


def test_registry_errors(tmp_path: Path) -> None:
    with pytest.raises(
        FileFormatError,
        match=r"unknown file extension '\.xyz': known extensions are .ts, .pl, "
        r".vs, .so, .lso, .gp, .ml, .vtu, .vtp, .vtk, .obj, .ply, .off, .stl",
    ):
        formats.read(tmp_path / "a.xyz")
    with pytest.raises(FileFormatError, match="unknown format 'dxf'"):
        formats.format_for(tmp_path / "a.ts", "dxf")
    lines = formats.read_one(DATA / "two_lines.pl")
    with pytest.raises(FileFormatError, match="tsurf files store SURFACE, not MULTILINESTRING"):
        formats.write(lines, tmp_path / "lines.ts")
    formats.write(lines, tmp_path / "lines.gocad", format="pline")
    assert formats.read_one(tmp_path / "lines.gocad", format="pl").same_as(lines)
    both = tmp_path / "both.ts"
    write_gocad_many([lines, lines], both)
    with pytest.raises(FileFormatError, match="expected one mesh, the file holds 2"):
        formats.read_one(both)
    assert set(formats.FORMATS) == {
        "tsurf",
        "pline",
        "vset",
        "tsolid",
        "lightsolid",
        "gocadgroup",
        "gocadmodel",
        "vtu",
        "vtp",
        "vtk",
        "obj",
        "ply",
        "off",
        "stl",
    }
