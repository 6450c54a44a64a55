"""Cutting a surface along paths: the three end cases, sides, geometry untouched, validation messages."""

from __future__ import annotations

import numpy as np
import pytest

from tests.interp_meshes import delaunay_disk, grid, vid
from tgsis.interpolation import (
    CutResult,
    InterpolationSetupError,
    border_edges,
    border_loops,
    check_disk,
    cut_along_paths,
    interior_vertices,
    shortest_edge_path,
)
from tgsis.mesh import Surface

NX, NY = 7, 6


def row(r: int, c0: int, c1: int) -> list[int]:
    """Grid vertices of row r from column c0 to c1 (either direction)."""
    step = 1 if c1 >= c0 else -1
    return [vid(NX, c, r) for c in range(c0, c1 + step, step)]


def wavy() -> Surface:
    s = grid(NX, NY, wavy=True)
    return Surface(
        s.vertices,
        s.triangles,
        vertex_properties={"depth": -s.vertices[:, 2]},
        cell_properties={"tag": np.arange(s.n_cells)},
        name="horizon",
    )


def check_cut_is_faithful(before: Surface, cut: CutResult) -> None:
    """Same triangles in the same order and orientation, every vertex exactly where its original is."""
    after, original = cut.surface, cut.original_vertex
    n = before.n_vertices
    assert original.dtype == np.int64 and np.array_equal(original[:n], np.arange(n))
    assert after.vertices.shape == (len(original), 3)
    assert np.array_equal(after.vertices.view(np.int64), before.vertices[original].view(np.int64))  # bit for bit
    assert np.array_equal(original[after.triangles], before.triangles)
    assert np.array_equal(after.vertex_properties["depth"], before.vertex_properties["depth"][original])
    assert np.array_equal(after.cell_properties["tag"], before.cell_properties["tag"])
    assert after.name == before.name
    # the error between before and after: every vertex of one is on the other
    assert set(map(tuple, after.vertices.tolist())) == set(map(tuple, before.vertices.tolist()))


def check_sides(before: Surface, cut: CutResult, path: list[int], duplicated: set[int]) -> None:
    """For a path along a grid row: triangles on its left keep the original vertices, those on its right use copies."""
    xy = before.vertices[:, :2]
    forward = xy[path[1], 0] > xy[path[0], 0]
    centroid_y = xy[before.triangles, 1].mean(axis=1)
    row_y = xy[path[0], 1]
    left = (centroid_y > row_y) if forward else (centroid_y < row_y)
    sides = {True: set(), False: set()}  # type: dict[bool, set[int]]
    for t, (new_tri, old_tri) in enumerate(zip(cut.surface.triangles.tolist(), before.triangles.tolist())):
        for new, old in zip(new_tri, old_tri):
            if old not in duplicated:
                assert new == old
            elif left[t]:
                assert new == old, (t, new_tri)
            else:
                assert new >= before.n_vertices and cut.original_vertex[new] == old, (t, new_tri)
                sides[False].add(new)
    assert len(sides[False]) == len(duplicated)  # one copy per duplicated vertex on the right


@pytest.mark.parametrize(
    ("path", "ends", "duplicated", "loops", "euler", "pieces"),
    [
        (row(2, 0, 6), "both_border", row(2, 0, 6), 2, 2, 2),  # a crack across the surface
        (row(2, 0, 3), "end_inside", row(2, 0, 2), 1, 1, 1),  # from the border, ending inside
        (row(2, 3, 0), "start_inside", row(2, 2, 0), 1, 1, 1),  # the same, walked the other way
        (row(2, 1, 5), "both_inside", row(2, 2, 4), 2, 0, 1),  # closed at both ends: a slit hole
    ],
)
def test_the_three_end_cases(
    path: list[int], ends: str, duplicated: list[int], loops: int, euler: int, pieces: int
) -> None:
    before = wavy()
    cut = cut_along_paths(before, [path])
    check_cut_is_faithful(before, cut)
    assert cut.ends == (ends,)
    assert cut.n_copies == len(duplicated)
    assert sorted(cut.original_vertex[before.n_vertices :].tolist()) == sorted(duplicated)
    report = check_disk(cut.surface)
    assert (report.n_border_loops, report.euler_characteristic, report.n_components) == (loops, euler, pieces)
    assert report.nonmanifold_vertices.size == 0 and report.nonmanifold_edges.size == 0
    assert report.inconsistent_edges.size == 0  # orientation preserved
    check_sides(before, cut, path, set(duplicated))
    # every path edge is now a border edge twice, once per side, run both ways
    back = cut.original_vertex[border_edges(cut.surface)]
    for a, b in zip(path[:-1], path[1:]):
        assert [tuple(e) for e in back.tolist()].count((a, b)) == 1
        assert [tuple(e) for e in back.tolist()].count((b, a)) == 1
    # a declared end case that matches is accepted
    same = cut_along_paths(before, [path], ends=[ends])  # type: ignore[list-item]
    assert np.array_equal(same.surface.triangles, cut.surface.triangles)


