"""Parameterisation onto the regular polygon, point location, compatible meshes (no database).

The spec's checks (shared/spec/interpolation.md, "Checks that say it is
right"): linear reproduction, bijectivity, compatible vertices on the target
and the error at most ε after refinement.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from tgsis.errors import InvalidInputError
from tgsis.interpolation.parameterize import (
    ParameterizationError,
    PointLocator,
    border_loop,
    compatible_patch,
    mean_value_embedding,
    mean_value_weights,
    mesh_error,
    parameterize_patch,
    polygon_corners,
)
from tgsis.interpolation.projection import closest_on_triangles, closest_points


def grid(k: int, size: float = 1.0) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """A flat k x k vertex grid on [0, size]^2 at z = 0, counter-clockwise triangles, its 4 corners."""
    x, y = np.meshgrid(np.linspace(0, size, k), np.linspace(0, size, k))
    vertices = np.c_[x.ravel(), y.ravel(), np.zeros(k * k)]
    index = np.arange(k * k).reshape(k, k)
    a, b, c, d = index[:-1, :-1].ravel(), index[:-1, 1:].ravel(), index[1:, 1:].ravel(), index[1:, :-1].ravel()
    triangles = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    return vertices, triangles, [0, k - 1, k * k - 1, k * k - k]


def ccw(xy: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    e1, e2 = xy[triangles[:, 1]] - xy[triangles[:, 0]], xy[triangles[:, 2]] - xy[triangles[:, 0]]
    area = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    out = triangles.copy()
    out[area < 0] = out[area < 0][:, ::-1]
    return out


def signed_areas(uv: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    e1, e2 = uv[triangles[:, 1]] - uv[triangles[:, 0]], uv[triangles[:, 2]] - uv[triangles[:, 0]]
    return np.asarray(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def random_disk(n: int, seed: int, bump: float = 0.3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Delaunay-triangulated random points in the unit disk (a rim of evenly spaced points), bumpy in z."""
    rng = np.random.default_rng(seed)
    rim = max(12, int(3 * np.sqrt(n)))
    angle = 2 * np.pi * np.sort(rng.random(rim))
    r = np.sqrt(rng.random(n - rim)) * 0.97
    theta = 2 * np.pi * rng.random(n - rim)
    xy = np.r_[np.c_[np.cos(angle), np.sin(angle)], np.c_[r * np.cos(theta), r * np.sin(theta)]]
    triangles = ccw(xy, Delaunay(xy).simplices.astype(np.int64))
    phase = rng.random(3) * 6
    z = bump * (
        np.sin(4 * xy[:, 0] + phase[0]) * np.cos(3 * xy[:, 1] + phase[1])
        + 0.5 * np.sin(9 * xy[:, 0] * xy[:, 1] + phase[2])
    )
    return np.c_[xy, z], triangles, np.arange(rim)


def test_polygon_corners_are_the_unit_regular_polygon() -> None:
    corners = polygon_corners(5)
    assert np.allclose(corners[0], [1, 0]) and np.allclose(np.linalg.norm(corners, axis=1), 1)
    assert np.allclose(corners[1], [np.cos(2 * np.pi / 5), np.sin(2 * np.pi / 5)])


def test_mean_value_weights_rows_are_convex_and_reproduce_planar_vertices() -> None:
    vertices, triangles, _ = random_disk(300, 1, bump=0.0)
    weights = mean_value_weights(vertices, triangles).tocsr()
    assert np.all(weights.data > 0)
    assert np.allclose(np.asarray(weights.sum(axis=1)).ravel(), 1.0)
    interior = np.setdiff1d(np.arange(len(vertices)), border_loop(triangles))
    # mean value coordinates reproduce the centre from its planar 1-ring
    assert np.abs((weights @ vertices)[interior] - vertices[interior]).max() < 1e-12


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_linear_reproduction(seed: int) -> None:
    """A planar patch with its border placed by an affine map gets that affine map everywhere."""
    rng = np.random.default_rng(seed)
    vertices, triangles, rim = random_disk(400, seed, bump=0.0)
    # put the plane anywhere in space: random rotation, scale and shift
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    placed = 3.7 * vertices @ q.T + rng.normal(size=3)
    affine, shift = rng.normal(size=(3, 2)), rng.normal(size=2)
    expected = placed @ affine + shift
    border = border_loop(triangles)
    got = mean_value_embedding(placed, triangles, border, expected[border])
    assert np.abs(got - expected).max() < 1e-10


