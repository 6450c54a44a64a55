"""Trajectories, controlling surfaces and the evolving surface they make (no database).

The spec's checks: trajectories start at the source and end at the compatible
target, attached vertices stay on their controlling surface(s) at every
sample, and the shape at t0 and t1 is the source and the compatible target.
"""

from __future__ import annotations

import numpy as np
import pytest

from tgsis.interpolation.parameterize import compatible_patch
from tgsis.interpolation.projection import ControllingSurface, IntersectionCurve, ProjectionError
from tgsis.interpolation.trajectories import (
    TrajectoryError,
    border_trajectories,
    evolving_surface,
    vertex_trajectories,
)
from tgsis.temporal import EvolvingSurface

from .test_interp_parameterize import dome, grid


def sheet(u: np.ndarray, v: np.ndarray, point: np.ufunc | object) -> tuple[np.ndarray, np.ndarray]:
    """A triangulated parametric sheet: vertices point(U, V) over the grid u x v."""
    uu, vv = np.meshgrid(u, v)
    vertices = np.asarray(point(uu.ravel(), vv.ravel()))  # type: ignore[operator]
    k, j = len(u), len(v)
    index = np.arange(k * j).reshape(j, k)
    a, b, c, d = index[:-1, :-1].ravel(), index[:-1, 1:].ravel(), index[1:, 1:].ravel(), index[1:, :-1].ravel()
    return vertices, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


# the wall x = 0.3 z^2 and the wall y = 0.2 z (1 - z), both sampled at z = 0 and z = 1 exactly
Z = np.linspace(-1.0, 2.0, 61)  # step 0.05: rows at 0 and 1
WALL_X = ControllingSurface(*sheet(np.linspace(-0.5, 1.5, 21), Z, lambda y, z: np.c_[0.3 * z**2, y, z]), name="wall x")
WALL_Y = ControllingSurface(
    *sheet(np.linspace(-0.5, 1.5, 21), Z, lambda x, z: np.c_[x, 0.2 * z * (1 - z), z]), name="wall y"
)


def lifted(source: np.ndarray) -> np.ndarray:
    """Target of the unit square at z=0: lifted to z=1 and squeezed to x in [0.3, 1], with a bump inside."""
    x, y = source[:, 0], source[:, 1]
    return np.asarray(np.c_[0.3 + 0.7 * x, y, 1 + 0.3 * np.sin(np.pi * x) * np.sin(np.pi * y)])


def relative_distance(surface: ControllingSurface, points: np.ndarray) -> float:
    return float(surface.distance(points).max() / surface.scale)


def test_linear_trajectories_without_attachments() -> None:
    source, triangles, _ = grid(7)
    target = lifted(source)
    paths = vertex_trajectories(source, target, triangles, 5)
    assert paths.shape == (5, 49, 3)
    assert np.array_equal(paths[0], source) and np.array_equal(paths[-1], target)
    assert np.allclose(paths[2], (source + target) / 2, atol=1e-15)
    assert np.array_equal(vertex_trajectories(source, target, triangles, 2), np.stack([source, target]))


def test_attached_to_one_surface_stays_on_it() -> None:
    source, triangles, corners = grid(8)
    target = lifted(source)
    left = np.flatnonzero(source[:, 0] == 0)[1:-1]  # the side x = 0 without its corners
    assert relative_distance(WALL_X, source[left]) < 1e-12 and relative_distance(WALL_X, target[left]) < 1e-12
    m = 7
    paths = vertex_trajectories(source, target, triangles, m, {int(v): [WALL_X] for v in left})
    assert np.array_equal(paths[0], source) and np.array_equal(paths[-1], target)
    for j in range(m):
        assert relative_distance(WALL_X, paths[j, left]) < 1e-9
    # the projection moved them: the straight line leaves the curved wall
    straight = source[left] + 0.5 * (target[left] - source[left])
    assert relative_distance(WALL_X, straight) > 1e-3
    # unattached border vertices stay linear
    right = np.flatnonzero(source[:, 0] == 1)
    assert np.allclose(paths[3, right], (source + 0.5 * (target - source))[right], atol=1e-15)


