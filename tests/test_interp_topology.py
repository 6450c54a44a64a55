"""Mesh topology helpers of the interpolation set-up: edges, borders, one-rings, disks, edge paths."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from tests.interp_meshes import (
    annulus,
    brute_border,
    brute_edges,
    delaunay_disk,
    grid,
    grid_triangles,
    mobius,
    shuffled,
    signed_area,
    torus,
    vid,
)
from tgsis.errors import InvalidInputError
from tgsis.interpolation import (
    InterpolationSetupError,
    MeshTopology,
    border_edges,
    border_loops,
    border_vertices,
    check_disk,
    interior_vertices,
    mesh_edges,
    one_ring,
    one_rings,
    shortest_edge_path,
)
from tgsis.mesh import Surface


def test_error_is_invalid_input() -> None:
    assert issubclass(InterpolationSetupError, InvalidInputError)
    err = InterpolationSetupError("setup", problems=["first thing", "second thing"])
    assert err.problems == ("first thing", "second thing")
    assert str(err).splitlines() == ["setup: 2 problems", "- first thing", "- second thing"]
    assert InterpolationSetupError.collect("setup", ["only"]).message == "only"


@pytest.mark.parametrize(
    "surface",
    [grid(5, 4), annulus(), delaunay_disk(60), shuffled(grid(6, 5))[0], torus()],
    ids=["grid", "annulus", "delaunay", "shuffled", "torus"],
)
def test_edges_and_border_match_brute_force(surface: Surface) -> None:
    edges = mesh_edges(surface)
    assert edges.dtype == np.int64 and edges.shape[1] == 2
    assert (edges[:, 0] < edges[:, 1]).all()
    assert np.array_equal(edges, np.unique(edges, axis=0))  # sorted, no repeat
    assert set(map(tuple, edges.tolist())) == brute_edges(surface.triangles)
    assert set(map(tuple, border_edges(surface).tolist())) == brute_border(surface.triangles)
    in_border = np.unique(border_edges(surface))
    assert np.array_equal(border_vertices(surface), in_border)
    assert np.array_equal(
        np.union1d(border_vertices(surface), interior_vertices(surface)), np.arange(surface.n_vertices)
    )
    assert np.intersect1d(border_vertices(surface), interior_vertices(surface)).size == 0


def test_grid_edge_count_and_edge_lookup() -> None:
    nx_, ny = 5, 4
    topo = MeshTopology.of(grid(nx_, ny))
    assert len(topo.edges) == (nx_ - 1) * ny + nx_ * (ny - 1) + (nx_ - 1) * (ny - 1)
    assert (
        topo.find_edges(
            [[vid(nx_, 1, 1), vid(nx_, 2, 1)], [vid(nx_, 2, 2), vid(nx_, 1, 1)], [vid(nx_, 0, 0), vid(nx_, 2, 0)]]
        ).tolist()[2]
        == -1
    )
    found = topo.find_edges([[1, 0], [0, 1]])
    assert found[0] == found[1] >= 0 and topo.edges[found[0]].tolist() == [0, 1]
    assert (topo.edge_triangle_count[topo.is_border_edge] == 1).all()


def test_border_loop_of_a_grid_is_ordered_and_counter_clockwise() -> None:
    s = grid(4, 3)
    loops = border_loops(s)
    assert len(loops) == 1
    assert loops[0].tolist() == [0, 1, 2, 3, 7, 11, 10, 9, 8, 4]
    assert signed_area(s.vertices, loops[0]) > 0


def test_border_loops_follow_the_triangles() -> None:
    s = annulus(7, 6)
    loops = border_loops(s)
    assert len(loops) == 2
    directed = brute_border(s.triangles)
    for loop in loops:
        steps = set(zip(loop.tolist(), np.roll(loop, -1).tolist()))
        assert steps <= directed  # every step is a border edge run like its triangle
        assert loop[0] == loop.min()
    assert sum(len(loop) for loop in loops) == len(directed)
    areas = sorted(signed_area(s.vertices, loop) for loop in loops)
    assert areas[0] == pytest.approx(-1.0) and areas[1] == pytest.approx(30.0)  # hole turns the other way
    flipped = Surface(s.vertices, s.triangles[:, ::-1])
    assert [loop.tolist() for loop in border_loops(flipped)] == [np.roll(loop[::-1], 1).tolist() for loop in loops]


def test_long_border_loop() -> None:
    """A thin strip: one border loop through every vertex (pointer jumping over a long cycle)."""
    nx_ = 20000
    s, new_of_old = shuffled(grid(nx_, 2), seed=3)
    loops = border_loops(s)
    assert len(loops) == 1 and len(loops[0]) == 2 * nx_
    expected = np.concatenate([np.arange(nx_), np.arange(2 * nx_ - 1, nx_ - 1, -1)])
    loop = new_of_old[expected]
    start = int(np.flatnonzero(loop == loops[0][0])[0])
    assert np.array_equal(np.roll(loop, -start), loops[0])


def test_closed_surface_has_no_border() -> None:
    t = torus()
    assert border_loops(t) == [] and border_vertices(t).size == 0
    assert interior_vertices(t).size == t.n_vertices


def test_border_loops_refuse_a_pinched_border() -> None:
    bowtie = Surface([[0, 0, 0], [1, 0, 0], [1, 1, 0], [2, 1, 0], [2, 2, 0]], [[0, 1, 2], [2, 3, 4]])
    with pytest.raises(InterpolationSetupError, match=r"border passes more than once through vertex 2"):
        border_loops(bowtie)


def _check_rings(surface: Surface) -> None:
    rings = one_rings(surface)
    triangles = {tuple(np.roll(t, -int(np.argmin(t))).tolist()) for t in surface.triangles}
    on_border = np.zeros(surface.n_vertices, dtype=bool)
    on_border[border_vertices(surface)] = True
    successor = {a: b for a, b in border_edges(surface).tolist()}
    predecessor = {b: a for a, b in border_edges(surface).tolist()}
    assert rings.indptr[-1] == len(rings.neighbours)
    for v in range(surface.n_vertices):
        ring = rings.ring(v).tolist()
        fan = surface.triangles[(surface.triangles == v).any(axis=1)]
        neighbours = set(fan.ravel().tolist()) - {v}
        assert sorted(ring) == sorted(neighbours)  # every neighbour once
        assert rings.closed[v] == (not on_border[v])
        pairs = list(zip(ring, ring[1:] + ring[:1])) if rings.closed[v] else list(zip(ring, ring[1:]))
        assert len(pairs) == len(fan)
        for j, k in pairs:
            t = (v, j, k)
            assert tuple(np.roll(t, -int(np.argmin(t))).tolist()) in triangles  # turns like the triangles
        ring_tris = rings.ring_triangles(v)
        assert [set(surface.triangles[t].tolist()) for t in ring_tris] == [{v, j, k} for j, k in pairs]
        if on_border[v]:
            assert ring[0] == successor[v] and ring[-1] == predecessor[v]
        assert one_ring(surface, v).tolist() == ring


@pytest.mark.parametrize(
    "surface",
    [grid(5, 4), annulus(), delaunay_disk(80), shuffled(grid(6, 5), 2)[0], torus()],
    ids=["grid", "annulus", "delaunay", "shuffled", "torus"],
)
def test_one_rings_turn_like_the_triangles(surface: Surface) -> None:
    _check_rings(surface)


def test_one_rings_of_a_grid() -> None:
    s = grid(4, 4)
    rings = one_rings(s)
    assert rings.ring(5).tolist() == [0, 1, 6, 10, 9, 4]  # interior: from its lowest triangle, turning ccw
    assert rings.ring(1).tolist() == [2, 6, 5, 0]  # border: successor to predecessor
    assert rings.ring(3).tolist() == [7, 2]
    assert rings.degree.tolist()[:4] == [3, 4, 4, 2]
    assert rings.closed.tolist()[5] and not rings.closed.tolist()[1]


def test_one_rings_skip_unused_vertices() -> None:
    s = Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]], [[0, 1, 2]])
    rings = one_rings(s)
    assert rings.ring(3).size == 0 and not rings.closed[3]
    assert rings.ring(0).tolist() == [1, 2]


@pytest.mark.parametrize(
    ("surface", "message"),
    [
        (
            Surface([[0, 0, 0], [1, 0, 0], [1, 1, 0], [2, 1, 0], [2, 2, 0]], [[0, 1, 2], [2, 3, 4]]),
            r"around vertex 2 form several fans",
        ),
        (
            Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], [[0, 1, 2], [1, 0, 3], [0, 1, 4]]),
            r"edges \(0, 1\) are on more than 2 triangles",
        ),
        (mobius(), r"oriented inconsistently"),
    ],
)
def test_one_rings_refuse_non_manifold_meshes(surface: Surface, message: str) -> None:
    with pytest.raises(InterpolationSetupError, match=message):
        one_rings(surface)


def test_one_rings_refuse_a_double_cone_vertex() -> None:
    """Two closed fans around one vertex (two cones touching at their tips): no ring is defined."""

    def cone(offset: int, apex: int, k: int) -> list[list[int]]:
        return [[apex, offset + i, offset + (i + 1) % k] for i in range(k)]

    k = 5
    vertices = np.zeros((1 + 2 * k, 3))
    vertices[1:] = np.random.default_rng(0).normal(size=(2 * k, 3))
    s = Surface(vertices, cone(1, 0, k) + cone(1 + k, 0, k))
    with pytest.raises(InterpolationSetupError, match=r"around vertex 0 form several fans"):
        one_rings(s)
    assert check_disk(s).nonmanifold_vertices.tolist() == [0]


def test_shortest_edge_path_is_edge_length_weighted() -> None:
    s = grid(6, 5, wavy=True)
    start, end = vid(6, 0, 0), vid(6, 5, 4)
    path = shortest_edge_path(s, start, end)
    assert path[0] == start and path[-1] == end and path.dtype == np.int64
    topo = MeshTopology.of(s)
    assert (topo.find_edges(np.stack([path[:-1], path[1:]], 1)) >= 0).all()
    length = float(np.linalg.norm(np.diff(s.vertices[path], axis=0), axis=1).sum())
    g = nx.Graph()
    for a, b in topo.edges.tolist():
        g.add_edge(a, b, weight=float(np.linalg.norm(s.vertices[a] - s.vertices[b])))
    assert length == pytest.approx(nx.shortest_path_length(g, start, end, weight="weight"))
    # hop count would prefer any staircase; edge lengths prefer the diagonals
    flat = grid(6, 6)
    assert shortest_edge_path(flat, 0, 35).tolist() == [0, 7, 14, 21, 28, 35]
    assert shortest_edge_path(flat, 3, 3).tolist() == [3]


def test_shortest_edge_path_avoids_vertices() -> None:
    flat = grid(6, 6)
    path = shortest_edge_path(flat, 0, 35, avoid=[14, 0, 35])
    assert 14 not in path.tolist() and path[0] == 0 and path[-1] == 35
    with pytest.raises(
        InterpolationSetupError, match=r"no edge path from vertex 0 to vertex 35 avoiding vertices 1, 6, 7"
    ):
        shortest_edge_path(flat, 0, 35, avoid=[1, 6, 7])
    with pytest.raises(InterpolationSetupError, match=r"start vertex 99 is not in the mesh"):
        shortest_edge_path(flat, 99, 3)
    with pytest.raises(InterpolationSetupError, match=r"needs vertex coordinates"):
        shortest_edge_path(MeshTopology(flat.triangles), 0, 3)


def test_a_grid_is_a_disk() -> None:
    for surface in (grid(5, 4), delaunay_disk(50), shuffled(grid(7, 3))[0]):
        report = check_disk(surface)
        assert report.ok, report.reasons
        assert report.euler_characteristic == 1 and report.n_border_loops == 1 and report.n_components == 1
        assert report.summary() == "a disk"


def _torus_minus_triangle() -> Surface:
    t = torus()
    return Surface(t.vertices, t.triangles[1:])


@pytest.mark.parametrize(
    ("surface", "reasons"),
    [
        (annulus(), ["2 border loops", "Euler characteristic V - E + F = 36 - 84 + 48 = 0, not 1"]),
        (
            Surface(grid(3, 3).vertices, np.concatenate([grid_triangles(3, 3)[:1], grid_triangles(3, 3)[6:7]])),
            [
                "it is in 2 pieces",
                "2 border loops",
                "Euler characteristic V - E + F = 6 - 6 + 2 = 2, not 1",
                "3 vertices on no triangle: 2, 5, 8",
            ],
        ),
        (
            Surface([[0, 0, 0], [1, 0, 0], [1, 1, 0], [2, 1, 0], [2, 2, 0]], [[0, 1, 2], [2, 3, 4]]),
            ["it is in 2 pieces", "1 non-manifold vertex (whose triangles form separate fans): 2"],
        ),  # bowtie
        (
            Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], [[0, 1, 2], [1, 0, 3], [0, 1, 4]]),
            ["1 edge on more than 2 triangles: (0, 1) (on 3 triangles)"],
        ),
        (
            Surface(
                grid(3, 3).vertices,
                np.concatenate([grid_triangles(3, 3)[:3], grid_triangles(3, 3)[3:4, ::-1], grid_triangles(3, 3)[4:]]),
            ),
            ["the triangles on 2 edges are oriented inconsistently (both run the edge the same way): (4, 5), (4, 8)"],
        ),
        (mobius(), ["oriented inconsistently", "Euler characteristic V - E + F = 16 - 32 + 16 = 0, not 1"]),
        (torus(), ["it has no border (a closed surface)", "Euler characteristic V - E + F = 30 - 90 + 60 = 0, not 1"]),
        (
            _torus_minus_triangle(),
            ["Euler characteristic V - E + F = 30 - 90 + 59 = -1, not 1 (genus 1: the surface has handles)"],
        ),
        (Surface(np.zeros((3, 3)), np.empty((0, 3))), ["it has no triangle"]),
    ],
)
def test_not_a_disk_says_why(surface: Surface, reasons: list[str]) -> None:
    report = check_disk(surface)
    assert not report.ok
    for expected in reasons:
        assert any(expected in r for r in report.reasons), (expected, report.reasons)
    assert len(report.reasons) == len(reasons), report.reasons


def test_disk_check_facts() -> None:
    report = check_disk(mobius())
    assert report.inconsistent_edges.tolist() == [[0, 8]]
    assert report.n_border_loops == 1 and report.n_components == 1
    report = check_disk(
        Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    )
    assert report.nonmanifold_edges.tolist() == [[0, 1]]
