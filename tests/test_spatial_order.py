"""The spatial order of ids at upload (issue 40, part 1): tgsis.mesh.spatial_order, insert_feature(order=...),
tgsis import --order.

A renumbered surface must stay the same surface: the same triangles as triples of vertex positions (with
their orientation), the same property values at the same positions, the same parts, atoms and metadata
facts, only numbered otherwise.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis import formats, gmaps
from tgsis.cli import main
from tgsis.db import features as F
from tgsis.errors import InvalidGeometryError, InvalidInputError
from tgsis.mesh import GeometryCollection, LineSet, Mesh, PointSet, Surface, TetraMesh, morton_codes, spatial_order
from tgsis.temporal import EvolvingSurface, SurfaceSeries, TopologyPeriod

Conn = psycopg.Connection[Any]
DATA = Path(__file__).resolve().parent / "data" / "gocad"


def curved(side: int = 40, seed: int = 5) -> Surface:
    """A curved, irregular surface in file (row-major) order, with a vertex and a cell property, two parts."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.linspace(0, 1, side), np.linspace(0, 1, side))
    u = u + rng.uniform(-0.004, 0.004, u.shape)
    x, y = np.cos(3 * u) * (2 + v), np.sin(3 * u) * (2 + v)  # a rolled sheet
    z = np.sin(5 * v) + 0.1 * u
    grid = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    n = len(grid)
    vertices = np.concatenate([grid, grid[[1, 3]]])  # vertices n, n + 1: GOCAD ATOMs of vertices 1 and 3
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    cells = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    cells[cells == 1] = n  # the cells of vertex 1 and 3 use their atoms (a cut along a line, as GOCAD does)
    cells[cells == 3] = n + 1
    part = (np.sort(cells, axis=1)[:, 0] % side >= side // 2).astype(np.int64)  # two halves, interleaved in file order
    order = np.argsort(part, kind="stable")  # parts as runs, as GOCAD files have them
    return Surface(
        vertices,
        cells[order],
        vertex_properties={"porosity": rng.random(len(vertices)), "vel": rng.random((len(vertices), 2))},
        cell_properties={"part": part[order], "facies": rng.integers(0, 9, len(cells))},
        name="rolled",
        metadata={
            "gocad_atoms": [[n, 1], [n + 1, 3]],
            "gocad_patoms": [n + 1],
            "gocad_vertex_flags": {"CNXYZ": [[0, 3], [10, 12]]},
            "gocad_property_control_nodes": {"Porosity": [2, 11, 40]},
            "zpositive": "Depth",
            "gocad_part_names": ["left", "right"],
        },
    )


def bits(a: np.ndarray) -> Any:
    return tuple(np.ascontiguousarray(a, dtype=np.float64).view(np.int64).ravel().tolist())


def cells_as_positions(mesh: Mesh) -> Counter[tuple[Any, ...]]:
    """Each cell as the bit patterns of its corners' positions, in corner order (orientation kept), with its
    cell property values."""
    props = [np.asarray(v).reshape(len(mesh.cells), -1) for _, v in sorted(mesh.cell_properties.items())]
    return Counter(
        (*(bits(mesh.vertices[i]) for i in cell), *(tuple(p[k].tolist()) for p in props))
        for k, cell in enumerate(mesh.cells)
    )


def vertices_as_positions(mesh: Mesh) -> Counter[tuple[Any, ...]]:
    props = [np.asarray(v).reshape(mesh.n_vertices, -1) for _, v in sorted(mesh.vertex_properties.items())]
    return Counter((bits(mesh.vertices[i]), *(bits(p[i]) for p in props)) for i in range(mesh.n_vertices))


def assert_same_surface(a: Mesh, b: Mesh) -> None:
    assert type(a) is type(b) and a.n_vertices == b.n_vertices and a.n_cells == b.n_cells
    assert vertices_as_positions(a) == vertices_as_positions(b)
    assert cells_as_positions(a) == cells_as_positions(b)


def chunks_touched(mesh: Mesh, center: np.ndarray, count: int) -> int:
    """The chunks of 1,024 vertex ids holding the ``count`` vertices nearest ``center``."""
    near = np.argsort(np.linalg.norm(mesh.vertices - center, axis=1), kind="stable")[:count]
    return len(np.unique(near >> 10))


# ------------------------------------------------------------------------------------------------ pure


def test_the_same_surface_renumbered() -> None:
    mesh = curved()
    ordered = spatial_order(mesh)
    assert_same_surface(mesh, ordered)
    assert not np.array_equal(ordered.vertices, mesh.vertices)  # renumbered indeed
    assert ordered.metadata["vertex_order"] == "spatial" and "vertex_order" not in mesh.metadata
    assert np.all(np.diff(morton_codes(ordered.vertices).astype(np.float64)) >= 0)  # along the curve


def test_deterministic_with_ties_by_index() -> None:
    mesh = curved()
    one, two = spatial_order(mesh), spatial_order(mesh.copy())
    assert one.same_as(two) and one.metadata == two.metadata
    again = spatial_order(one)  # idempotent: an ordered mesh stays as it is
    assert again.same_as(one) and again.metadata == one.metadata
    # equal positions (an atom and its vertex, a duplicate) keep their order: the lower index first
    pairs = [[a, r] for a, r in one.metadata["gocad_atoms"]]
    for atom, ref in pairs:
        assert bits(one.vertices[atom]) == bits(one.vertices[ref]) and ref < atom  # the vertex first, as in the file
    tied = PointSet(np.zeros((5, 3)), vertex_properties={"v": np.arange(5.0)})
    assert spatial_order(tied).vertex_properties["v"].tolist() == [0, 1, 2, 3, 4]


def test_parts_stay_runs_in_part_order() -> None:
    ordered = spatial_order(curved())
    part = ordered.cell_properties["part"]
    assert part.tolist() == sorted(part.tolist())  # one run per part, in part order
    # inside a part, cells by their smallest corner
    for p in (0, 1):
        smallest = ordered.cells[part == p].min(axis=1)
        assert np.all(np.diff(smallest) >= 0)


def test_metadata_vertex_indices_follow_their_vertices() -> None:
    mesh = curved()
    ordered = spatial_order(mesh)
    n = mesh.n_vertices - 2
    porosity = ordered.vertex_properties["porosity"]
    assert len(set(porosity.tolist())) == mesh.n_vertices  # a vertex is known by its porosity

    def new(i: int) -> int:
        hits = np.flatnonzero(porosity == mesh.vertex_properties["porosity"][i])
        assert len(hits) == 1
        return int(hits[0])

    assert ordered.metadata["gocad_atoms"] == sorted([[new(n), new(1)], [new(n + 1), new(3)]])
    assert ordered.metadata["gocad_patoms"] == [new(n + 1)]
    flagged = sorted(new(i) for i in (0, 1, 2, 10, 11))
    ranges = ordered.metadata["gocad_vertex_flags"]["CNXYZ"]
    assert sorted(i for a, b in ranges for i in range(a, b)) == flagged
    assert all(a < b for a, b in ranges)
    assert ordered.metadata["gocad_property_control_nodes"] == {"Porosity": sorted([new(2), new(11), new(40)])}
    assert ordered.metadata["gocad_part_names"] == ["left", "right"] and ordered.metadata["zpositive"] == "Depth"


def test_metadata_that_is_not_vertex_indices_is_refused() -> None:
    mesh = curved(6)
    mesh.metadata["gocad_atoms"] = [[5, 99]]
    with pytest.raises(InvalidGeometryError, match="gocad_atoms"):
        spatial_order(mesh)
    mesh = curved(6)
    for ranges in ([[4, 2]], [[0, 1, 2]], [["a", 2]]):
        mesh.metadata["gocad_vertex_flags"] = {"CNXYZ": ranges}
        with pytest.raises(InvalidGeometryError, match="gocad_vertex_flags"):
            spatial_order(mesh)


def test_spatial_order_keeps_regions_in_few_chunks() -> None:
    mesh = curved(side=120)
    rng = np.random.default_rng(2)
    ordered = spatial_order(mesh)
    centers = mesh.vertices[rng.choice(mesh.n_vertices, 8)]
    file_chunks = sum(chunks_touched(mesh, c, 1000) for c in centers)
    spatial_chunks = sum(chunks_touched(ordered, c, 1000) for c in centers)
    assert spatial_chunks < file_chunks


def test_every_mesh_type_and_collections() -> None:
    rng = np.random.default_rng(9)
    points = rng.random((50, 3))
    meshes: list[Mesh] = [
        PointSet(points, vertex_properties={"a": rng.random(50)}),
        LineSet(points, np.stack([np.arange(49), np.arange(1, 50)], 1)),
        TetraMesh(points[:5], [[0, 1, 2, 3], [1, 2, 3, 4]], cell_properties={"d": [1.0, 2.0]}),
        Surface(np.empty((0, 3)), np.empty((0, 3), dtype=np.int64)),
    ]
    for mesh in meshes:
        assert_same_surface(mesh, spatial_order(mesh))
    collection = GeometryCollection(meshes[:3], name="block")
    ordered = spatial_order(collection)
    assert isinstance(ordered, GeometryCollection) and ordered.metadata["vertex_order"] == "spatial"
    for a, b in zip(collection.members, ordered.members):
        assert_same_surface(a, b)
        assert b.metadata["vertex_order"] == "spatial"
    assert np.array_equal(ordered.members[0].cells.ravel(), np.arange(50))  # one point per vertex, in order


def test_morton_codes_one_scale_and_huge_coordinates() -> None:
    # one scale: a box 1000 long in x and 1 in y does not stretch y to the full 21 bits
    codes = morton_codes([[0, 0, 0], [1000, 0, 0], [0, 1, 0]])
    y = sum(((int(codes[2]) >> (3 * i + 1)) & 1) << i for i in range(21))
    assert y == int((2**21 - 1) / 1000) and int(codes[2]) & 0b101101101101 == 0  # 1/1000 of the range, x = z = 0
    assert int(morton_codes([[0, 0, 0], [1, 1, 1]])[1]) == 2**63 - 1  # the far corner: every bit
    huge = morton_codes([[-1e308, 0, 0], [1e308, 1e308, -1e308]])
    assert huge.dtype == np.uint64 and len(set(huge.tolist())) == 2


# ------------------------------------------------------------------------------------------------ server


@pytest.fixture
def rolled(conn: Conn) -> F.FeatureClass:
    fc = F.create_feature_class(
        conn, "rolled", "SURFACE", cell_properties=[("porosity", "float8"), ("vel", "float8", 2)]
    )
    conn.commit()
    return fc


def test_insert_feature_spatial_stores_the_new_order(conn: Conn, rolled: F.FeatureClass) -> None:
    mesh = curved()
    mesh.cell_properties = {"part": mesh.cell_properties["part"]}  # the class stores vertex properties
    file_id = F.insert_feature(conn, rolled, mesh)
    spatial_id = F.insert_feature(conn, rolled, mesh, order="spatial")
    conn.commit()
    stored_file = F.fetch_feature(conn, rolled, file_id).mesh
    stored_spatial = F.fetch_feature(conn, rolled, spatial_id).mesh
    assert isinstance(stored_file, Surface) and isinstance(stored_spatial, Surface)
    expected = spatial_order(mesh)
    assert stored_spatial.same_as(expected)  # ids as spatial_order numbers them, properties and parts with them
    assert np.array_equal(stored_file.vertices.view(np.int64), mesh.vertices.view(np.int64))  # default: unchanged
    assert_same_surface(stored_file, stored_spatial)
    assert stored_spatial.metadata["vertex_order"] == "spatial" and "vertex_order" not in stored_file.metadata
    assert stored_spatial.metadata["gocad_atoms"] == expected.metadata["gocad_atoms"]
    atoms = conn.execute("SELECT vrtxid, refid FROM tgsis.atom WHERE geoid = %s ORDER BY 1", (spatial_id,)).fetchall()
    assert [list(r) for r in atoms] == expected.metadata["gocad_atoms"]
    row = conn.execute("SELECT metadata->>'vertex_order' FROM tgsis.geometry WHERE geoid = %s", (spatial_id,))
    assert row.fetchone() == ("spatial",)


def test_insert_feature_spatial_collection(conn: Conn) -> None:
    fc = F.create_feature_class(conn, "blocks", "GEOMETRYCOLLECTION")
    rng = np.random.default_rng(1)
    collection = GeometryCollection([PointSet(rng.random((30, 3))), curved(8)], name="block", metadata={"note": "kept"})
    collection.members[1].vertex_properties = {}
    collection.members[1].cell_properties = {"part": collection.members[1].cell_properties["part"]}
    fid = F.insert_feature(conn, fc, collection, order="spatial")
    conn.commit()
    stored = F.fetch_feature(conn, fc, fid).mesh
    assert isinstance(stored, GeometryCollection)
    for original, member in zip(collection.members, stored.members):
        assert member.same_as(spatial_order(original))
        assert member.metadata["vertex_order"] == "spatial"
    orders = conn.execute(
        "SELECT count(*) FROM tgsis.geometry WHERE collection = %s AND metadata->>'vertex_order' = 'spatial'", (fid,)
    ).fetchone()
    assert orders == (2,)


def test_order_refused_by_name(conn: Conn, rolled: F.FeatureClass) -> None:
    mesh = curved(5)
    mesh.cell_properties = {}
    with pytest.raises(InvalidInputError, match="'morton' is not one of 'file', 'spatial'"):
        F.insert_feature(conn, rolled, mesh, order="morton")
    series_fc = F.create_feature_class(conn, "tops", "SURFACE", time_model="INSTANTS", cell_properties=[])
    series = SurfaceSeries([1.0, 2.0], [mesh, mesh])
    with pytest.raises(InvalidInputError, match=r"model 2 \(.*\).*keep their order"):
        F.insert_feature(conn, series_fc, series, order="spatial")
    evolving_fc = F.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING", cell_properties=[])
    positions = np.stack([mesh.vertices, mesh.vertices + 1.0])
    evolving = EvolvingSurface([TopologyPeriod([0.0, 1.0], mesh.cells, positions)])
    with pytest.raises(InvalidInputError, match=r"EvolvingSurface as model 3 "):
        F.insert_feature(conn, evolving_fc, evolving, order="spatial")
    gmap_fc = F.create_feature_class(conn, "solids", "GMAP", time_model="MULTIDIM", cell_level=3)
    solid = gmaps.GMap.from_tetrahedra(mesh.vertices[:5], [[0, 1, 2, 3], [1, 2, 3, 4]])
    with pytest.raises(InvalidInputError, match=r"GMap as model 5 "):
        F.insert_feature(conn, gmap_fc, solid, order="spatial")
    conn.rollback()
    assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == (0,)


# ------------------------------------------------------------------------------------------------ the command


def test_import_order_option(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    mesh = curved(12)
    mesh.vertex_properties = {}
    mesh.cell_properties = {"part": mesh.cell_properties["part"]}
    mesh.metadata = {k: v for k, v in mesh.metadata.items() if k in ("gocad_atoms", "gocad_part_names")}
    path = tmp_path / "rolled.ts"
    formats.write(mesh, path)
    assert main(["--dsn", db_dsn, "class", "create", "faults", "--geotype", "SURFACE"]) == 0
    for order in ("file", "spatial"):
        assert main(["--dsn", db_dsn, "import", str(path), "--class", "faults", "--order", order, "--name", order]) == 0
    capsys.readouterr()
    with psycopg.connect(db_dsn) as conn:
        ids: dict[str, int] = dict(conn.execute("SELECT geoname, geoid FROM tgsis.geometry").fetchall())
        fetched: dict[str, Any] = {name: F.fetch_feature(conn, "faults", geoid).mesh for name, geoid in ids.items()}
    read = formats.read(path)[0]
    assert fetched["file"].same_as(read)
    assert fetched["spatial"].same_as(spatial_order(read))
    assert fetched["spatial"].metadata["vertex_order"] == "spatial"
    # --replace writes by difference, keeping the stored ids: it cannot renumber, so it refuses the spatial order
    args = ["import", str(path), "--class", "faults", "--name", "file", "--replace", "--order", "spatial"]
    assert main(["--dsn", db_dsn, *args]) == 1
    assert "--order spatial does not go with --replace" in capsys.readouterr().err
    # a replace of the spatially ordered feature by its file keeps its ids, so it keeps saying they are spatial
    moved = read.vertices.copy()
    moved[3] += 1.5
    edited = type(read)(moved, read.cells, cell_properties=read.cell_properties, metadata=read.metadata)
    formats.write(edited, path)
    args = ["import", str(path), "--class", "faults", "--name", "spatial", "--replace"]
    assert main(["--dsn", db_dsn, *args]) == 0
    with psycopg.connect(db_dsn) as conn:
        replaced = F.fetch_feature(conn, "faults", ids["spatial"]).mesh
    assert isinstance(replaced, tgsis.Surface)
    assert replaced.metadata["vertex_order"] == "spatial"
    assert sorted(map(tuple, replaced.vertices.tolist())) == sorted(map(tuple, edited.vertices.tolist()))
    # refused: a model-2 instant, and an unknown order (argparse)
    assert main(["--dsn", db_dsn, "class", "create", "tops", "--geotype", "SURFACE", "--time-model", "INSTANTS"]) == 0
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "import", str(path), "--class", "tops", "--at", "1", "--order", "spatial"]) == 1
    assert "--order spatial renumbers static features only" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--dsn", db_dsn, "import", str(path), "--class", "faults", "--order", "morton"])