def test_end_inside_keeps_one_border_loop_through_the_crack() -> None:
    before = wavy()
    path = row(2, 0, 3)
    cut = cut_along_paths(before, [path])
    (loop,) = border_loops(cut.surface)
    walked = cut.original_vertex[loop].tolist()
    i = walked.index(vid(NX, 3, 2))  # the inner end is visited once, between the two lips
    lips = [walked[(i - k) % len(walked)] for k in (1, 2, 3)], [walked[(i + k) % len(walked)] for k in (1, 2, 3)]
    assert lips[0] == lips[1] == row(2, 2, 0)
    assert walked.count(vid(NX, 3, 2)) == 1


def test_crossing_cracks() -> None:
    before = wavy()
    across, down = row(2, 0, 6), [vid(NX, 3, r) for r in range(NY)]
    cut = cut_along_paths(before, [across, down], names=["east-west", "north-south"])
    check_cut_is_faithful(before, cut)
    centre = vid(NX, 3, 2)
    copies = cut.original_vertex[before.n_vertices :].tolist()
    assert copies.count(centre) == 3  # four fans meet there
    assert cut.n_copies == 6 + 5 + 3
    report = check_disk(cut.surface)
    assert report.n_components == 4 and report.nonmanifold_vertices.size == 0


def test_crack_along_a_shortest_path_on_an_irregular_mesh() -> None:
    s = delaunay_disk(200, seed=4)
    s = Surface(
        s.vertices,
        s.triangles,
        vertex_properties={"depth": s.vertices[:, 0]},
        cell_properties={"tag": np.zeros(s.n_cells)},
    )
    inner = interior_vertices(s)
    xy = s.vertices[inner, :2]
    a = int(inner[np.argmin(np.linalg.norm(xy - [-0.4, 0.0], axis=1))])
    b = int(inner[np.argmin(np.linalg.norm(xy - [0.4, 0.1], axis=1))])
    path = shortest_edge_path(s, a, b)
    assert len(path) >= 3
    cut = cut_along_paths(s, [path], names=["fault"])
    check_cut_is_faithful(s, cut)
    assert cut.ends == ("both_inside",) and cut.n_copies == len(path) - 2
    report = check_disk(cut.surface)
    assert (report.n_border_loops, report.euler_characteristic) == (2, 0)
    hole = [loop for loop in border_loops(cut.surface) if len(loop) == 2 * (len(path) - 1)]
    assert len(hole) == 1 and set(cut.original_vertex[hole[0]].tolist()) == set(path.tolist())


def test_no_path_changes_nothing() -> None:
    before = wavy()
    cut = cut_along_paths(before, [])
    assert cut.surface.same_as(before) and cut.surface is not before and cut.n_copies == 0


def test_only_the_triangles_around_the_path_matter() -> None:
    """A non-manifold fin far from the crack does not stop the cut, and is left as it is."""
    s = wavy()
    fin = [[vid(NX, 5, 4), vid(NX, 6, 4), s.n_vertices]]  # a third triangle on the edge (33, 34)
    before = Surface(
        np.vstack([s.vertices, [[5.5, 4.0, 1.0]]]),
        np.vstack([s.triangles, fin]),
        vertex_properties={"depth": np.append(s.vertex_properties["depth"], 0.0)},
        cell_properties={"tag": np.arange(s.n_cells + 1)},
        name="horizon",
    )
    assert check_disk(before).nonmanifold_edges.tolist() == [[33, 34]]
    cut = cut_along_paths(before, [row(2, 0, 3)])
    check_cut_is_faithful(before, cut)
    assert cut.n_copies == 3 and cut.surface.triangles[-1].tolist() == fin[0]
    assert check_disk(cut.surface).nonmanifold_edges.tolist() == [[33, 34]]