def test_linear_reproduction_of_a_square_onto_the_square_polygon() -> None:
    """parameterize itself: a flat square with its 4 corners as controls maps affinely onto the 4-polygon."""
    vertices, triangles, corners = grid(15, size=2.0)
    result = parameterize_patch(vertices, triangles, corners)
    # (0,0)->(1,0), (2,0)->(0,1), (2,2)->(-1,0), (0,2)->(0,-1)
    expected = np.array([1.0, 0.0]) + vertices[:, :2] @ np.array([[-0.5, 0.5], [-0.5, -0.5]])
    assert np.abs(result.uv - expected).max() < 1e-10
    assert result.orientation == 1


@pytest.mark.parametrize("seed,k", [(3, 3), (4, 4), (5, 5), (6, 7)])
def test_bijective_on_random_bumpy_disks(seed: int, k: int) -> None:
    vertices, triangles, rim = random_disk(1500, seed, bump=0.5)
    controls = rim[np.linspace(0, len(rim), k, endpoint=False).astype(int)]
    result = parameterize_patch(vertices, triangles, controls)
    areas = signed_areas(result.uv, triangles) * result.orientation
    assert areas.min() > 0, f"{np.sum(areas <= 0)} parameter triangles flipped"
    assert np.isclose(areas.sum() / 2, k / 2 * np.sin(2 * np.pi / k))  # they tile the polygon
    assert np.array_equal(result.uv[controls], polygon_corners(k))
    # border vertices on the polygon's sides, in order: angle increases along the border
    angles = np.unwrap(np.arctan2(result.uv[result.border, 1], result.uv[result.border, 0]))
    assert np.all(np.diff(angles) > 0)