def test_attached_to_two_surfaces_stays_on_their_intersection_curve() -> None:
    curve = IntersectionCurve(WALL_X, WALL_Y)
    assert len(curve.polylines) == 1 and len(curve.polylines[0]) >= len(Z)
    # the curve's nodes lie on both walls
    assert relative_distance(WALL_X, curve.nodes) < 1e-12 and relative_distance(WALL_Y, curve.nodes) < 1e-12
    source, triangles, corners = grid(8)
    target = lifted(source)
    corner = corners[0]  # (0, 0, 0) -> (0.3, 0, 1): on both walls at both ends
    left = np.flatnonzero(source[:, 0] == 0)[1:-1]
    attachments = {corner: [WALL_X, WALL_Y], **{int(v): [WALL_X] for v in left}}
    m = 9
    paths = vertex_trajectories(source, target, triangles, m, attachments, controls=corners)
    assert np.array_equal(paths[0], source) and np.array_equal(paths[-1], target)
    for j in range(m):
        assert relative_distance(WALL_X, paths[j, [corner]]) < 1e-9
        assert relative_distance(WALL_Y, paths[j, [corner]]) < 1e-9
        assert relative_distance(WALL_X, paths[j, left]) < 1e-9
    assert abs(paths[m // 2, corner, 1]) > 1e-3  # it left the plane y = 0 to follow the curve
    with pytest.raises(TrajectoryError, match="not a control vertex"):
        vertex_trajectories(source, target, triangles, m, {int(left[0]): [WALL_X, WALL_Y]}, controls=corners)


def test_intersection_curve_closes_around_a_cylinder() -> None:
    """A plane through a (seamed) cylinder: one closed polyline, first node repeated at the end."""
    u = np.linspace(0, 2 * np.pi, 41)
    cylinder = ControllingSurface(
        *sheet(u, np.linspace(-1, 1, 5), lambda a, z: np.c_[np.cos(a), np.sin(a), z]), name="cylinder"
    )
    tilted = ControllingSurface(
        *sheet(np.linspace(-2, 2, 3), np.linspace(-2, 2, 3), lambda x, y: np.c_[x, y, 0.2 * x + 0.1]), name="tilted"
    )
    curve = IntersectionCurve(cylinder, tilted)
    assert len(curve.polylines) == 1
    line = curve.polylines[0]
    assert line[0] == line[-1] and len(line) > 40
    points = np.array([[2.0, 0.0, 0.0], [0.0, 0.0, 0.3], [-0.5, 0.5, 1.0]])
    projected = curve.project(points)
    assert relative_distance(cylinder, projected) < 1e-9 and relative_distance(tilted, projected) < 1e-9


def test_attachment_errors() -> None:
    source, triangles, corners = grid(5)
    target = lifted(source)
    with pytest.raises(TrajectoryError, match="not a border vertex"):
        vertex_trajectories(source, target, triangles, 4, {12: [WALL_X]})
    with pytest.raises(TrajectoryError, match="one or two"):
        vertex_trajectories(source, target, triangles, 4, {0: [WALL_X, WALL_Y, WALL_X]})
    with pytest.raises(TrajectoryError, match="from controlling surface 'wall x' in the source"):
        vertex_trajectories(source, target, triangles, 4, {4: [WALL_X]})  # (1, 0, 0) is off the wall
    with pytest.raises(TrajectoryError, match="m >= 2"):
        vertex_trajectories(source, target, triangles, 1)
    far = ControllingSurface([[5, 5, 5], [6, 5, 5], [5, 6, 5]], [[0, 1, 2]], name="far")
    with pytest.raises(ProjectionError, match="do not cross"):
        border_trajectories(source, target, [0], 4, {0: [WALL_X, far]})


def test_evolving_surface_from_a_compatible_patch() -> None:
    """The whole chain: compatible patch, trajectories with an attachment, model-3 surface at t0, t1 and between."""
    source, source_tri, corners = grid(6)
    target, target_tri, target_corners = dome(300, 7)
    patch = compatible_patch(source, source_tri, corners, target, target_tri, target_corners, tolerance=0.02)
    # the target's side x = 0 is the line z = 0: attach the source's side x = 0 to the plane x = 0
    plane = ControllingSurface([[0, -1, -1], [0, 2, -1], [0, 2, 2], [0, -1, 2]], [[0, 1, 2], [0, 2, 3]], name="plane")
    side = np.flatnonzero(patch.source_vertices[:, 0] == 0)
    m, t0, t1 = 6, -120.0, -80.0
    paths = vertex_trajectories(
        patch.source_vertices, patch.target_positions, patch.triangles, m, {int(v): [plane] for v in side}
    )
    assert np.array_equal(paths[0], patch.source_vertices)
    assert np.array_equal(paths[-1], patch.target_positions)
    surface = evolving_surface(patch.triangles, paths, t0, t1, name="horizon")
    assert isinstance(surface, EvolvingSurface) and surface.start == t0 and surface.end == t1
    start, end = surface.at(t0), surface.at(t1)
    assert start is not None and end is not None
    assert np.array_equal(start.vertices, patch.source_vertices)
    assert np.array_equal(end.vertices, patch.target_positions)
    assert np.array_equal(start.triangles, patch.triangles)
    middle = surface.at(t0 + 2 * (t1 - t0) / (m - 1))
    assert middle is not None and np.allclose(middle.vertices, paths[2], atol=1e-14)
    assert surface.at(t1 + 1) is None and surface.at(t0 - 1) is None
    for j in range(m):
        assert np.abs(paths[j, side, 0]).max() < 1e-12