@pytest.mark.parametrize(
    ("paths", "kwargs", "message"),
    [
        (
            [[vid(NX, 0, 2), vid(NX, 2, 2)]],
            {},
            r"^cutting path 0 is not an edge path: vertices 14 and 16 "
            r"\(positions 0 and 1\) share no edge$",
        ),
        (
            [[14, 15, 22, 15]],
            {"names": ["F1"]},
            r"^cutting path 0 \('F1'\) passes twice through vertex 15 "
            r"\(positions 1 and 3\)$",
        ),
        (
            [[0, 1, 2]],
            {},
            r"^cutting path 0: edges \(0, 1\), \(1, 2\) \(from positions 0, 1\) are on the border "
            r"already: there is "
            r"nothing to cut$",
        ),
        (
            [[vid(NX, 1, 1), vid(NX, 1, 0), vid(NX, 2, 1)]],
            {},
            r"^cutting path 0 passes through border vertex 1 \(position 1\): only its end vertices may be on the border",
        ),
        (
            [row(2, 0, 6)],
            {"ends": ["both_inside"]},
            r"^cutting path 0 is declared 'both_inside', but its start vertex 14 is on the border and its end vertex 20 "
            r"is on the border \('both_border'\)$",
        ),
        (
            [row(2, 1, 3)],
            {"ends": ["end_inside"], "names": ["f"]},
            r"^cutting path 0 \('f'\) is declared 'end_inside', but its start vertex 15 is inside the surface and its end "
            r"vertex 17 is inside the surface \('both_inside'\)$",
        ),
        ([row(2, 0, 2)], {"ends": ["sideways"]}, r"cutting path 0: unknown end case 'sideways'"),
        (
            [row(2, 2, 3)],
            {},
            r"^cutting path 0 ends inside the surface at both ends but has only the 2 vertices 16 and "
            r"17: a crack closed at both ends needs a vertex between them$",
        ),
        (
            [row(2, 0, 3), [vid(NX, 2, 2), vid(NX, 3, 2), vid(NX, 3, 3)]],
            {"names": [None, "b"]},
            r"^cutting path 0 and cutting path 1 \('b'\) share the edge \(16, 17\): cutting paths may meet at vertices only$",
        ),
        ([[3, 99]], {}, r"^cutting path 0 refers to vertex 99 \(position 1\), but the mesh has 42 vertices$"),
        ([[3]], {}, r"^cutting path 0 has 1 vertex: a path needs at least 2$"),
        ([[3.0, 4.0]], {}, r"^cutting path 0 is not a sequence of vertex indices"),
    ],
)
def test_bad_cutting_paths_are_named(paths: list[list[int]], kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(InterpolationSetupError, match=message) as info:
        cut_along_paths(wavy(), paths, **kwargs)  # type: ignore[arg-type]
    assert len(info.value.problems) == 1


def test_all_bad_paths_are_reported_at_once() -> None:
    with pytest.raises(InterpolationSetupError) as info:
        cut_along_paths(wavy(), [row(2, 0, 3), [0, 1], [vid(NX, 0, 2), vid(NX, 2, 2)]], names=["ok", "edge", "gap"])
    lines = str(info.value).splitlines()
    assert lines[0] == "cutting paths: 2 problems"
    assert lines[1].startswith("- cutting path 1 ('edge'): edge (0, 1)")
    assert lines[2].startswith("- cutting path 2 ('gap') is not an edge path")


@pytest.mark.parametrize("seed", range(6))
def test_random_cracks_on_an_irregular_mesh(seed: int) -> None:
    """Shortest paths between random vertices, inner vertices off the border: each end case changes the topology
    as it should, and nothing moves."""
    s = delaunay_disk(150, seed=seed)
    s = Surface(
        s.vertices,
        s.triangles,
        vertex_properties={"depth": s.vertices[:, 2]},
        cell_properties={"tag": np.arange(s.n_cells)},
    )
    rng = np.random.default_rng(seed)
    border = border_loops(s)[0]
    inner = interior_vertices(s)
    a_border, b_border = border[0], border[len(border) // 2]
    cases = {
        "both_border": (a_border, b_border),
        "end_inside": (a_border, int(rng.choice(inner))),
        "start_inside": (int(rng.choice(inner)), b_border),
        "both_inside": tuple(int(v) for v in rng.choice(inner, 2, replace=False)),
    }
    expected = {
        "both_border": (0, 2, 2, 2),
        "end_inside": (1, 1, 1, 1),
        "start_inside": (1, 1, 1, 1),
        "both_inside": (2, 0, 2, 1),
    }  # (uncopied ends, Euler characteristic, border loops, pieces)
    for ends, (a, b) in cases.items():
        path = shortest_edge_path(s, a, b, avoid=border)
        if ends == "both_inside" and len(path) < 3:
            continue
        cut = cut_along_paths(s, [path], ends=[ends])  # type: ignore[list-item]
        check_cut_is_faithful(s, cut)
        kept, euler, loops, pieces = expected[ends]
        assert cut.n_copies == len(path) - kept
        report = check_disk(cut.surface)
        assert (report.euler_characteristic, report.n_border_loops, report.n_components) == (euler, loops, pieces)
        assert report.nonmanifold_vertices.size == 0 and report.inconsistent_edges.size == 0
