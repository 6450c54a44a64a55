"""Interpolation end to end: a salt-dome-like case, a fence splitting two patches, a cut; stored and read back."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from scipy.spatial import Delaunay

import tgsis
from tgsis.interpolation import InterpolationSetup, InterpolationSetupError, ParameterizationError, mesh_error
from tgsis.interpolation.interpolate import average_shape, interpolate
from tgsis.interpolation.setup import CutPath

Conn = psycopg.Connection[Any]


def _flat(nx: int, ny: int) -> tgsis.Surface:
    """A flat rectangle [0, 4] x [0, 2] as a regular grid; corners 0, nx-1, nx*ny-1, nx*(ny-1)."""
    u, v = np.meshgrid(np.linspace(0, 4, nx), np.linspace(0, 2, ny))
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        np.stack([u.ravel(), v.ravel(), np.zeros(u.size)], 1),
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        name="flat",
    )


def _dome(seed: int = 0) -> tuple[tgsis.Surface, list[int]]:
    """A dome over [0, 4] x [0, 2], Delaunay-triangulated from scattered points: another topology."""
    rng = np.random.default_rng(seed)
    corners = np.array([[0, 0], [4, 0], [4, 2], [0, 2]], dtype=float)
    sides = np.concatenate(
        [
            np.stack([np.linspace(0, 4, 13)[1:-1], np.zeros(11)], 1),
            np.stack([np.full(7, 4.0), np.linspace(0, 2, 9)[1:-1]], 1),
            np.stack([np.linspace(4, 0, 13)[1:-1], np.full(11, 2.0)], 1),
            np.stack([np.zeros(7), np.linspace(2, 0, 9)[1:-1]], 1),
        ]
    )
    inside = rng.random((150, 2)) * [3.8, 1.8] + 0.1
    xy = np.concatenate([corners, sides, inside])
    z = 0.8 * np.exp(-((xy[:, 0] - 2) ** 2 + (xy[:, 1] - 1) ** 2) / 0.5)
    tri = Delaunay(xy).simplices
    e1, e2 = xy[tri[:, 1]] - xy[tri[:, 0]], xy[tri[:, 2]] - xy[tri[:, 0]]
    normal_up = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] > 0
    tri[~normal_up] = tri[~normal_up][:, [0, 2, 1]]
    return tgsis.Surface(np.column_stack([xy, z]), tri, name="dome"), [0, 1, 2, 3]


def _flat_corners(nx: int, ny: int) -> list[int]:
    return [0, nx - 1, nx * ny - 1, nx * (ny - 1)]


def test_salt_dome_into_the_database_and_back(conn: Conn) -> None:
    source, (target, target_corners) = _flat(21, 11), _dome()
    setup = InterpolationSetup(tuple(_flat_corners(21, 11)), tuple(target_corners), steps=5, tolerance=0.05)
    result = interpolate(source, target, setup, -10.0, 0.0, name="dome")
    assert result.error <= 0.05
    # the ends: the source (refined, same shape) at t0, the compatible target at t1, on the target
    at0, at1 = result.evolving.at(-10.0), result.evolving.at(0.0)
    assert at0 is not None and at1 is not None
    assert np.array_equal(at0.vertices, result.source.vertices)
    assert np.array_equal(at1.vertices, result.target.vertices)
    assert np.abs(result.source.vertices[:, 2]).max() == 0.0  # refinement kept the plane
    assert mesh_error(result.target.vertices, result.target.cells, target.vertices, target.cells) <= 0.05
    assert set(result.timings) >= {"partition", "compatible", "trajectories"}
    # stored as model 3 and read back
    fc = tgsis.create_feature_class(conn, "domes", "SURFACE", time_model="EVOLVING", time_unit="Ma")
    fid = tgsis.insert_feature(conn, fc, result.evolving)
    conn.commit()
    middle = tgsis.get_at(conn, fid, -5.0)
    expected = result.evolving.at(-5.0)
    assert middle is not None and expected is not None
    assert np.array_equal(middle.vertices, expected.vertices)


def _stored_and_read_back(conn: Conn, evolving: tgsis.EvolvingSurface, times: list[float]) -> None:
    """Store as model 3, read the shape back at ``times``: bit-identical to EvolvingSurface.at."""
    fc = tgsis.create_feature_class(
        conn, f"interp_{len(times)}_{evolving.periods[0].triangles.shape[0]}", "SURFACE", time_model="EVOLVING"
    )
    fid = tgsis.insert_feature(conn, fc, evolving)
    conn.commit()
    for t in times:
        got, expected = tgsis.get_at(conn, fid, t), evolving.at(t)
        assert got is not None and expected is not None
        assert np.array_equal(got.vertices, expected.vertices) and np.array_equal(got.cells, expected.cells)


def test_a_fence_splits_the_surface_into_two_patches(conn: Conn) -> None:
    nx, ny = 21, 11
    source, (target, target_corners) = _flat(nx, ny), _dome(1)
    # controls: the four corners plus the middles of the long sides; the fence joins the two middles
    s_mid = [nx // 2, nx * (ny - 1) + nx // 2]
    t_mid = [int(np.argmin(np.linalg.norm(target.vertices[:, :2] - p, axis=1))) for p in ([2, 0], [2, 2])]
    s_fence = [s_mid[0] + nx * j for j in range(ny)]
    from tgsis.interpolation import shortest_edge_path

    t_fence = shortest_edge_path(target, t_mid[0], t_mid[1]).tolist()
    setup = InterpolationSetup(
        (0, s_mid[0], nx - 1, nx * ny - 1, s_mid[1], nx * (ny - 1)),
        (target_corners[0], t_mid[0], target_corners[1], target_corners[2], t_mid[1], target_corners[3]),
        source_fences=(tuple(s_fence),),
        target_fences=(tuple(t_fence),),
        fence_names=("middle",),
        steps=4,
        tolerance=0.1,
    )
    result = interpolate(source, target, setup, 0.0, 1.0)
    assert result.error <= 0.1
    # fence vertices go onto the target's fence path, and the two patches meet there (no gap)
    fence_targets = result.target.vertices[s_fence]
    fence_line = target.vertices[t_fence]
    gaps = np.min(np.linalg.norm(fence_targets[:, None, :2] - fence_line[None, :, :2], axis=2), axis=1)
    assert gaps.max() < 0.5
    assert result.source.n_vertices == result.target.n_vertices
    _stored_and_read_back(conn, result.evolving, [0.0, 0.4, 1.0])


def test_a_cut_opens_a_crack(conn: Conn) -> None:
    nx, ny = 21, 11
    source = _flat(nx, ny)
    # a crack from the middle of the bottom border up to the centre: ends inside at one end
    crack = [nx // 2 + nx * j for j in range(6)]
    target, corners = _dome(2)
    setup = InterpolationSetup(
        tuple(_flat_corners(nx, ny)), tuple(corners), cuts=(CutPath(tuple(crack), "crack"),), steps=3, tolerance=0.2
    )
    result = interpolate(source, target, setup, 0.0, 1.0)
    assert result.source.n_vertices > source.n_vertices  # the crack's vertices were duplicated
    assert np.allclose(result.source.vertices[source.n_vertices :, 2], 0.0)
    _stored_and_read_back(conn, result.evolving, [0.0, 0.5, 1.0])


def test_set_up_mistakes_name_what_is_wrong() -> None:
    source, (target, corners) = _flat(11, 6), _dome()
    with pytest.raises(InterpolationSetupError, match="two different finite times"):
        interpolate(source, target, InterpolationSetup((0, 10, 65, 55), tuple(corners)), 1.0, 1.0)
    with pytest.raises(InterpolationSetupError, match="control"):
        interpolate(source, target, InterpolationSetup((0, 10), tuple(corners[:2])), 0.0, 1.0)


def test_average_of_two_versions_is_the_middle_shape() -> None:
    source, (target, corners) = _flat(15, 8), _dome()
    setup = InterpolationSetup(tuple(_flat_corners(15, 8)), tuple(corners), steps=3, tolerance=0.1)
    middle = average_shape(source, target, setup)
    full = interpolate(source, target, setup, 0.0, 1.0)
    assert np.allclose(middle.vertices, 0.5 * (full.source.vertices + full.target.vertices))


def test_an_attached_border_stays_on_its_wall_read_from_the_set_up_file(tmp_path: Path) -> None:
    from tgsis import formats
    from tgsis.interpolation.setup import Attachment

    nx, ny = 17, 9
    source, (target, corners) = _flat(nx, ny), _dome(3)
    wall = tgsis.Surface([[0, -1, -5], [0, 3, -5], [0, 3, 5], [0, -1, 5]], [[0, 1, 2], [0, 2, 3]], name="west")
    formats.write(wall, tmp_path / "west.ts")
    west = [nx * j for j in range(ny)]  # the source's x = 0 border
    InterpolationSetup(
        tuple(_flat_corners(nx, ny)),
        tuple(corners),
        controlling_surfaces={"west": "west.ts"},
        attachments=tuple(Attachment(v, ("west",)) for v in west),
        steps=6,
        tolerance=0.2,
    ).save(tmp_path / "setup.json")
    setup = InterpolationSetup.load(tmp_path / "setup.json")  # the wall is read from beside the file
    result = interpolate(source, target, setup, 0.0, 1.0)
    assert np.abs(result.trajectories[:, west, 0]).max() <= 1e-9  # on the wall at every sample
    # the wall is a plane holding the attached vertices' straight paths: nothing moves them off those, so the
    # solved interior goes straight too (the design's convex combinations bent it away from them, issue 37)
    straight = result.trajectories[0] + 0.4 * (result.trajectories[-1] - result.trajectories[0])
    assert np.abs(result.evolving.at(0.4).vertices - straight).max() <= 1e-9  # type: ignore[union-attr]


def test_the_source_may_be_the_later_shape() -> None:
    """The dome (later, more complex) as the source at t = 1, the flat layer as the target at t = 0."""
    (source, source_corners), target = _dome(), _flat(21, 11)
    setup = InterpolationSetup(tuple(source_corners), tuple(_flat_corners(21, 11)), steps=5, tolerance=0.05)
    result = interpolate(source, target, setup, 1.0, 0.0, name="dome backwards")
    evolving = result.evolving
    assert (evolving.start, evolving.end) == (0.0, 1.0)
    at0, at1 = evolving.at(0.0), evolving.at(1.0)
    assert at0 is not None and at1 is not None
    assert np.array_equal(at1.vertices, result.source.vertices)  # the source at its own time, t0 = 1
    assert np.array_equal(at0.vertices, result.target.vertices)  # the compatible target at t1 = 0
    assert np.abs(at0.vertices[:, 2]).max() <= 0.05  # flat within the tolerance
    # the same samples as forwards, read in the other direction
    forwards = interpolate(source, target, setup, 0.0, 1.0)
    middle, forwards_middle = evolving.at(0.25), forwards.evolving.at(0.75)
    assert middle is not None and forwards_middle is not None
    assert np.allclose(middle.vertices, forwards_middle.vertices, atol=1e-9)


def test_the_source_and_target_times_must_differ() -> None:
    source, (target, corners) = _flat(21, 11), _dome()
    setup = InterpolationSetup(tuple(_flat_corners(21, 11)), tuple(corners), steps=5, tolerance=0.05)
    for t0, t1 in ((1.0, 1.0), (float("nan"), 1.0)):
        with pytest.raises(InterpolationSetupError, match="two different finite times"):
            interpolate(source, target, setup, t0, t1)


def test_vertex_properties_travel_with_the_vertices() -> None:
    """A property both meshes carry goes linearly from the source's value to the target's, along each trajectory."""
    flat, (dome, corners) = _flat(21, 11), _dome()
    source = tgsis.Surface(
        flat.vertices,
        flat.cells,
        vertex_properties={
            "age": np.zeros(flat.n_vertices),
            "xpos": flat.vertices[:, 0],
            "only_here": np.ones(flat.n_vertices),
        },
    )
    target = tgsis.Surface(
        dome.vertices,
        dome.cells,
        vertex_properties={"age": np.full(dome.n_vertices, 10.0), "xpos": dome.vertices[:, 0]},
    )
    setup = InterpolationSetup(tuple(_flat_corners(21, 11)), tuple(corners), steps=5, tolerance=0.05)
    result = interpolate(source, target, setup, 0.0, 1.0, alive=True)
    assert result.dropped_properties == ("only_here",) and result.evolving.alive
    period = result.evolving.periods[0]
    assert set(period.vertex_properties) == {"age", "xpos"}
    # a constant on each side: exactly 10 s at step s
    assert np.allclose(period.vertex_properties["age"], 10.0 * np.linspace(0, 1, 5)[:, None], atol=1e-12)
    # a linear field is reproduced exactly by the barycentric transfer: x at the source, x of the compatible target
    assert np.allclose(period.vertex_properties["xpos"][0], result.source.vertices[:, 0], atol=1e-9)
    assert np.allclose(period.vertex_properties["xpos"][-1], result.target.vertices[:, 0], atol=1e-6)
    # and backwards in time, the values run the other way
    back = interpolate(source, target, setup, 1.0, 0.0).evolving.periods[0]
    assert np.allclose(back.vertex_properties["age"], period.vertex_properties["age"][::-1])


def test_interpolate_takes_the_designs_centroid_refinement() -> None:
    """split="centroid" (the design's rule) reaches compatible_patch: 4 more vertices at ε = 0.05, and at ε = 0.02
    it stalls where the default edge bisection converges; an unknown rule is refused before any work."""
    source, (target, corners) = _flat(13, 7), _dome()
    loose = InterpolationSetup(tuple(_flat_corners(13, 7)), tuple(corners), steps=2, tolerance=0.05)
    auto = interpolate(source, target, loose, 0.0, 1.0)
    centroid = interpolate(source, target, loose, 0.0, 1.0, split="centroid")
    assert (auto.source.n_vertices, centroid.source.n_vertices) == (99, 103)
    assert centroid.error <= 0.05
    tight = InterpolationSetup(tuple(_flat_corners(13, 7)), tuple(corners), steps=2, tolerance=0.02)
    assert interpolate(source, target, tight, 0.0, 1.0, split="auto").error <= 0.02
    with pytest.raises(ParameterizationError, match="after 30 refinement rounds"):
        interpolate(source, target, tight, 0.0, 1.0, split="centroid")
    with pytest.raises(InterpolationSetupError, match="split 'middle' is not one of 'auto', 'centroid'"):
        interpolate(source, target, tight, 0.0, 1.0, split="middle")