def test_controls_against_the_orientation_give_a_mirrored_but_bijective_map() -> None:
    vertices, triangles, rim = random_disk(500, 8)
    controls = rim[[0, len(rim) // 3, 2 * len(rim) // 3]][::-1]
    result = parameterize_patch(vertices, triangles, controls)
    assert result.orientation == -1
    assert np.all(signed_areas(result.uv, triangles) < 0)


def test_chord_length_border() -> None:
    """Border vertices between two controls sit at their relative arc length along the polygon side."""
    vertices, triangles, corners = grid(6)
    vertices[1:5, 0] = [0.1, 0.2, 0.5, 0.9]  # uneven spacing along the first side
    result = parameterize_patch(vertices, triangles, corners)
    side = result.uv[:6]
    s = np.array([0, 0.1, 0.2, 0.5, 0.9, 1.0])
    assert np.abs(side - (np.array([1, 0]) + s[:, None] * np.array([-1, 1]))).max() < 1e-15


def test_set_up_errors() -> None:
    vertices, triangles, corners = grid(6)
    with pytest.raises(ParameterizationError, match="at least 3"):
        parameterize_patch(vertices, triangles, corners[:2])
    with pytest.raises(ParameterizationError, match="not on the border"):
        parameterize_patch(vertices, triangles, [0, 5, 14])
    with pytest.raises(ParameterizationError, match="cyclic order"):
        parameterize_patch(vertices, triangles, [corners[0], corners[2], corners[1], corners[3]])
    # an annulus: the square without the two triangles of its middle cell (row 2, column 2 of 5 x 5)
    annulus = np.delete(triangles, [12, 37], axis=0)
    with pytest.raises(ParameterizationError, match="several loops"):
        parameterize_patch(vertices, annulus, corners)
    # two squares sharing a corner vertex: the border touches itself
    shifted = vertices + [1.0, 1.0, 0.0]
    bowtie = np.r_[triangles, triangles + len(vertices)]
    both = np.r_[vertices, shifted]
    bowtie[bowtie == len(vertices)] = 35  # glue the second square's first corner to the first's last
    with pytest.raises(ParameterizationError):
        parameterize_patch(both, bowtie, corners)
    flipped = triangles.copy()
    flipped[0] = flipped[0, ::-1]
    with pytest.raises(ParameterizationError, match="consistently oriented"):
        parameterize_patch(vertices, flipped, corners)
    assert issubclass(ParameterizationError, InvalidInputError)


def test_point_location_exact_at_vertices_and_on_edges() -> None:
    vertices, triangles, _ = random_disk(800, 11)
    uv = parameterize_patch(vertices, triangles, [0, 20, 40, 60]).uv
    locator = PointLocator(uv, triangles)
    tri, bary, _ = locator.locate(uv)
    assert np.all(tri >= 0)
    # a vertex is found with barycentric coordinates exactly (1, 0, 0) at itself
    corner_of = locator.triangles[tri]
    assert np.all(np.sum(bary == 1.0, axis=1) == 1)
    assert np.array_equal(corner_of[np.arange(len(uv)), np.argmax(bary, axis=1)], np.arange(len(uv)))
    # edge midpoints and random interior points are reproduced by their barycentric coordinates
    rng = np.random.default_rng(0)
    mids = (uv[triangles[:, 0]] + uv[triangles[:, 1]]) / 2
    w = rng.dirichlet([1, 1, 1], size=len(triangles))
    inner = np.einsum("tk,tkj->tj", w, uv[triangles])
    for points in (mids, inner):
        tri, bary, dist = locator.locate(points)
        assert np.all(tri >= 0) and np.all(bary >= 0) and np.allclose(bary.sum(axis=1), 1)
        assert np.abs(np.einsum("pk,pkj->pj", bary, uv[triangles[tri]]) - points).max() < 1e-14
        assert dist.max() <= 1e-15
    assert np.array_equal(locator.locate(inner)[0], np.arange(len(triangles)))
    # a clockwise parameter mesh (controls against the triangles) is searched the same way
    mirrored = PointLocator(uv[:, ::-1], triangles)
    assert np.array_equal(mirrored.locate(inner[:, ::-1])[0], np.arange(len(triangles)))


def test_point_location_at_the_border_within_tolerance_and_outside() -> None:
    vertices, triangles, corners = grid(9)
    uv = parameterize_patch(vertices, triangles, corners).uv
    locator = PointLocator(uv, triangles)
    side = np.array([1.0, 0.0]) + np.linspace(0, 1, 37)[:, None] * np.array([-1.0, 1.0])
    outward = np.array([1.0, 1.0]) / np.sqrt(2)
    tri, bary, dist = locator.locate(np.r_[side, side[5:6] + 1e-12 * outward, side[5:6] + 1e-3 * outward, [[5.0, 5.0]]])
    assert np.all(tri[:38] >= 0) and np.all(dist[:37] <= 1e-15) and 0 < dist[37] < 1e-11
    assert tri[38] == -1 and tri[39] == -1


def dome(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """A dome over the unit square, Delaunay-triangulated random points (a different triangulation from grid)."""
    rng = np.random.default_rng(seed)
    edge = np.linspace(0, 1, 11)[:-1]
    rim = np.r_[
        np.c_[edge, 0 * edge], np.c_[1 + 0 * edge, edge], np.c_[1 - edge, 1 + 0 * edge], np.c_[0 * edge, 1 - edge]
    ]
    xy = np.r_[rim, 0.02 + 0.96 * rng.random((n, 2))]
    triangles = ccw(xy, Delaunay(xy).simplices.astype(np.int64))
    z = 0.4 * np.sin(np.pi * xy[:, 0]) * np.sin(np.pi * xy[:, 1])
    return np.c_[xy, z], triangles, [0, 10, 20, 30]


def test_compatible_mesh_lies_on_the_target_and_refines_below_the_tolerance() -> None:
    source, source_tri, source_corners = grid(6)
    target, target_tri, target_corners = dome(400, 3)
    first = compatible_patch(source, source_tri, source_corners, target, target_tri, target_corners, tolerance=1.0)
    assert first.rounds == 0 and len(first.source_vertices) == len(source)
    # every compatible vertex lies on the target, the controls on the target's controls exactly
    on_target = closest_points(first.target_positions, target, target_tri).distances
    assert on_target.max() < 1e-12
    assert np.array_equal(first.target_positions[source_corners], target[target_corners])
    coarse_error = mesh_error(first.target_positions, first.triangles, target, target_tri)
    assert coarse_error == pytest.approx(first.error)

    epsilon = 0.01
    assert coarse_error > epsilon
    patch = compatible_patch(source, source_tri, source_corners, target, target_tri, target_corners, tolerance=epsilon)
    assert patch.rounds > 0 and len(patch.source_vertices) > len(source)
    assert patch.error <= epsilon
    assert mesh_error(patch.target_positions, patch.triangles, target, target_tri) <= epsilon
    assert closest_points(patch.target_positions, target, target_tri).distances.max() < 1e-12
    # the source's shape is unchanged: old vertices kept, new ones inside old triangles, same area
    assert np.array_equal(patch.source_vertices[: len(source)], source)
    new = patch.source_vertices[len(source) :]
    assert closest_points(new, source, source_tri).distances.max() < 1e-15

    def area(xyz: np.ndarray, tri: np.ndarray) -> float:
        return float(
            np.linalg.norm(np.cross(xyz[tri[:, 1]] - xyz[tri[:, 0]], xyz[tri[:, 2]] - xyz[tri[:, 0]]), axis=1).sum() / 2
        )

    assert area(patch.source_vertices, patch.triangles) == pytest.approx(area(source, source_tri), abs=1e-12)
    # the refined source is still a valid parameterised disk with g_s extended linearly
    assert np.all(signed_areas(patch.source_uv, patch.triangles) > 0)
    border = border_loop(patch.triangles, len(patch.source_vertices))
    assert len(border) == 20 and border.max() < len(source)  # patch borders are never split


def test_centroid_splits_alone_stall_where_edge_bisection_converges() -> None:
    """The spec's rule (centroid splits only) never shortens an edge: here it stalls above ε."""
    source, source_tri, corners = grid(6)
    target, target_tri, target_corners = dome(400, 3)
    with pytest.raises(ParameterizationError, match="after 30 refinement rounds"):
        compatible_patch(
            source, source_tri, corners, target, target_tri, target_corners, tolerance=0.01, split="centroid"
        )
    patch = compatible_patch(source, source_tri, corners, target, target_tri, target_corners, tolerance=0.01)
    assert patch.rounds <= 6 and patch.error <= 0.01


def test_refinement_that_cannot_reach_the_tolerance_is_an_error() -> None:
    source, source_tri, corners = grid(4)
    target, target_tri, target_corners = dome(300, 5)
    with pytest.raises(ParameterizationError, match="after 1 refinement rounds") as raised:
        compatible_patch(source, source_tri, corners, target, target_tri, target_corners, tolerance=1e-4, max_rounds=1)
    assert raised.value.hint and "the farthest is target vertex" in raised.value.message
    with pytest.raises(ParameterizationError, match="pair up"):
        compatible_patch(source, source_tri, corners, target, target_tri, target_corners[:3], tolerance=0.1)


def test_closest_points_match_brute_force() -> None:
    vertices, triangles, _ = random_disk(500, 21, bump=0.4)
    rng = np.random.default_rng(1)
    points = rng.uniform(-1.2, 1.2, size=(300, 3))
    got = closest_points(points, vertices, triangles)
    corners = vertices[triangles]
    for i in range(0, 300, 7):
        p = np.repeat(points[i : i + 1], len(triangles), axis=0)
        d = np.linalg.norm(closest_on_triangles(p, corners[:, 0], corners[:, 1], corners[:, 2]) - p, axis=1)
        assert got.distances[i] == pytest.approx(d.min(), abs=1e-14)
        assert d[got.triangles[i]] == pytest.approx(d.min(), abs=1e-14)
